//! Check (k), library part: every kind of bad input of issue 5 row 9 is an error naming the
//! field (or the time, for divergence), never a panic and never silently clipped.

use vicpilco_env::arm::{
    ActionMode, ArmConfig, ArmEnv, ControllerKind, OnDivergence, ReferenceOrigin, ReferenceSpec,
};
use vicpilco_env::{EnvError, Environment};

const START: [f64; 6] = [0.5, 0.0, 0.0, 0.0, 0.0, 0.0];

fn env(cfg: ArmConfig) -> ArmEnv {
    let mut e = ArmEnv::new(cfg).unwrap();
    e.reset(&START, 1).unwrap();
    e
}

#[test]
fn stiffness_not_positive() {
    let mut e = env(ArmConfig::default());
    let err = e.step(&[-3.0, 100.0]).unwrap_err();
    assert_eq!(err.to_string(), "stiffness k_x = -3 must be > 0 and finite");
    let err = e.step(&[100.0, 0.0]).unwrap_err();
    assert!(
        err.to_string().starts_with("stiffness k_y = 0 must be > 0"),
        "{err}"
    );
    // The rejected actions did not advance the episode.
    assert_eq!(e.sim().unwrap().t(), 0.0);
}

#[test]
fn stiffness_not_finite() {
    let mut e = env(ArmConfig::default());
    for bad in [f64::NAN, f64::INFINITY] {
        let err = e.step(&[bad, 100.0]).unwrap_err();
        assert!(
            matches!(err, EnvError::InvalidAction { ref field, .. } if field == "k_x"),
            "{err}"
        );
    }
}

#[test]
fn reference_increment_above_limit() {
    let mut e = env(ArmConfig {
        mode: ActionMode::vilta(),
        ..ArmConfig::default()
    });
    assert!(e.step(&[100.0, 100.0, 0.0025, -0.0025]).is_ok());
    let err = e.step(&[100.0, 100.0, 0.0, -0.003]).unwrap_err();
    assert_eq!(
        err.to_string(),
        "reference increment dy_ref = -0.003 must be within ±0.0025 m per tick"
    );
}

#[test]
fn wrong_action_length() {
    let mut e = env(ArmConfig::default());
    let err = e.step(&[100.0, 100.0, 0.0]).unwrap_err();
    assert_eq!(
        err,
        EnvError::Dimension {
            what: "action",
            got: 3,
            expected: 2
        }
    );
}

#[test]
fn start_out_of_reach() {
    let mut e = ArmEnv::new(ArmConfig::default()).unwrap();
    let err = e.reset(&[1.5, 0.0, 0.0, 0.0, 0.0, 0.0], 1).unwrap_err();
    assert!(
        matches!(err, EnvError::OutOfReach { x, .. } if x == 1.5),
        "{err}"
    );
    assert!(err.to_string().contains("out of reach"), "{err}");
    // Folded onto the base: singular.
    let err = e.reset(&[0.4, 0.0, 0.0, 0.0, 0.0, 0.0], 1).unwrap_err();
    assert!(err.to_string().contains("singular"), "{err}");
    let err = e
        .reset(&[0.5, f64::NAN, 0.0, 0.0, 0.0, 0.0], 1)
        .unwrap_err();
    assert!(err.to_string().contains("start state y"), "{err}");
    let err = e.reset(&[0.5, 0.0], 1).unwrap_err();
    assert!(matches!(
        err,
        EnvError::Dimension {
            got: 2,
            expected: 6,
            ..
        }
    ));
    // Inside the wall face (0.25 m deep).
    let err = e.reset(&[0.9, 0.0, 0.0, 0.0, 0.0, 0.0], 1).unwrap_err();
    assert!(err.to_string().contains("inside a surface"), "{err}");
    // Not reset yet: stepping is an error, not a panic.
    assert_eq!(e.step(&[100.0, 100.0]).unwrap_err(), EnvError::NotReset);
}

