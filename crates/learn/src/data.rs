//! Recorded roll-outs and the GP training set built from them.

use crate::step::{StepSpec, Target};
use faer::Mat;
use vicpilco_env::StepInfo;
use vicpilco_pilco::squash::TrigAug;

/// One episode on the system.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct Rollout {
    /// H+1 noisy observations, the first from `reset`.
    pub observations: Vec<Vec<f64>>,
    /// H actions (after squashing: what the system received).
    pub actions: Vec<Vec<f64>>,
    /// H+1 noise-free states (from the simulator; equal to the observations on a robot that
    /// cannot tell).
    pub true_states: Vec<Vec<f64>>,
    /// Per step: flags (e.g. `in_hole`) and named values the system reported.
    #[serde(default)]
    pub infos: Vec<StepInfo>,
    /// Whether this roll-out's transitions were added to the GP training set.
    pub used_for_training: bool,
}

impl Rollout {
    pub fn len(&self) -> usize {
        self.actions.len()
    }
    pub fn is_empty(&self) -> bool {
        self.actions.is_empty()
    }
}

/// The vector `[x; sin θ, cos θ per angle; time]` the policy and the GP inputs index into.
pub fn augment(spec: &StepSpec, trig: Option<&TrigAug>, x: &[f64], t: usize) -> Vec<f64> {
    let mut a = x.to_vec();
    if let Some(tr) = trig {
        a.extend(tr.apply(x));
    }
    if spec.time_input {
        a.push(t as f64 * spec.dt);
    }
    a
}

/// GP training inputs `[aug(x_t)[dyn_inputs]; u_t]` and targets (`x_{t+1} − x_t` for relative
/// dimensions, `x_{t+1}` for absolute ones, each minus the prior mean shift `r_k(t)`), from
/// every whole step (a step the system ended early is left out).
pub fn training_set(
    spec: &StepSpec,
    rollouts: &[Rollout],
    prior_shift: Option<&[Vec<f64>]>,
) -> (Mat<f64>, Mat<f64>) {
    let trig = (!spec.angles.is_empty()).then(|| {
        TrigAug::new(spec.state_dim, &spec.angles, &vec![1.0; spec.angles.len()])
            .expect("angles validated by the predictor")
    });
    let mut xs: Vec<Vec<f64>> = Vec::new();
    let mut ys: Vec<Vec<f64>> = Vec::new();
    for r in rollouts.iter().filter(|r| r.used_for_training) {
        for t in 0..r.len() {
            // A step the system cut short spans less than dt: not a sample of the dynamics.
            if r.infos.get(t).is_some_and(|i| i.stopped_early.is_some()) {
                continue;
            }
            let aug = augment(spec, trig.as_ref(), &r.observations[t], t);
            let mut input: Vec<f64> = spec.dyn_inputs.iter().map(|&i| aug[i]).collect();
            input.extend_from_slice(&r.actions[t]);
            let target = (0..spec.state_dim)
                .map(|k| {
                    let next = r.observations[t + 1][k];
                    let base = if spec.targets[k] == Target::Relative {
                        r.observations[t][k]
                    } else {
                        0.0
                    };
                    let shift = prior_shift.and_then(|s| s.get(t)).map_or(0.0, |s| s[k]);
                    next - base - shift
                })
                .collect();
            xs.push(input);
            ys.push(target);
        }
    }
    let d = xs.first().map_or(0, Vec::len);
    let e = spec.state_dim;
    (
        Mat::from_fn(xs.len(), d, |i, j| xs[i][j]),
        Mat::from_fn(ys.len(), e, |i, j| ys[i][j]),
    )
}
