//! Set-ups the learning loop must refuse before it touches the system.

use faer::Mat;
use vicpilco_env::{EnvError, Environment, Step, StepInfo};
use vicpilco_gp::train::Wolfe;
use vicpilco_gp::DynamicsOptions;
use vicpilco_learn::outer::{LoopSetup, OptimiserOptions};
use vicpilco_learn::selection::ModelSelection;
use vicpilco_learn::start::StartDistribution;
use vicpilco_learn::step::{LinearPrior, StepSpec, Target};
use vicpilco_learn::value::ReturnSpec;
use vicpilco_learn::LearnError;
use vicpilco_pilco::cost::{CostSum, EnergyCost, SaturatingCost};
use vicpilco_pilco::policy::LinearPolicy;
use vicpilco_pilco::squash::{PartialSat, SatRange};

/// A one-dimensional integrator `x' = x + a·dt` that counts how often it is used.
#[derive(Default)]
struct Integrator {
    x: f64,
    t: usize,
    calls: usize,
}

impl Environment for Integrator {
    fn state_dim(&self) -> usize {
        1
    }
    fn action_dim(&self) -> usize {
        1
    }
    fn dt(&self) -> f64 {
        0.1
    }
    fn horizon(&self) -> usize {
        5
    }
    fn state_names(&self) -> Vec<String> {
        vec!["x".into()]
    }
    fn action_names(&self) -> Vec<String> {
        vec!["a".into()]
    }
    fn reset(&mut self, start: &[f64], _seed: u64) -> Result<Vec<f64>, EnvError> {
        self.calls += 1;
        (self.x, self.t) = (start[0], 0);
        Ok(vec![self.x])
    }
    fn step(&mut self, action: &[f64]) -> Result<Step, EnvError> {
        self.calls += 1;
        self.x += action[0] * self.dt();
        self.t += 1;
        Ok(Step {
            observation: vec![self.x],
            info: StepInfo {
                t: self.t as f64 * self.dt(),
                true_state: vec![self.x],
                ..Default::default()
            },
            done: self.t == self.horizon(),
        })
    }
}

fn setup(initial_rollouts: usize, episodes: usize) -> LoopSetup<LinearPolicy> {
    let spec = StepSpec {
        state_dim: 1,
        angles: vec![],
        time_input: false,
        policy_inputs: vec![0],
        dyn_inputs: vec![0],
        targets: vec![Target::Relative],
        linear_prior: vec![],
        dt: 0.1,
    };
    let width = Mat::from_fn(1, 1, |_, _| 1.0);
    let cost = SaturatingCost::new(&[0], width.as_ref(), &[1.0]).unwrap();
    let start_cov = Mat::from_fn(1, 1, |_, _| 0.01);
    LoopSetup {
        spec,
        squash: None,
        ret: ReturnSpec {
            state_cost: Some(CostSum::new(1, vec![cost]).unwrap()),
            cost_angles: vec![],
            w_mean: 1.0,
            w_std: 0.0,
            energy: None,
            gamma: 1.0,
            horizon: 5,
        },
        prediction_starts: vec![(vec![0.0], start_cov.clone())],
        env_start: StartDistribution::Gaussian {
            mean: vec![0.0],
            cov: start_cov,
        },
        prior_shift: None,
        dynamics: DynamicsOptions::default(),
        model_selection: ModelSelection::Likelihood,
        optimiser: OptimiserOptions {
            length: 2,
            mfepls: 5,
            memory: 5,
            wolfe: Wolfe::PILCO,
            scale_params: None,
            max_slope_ratio: None,
        },
        initial_rollouts,
        episodes,
        rollouts_per_episode: 1,
        policy: LinearPolicy::new(Mat::<f64>::zeros(1, 1).as_ref(), &[0.0]).unwrap(),
        explore: Box::new(|_, t, _| vec![if t % 2 == 0 { 1.0 } else { -0.5 }]),
        success: Box::new(|_| false),
        seed: 1,
    }
}

