//! Tests shared by both classic systems: noise, seeding, action checks and the episode
//! life cycle.

use super::*;
use std::f64::consts::PI;

/// 10⁴ observations at rest (the true state stays exactly 0, see the `rest_at_bottom_stays`
/// tests): per entry, the sample std of observation − truth is within 3 % of `noise_std`
/// and the sample mean within 4 σ/√n of 0.
fn check_noise<P: ClassicSystem + Dynamics<N>, const N: usize>(mut scenario: Scenario<P>) {
    let n = 10_000;
    scenario.horizon = n;
    let std = scenario.noise_std.clone();
    let mut env = ClassicEnv::<P, N>::new(scenario).unwrap();
    let mut sum = [0.0; N];
    let mut sq = [0.0; N];
    let first = env.reset(&[0.0; N], 77).unwrap();
    let mut add = |o: &[f64]| {
        for i in 0..N {
            sum[i] += o[i];
            sq[i] += o[i] * o[i];
        }
    };
    add(&first);
    for _ in 0..n - 1 {
        let s = env.step(&[0.0]).unwrap();
        assert_eq!(s.info.true_state, vec![0.0; N]);
        add(&s.observation);
    }
    for i in 0..N {
        let mean = sum[i] / n as f64;
        let sd = ((sq[i] - n as f64 * mean * mean) / (n - 1) as f64).sqrt();
        assert!(
            (sd / std[i] - 1.0).abs() < 0.03,
            "{}: std {sd} vs {}",
            P::STATE_NAMES[i],
            std[i]
        );
        assert!(
            mean.abs() < 4.0 * std[i] / (n as f64).sqrt(),
            "{}: mean {mean}",
            P::STATE_NAMES[i]
        );
    }
}

#[test]
fn noise_statistics_pendulum() {
    check_noise::<PendulumPhysics, 2>(PendulumScenario::default());
}

#[test]
fn noise_statistics_cartpole() {
    check_noise::<CartPolePhysics, 4>(CartPoleScenario::default());
}

/// The observations of one episode driven by a fixed action sequence.
fn trace<E: Environment>(env: &mut E, start: &[f64], seed: u64, max: f64) -> Vec<Vec<f64>> {
    let mut out = vec![env.reset(start, seed).unwrap()];
    for k in 0..env.horizon() {
        let u = max * (0.37 * k as f64).sin();
        out.push(env.step(&[u]).unwrap().observation);
    }
    out
}

fn bits(t: &[Vec<f64>]) -> Vec<u64> {
    t.iter().flatten().map(|v| v.to_bits()).collect()
}

/// Same seed, same trace bit for bit (also across environment instances and after another
/// episode); different seeds give different traces with the same true states.
#[test]
fn seeded_determinism() {
    let mut a = Pendulum::default();
    let mut b = Pendulum::default();
    let start = [0.05, -0.1];
    let t1 = trace(&mut a, &start, 11, 2.5);
    let _ = trace(&mut a, &start, 12, 2.5);
    let t2 = trace(&mut a, &start, 11, 2.5);
    let t3 = trace(&mut b, &start, 11, 2.5);
    assert_eq!(bits(&t1), bits(&t2));
    assert_eq!(bits(&t1), bits(&t3));
    let t4 = trace(&mut b, &start, 12, 2.5);
    assert!(
        t1.iter().zip(&t4).all(|(x, y)| x != y),
        "every observation must differ"
    );

    let mut c = CartPole::default();
    let start = [0.1, 0.0, -0.05, 0.02];
    let u1 = trace(&mut c, &start, 5, 10.0);
    let u2 = trace(&mut c, &start, 5, 10.0);
    let u3 = trace(&mut c, &start, 6, 10.0);
    assert_eq!(bits(&u1), bits(&u2));
    assert_ne!(bits(&u1), bits(&u3));
}

/// `reset` sets the true state to `start` exactly; the first observation is noisy.
#[test]
fn reset_sets_start_exactly() {
    let mut env = CartPole::default();
    let start = [0.1, -0.2, 0.3, 3.0];
    let obs = env.reset(&start, 9).unwrap();
    assert_eq!(env.true_state(), Some(start));
    assert_ne!(obs, start.to_vec());
    assert!(obs.iter().zip(&start).all(|(o, s)| (o - s).abs() < 0.1));
}

fn action_error<E: Environment>(env: &mut E, action: &[f64]) -> String {
    let start = vec![0.0; env.state_dim()];
    env.reset(&start, 1).unwrap();
    env.step(action).unwrap_err().to_string()
}

