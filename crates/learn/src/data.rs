//! Recorded roll-outs and the GP training set built from them.

use crate::step::{StepSpec, Target};
use faer::Mat;
use vicpilco_env::StepInfo;
use vicpilco_pilco::squash::TrigAug;

/// One episode on the system.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct Rollout {
    /// `len() + 1` noisy observations, the first from `reset`.
    pub observations: Vec<Vec<f64>>,
    /// `len()` actions (after squashing: what the system received).
    pub actions: Vec<Vec<f64>>,
    /// `len() + 1` noise-free states (from the simulator; equal to the observations on a robot that
    /// cannot tell).
    pub true_states: Vec<Vec<f64>>,
    /// Per step: flags (e.g. `in_hole`) and named values the system reported.
    #[serde(default)]
    pub infos: Vec<StepInfo>,
    /// Whether this roll-out's transitions were added to the GP training set.
    pub used_for_training: bool,
}

impl Rollout {
    /// Steps recorded: the horizon H, or fewer if the system ended the episode early.
    pub fn len(&self) -> usize {
        self.actions.len()
    }
    /// No step was recorded: only the observation from `reset`.
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
/// dimensions, `x_{t+1}` for absolute ones, each minus its linear prior terms in `x_t` and the
/// prior mean shift `r_k(t)`), from
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
                    let linear = spec.linear_prior_mean(k, &r.observations[t]);
                    let shift = prior_shift.and_then(|s| s.get(t)).map_or(0.0, |s| s[k]);
                    next - base - linear - shift
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::step::LinearPrior;

    fn spec(targets: Vec<Target>, linear_prior: Vec<LinearPrior>) -> StepSpec {
        StepSpec {
            state_dim: 2,
            angles: vec![],
            time_input: false,
            policy_inputs: vec![0, 1],
            dyn_inputs: vec![0, 1],
            targets,
            linear_prior,
            dt: 0.1,
        }
    }

    #[test]
    fn targets_are_the_next_state_less_their_linear_prior_terms() {
        let rollout = Rollout {
            observations: vec![vec![1.0, 10.0], vec![1.5, 12.0], vec![2.5, 11.0]],
            actions: vec![vec![0.1], vec![0.2]],
            true_states: vec![vec![0.0; 2]; 3],
            infos: vec![],
            used_for_training: true,
        };
        let term = |target, state, coefficient| LinearPrior {
            target,
            state,
            coefficient,
        };
        let with_prior = spec(
            vec![Target::Relative, Target::Absolute],
            vec![term(1, 0, 3.0), term(0, 1, -0.5)],
        );
        let (inputs, targets) = training_set(&with_prior, std::slice::from_ref(&rollout), None);
        assert_eq!((inputs.nrows(), inputs.ncols()), (2, 3));
        // Step 0: Δx − (−0.5 · 10), y' − 3 · 1; step 1: Δx − (−0.5 · 12), y' − 3 · 1.5.
        let want = [[0.5 + 5.0, 12.0 - 3.0], [1.0 + 6.0, 11.0 - 4.5]];
        for (i, row) in want.iter().enumerate() {
            for (j, w) in row.iter().enumerate() {
                assert!((targets[(i, j)] - w).abs() < 1e-12, "({i}, {j})");
            }
        }
        // A unit prior on its own state is a relative target.
        let unit = spec(
            vec![Target::Absolute; 2],
            vec![term(0, 0, 1.0), term(1, 1, 1.0)],
        );
        let relative = spec(vec![Target::Relative; 2], vec![]);
        let a = training_set(&unit, std::slice::from_ref(&rollout), None).1;
        let b = training_set(&relative, std::slice::from_ref(&rollout), None).1;
        assert_eq!(a, b);
    }
}