#[test]
fn no_initial_rollouts_before_an_update_is_refused_before_the_system_runs() {
    let mut env = Integrator::default();
    let err = setup(0, 1).run(&mut env, &mut ()).err().expect("refused");
    assert!(
        matches!(&err, LearnError::Spec(msg) if msg.contains("initial_rollouts")),
        "{err}"
    );
    assert_eq!(env.calls, 0, "the system was used before the refusal");
    // Without updates there is nothing to fit, so no roll-out is needed.
    setup(0, 0)
        .run(&mut env, &mut ())
        .map_err(|e| e.to_string())
        .unwrap();
}

/// Each part that must fit the others or the system is checked before the first reset, and the
/// error names it: what would otherwise panic deep in a prediction, or after a roll-out.
#[test]
fn parts_that_do_not_fit_are_refused_before_the_system_runs() {
    type Spoil = fn(&mut LoopSetup<LinearPolicy>);
    let cases: [(&str, Spoil); 18] = [
        ("prior_shift", |s| s.prior_shift = Some(vec![vec![0.0]; 4])),
        ("prior_shift", |s| {
            s.prior_shift = Some(vec![vec![0.0, 1.0]; 5])
        }),
        ("prediction_starts", |s| {
            s.prediction_starts = vec![(vec![0.0, 0.0], Mat::zeros(2, 2))]
        }),
        ("prediction_starts", |s| s.prediction_starts.clear()),
        ("ret.horizon", |s| s.ret.horizon = 6),
        ("ret.cost_angles", |s| s.ret.cost_angles = vec![1]),
        ("policy_inputs", |s| s.spec.policy_inputs = vec![0, 0]),
        ("ret.state_cost", |s| {
            let w = Mat::<f64>::identity(2, 2);
            s.ret.state_cost = Some(CostSum::loss_sat(w.as_ref(), &[0.0, 0.0]).unwrap())
        }),
        ("ret.energy", |s| {
            let e = EnergyCost::new(&[1.0, 1.0], &[true, true]).unwrap();
            s.ret.energy = Some((e, 0.1))
        }),
        ("squash", |s| {
            let a_max = SatRange::Symmetric { a_max: 1.0 };
            s.squash = Some(PartialSat::new(2, &[0, 1], &[a_max, a_max]).unwrap())
        }),
        ("spec.state_dim", |s| {
            s.spec.state_dim = 2;
            s.spec.targets = vec![Target::Relative; 2];
        }),
        // Two actions for a system with one.
        ("spec.state_dim", |s| s.policy = LinearPolicy::zeros(1, 2)),
        // The step layout's own rules (StepSpec::validate).
        ("angles", |s| s.spec.angles = vec![1]),
        ("dyn_inputs", |s| s.spec.dyn_inputs = vec![3]),
        ("targets", |s| s.spec.targets = vec![Target::Relative; 2]),
        ("linear_prior", |s| {
            s.spec.linear_prior = vec![LinearPrior {
                target: 1,
                state: 0,
                coefficient: 1.0,
            }]
        }),
        ("linear_prior", |s| {
            s.spec.linear_prior = vec![LinearPrior {
                target: 0,
                state: 0,
                coefficient: f64::NAN,
            }]
        }),
        ("dt", |s| {
            s.spec.time_input = true;
            s.spec.dyn_inputs = vec![0, 1];
            s.spec.dt = 0.0;
        }),
    ];
    for (field, spoil) in cases {
        let mut env = Integrator::default();
        let mut bad = setup(1, 1);
        spoil(&mut bad);
        let err = bad
            .run(&mut env, &mut ())
            .err()
            .unwrap_or_else(|| panic!("{field}: not refused"));
        assert!(
            matches!(&err, LearnError::Spec(msg) if msg.starts_with(field)),
            "{field}: {err}"
        );
        assert_eq!(
            env.calls, 0,
            "{field}: the system was used before the refusal"
        );
    }
    // The unspoilt set-up runs.
    let mut env = Integrator::default();
    setup(1, 1)
        .run(&mut env, &mut ())
        .map_err(|e| e.to_string())
        .unwrap();
    assert!(env.calls > 0);
}