#[test]
fn divergence_reports_time() {
    // A stiffness far beyond what a 1 kHz loop can hold makes the closed loop unstable.
    for k in [1e9, f64::MAX] {
        let mut e = env(ArmConfig {
            on_divergence: OnDivergence::Error,
            ..ArmConfig::default()
        });
        let err = (0..100)
            .find_map(|_| e.step(&[k, k]).err())
            .expect("must diverge");
        match &err {
            EnvError::Diverged { t, detail } => {
                eprintln!("(k) k = {k:e}: {err}");
                assert!(*t > 0.0 && *t < 10.0 && !detail.is_empty());
                assert!(
                    detail.contains("reference at (") && detail.contains("gains ("),
                    "{detail}"
                );
            }
            other => panic!("expected divergence, got {other}"),
        }
        assert!(err.to_string().starts_with("simulation diverged at t = "));
        // The arm stopped mid-step: stepping on is refused until a reset.
        assert!(matches!(
            e.step(&[100.0, 100.0]).unwrap_err(),
            EnvError::EpisodeOver { .. }
        ));
    }
}

/// By default a runaway ends the episode instead of the run: the step reports the last sound
/// state (finite, joints within `max_joint_speed`), flags `diverged`, names what ran away, and
/// the episode is over.
#[test]
fn divergence_ends_the_episode_at_the_last_sound_state() {
    for k in [1e9, f64::MAX] {
        let cfg = ArmConfig::default();
        let mut e = env(cfg.clone());
        let mut steps = Vec::new();
        while steps.last().is_none_or(|s: &vicpilco_env::Step| !s.done) {
            steps.push(e.step(&[k, k]).expect("a runaway is not an error"));
        }
        let last = steps.last().unwrap();
        assert!(steps.len() < cfg.horizon, "k = {k:e} never diverged");
        assert!(last.info.flags["diverged"]);
        assert!(!last.info.flags["singular"]);
        let why = last.info.stopped_early.as_deref().expect("a reason");
        assert!(why.starts_with("simulation diverged at t = "), "{why}");
        assert!(why.contains("exceeds max_joint_speed") || why.contains("not finite"));
        // Whole steps before it have no reason and no flag.
        for s in &steps[..steps.len() - 1] {
            assert!(s.info.stopped_early.is_none() && !s.info.flags["diverged"]);
        }
        // The state reported is the one before the runaway tick.
        let sim = e.sim().unwrap();
        let qd = &sim.state()[3..];
        assert!(sim.state().iter().all(|v| v.is_finite()));
        assert!(qd.iter().all(|v| v.abs() <= cfg.max_joint_speed), "{qd:?}");
        assert!(last.observation.iter().all(|v| v.is_finite()));
        assert!(last.info.true_state.iter().all(|v| v.is_finite()));
        assert_eq!(last.info.t, sim.t());
        assert!(last.info.t < steps.len() as f64 * cfg.step_dt);
        assert!(matches!(
            e.step(&[100.0, 100.0]).unwrap_err(),
            EnvError::EpisodeOver { .. }
        ));
    }
}

/// What stopped vilta-var seed 2: VILTA increments that drive the integrated reference out of
/// the arm's reach. The episode ends (runaway or singular Jacobian), never the run.
#[test]
fn a_vilta_reference_driven_out_of_reach_ends_the_episode() {
    let cfg = ArmConfig {
        mode: ActionMode::Vilta {
            delta_max: 0.0025,
            delta_tick: 0.005,
            origin: ReferenceOrigin::Start,
            max_lead: None,
            lead_state: false,
        },
        ..ArmConfig::default()
    };
    let mut e = env(cfg.clone());
    let mut last = None;
    for _ in 0..cfg.horizon {
        let s = e.step(&[127.5, 127.5, 0.0, -0.0025]).expect("not an error");
        let done = s.done;
        last = Some(s);
        if done {
            break;
        }
    }
    let last = last.unwrap();
    let why = last.info.stopped_early.as_deref().expect("ended early");
    eprintln!("ended at t = {:.3} s: {why}", last.info.t);
    assert!(last.info.flags["diverged"] || last.info.flags["singular"]);
    assert!(last.info.t < cfg.horizon as f64 * cfg.step_dt);
}