/// Wrong length, non-finite and out-of-range actions are errors naming the field; nothing is
/// clipped, and the limit itself is allowed.
#[test]
fn bad_actions_rejected() {
    let mut p = Pendulum::default();
    let e = action_error(&mut p, &[]);
    assert!(e.contains("action") && e.contains("0 entries"), "{e}");
    let e = action_error(&mut p, &[0.0, 1.0]);
    assert!(e.contains("action") && e.contains("2 entries"), "{e}");
    let e = action_error(&mut p, &[f64::NAN]);
    assert!(e.contains("torque") && e.contains("finite"), "{e}");
    let e = action_error(&mut p, &[2.6]);
    assert!(e.contains("torque") && e.contains("2.5"), "{e}");
    let e = action_error(&mut p, &[f64::NEG_INFINITY]);
    assert!(e.contains("torque"), "{e}");
    p.reset(&[0.0, 0.0], 1).unwrap();
    p.step(&[2.5]).unwrap();
    p.step(&[-2.5]).unwrap();

    let mut c = CartPole::default();
    let e = action_error(&mut c, &[-10.5]);
    assert!(e.contains("force") && e.contains("±10 N"), "{e}");
    let e = action_error(&mut c, &[f64::INFINITY]);
    assert!(e.contains("force") && e.contains("finite"), "{e}");
    // a rejected action leaves the episode untouched
    c.reset(&[0.0; 4], 1).unwrap();
    assert!(c.step(&[11.0]).is_err());
    assert_eq!(c.true_state(), Some([0.0; 4]));
    c.step(&[10.0]).unwrap();
}

/// Bad start states are errors naming the field.
#[test]
fn bad_starts_rejected() {
    let mut c = CartPole::default();
    let e = c.reset(&[0.0; 3], 1).unwrap_err().to_string();
    assert!(e.contains("start state") && e.contains("3 entries"), "{e}");
    let e = c
        .reset(&[0.0, 0.0, f64::NAN, 0.0], 1)
        .unwrap_err()
        .to_string();
    assert!(e.contains("dtheta"), "{e}");
}

/// `step` before `reset` and after `done` are errors; `done` comes with step H exactly; time
/// and the diagnostics are filled in.
#[test]
fn episode_life_cycle() {
    let mut env = Pendulum::default();
    assert_eq!(env.step(&[0.0]), Err(EnvError::NotReset));
    env.reset(&[0.0, 0.0], 4).unwrap();
    for k in 1..=40 {
        let s = env.step(&[1.0]).unwrap();
        assert_eq!(s.done, k == 40);
        assert!((s.info.t - 0.1 * k as f64).abs() < 1e-12);
        assert_eq!(s.info.values["action"], 1.0);
        let z = &s.info.true_state;
        let sc = env.scenario();
        assert_eq!(s.info.values["tip_distance"], sc.tip_distance(z));
        assert_eq!(s.info.values["cost"], sc.immediate_cost(z));
        assert_eq!(s.info.values["energy"], sc.physics.energy(z));
    }
    assert!(matches!(
        env.step(&[0.0]),
        Err(EnvError::EpisodeOver { .. })
    ));
    env.reset(&[0.0, 0.0], 4).unwrap();
    assert!(env.step(&[0.0]).is_ok());
}

/// The trait is object-safe for these environments and reports PILCO's dimensions.
#[test]
fn as_trait_objects() {
    let envs: Vec<Box<dyn Environment>> =
        vec![Box::new(Pendulum::default()), Box::new(CartPole::default())];
    assert_eq!(envs[0].state_names(), ["dtheta", "theta"]);
    assert_eq!(envs[0].action_names(), ["torque"]);
    assert_eq!(envs[1].state_names(), ["x", "v", "dtheta", "theta"]);
    assert_eq!(envs[1].action_names(), ["force"]);
    for e in &envs {
        assert_eq!(e.dt(), 0.1);
        assert_eq!(e.horizon(), 40);
        assert_eq!(e.action_dim(), 1);
    }
}

