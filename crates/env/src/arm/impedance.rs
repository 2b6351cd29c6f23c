//! Cartesian impedance controllers on the measured signals (§2-2).
//!
//! Desired impedance per task axis (x, y, φ): K_d = diag(k_x, k_y, k_φ), M_d, and
//! B_d = 2ζ·sqrt((K_d + K_e)·M_d) with K_e = K_env on an axis whose K_env surface is engaged
//! (§5-2-3; the thesis prints sqrt((K_d + K_e)/M_d), which is not a damping). Errors
//! e = x_v − x, ė = ẋ_v − ẋ with x = f_k(q̃), ẋ = J(q̃) q̃̇ from the noisy joints.
//!
//! * SIC (eq. 2-8, g = 0): τ = Jᵀ[K_d e + B_d ė].
//! * GIC (eqs. 2-11, 2-17, 2-18): τ = M̂(q̃)α + Ĉ(q̃, q̃̇)q̃̇ + JᵀW̃,
//!   α = J⁻¹(ẍ_v + M_d⁻¹(B_d ė + K_d e − W̃) − J̇q̃̇), where hats are the nominal model and W̃ the
//!   F/T reading; with a perfect model this gives M_d ë + B_d ė + K_d e = W (eq. 2-19, T_J = I).

use super::contact::Contact;
use super::dynamics::ArmModel;
use super::kinematics::{fk, jacobian, jdot_qdot, Trig};
use super::mat3::{det, mul_mtv, mul_mv, solve, V3};
use super::params::{ControllerKind, ImpedanceParams};
use super::plan::RefPoint;
use super::sensors::Reading;

/// Impedance gains of one control tick.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Gains {
    /// K_d (N/m, N/m, N·m/rad).
    pub k: V3,
    /// B_d (N·s/m, N·s/m, N·m·s/rad).
    pub b: V3,
    /// M_d (kg, kg, kg·m²).
    pub m: V3,
}

impl Gains {
    /// Gains for stiffness (k_x, k_y), the fixed rotational stiffness, and the damping rule
    /// with K_e = `k_env` on the axes where `contact` engages a surface.
    pub fn new(imp: &ImpedanceParams, k_xy: [f64; 2], contact: &Contact, k_env: f64) -> Gains {
        let k = [k_xy[0], k_xy[1], imp.k_phi];
        let stiff = contact.stiff_axes();
        let ke = [
            if stiff[0] { k_env } else { 0.0 },
            if stiff[1] { k_env } else { 0.0 },
            0.0,
        ];
        let b = std::array::from_fn(|i| 2.0 * imp.zeta * ((k[i] + ke[i]) * imp.mass[i]).sqrt());
        Gains { k, b, m: imp.mass }
    }
}

/// Task-space state estimated from a reading.
#[derive(Clone, Copy, Debug)]
pub struct TaskState {
    /// (x, y, φ).
    pub x: V3,
    /// (ẋ, ẏ, φ̇).
    pub xd: V3,
    /// det J.
    pub det_j: f64,
}

/// Estimates (x, ẋ) from joint readings (eq. 2-4).
pub fn task_state(model: &ArmModel, q: &V3, qd: &V3) -> TaskState {
    let t = Trig::new(q);
    let l = model.lengths();
    let j = jacobian(l, &t);
    TaskState {
        x: fk(l, q, &t),
        xd: mul_mv(&j, qd),
        det_j: det(&j),
    }
}

/// Joint torques of the chosen law. `model` is the controller's nominal arm. The caller must
/// have checked that J(q̃) is not singular (GIC solves with it).
pub fn torque(
    kind: ControllerKind,
    model: &ArmModel,
    r: &Reading,
    refp: &RefPoint,
    g: &Gains,
) -> V3 {
    if kind == ControllerKind::Off {
        return [0.0; 3];
    }
    let t = Trig::new(&r.q);
    let l = model.lengths();
    let j = jacobian(l, &t);
    let x = fk(l, &r.q, &t);
    let xd = mul_mv(&j, &r.qd);
    let e: V3 = std::array::from_fn(|i| refp.x[i] - x[i]);
    let ed: V3 = std::array::from_fn(|i| refp.xd[i] - xd[i]);
    match kind {
        ControllerKind::Sic => {
            let w: V3 = std::array::from_fn(|i| g.k[i] * e[i] + g.b[i] * ed[i]);
            mul_mtv(&j, &w)
        }
        ControllerKind::Gic => {
            let wm = [r.f[0], r.f[1], 0.0];
            let jdqd = jdot_qdot(l, &t, &r.qd);
            let a: V3 = std::array::from_fn(|i| {
                refp.xdd[i] + (g.b[i] * ed[i] + g.k[i] * e[i] - wm[i]) / g.m[i] - jdqd[i]
            });
            let alpha = solve(&j, &a);
            let m = model.mass_matrix(&t);
            let h = model.coriolis_vector(&t, &r.qd);
            let ma = mul_mv(&m, &alpha);
            let jw = mul_mtv(&j, &wm);
            std::array::from_fn(|i| ma[i] + h[i] + jw[i])
        }
        ControllerKind::Off => unreachable!("handled above"),
    }
}

#[cfg(test)]
mod tests {
    use super::super::kinematics::ik;
    use super::super::params::ArmParams;
    use super::*;

    #[test]
    fn damping_rule_and_static_equilibrium() {
        let imp = ImpedanceParams::default();
        let free = Gains::new(&imp, [250.0, 50.0], &Contact::default(), 1e5);
        assert!((free.b[0] - 1.4 * 250f64.sqrt()).abs() < 1e-12);
        let face = Contact {
            face: true,
            ..Contact::default()
        };
        let g = Gains::new(&imp, [250.0, 50.0], &face, 1e5);
        assert!((g.b[0] - 1.4 * (1e5f64 + 250.0).sqrt()).abs() < 1e-9);
        assert_eq!(g.b[1], free.b[1]);
        // At rest with K_d e = W the GIC commands exactly Jᵀ W (no acceleration).
        let model = ArmModel::new(&ArmParams::default());
        let q = ik(&[0.4; 3], &[0.65, 0.0, 0.0], 1e-3).unwrap();
        let r = Reading {
            q,
            qd: [0.0; 3],
            f: [250.0 * 0.05, 0.0],
        };
        let refp = RefPoint {
            x: [0.70, 0.0, 0.0],
            ..RefPoint::default()
        };
        let tau = torque(ControllerKind::Gic, &model, &r, &refp, &g);
        let j = jacobian(&[0.4; 3], &Trig::new(&q));
        let expect = mul_mtv(&j, &[12.5, 0.0, 0.0]);
        let sic = torque(ControllerKind::Sic, &model, &r, &refp, &g);
        for i in 0..3 {
            assert!((tau[i] - expect[i]).abs() < 1e-9);
            assert!((sic[i] - expect[i]).abs() < 1e-9);
        }
    }
}
