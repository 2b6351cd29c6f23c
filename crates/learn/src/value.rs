//! The expected return of a policy over a horizon and its gradient w.r.t. every policy
//! parameter by one reverse sweep (thesis eq. 4-7 with the costs of §4-2).
//!
//! `J = (1/K) Σ_k Σ_{t=1..H} γ^t (w1·E[c(x_t)] + w2·std[c(x_t)] + w3·E[c_a(u_{t−1})])`
//!
//! where `c` is the sum of the saturating state costs, `c_a` the energy cost of the action
//! that led to `x_t`, and K the number of start distributions. The start state is not
//! charged (PILCO's `value`). The reverse sweep visits each step once, so a value+gradient
//! costs a small constant times a value, whatever the number of policy parameters.

use crate::joint::{Joint, JointBar};
use crate::step::{check_state_gaussian, Predictor, StepTape};
use crate::LearnError;
use faer::Mat;
use rayon::prelude::*;
use vicpilco_pilco::cost::{CostSum, EnergyCost};
use vicpilco_pilco::policy::Policy;
use vicpilco_pilco::squash::{SinesCache, TrigAug};
use vicpilco_pilco::{CostBar, GaussianBar};

/// The immediate cost and the discounting of the return.
#[derive(Clone, Debug)]
pub struct ReturnSpec {
    /// Sum of saturating costs on the state (None: no state cost). With `cost_angles`
    /// non-empty, the costs see the augmented state `[x; sin θ, cos θ per angle]` (PILCO's
    /// pendulum and cart-pole costs on the pendulum tip).
    pub state_cost: Option<CostSum>,
    /// State dimensions augmented with their sine and cosine before the state cost.
    pub cost_angles: Vec<usize>,
    /// w1: weight of `E[c]`.
    pub w_mean: f64,
    /// w2: weight of `std[c]`; negative rewards exploration.
    pub w_std: f64,
    /// Energy cost on the action and its weight w3.
    pub energy: Option<(EnergyCost, f64)>,
    /// γ.
    pub gamma: f64,
    /// H.
    pub horizon: usize,
}

impl ReturnSpec {
    /// Checks the costs against a state of `d0` entries and `actions` actions: the cost angles
    /// index the state, the state cost takes the state with their sines and cosines appended,
    /// the energy cost takes the actions. Fails with [`LearnError::Spec`] naming the field
    /// (`ret.cost_angles`, `ret.state_cost`, `ret.energy`).
    pub fn check(&self, d0: usize, actions: usize) -> Result<(), LearnError> {
        let bad = |what: &str, detail: String| Err(LearnError::Spec(format!("{what}: {detail}")));
        if let Some(&i) = self.cost_angles.iter().find(|&&i| i >= d0) {
            return bad(
                "ret.cost_angles",
                format!("index {i} ≥ state dimension {d0}"),
            );
        }
        let cost_width = d0 + 2 * self.cost_angles.len();
        if let Some(c) = self
            .state_cost
            .as_ref()
            .filter(|c| c.n_inputs() != cost_width)
        {
            return bad(
                "ret.state_cost",
                format!(
                    "{} inputs, but the state with its cost angles has {cost_width}",
                    c.n_inputs()
                ),
            );
        }
        if let Some((e, _)) = self
            .energy
            .as_ref()
            .filter(|(e, _)| e.n_inputs() != actions)
        {
            return bad(
                "ret.energy",
                format!("{} inputs for {actions} actions", e.n_inputs()),
            );
        }
        Ok(())
    }

    /// The predicted return of the first start distribution as reported to users: the
    /// discounted sum of the weighted expected costs (energy included) and of the per-step cost
    /// standard deviations (an upper bound on the return's std, as PILCO plots it).
    pub fn predicted_return(&self, out: &ValueOut) -> (f64, f64) {
        let w3 = self.energy.as_ref().map_or(0.0, |(_, w)| *w);
        let mut mean = 0.0;
        let mut std = 0.0;
        for (t, s) in out.trajectories[0].iter().enumerate() {
            let disc = self.gamma.powi(t as i32 + 1);
            mean += disc * (self.w_mean * s.cost_mean + w3 * s.energy_mean);
            std += disc * self.w_mean * s.cost_var.max(0.0).sqrt();
        }
        (mean, std)
    }
}