/// The random initial policy stays within the limits and covers them.
#[test]
fn random_actions_uniform_in_limits() {
    let s = CartPoleScenario::default();
    let mut rng = ChaCha8Rng::seed_from_u64(0);
    let u: Vec<f64> = (0..10_000).map(|_| s.random_action(&mut rng)).collect();
    assert!(u.iter().all(|u| u.abs() <= 10.0));
    let mean = u.iter().sum::<f64>() / u.len() as f64;
    let var = u.iter().map(|u| u * u).sum::<f64>() / u.len() as f64 - mean * mean;
    // U(−10, 10): mean 0, variance 100/3
    assert!(
        mean.abs() < 0.2 && (var / (100.0 / 3.0) - 1.0).abs() < 0.03,
        "{mean} {var}"
    );
    let mut env = CartPole::default();
    env.reset(&[0.0; 4], 2).unwrap();
    for _ in 0..40 {
        env.step(&[s.random_action(&mut rng)]).unwrap();
    }
}

/// Invalid scenarios are rejected with the field named.
#[test]
fn invalid_scenarios_rejected() {
    let err = |s: PendulumScenario| Pendulum::new(s).unwrap_err().to_string();
    let d = PendulumScenario::default;
    assert!(err(Scenario { dt: 0.0, ..d() }).contains("scenario.dt"));
    let noise_std = vec![0.1];
    assert!(err(Scenario { noise_std, ..d() }).contains("scenario.noise_std"));
    let policy_inputs = vec![0, 4];
    assert!(err(Scenario {
        policy_inputs,
        ..d()
    })
    .contains("scenario.policy_inputs"));
    let physics = PendulumPhysics {
        length: -1.0,
        ..Default::default()
    };
    assert!(err(Scenario { physics, ..d() }).contains("pendulum.length"));
    // The cost is written for one angle: two would index past its Q, none would blind it.
    for angle_indices in [vec![0, 1], vec![]] {
        let e = err(Scenario {
            angle_indices,
            ..d()
        });
        assert!(
            e.contains("scenario.angle_indices") && e.contains("must be 1 index long"),
            "{e}"
        );
    }
    let err = |s: CartPoleScenario| CartPole::new(s).unwrap_err().to_string();
    let d = CartPoleScenario::default;
    let angle_indices = vec![1, 3];
    assert!(err(Scenario {
        angle_indices,
        ..d()
    })
    .contains("scenario.angle_indices"));
    let max_action = f64::NAN;
    assert!(err(Scenario { max_action, ..d() }).contains("max_action"));
    let cost_target = vec![0.0, PI];
    assert!(err(Scenario { cost_target, ..d() }).contains("cost_target"));
}

/// Angles are not wrapped: a pendulum spinning over the top keeps accumulating θ.
#[test]
fn angles_not_wrapped() {
    let mut env = Pendulum::default();
    env.reset(&[10.0, 0.0], 0).unwrap();
    let mut prev = 0.0;
    for _ in 0..40 {
        let theta = env.step(&[2.5]).unwrap().info.true_state[1];
        assert!(theta > prev, "θ must grow monotonically: {prev} → {theta}");
        prev = theta;
    }
    assert!(prev > 4.0 * PI, "θ = {prev}");
}

/// Start states drawn from a correlated start distribution have its mean and covariance
/// (2·10⁴ draws: mean and covariance entries within 0.04, about 4 standard errors);
/// the defaults are accepted and a singular covariance is an error.
#[test]
fn start_sampling() {
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let s = PendulumScenario {
        start_mean: vec![1.0, -2.0],
        start_cov: vec![vec![1.0, 0.6], vec![0.6, 0.5]],
        ..Default::default()
    };
    let n = 20_000;
    let xs: Vec<Vec<f64>> = (0..n).map(|_| s.sample_start(&mut rng).unwrap()).collect();
    let m: Vec<f64> = (0..2)
        .map(|i| xs.iter().map(|x| x[i]).sum::<f64>() / n as f64)
        .collect();
    for i in 0..2 {
        assert!((m[i] - s.start_mean[i]).abs() < 0.04, "mean {m:?}");
        for j in 0..2 {
            let c = xs
                .iter()
                .map(|x| (x[i] - m[i]) * (x[j] - m[j]))
                .sum::<f64>()
                / n as f64;
            assert!((c - s.start_cov[i][j]).abs() < 0.04, "cov[{i}][{j}] = {c}");
        }
    }
    assert_eq!(
        CartPoleScenario::default()
            .sample_start(&mut rng)
            .unwrap()
            .len(),
        4
    );
    let singular = PendulumScenario {
        start_cov: vec![vec![1.0, 1.0], vec![1.0, 1.0]],
        ..Default::default()
    };
    let e = singular.sample_start(&mut rng).unwrap_err().to_string();
    assert!(e.contains("start_cov"), "{e}");
}
