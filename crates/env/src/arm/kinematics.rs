//! Kinematics of the planar 3R arm in task coordinates x_e = (x, y, φ), φ = q1 + q2 + q3
//! (§2-1, eq. 2-4 with n = m = 3: the analytical Jacobian is square and T_J = I in the plane).

use super::mat3::{M3, V3};

/// Sines and cosines of the absolute link angles θ_i = q1 + … + q_i, computed once and shared
/// by kinematics and dynamics.
#[derive(Clone, Copy, Debug)]
pub struct Trig {
    /// cos θ_i.
    pub c: [f64; 3],
    /// sin θ_i.
    pub s: [f64; 3],
}

impl Trig {
    /// From joint angles.
    #[inline]
    pub fn new(q: &V3) -> Trig {
        let t1 = q[0];
        let t2 = t1 + q[1];
        let t3 = t2 + q[2];
        let (s1, c1) = t1.sin_cos();
        let (s2, c2) = t2.sin_cos();
        let (s3, c3) = t3.sin_cos();
        Trig {
            c: [c1, c2, c3],
            s: [s1, s2, s3],
        }
    }
}

/// Absolute link angle rates θ̇_i = q̇1 + … + q̇_i.
#[inline]
pub fn abs_rates(qd: &V3) -> V3 {
    [qd[0], qd[0] + qd[1], qd[0] + qd[1] + qd[2]]
}

/// Forward kinematics (x, y, φ) of the TCP at the end of link 3.
#[inline]
pub fn fk(l: &V3, q: &V3, t: &Trig) -> V3 {
    [
        l[0] * t.c[0] + l[1] * t.c[1] + l[2] * t.c[2],
        l[0] * t.s[0] + l[1] * t.s[1] + l[2] * t.s[2],
        q[0] + q[1] + q[2],
    ]
}

/// Analytical Jacobian ∂(x, y, φ)/∂q.
#[inline]
pub fn jacobian(l: &V3, t: &Trig) -> M3 {
    // Column j collects links i ≥ j.
    let sx = [l[0] * t.s[0], l[1] * t.s[1], l[2] * t.s[2]];
    let cx = [l[0] * t.c[0], l[1] * t.c[1], l[2] * t.c[2]];
    let s3 = sx[2];
    let s2 = sx[1] + s3;
    let s1 = sx[0] + s2;
    let c3 = cx[2];
    let c2 = cx[1] + c3;
    let c1 = cx[0] + c2;
    [[-s1, -s2, -s3], [c1, c2, c3], [1.0, 1.0, 1.0]]
}

/// J̇(q, q̇)·q̇, the velocity-product part of the TCP acceleration.
#[inline]
pub fn jdot_qdot(l: &V3, t: &Trig, qd: &V3) -> V3 {
    let w = abs_rates(qd);
    let mut r = [0.0; 3];
    for i in 0..3 {
        let w2 = w[i] * w[i] * l[i];
        r[0] -= w2 * t.c[i];
        r[1] -= w2 * t.s[i];
    }
    r
}

/// Inverse kinematics for (x, y, φ) with the elbow q2 > 0. `min_sin_q2` rejects poses at or
/// too near the stretched/folded singularities (det J = l1·l2·sin q2). Errors say why.
pub fn ik(l: &V3, pose: &V3, min_sin_q2: f64) -> Result<V3, String> {
    let [x, y, phi] = *pose;
    let wx = x - l[2] * phi.cos();
    let wy = y - l[2] * phi.sin();
    let r2 = wx * wx + wy * wy;
    let c2 = (r2 - l[0] * l[0] - l[1] * l[1]) / (2.0 * l[0] * l[1]);
    if !c2.is_finite() {
        return Err("non-finite pose".into());
    }
    if c2 > 1.0 {
        return Err(format!(
            "the wrist point is {:.4} m from the base, beyond the reach l1 + l2 = {:.4} m",
            r2.sqrt(),
            l[0] + l[1]
        ));
    }
    if c2 < -1.0 {
        return Err(format!(
            "the wrist point is {:.4} m from the base, inside |l1 − l2| = {:.4} m",
            r2.sqrt(),
            (l[0] - l[1]).abs()
        ));
    }
    let q2 = c2.acos();
    let s2 = q2.sin();
    if s2 < min_sin_q2 {
        return Err(format!(
            "the arm would be singular there (sin q2 = {s2:.2e} < {min_sin_q2:.2e})"
        ));
    }
    let q1 = wy.atan2(wx) - (l[1] * s2).atan2(l[0] + l[1] * c2);
    let q3 = phi - q1 - q2;
    Ok([q1, q2, q3])
}

#[cfg(test)]
mod tests {
    use super::super::mat3::mul_mv;
    use super::*;

    const L: V3 = [0.4, 0.4, 0.4];

    #[test]
    fn ik_inverts_fk_and_elbow_positive() {
        for pose in [
            [0.5, 0.0, 0.0],
            [0.7, 0.2, 0.0],
            [0.8, 0.2, 0.0],
            [0.3, -0.4, 0.5],
        ] {
            let q = ik(&L, &pose, 1e-3).unwrap();
            assert!(q[1] > 0.0);
            let x = fk(&L, &q, &Trig::new(&q));
            for i in 0..3 {
                assert!((x[i] - pose[i]).abs() < 1e-12, "{pose:?} {x:?}");
            }
        }
        assert!(ik(&L, &[1.5, 0.0, 0.0], 1e-3).is_err());
        assert!(ik(&L, &[0.4, 0.0, 0.0], 1e-3).is_err()); // wrist at the base: folded, singular
    }

    #[test]
    fn jacobian_and_jdot_match_finite_differences() {
        let q = [0.3, 1.1, -0.7];
        let qd = [0.5, -1.2, 0.8];
        let t = Trig::new(&q);
        let j = jacobian(&L, &t);
        let e = 1e-6;
        for k in 0..3 {
            let mut qp = q;
            let mut qm = q;
            qp[k] += e;
            qm[k] -= e;
            let xp = fk(&L, &qp, &Trig::new(&qp));
            let xm = fk(&L, &qm, &Trig::new(&qm));
            for i in 0..3 {
                assert!((j[i][k] - (xp[i] - xm[i]) / (2.0 * e)).abs() < 1e-8);
            }
        }
        // d/dt (J q̇) at fixed q̇ along q(t) = q + t q̇
        let qp: V3 = std::array::from_fn(|i| q[i] + e * qd[i]);
        let qm: V3 = std::array::from_fn(|i| q[i] - e * qd[i]);
        let vp = mul_mv(&jacobian(&L, &Trig::new(&qp)), &qd);
        let vm = mul_mv(&jacobian(&L, &Trig::new(&qm)), &qd);
        let a = jdot_qdot(&L, &t, &qd);
        for i in 0..3 {
            assert!((a[i] - (vp[i] - vm[i]) / (2.0 * e)).abs() < 1e-7);
        }
    }
}