/// One predicted step as recorded for reports.
#[derive(Clone, Debug)]
pub struct PredictedStep {
    /// Mean of `x_{t+1}` (D0) for entry `t` of a trajectory (the start state has no entry).
    pub mean: Vec<f64>,
    /// Covariance of `x_{t+1}` (D0×D0).
    pub cov: Mat<f64>,
    /// Mean of the (squashed) action `u_t` that led to `x_{t+1}`.
    pub action_mean: Vec<f64>,
    /// Covariance of `u_t` (A×A).
    pub action_cov: Mat<f64>,
    /// `E[c(x_{t+1})]` of the state cost, unweighted and undiscounted (0 without one).
    pub cost_mean: f64,
    /// `Var[c(x_{t+1})]` of the state cost, unweighted (0 without one).
    pub cost_var: f64,
    /// `E[c_a(u_t)]` of the energy cost, unweighted and undiscounted (0 without one).
    pub energy_mean: f64,
    /// The weighted immediate cost `w1 E[c] + w2 std[c] + w3 E[c_a]`.
    pub immediate: f64,
}

/// The result of [`value`].
#[derive(Clone, Debug)]
pub struct ValueOut {
    /// J: the discounted weighted immediate costs (exploration term included) summed over the
    /// horizon and averaged over the start distributions; what the policy optimisation
    /// minimises.
    pub j: f64,
    /// `dJ/dψ` in the policy's parameter order, when asked for.
    pub grad: Option<Vec<f64>>,
    /// One predicted trajectory per start distribution.
    pub trajectories: Vec<Vec<PredictedStep>>,
}

/// Return, its gradient (when asked) and the predicted trajectory from one start.
type StartValue = (f64, Option<Vec<f64>>, Vec<PredictedStep>);

/// The state cost's input: the state, or the state with sine/cosine of its angles appended.
struct CostInput {
    joint: Joint,
    trig: Option<(Mat<f64>, SinesCache)>,
}

impl CostInput {
    fn new(trig: Option<&TrigAug>, m: &[f64], s: &Mat<f64>) -> Self {
        let mut joint = Joint::new(m.to_vec(), s.clone());
        let trig = trig.map(|tr| {
            let (mo, cache) = tr.forward(m, s.as_ref());
            joint.append(&(0..m.len()).collect::<Vec<_>>(), &mo);
            (mo.v, cache)
        });
        Self { joint, trig }
    }

    /// Adjoint of the state from the adjoint of the cost input.
    fn backward(&self, trig: Option<&TrigAug>, bar: GaussianBar) -> GaussianBar {
        let (Some(tr), Some((c, cache))) = (trig, &self.trig) else {
            return bar;
        };
        let d0 = tr.n_inputs();
        let all: Vec<usize> = (0..d0).collect();
        let mut zbar = JointBar {
            mean: bar.mean,
            cov: bar.cov,
        };
        let mb = zbar.pop_append(&self.joint, &all, c.as_ref());
        let gb = tr.backward(cache, &mb);
        zbar.add_marginal(&all, &gb);
        zbar.into_gaussian_bar()
    }
}

struct StepRecord<C> {
    tape: StepTape<C>,
    cost_cache: Option<(vicpilco_pilco::cost::CostSumCache, CostInput)>,
    energy_cache: Option<vicpilco_pilco::cost::EnergyCache>,
    std: f64,
}

