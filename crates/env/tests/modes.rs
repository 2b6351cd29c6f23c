//! VILTA reference integration, the singular-pose stop, and the Environment trait object.

use vicpilco_env::arm::{ActionMode, ArmConfig, ArmEnv, ControllerKind, Geometry, ReferenceSpec};
use vicpilco_env::Environment;

/// Δ is metres per 5 ms tick at any control rate: Δ = 0.0025 moves the reference 0.05 m per
/// 0.1 s step at 1 kHz and at 200 Hz alike, with ẋ_v = 0.5 m/s.
#[test]
fn vilta_reference_rate_independent() {
    for hz in [1000.0, 200.0] {
        let cfg = ArmConfig {
            mode: ActionMode::vilta(),
            control_hz: hz,
            ..ArmConfig::ideal()
        };
        let mut env = ArmEnv::new(cfg).unwrap();
        assert_eq!(env.action_dim(), 4);
        assert_eq!(env.action_names(), ["k_x", "k_y", "dx_ref", "dy_ref"]);
        env.reset(&[0.5, 0.0, 0.0, 0.0, 0.0, 0.0], 1).unwrap();
        let s = env.step(&[250.0, 250.0, 0.0025, -0.001]).unwrap();
        let r = s.info.reference.unwrap();
        assert!(
            (r[0] - 0.55).abs() < 1e-12 && (r[1] + 0.02).abs() < 1e-12,
            "{hz} Hz: {r:?}"
        );
        assert!((r[2] - 0.5).abs() < 1e-12 && (r[3] + 0.2).abs() < 1e-12);
        let s = env.step(&[250.0, 250.0, 0.0, 0.0]).unwrap();
        let r = s.info.reference.unwrap();
        assert!((r[0] - 0.55).abs() < 1e-12 && r[2] == 0.0);
        assert!(
            (s.info.true_state[0] - 0.55).abs() < 0.02,
            "the arm follows: {}",
            s.info.true_state[0]
        );
    }
}

/// A reference ramping beyond reach stretches the arm until |det J| < 1e-4: the episode ends
/// with the `singular` flag, and further steps are refused. (SIC; GIC's J⁻¹ makes the joint
/// speeds run away first, which is reported as divergence.)
#[test]
fn singular_pose_ends_episode() {
    let cfg = ArmConfig {
        controller: ControllerKind::Sic,
        reference: ReferenceSpec::Ramp {
            from: [0.6, 0.0, 0.0],
            to: [1.4, 0.0, 0.0],
            t0: 0.0,
            t1: 5.0,
        },
        geometry: Geometry::default().shifted(5.0, 0.0), // no wall in the way
        ..ArmConfig::ideal()
    };
    let mut env = ArmEnv::new(cfg).unwrap();
    env.reset(&[0.6, 0.0, 0.0, 0.0, 0.0, 0.0], 1).unwrap();
    let mut last = None;
    for _ in 0..100 {
        let s = env.step(&[250.0, 250.0]).unwrap();
        let done = s.done;
        last = Some(s);
        if done {
            break;
        }
    }
    let last = last.unwrap();
    assert!(
        last.done && last.info.flags["singular"],
        "t = {}",
        last.info.t
    );
    assert!(last.info.t < 10.0);
    assert!(env.step(&[250.0, 250.0]).is_err());
}