#[test]
fn episode_over() {
    let mut e = ArmEnv::new(ArmConfig {
        horizon: 2,
        ..ArmConfig::default()
    })
    .unwrap();
    e.reset(&START, 1).unwrap();
    assert!(!e.step(&[100.0, 100.0]).unwrap().done);
    assert!(e.step(&[100.0, 100.0]).unwrap().done);
    assert!(matches!(
        e.step(&[100.0, 100.0]).unwrap_err(),
        EnvError::EpisodeOver { .. }
    ));
    e.reset(&START, 1).unwrap();
    assert!(e.step(&[100.0, 100.0]).is_ok());
}

#[test]
fn config_negative_mass() {
    let mut cfg = ArmConfig::default();
    cfg.arm.mass[1] = -1.0;
    let err = ArmEnv::new(cfg).unwrap_err();
    assert_eq!(err.to_string(), "config arm.mass[1] = -1 must be > 0");
    let mut cfg = ArmConfig::default();
    cfg.impedance.mass[2] = 0.0;
    assert!(ArmEnv::new(cfg)
        .unwrap_err()
        .to_string()
        .contains("impedance.mass[2]"));
    let cfg = ArmConfig {
        mismatch: -1.15,
        ..ArmConfig::default()
    };
    assert!(ArmEnv::new(cfg)
        .unwrap_err()
        .to_string()
        .contains("mismatch"));
}

/// A link with its mass on its joint, no inertia of its own and no motor inertia would make
/// the mass matrix singular: refused, naming it. Any one of the three is enough.
#[test]
fn config_link_that_cannot_resist_its_rotation() {
    let degenerate = |cfg: &mut ArmConfig| {
        cfg.arm.com[2] = 0.0;
        cfg.arm.inertia[2] = 0.0;
        cfg.arm.motor_inertia[2] = 0.0;
    };
    let mut cfg = ArmConfig::default();
    degenerate(&mut cfg);
    let err = ArmEnv::new(cfg).unwrap_err().to_string();
    assert!(
        err.starts_with("config arm.inertia[2] = 0 must be > 0 while com[2] and motor_inertia[2]"),
        "{err}"
    );
    let fixes: [fn(&mut ArmConfig); 3] = [
        |c| c.arm.com[2] = 0.01,
        |c| c.arm.inertia[2] = 1e-6,
        |c| c.arm.motor_inertia[2] = 1e-6,
    ];
    for fix in fixes {
        let mut cfg = ArmConfig::default();
        degenerate(&mut cfg);
        fix(&mut cfg);
        assert!(ArmEnv::new(cfg).is_ok());
    }
}

#[test]
fn config_step_longer_than_control_period() {
    let cfg = ArmConfig {
        h: 2e-3,
        ..ArmConfig::default()
    };
    let err = ArmEnv::new(cfg).unwrap_err();
    assert_eq!(
        err.to_string(),
        "config h = 0.002 must be ≤ 1/control_hz = 0.001"
    );
    let cfg = ArmConfig {
        control_hz: 333.0,
        ..ArmConfig::default()
    };
    assert!(ArmEnv::new(cfg)
        .unwrap_err()
        .to_string()
        .contains("step_dt"));
    let cfg = ArmConfig {
        reference: ReferenceSpec::Ramp {
            from: [0.5, 0.0, 0.0],
            to: [0.6, 0.0, 0.0],
            t0: 1.0,
            t1: 1.0,
        },
        ..ArmConfig::default()
    };
    assert!(ArmEnv::new(cfg)
        .unwrap_err()
        .to_string()
        .contains("reference.t1"));
}

#[test]
fn unknown_controller() {
    let err = "pid".parse::<ControllerKind>().unwrap_err();
    assert_eq!(err, EnvError::UnknownController("pid".into()));
    assert_eq!(
        err.to_string(),
        "unknown controller \"pid\": expected one of gic, sic, off"
    );
    assert_eq!(
        "GIC".parse::<ControllerKind>().unwrap(),
        ControllerKind::Gic
    );
    // Through a serialized configuration too.
    let mut json = serde_json::to_value(ArmConfig::default()).unwrap();
    json["controller"] = "pid".into();
    let parsed: Result<ArmConfig, _> = serde_json::from_value(json);
    assert!(parsed.unwrap_err().to_string().contains("pid"));
}