fn one_start<P: Policy>(
    pred: &Predictor<'_, P>,
    spec: &ReturnSpec,
    m0: &[f64],
    s0: &Mat<f64>,
    with_grad: bool,
) -> Result<StartValue, LearnError>
where
    P::Cache: Send,
{
    let trig = if spec.cost_angles.is_empty() {
        None
    } else {
        Some(TrigAug::new(
            m0.len(),
            &spec.cost_angles,
            &vec![1.0; spec.cost_angles.len()],
        )?)
    };
    let mut m = m0.to_vec();
    let mut s = s0.clone();
    let mut j = 0.0;
    let mut records = Vec::with_capacity(if with_grad { spec.horizon } else { 0 });
    let mut steps = Vec::with_capacity(spec.horizon);
    for t in 0..spec.horizon {
        let out = pred.step_checked(t, &m, &s)?;
        let disc = spec.gamma.powi(t as i32 + 1);
        let (cost_mean, cost_var, cost_cache) = match &spec.state_cost {
            Some(c) => {
                let aug = CostInput::new(trig.as_ref(), &out.next_mean, &out.next_cov);
                let (cm, cache) = c.forward(&aug.joint.mean, aug.joint.cov.as_ref());
                (cm.mean, cm.var, Some((cache, aug)))
            }
            None => (0.0, 0.0, None),
        };
        let (energy_mean, energy_cache) = match &spec.energy {
            Some((e, _)) => {
                let (cm, cache) = e.forward(&out.action_mean, out.action_cov.as_ref());
                (cm.mean, Some(cache))
            }
            None => (0.0, None),
        };
        let std = cost_var.max(0.0).sqrt();
        let w3 = spec.energy.as_ref().map_or(0.0, |(_, w)| *w);
        let immediate = spec.w_mean * cost_mean + spec.w_std * std + w3 * energy_mean;
        if !immediate.is_finite() {
            return Err(LearnError::NonFinite(format!(
                "predicted immediate cost at step {} is {immediate}",
                t + 1
            )));
        }
        j += disc * immediate;
        steps.push(PredictedStep {
            mean: out.next_mean.clone(),
            cov: out.next_cov.clone(),
            action_mean: out.action_mean.clone(),
            action_cov: out.action_cov.clone(),
            cost_mean,
            cost_var,
            energy_mean,
            immediate,
        });
        m = out.next_mean;
        s = out.next_cov;
        if with_grad {
            records.push(StepRecord {
                tape: out.tape,
                cost_cache,
                energy_cache,
                std,
            });
        }
    }
    if !with_grad {
        return Ok((j, None, steps));
    }
    let d0 = m0.len();
    let mut p_bar = vec![0.0; pred.policy.n_params()];
    let mut next_bar = GaussianBar::zeros(d0);
    for t in (0..spec.horizon).rev() {
        let rec = &records[t];
        let disc = spec.gamma.powi(t as i32 + 1);
        if let (Some(c), Some((cache, aug))) = (&spec.state_cost, &rec.cost_cache) {
            let var_bar = if rec.std > 0.0 {
                spec.w_std / (2.0 * rec.std)
            } else {
                0.0
            };
            let gb_aug = c.backward(
                cache,
                &CostBar {
                    mean: disc * spec.w_mean,
                    var: disc * var_bar,
                    v: None,
                },
            );
            let gb = aug.backward(trig.as_ref(), gb_aug);
            for k in 0..d0 {
                next_bar.mean[k] += gb.mean[k];
                for l in 0..d0 {
                    next_bar.cov[(k, l)] += gb.cov[(k, l)];
                }
            }
        }
        let action_bar = match (&spec.energy, &rec.energy_cache) {
            (Some((e, w3)), Some(cache)) => Some(e.backward(
                cache,
                &CostBar {
                    mean: disc * w3,
                    var: 0.0,
                    v: None,
                },
            )),
            _ => None,
        };
        next_bar = pred.step_backward(&rec.tape, &next_bar, action_bar.as_ref(), &mut p_bar)?;
    }
    Ok((j, Some(p_bar), steps))
}

/// Checks start distributions of a state of `d0` entries: at least one, each with `d0`
/// finite means and a `d0`×`d0` finite covariance. Fails with [`LearnError::Spec`] naming
/// `what` (the caller's name for them) and the start.
pub fn check_starts(
    what: &str,
    starts: &[(Vec<f64>, Mat<f64>)],
    d0: usize,
) -> Result<(), LearnError> {
    if starts.is_empty() {
        return Err(LearnError::Spec(format!(
            "{what}: none given (at least one)"
        )));
    }
    for (k, (m, s)) in starts.iter().enumerate() {
        check_state_gaussian(&format!("{what}: start {k}"), m, s.as_ref(), d0)?;
    }
    Ok(())
}

/// Expected return (and optionally its gradient) averaged over the start distributions.
/// Checks `spec` ([`ReturnSpec::check`]) and `starts` ([`check_starts`]) against `pred`'s
/// state and actions first.
pub fn value<P>(
    pred: &Predictor<'_, P>,
    spec: &ReturnSpec,
    starts: &[(Vec<f64>, Mat<f64>)],
    with_grad: bool,
) -> Result<ValueOut, LearnError>
where
    P: Policy + Sync,
    P::Cache: Send,
{
    // Once per call, here at the entry: the horizon's steps then run unchecked.
    spec.check(pred.spec.state_dim, pred.n_actions())?;
    check_starts("starts", starts, pred.spec.state_dim)?;
    let results: Vec<_> = starts
        .par_iter()
        .map(|(m0, s0)| one_start(pred, spec, m0, s0, with_grad))
        .collect();
    let k = starts.len() as f64;
    let mut j = 0.0;
    let mut grad = with_grad.then(|| vec![0.0; pred.policy.n_params()]);
    let mut trajectories = Vec::with_capacity(starts.len());
    // Summed in start order, so the result does not depend on thread scheduling.
    for r in results {
        let (jk, gk, steps) = r?;
        j += jk / k;
        if let (Some(g), Some(gk)) = (grad.as_mut(), gk) {
            for (a, b) in g.iter_mut().zip(gk) {
                *a += b / k;
            }
        }
        trajectories.push(steps);
    }
    Ok(ValueOut {
        j,
        grad,
        trajectories,
    })
}