/// The learning loop can hold the arm as `Box<dyn Environment>`.
#[test]
fn object_safe() {
    let mut envs: Vec<Box<dyn Environment>> = vec![
        Box::new(ArmEnv::new(ArmConfig::default()).unwrap()),
        Box::new(
            ArmEnv::new(ArmConfig {
                mode: ActionMode::vilta(),
                ..ArmConfig::default()
            })
            .unwrap(),
        ),
    ];
    for env in envs.iter_mut() {
        assert_eq!(env.state_dim(), 6);
        assert_eq!(env.dt(), 0.1);
        assert_eq!(env.horizon(), 100);
        assert_eq!(env.state_names(), ["x", "y", "xd", "yd", "fx", "fy"]);
        let s0 = env.reset(&[0.5, 0.0, 0.0, 0.0, 0.0, 0.0], 9).unwrap();
        assert_eq!(s0.len(), 6);
        assert!((s0[0] - 0.5).abs() < 2e-3);
        let a = vec![100.0; 2]
            .into_iter()
            .chain(vec![0.0; env.action_dim() - 2])
            .collect::<Vec<_>>();
        let s = env.step(&a).unwrap();
        assert_eq!(s.observation.len(), 6);
        assert!((s.info.t - 0.1).abs() < 1e-12);
    }
}

/// Pushing on with Δx at its limit after the peg meets the wall face: a reference integrated
/// from the start runs on into the wall and the force grows with it (by k · v_max · Δt =
/// 12.5 N per step at 250 N/m); one restarted at the measured position each step stays within
/// v_max · Δt of the TCP, so the force stays where it is (the stiffness's k · v_max · Δt plus
/// the contact damping's B_d · v_max).
#[test]
fn measured_reference_origin_keeps_the_force_against_a_wall_from_growing() {
    use vicpilco_env::arm::ReferenceOrigin;
    let forces = |origin: ReferenceOrigin| {
        let cfg = ArmConfig {
            mode: ActionMode::Vilta {
                delta_max: 0.0025,
                delta_tick: 0.005,
                origin,
                max_lead: None,
                lead_state: false,
            },
            ..ArmConfig::ideal()
        };
        let mut env = ArmEnv::new(cfg).unwrap();
        env.reset(&[0.5, 0.0, 0.0, 0.0, 0.0, 0.0], 1).unwrap();
        let mut f = Vec::new();
        for _ in 0..40 {
            let s = env.step(&[250.0, 250.0, 0.0025, 0.0]).unwrap();
            // At the face (x = 0.65 m) after a few steps.
            f.push((s.info.true_state[0], s.observation[4]));
        }
        f
    };
    let integrated = forces(ReferenceOrigin::Start);
    let measured = forces(ReferenceOrigin::Measured);
    for f in [&integrated, &measured] {
        assert!(
            f[20..].iter().all(|(x, _)| (x - 0.65).abs() < 0.01),
            "{f:?}"
        );
    }
    let growth = |f: &[(f64, f64)]| f[39].1 - f[20].1;
    assert!(
        (growth(&integrated) - 19.0 * 12.5).abs() < 25.0,
        "integrated: {integrated:?}"
    );
    assert!(growth(&measured).abs() < 5.0, "measured: {measured:?}");
    assert!(measured[39].1 < integrated[39].1 / 2.0);
}

/// With `max_lead` the reference pushed on into the wall face stops `max_lead` ahead of the
/// TCP: the force levels off at k · max_lead, steady (no rattle from the damping term),
/// instead of growing by k · v_max · Δt per step, and the reported reference stays within
/// `max_lead` of the TCP; pulled back, the reference leaves the wall at once.
#[test]
fn max_lead_holds_the_reference_and_the_force_against_a_wall() {
    use vicpilco_env::arm::ReferenceOrigin;
    let (k, lead) = (250.0, 0.05);
    let cfg = ArmConfig {
        mode: ActionMode::Vilta {
            delta_max: 0.0025,
            delta_tick: 0.005,
            origin: ReferenceOrigin::Start,
            max_lead: Some(lead),
            lead_state: false,
        },
        ..ArmConfig::ideal()
    };
    let mut env = ArmEnv::new(cfg).unwrap();
    env.reset(&[0.5, 0.0, 0.0, 0.0, 0.0, 0.0], 1).unwrap();
    let mut pressed = Vec::new();
    for _ in 0..40 {
        let s = env.step(&[k, k, 0.0025, 0.0]).unwrap();
        let (x, r) = (s.info.true_state[0], s.info.reference.clone().unwrap());
        assert!(
            r[0] - x <= lead + 1e-3,
            "reference {r:?} leads x = {x} by more than {lead}"
        );
        pressed.push((x, s.observation[4]));
    }
    assert!(
        pressed[20..].iter().all(|(x, _)| (x - 0.65).abs() < 0.01),
        "{pressed:?}"
    );
    let f_end = pressed[39].1;
    assert!(
        (f_end - k * lead).abs() < 2.0,
        "force {f_end} N against k · max_lead = {} N: {pressed:?}",
        k * lead
    );
    assert!(
        pressed[20..].iter().all(|(_, f)| (f - f_end).abs() < 1.0),
        "{pressed:?}"
    );
    // One step of pulling back at full speed takes the reference 5 cm back: off the wall.
    let s = env.step(&[k, k, -0.0025, 0.0]).unwrap();
    assert!(s.observation[4].abs() < 5.0, "{:?}", s.observation);
}