/// Every value+gradient pass of a policy update is one the optimiser counts: the start point's,
/// made first to name a failure there, is handed to the optimiser rather than computed twice.
#[test]
fn each_update_evaluates_its_start_point_once() {
    #[derive(Default)]
    struct Count {
        passes: std::collections::BTreeMap<usize, usize>,
        counted: Vec<(usize, usize)>,
    }
    impl vicpilco_learn::record::LoopObserver for Count {
        fn objective(&mut self, episode: usize, _j: f64) {
            *self.passes.entry(episode).or_default() += 1;
        }
        fn episode_done(&mut self, record: &vicpilco_learn::record::EpisodeRecord) {
            self.counted.push((record.index, record.evaluations));
        }
    }
    let mut count = Count::default();
    setup(1, 2)
        .run(&mut Integrator::default(), &mut count)
        .map_err(|e| e.to_string())
        .unwrap();
    assert_eq!(count.counted.len(), 2);
    for (episode, evaluations) in &count.counted {
        assert!(*evaluations > 0);
        assert_eq!(count.passes[episode], *evaluations, "update {episode}");
    }
}

/// The integrator with each step's result damaged by `spoil(step, t)` (t counted from 1).
struct Spoilt {
    inner: Integrator,
    spoil: fn(&mut Step, usize),
}

impl Environment for Spoilt {
    fn state_dim(&self) -> usize {
        self.inner.state_dim()
    }
    fn action_dim(&self) -> usize {
        self.inner.action_dim()
    }
    fn dt(&self) -> f64 {
        self.inner.dt()
    }
    fn horizon(&self) -> usize {
        self.inner.horizon()
    }
    fn state_names(&self) -> Vec<String> {
        self.inner.state_names()
    }
    fn action_names(&self) -> Vec<String> {
        self.inner.action_names()
    }
    fn reset(&mut self, start: &[f64], seed: u64) -> Result<Vec<f64>, EnvError> {
        self.inner.reset(start, seed)
    }
    fn step(&mut self, action: &[f64]) -> Result<Step, EnvError> {
        let mut s = self.inner.step(action)?;
        (self.spoil)(&mut s, self.inner.t);
        Ok(s)
    }
}

/// A system that returns a NaN is stopped there with an error naming the step and entry, not
/// carried into the recorded return and the summary.
#[test]
fn a_non_finite_state_from_the_system_is_an_error_naming_the_step() {
    let mut env = Spoilt {
        inner: Integrator::default(),
        spoil: |s, t| {
            if t == 3 {
                s.info.true_state[0] = f64::NAN;
            }
        },
    };
    let err = setup(1, 1).run(&mut env, &mut ()).err().expect("refused");
    assert!(
        matches!(&err, LearnError::Env(msg)
            if msg == "step 2: the true state has a non-finite entry 0 (NaN)"),
        "{err}"
    );
}

/// An observation or true state of the wrong length (a system that leaves `info.true_state`
/// at its empty default) is stopped at the step with an error, where it used to panic later in
/// the recorded cost, the training set or the policy's action.
#[test]
fn a_state_of_the_wrong_length_from_the_system_is_an_error_naming_the_step() {
    type Spoil = fn(&mut Step, usize);
    let cases: [(Spoil, &str); 3] = [
        (
            |s, _| s.info.true_state.clear(),
            "step 0: the true state has 0 entries, the system's state_dim is 1",
        ),
        (
            |s, t| {
                if t == 2 {
                    s.observation.clear()
                }
            },
            "step 1: the observation has 0 entries, the system's state_dim is 1",
        ),
        (
            |s, t| {
                if t == 4 {
                    s.observation.push(0.0)
                }
            },
            "step 3: the observation has 2 entries, the system's state_dim is 1",
        ),
    ];
    for (spoil, want) in cases {
        let mut env = Spoilt {
            inner: Integrator::default(),
            spoil,
        };
        let err = setup(1, 1).run(&mut env, &mut ()).err().expect("refused");
        assert!(
            matches!(&err, LearnError::Env(msg) if msg == want),
            "{want}: {err}"
        );
    }
}
