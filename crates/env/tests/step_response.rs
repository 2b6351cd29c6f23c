//! Check (c): step response in free space (joint friction off). A +0.02 m reference step in x,
//! then (separately) in y, k ∈ {5, 50, 250} on both axes.

mod common;
use common::run;
use vicpilco_env::arm::{ArmConfig, ArmParams, ControllerKind, ReferenceSpec};

const START: [f64; 2] = [0.5, 0.0];
const STEP: f64 = 0.02;

fn cfg(controller: ControllerKind, axis: usize, mismatch: f64) -> ArmConfig {
    let mut target = [START[0], START[1], 0.0];
    target[axis] += STEP;
    ArmConfig {
        controller,
        mismatch,
        arm: ArmParams {
            joint_friction: [0.0; 3],
            ..ArmParams::default()
        },
        reference: ReferenceSpec::Fixed(target),
        ..ArmConfig::ideal()
    }
}

/// Error of M ë + B ė + K e = 0 from e(0) = e0, ė(0) = 0 (underdamped, ζ < 1).
fn analytic_error(e0: f64, k: f64, m: f64, zeta: f64, t: f64) -> f64 {
    let wn = (k / m).sqrt();
    let wd = wn * (1.0 - zeta * zeta).sqrt();
    e0 * (-zeta * wn * t).exp() * ((wd * t).cos() + zeta * wn / wd * (wd * t).sin())
}

/// (max |x − x_analytic| over 5 s, max |e| over [4, 5) s, overshoot as a fraction of the step).
fn response(controller: ControllerKind, axis: usize, k: f64, mismatch: f64) -> (f64, f64, f64) {
    let (env, _) = run(cfg(controller, axis, mismatch), START, [k, k], 1, 50);
    let target = START[axis] + STEP;
    let (mut max_dev, mut late_err, mut overshoot): (f64, f64, f64) = (0.0, 0.0, 0.0);
    for r in env.trace() {
        let e = target - r.x[axis];
        max_dev = max_dev.max((e - analytic_error(STEP, k, 1.0, 0.7, r.t)).abs());
        overshoot = overshoot.max(-e / STEP);
        if r.t >= 4.0 {
            late_err = late_err.max(e.abs());
        }
    }
    (max_dev, late_err, overshoot)
}

#[test]
fn check_c_gic_matches_second_order_model() {
    for axis in [0, 1] {
        for k in [5.0, 50.0, 250.0] {
            let (dev, late, os) = response(ControllerKind::Gic, axis, k, 1.0);
            eprintln!(
                "(c) GIC axis {} k = {k}: max deviation from analytic {:.3} % of the step, overshoot {:.1} %",
                ["x", "y"][axis],
                100.0 * dev / STEP,
                100.0 * os
            );
            assert!(dev <= 0.03 * STEP, "axis {axis} k {k}: deviation {dev}");
            assert!(late <= 5e-4);
        }
    }
}

#[test]
fn check_c_gic_with_mismatch_settles() {
    for axis in [0, 1] {
        for k in [5.0, 50.0, 250.0] {
            let (_, late, os) = response(ControllerKind::Gic, axis, k, 1.15);
            eprintln!(
                "(c) GIC + 15 % mismatch axis {} k = {k}: max |e| on [4, 5) s = {:.3} mm, overshoot {:.1} %",
                ["x", "y"][axis],
                late * 1e3,
                100.0 * os
            );
            assert!(late <= 5e-4, "axis {axis} k {k}: {late}");
        }
    }
}

/// SIC along x: settles within 0.5 mm with overshoot ≤ 20 % (the criterion).
#[test]
fn check_c_sic_x_settles_with_small_overshoot() {
    for k in [5.0, 50.0, 250.0] {
        let (_, late, os) = response(ControllerKind::Sic, 0, k, 1.0);
        eprintln!(
            "(c) SIC axis x k = {k}: max |e| on [4, 5) s = {:.3} mm, overshoot {:.1} %",
            late * 1e3,
            100.0 * os
        );
        assert!(late <= 5e-4, "k {k}: {late}");
        assert!(os <= 0.20, "k {k}: overshoot {os}");
    }
}

/// SIC along y does NOT meet the criterion for k ≤ 50 (documented in the README):
/// SIC shapes no inertia, and at the start pose P0 the arm's apparent mass along y is
/// Θ_yy ≈ 12 kg (the folded arm swings about the base), while B_d is sized for M_d = 1 kg, so
/// the y response is underdamped (ζ_eff ≈ 0.7·sqrt(M_d/Θ_yy)) and slow. This test pins the
/// measured behaviour so a change shows up: stable and decaying, overshoot below 55 %.
#[test]
fn check_c_sic_y_underdamped_documented() {
    for k in [5.0, 50.0, 250.0] {
        let (_, late, os) = response(ControllerKind::Sic, 1, k, 1.0);
        eprintln!(
            "(c) SIC axis y k = {k}: max |e| on [4, 5) s = {:.3} mm, overshoot {:.1} % (issue wants ≤ 0.5 mm, ≤ 20 %)",
            late * 1e3,
            100.0 * os
        );
        assert!(late < 0.6 * STEP, "k {k}: {late}");
        assert!(os < 0.55, "k {k}: overshoot {os}");
    }
}