#[test]
fn max_lead_must_be_positive() {
    use vicpilco_env::arm::ReferenceOrigin;
    for bad in [0.0, -0.01, f64::NAN] {
        let cfg = ArmConfig {
            mode: ActionMode::Vilta {
                delta_max: 0.0025,
                delta_tick: 0.005,
                origin: ReferenceOrigin::Start,
                max_lead: Some(bad),
                lead_state: false,
            },
            ..ArmConfig::ideal()
        };
        let err = ArmEnv::new(cfg).unwrap_err().to_string();
        assert!(err.contains("mode.max_lead"), "{bad}: {err}");
    }
}

/// With `lead_state` the state gains the reference's lead over the TCP, exactly x_v − x on
/// the true state and x_v − x̂ on the observation; a start's lead entries place the reference
/// that far ahead of the start pose.
#[test]
fn lead_state_reports_the_reference_lead() {
    use vicpilco_env::arm::ReferenceOrigin;
    let cfg = ArmConfig {
        mode: ActionMode::Vilta {
            delta_max: 0.0025,
            delta_tick: 0.005,
            origin: ReferenceOrigin::Start,
            max_lead: None,
            lead_state: true,
        },
        ..ArmConfig::default()
    };
    let mut env = ArmEnv::new(cfg).unwrap();
    assert_eq!(env.state_dim(), 8);
    assert_eq!(
        env.state_names(),
        ["x", "y", "xd", "yd", "fx", "fy", "lead_x", "lead_y"]
    );
    assert!(env.reset(&[0.5, 0.0, 0.0, 0.0, 0.0, 0.0], 1).is_err());
    let s0 = env
        .reset(&[0.5, 0.0, 0.0, 0.0, 0.0, 0.0, 0.02, -0.01], 1)
        .unwrap();
    assert!((s0[6] - (0.52 - s0[0])).abs() < 1e-12, "{s0:?}");
    assert!((s0[7] - (-0.01 - s0[1])).abs() < 1e-12, "{s0:?}");
    let mut leads = Vec::new();
    for _ in 0..5 {
        let s = env.step(&[100.0, 100.0, 0.001, 0.0]).unwrap();
        let (z, r) = (&s.info.true_state, s.info.reference.clone().unwrap());
        assert_eq!(z.len(), 8);
        assert!((z[6] - (r[0] - z[0])).abs() < 1e-15, "{z:?} {r:?}");
        assert!((z[7] - (r[1] - z[1])).abs() < 1e-15, "{z:?} {r:?}");
        assert!(
            (s.observation[6] - (r[0] - s.observation[0])).abs() < 1e-12,
            "{:?} {r:?}",
            s.observation
        );
        leads.push(z[6]);
    }
    // The start's 2 cm lead pulls the arm on, so it catches up with the 0.2 m/s reference.
    assert!(leads[0] > 0.02 && leads[4].abs() < 0.005, "{leads:?}");
}
