//! Check (d): pressing against the wall with the reference fixed 50 mm behind the face,
//! k_x ∈ {5, 50, 250}, GIC and SIC. The expected force is k_x·0.05/(1 + k_x/K_env).

mod common;
use common::{mean_std, run, window};
use vicpilco_env::arm::{ArmConfig, ControllerKind, ReferenceSpec, SensorParams};

const K_ENV: f64 = 1e5;

fn wall_cfg(controller: ControllerKind, noise: bool, hz: f64) -> ArmConfig {
    ArmConfig {
        controller,
        noise,
        control_hz: hz,
        reference: ReferenceSpec::Fixed([0.70, 0.0, 0.0]),
        ..ArmConfig::ideal()
    }
}

struct Press {
    mean_true: f64,
    std_true: f64,
    mean_meas: f64,
    std_meas: f64,
    /// std of (measured − true): the F/T sensor noise alone.
    std_ft_noise: f64,
}

/// Starts at (0.62, 0), presses for `secs` and takes statistics over [t0, secs).
fn press(cfg: ArmConfig, k: f64, t0: f64, secs: usize) -> Press {
    let (env, _) = run(cfg, [0.62, 0.0], [k, 250.0], 3, secs * 10);
    let w = window(env.trace(), t0, secs as f64);
    let ft: Vec<f64> = w.iter().map(|r| r.f_true[0]).collect();
    let fm: Vec<f64> = w.iter().map(|r| r.f_meas[0]).collect();
    let dn: Vec<f64> = w.iter().map(|r| r.f_meas[0] - r.f_true[0]).collect();
    let (mean_true, std_true) = mean_std(&ft);
    let (mean_meas, std_meas) = mean_std(&fm);
    Press {
        mean_true,
        std_true,
        mean_meas,
        std_meas,
        std_ft_noise: mean_std(&dn).1,
    }
}

/// Noise-free, 1 kHz: after settling (5 s), the mean true f_x over 1 s is within 2 % of the
/// expected force and its std ≤ 1 % of the mean (no limit cycle).
#[test]
fn check_d_wall_force_no_noise() {
    for controller in [ControllerKind::Gic, ControllerKind::Sic] {
        for k in [5.0, 50.0, 250.0] {
            let expect = k * 0.05 / (1.0 + k / K_ENV);
            let p = press(wall_cfg(controller, false, 1000.0), k, 5.0, 6);
            eprintln!(
                "(d) {controller} k_x = {k}: mean f_x = {:.5} N (expected {expect:.5}), std {:.2e} N",
                p.mean_true, p.std_true
            );
            assert!(
                (p.mean_true / expect - 1.0).abs() < 0.02,
                "{controller} k={k}: mean {}",
                p.mean_true
            );
            assert!(
                p.std_true <= 0.01 * p.mean_true,
                "{controller} k={k}: std {}",
                p.std_true
            );
        }
    }
}

/// With noise, 1 kHz: the measured f_x has the expected mean within 2 % (over 7 s, so the
/// k_x = 5 case is resolved) and the F/T noise on it has std 0.1 N ± 10 %. With only the F/T
/// noise on, the measured std is 0.1 N ± 10 %. With all sensors noisy the true force itself
/// fluctuates (tachometer noise × B_d ≈ 443 N·s/m in contact), so the measured std is about
/// 0.15 N; this is printed and bounded here, and documented in the README.
#[test]
fn check_d_wall_force_with_noise() {
    for controller in [ControllerKind::Gic, ControllerKind::Sic] {
        for k in [5.0, 50.0, 250.0] {
            let expect = k * 0.05 / (1.0 + k / K_ENV);
            let p = press(wall_cfg(controller, true, 1000.0), k, 3.0, 10);
            eprintln!(
                "(d) {controller} k_x = {k} noisy: measured mean {:.4} (expected {expect:.4}), measured std {:.4}, true std {:.4}, F/T noise std {:.4}",
                p.mean_meas, p.std_meas, p.std_true, p.std_ft_noise
            );
            assert!(
                (p.mean_meas / expect - 1.0).abs() < 0.02,
                "{controller} k={k}: mean {}",
                p.mean_meas
            );
            assert!(
                (p.std_ft_noise / 0.1 - 1.0).abs() < 0.1,
                "F/T noise std {}",
                p.std_ft_noise
            );
            assert!(p.std_meas < 0.2, "measured std {}", p.std_meas);
            let ft_only = ArmConfig {
                sensors: SensorParams {
                    encoder_std: 0.0,
                    tacho_std: 0.0,
                    ..SensorParams::default()
                },
                ..wall_cfg(controller, true, 1000.0)
            };
            let p = press(ft_only, k, 3.0, 10);
            eprintln!(
                "(d) {controller} k_x = {k} F/T noise only: measured std {:.4}",
                p.std_meas
            );
            assert!(
                (p.std_meas / 0.1 - 1.0).abs() < 0.1,
                "{controller} k={k}: std {}",
                p.std_meas
            );
            assert!((p.mean_meas / expect - 1.0).abs() < 0.02);
        }
    }
}

/// The thesis's 200 Hz control rate, for the record (see the README): not a pass/fail check.
/// Run with `cargo test -p vicpilco-env --release --test wall -- --ignored --nocapture`.
#[test]
#[ignore]
fn check_d_wall_force_200hz_outcome() {
    for controller in [ControllerKind::Gic, ControllerKind::Sic] {
        for k in [5.0, 50.0, 250.0] {
            let expect = k * 0.05 / (1.0 + k / K_ENV);
            let mut cfg = wall_cfg(controller, false, 200.0);
            cfg.h = 1e-4;
            let (env, _) = run(cfg, [0.62, 0.0], [k, 250.0], 3, 60);
            let w = window(env.trace(), 5.0, 6.0);
            let ft: Vec<f64> = w.iter().map(|r| r.f_true[0]).collect();
            let (m, s) = mean_std(&ft);
            let (lo, hi) = ft
                .iter()
                .fold((f64::MAX, f64::MIN), |(a, b), &f| (a.min(f), b.max(f)));
            let sep = w.iter().filter(|r| !r.contact.face).count();
            eprintln!(
                "(d, 200 Hz) {controller} k_x = {k}: mean f_x {m:.4} (expected {expect:.4}), std {s:.4}, range [{lo:.3}, {hi:.3}], ticks off the wall {sep}/{}",
                w.len()
            );
        }
    }
}
