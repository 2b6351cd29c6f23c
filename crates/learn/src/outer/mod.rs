//! The PILCO outer loop: initial roll-outs, then repeat {train the dynamics GP (warm start);
//! optimise the policy on the predicted return; roll it out on the system; record}.
//!
//! The loop owns every side effect (progress, logging) through a [`LoopObserver`]; GP
//! training, policy optimisation and roll-outs know nothing of them. Randomness is derived
//! from the master seed per (episode, purpose), so an episode can be reproduced alone.

mod check;
mod rollout;

pub use rollout::{derive_seed, rollout};
use rollout::{PURPOSE_EXPLORE, PURPOSE_EXTRA_ROLLOUT, PURPOSE_NOISE, PURPOSE_START};

use crate::data::{augment, training_set, Rollout};
use crate::record::{EpisodeRecord, LoopObserver, LoopOutcome, LoopState, Phase};
use crate::selection::ModelSelection;
use crate::start::StartDistribution;
use crate::step::{Predictor, StepSpec};
use crate::value::{value, ReturnSpec, ValueOut};
use crate::LearnError;
use faer::Mat;
use std::time::Instant;
use vicpilco_env::Environment;
use vicpilco_gp::moments::MmModel;
use vicpilco_gp::train::initial_hyper;
use vicpilco_gp::train::{minimize, MinimizeOptions, Termination, Wolfe};
use vicpilco_gp::{DynamicsModel, DynamicsOptions};
use vicpilco_pilco::policy::{CentreScale, Policy};
use vicpilco_pilco::squash::{PartialSat, TrigAug};

/// PILCO's policy-optimisation budget.
#[derive(Clone, Copy, Debug, serde::Serialize, serde::Deserialize)]
pub struct OptimiserOptions {
    /// "Length": at most this many line searches (L-BFGS iterations).
    pub length: u64,
    /// "MFEPLS": at most this many function evaluations per line search.
    pub mfepls: u64,
    /// L-BFGS memory.
    pub memory: usize,
    /// Line-search acceptance ([`Wolfe::PILCO`]: PILCO's more exact line searches).
    pub wolfe: Wolfe,
    /// Search over `ψ / scale` with the policy's [`Policy::param_scales`] for this rule,
    /// taken at the start of each update (ours; `None`: PILCO's raw parameters). The
    /// objective is the same function; only the optimiser's steps change.
    pub scale_params: Option<CentreScale>,
    /// "MSR": PILCO's maximum slope ratio, which caps each line search's first trial step
    /// ([`MinimizeOptions::max_slope_ratio`]; 100 in PILCO and the thesis's Table 5-4).
    /// `None`: every line search first tries L-BFGS's step 1, as runs made before
    /// 2026-12-07 did.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_slope_ratio: Option<f64>,
}

/// Exploration for the initial roll-outs: `(seed, t, observation) → action`.
pub type ExplorePolicy = Box<dyn Fn(u64, usize, &[f64]) -> Vec<f64> + Send + Sync>;

/// Whether a roll-out achieved the task.
pub type SuccessTest = Box<dyn Fn(&Rollout) -> bool + Send + Sync>;

/// One learning problem: the prediction layout, cost, budgets and the system's start
/// distribution. `P` is the policy type.
pub struct LoopSetup<P> {
    /// Which variables feed the policy and the dynamics GP, and the GP's targets.
    pub spec: StepSpec,
    /// Saturation of the policy's raw output into the action bounds (`None`: the raw output
    /// is the action).
    pub squash: Option<PartialSat>,
    /// Immediate cost, weights, discount γ and horizon H of the predicted and recorded
    /// returns.
    pub ret: ReturnSpec,
    /// Start distributions the predicted return is averaged over (K).
    pub prediction_starts: Vec<(Vec<f64>, Mat<f64>)>,
    /// Distribution the system's real start states are drawn from.
    pub env_start: StartDistribution,
    /// Known prior mean of the GP targets per step (H rows of D0), if any.
    pub prior_shift: Option<Vec<Vec<f64>>>,
    /// How each update trains the dynamics GP: full or sparse, training budget, cold restart.
    pub dynamics: DynamicsOptions,
    /// How each update picks its model's hyper-parameters.
    pub model_selection: ModelSelection,
    /// Budget and line search of each update's policy optimisation.
    pub optimiser: OptimiserOptions,
    /// Roll-outs with the exploration policy before learning.
    pub initial_rollouts: usize,
    /// Policy updates.
    pub episodes: usize,
    /// Roll-outs after each update; only the first adds data to the GP, all count for
    /// [`EpisodeRecord::success_fraction`].
    pub rollouts_per_episode: usize,
    /// The policy before any update: its structure, and the parameters the first update
    /// starts from ([`Self::resume`] replaces them with the checkpoint's).
    pub policy: P,
    /// The initial roll-outs' actions: `(seed, t, observation) → action`.
    pub explore: ExplorePolicy,
    /// Did a roll-out succeed?
    pub success: SuccessTest,
    /// Master seed: every start state, system noise and exploration stream is derived from it
    /// per episode ([`derive_seed`]).
    pub seed: u64,
}

impl<P: Policy + Clone + Sync> LoopSetup<P>
where
    P::Cache: Send,
{
    fn trig(&self) -> Option<TrigAug> {
        (!self.spec.angles.is_empty()).then(|| {
            TrigAug::new(
                self.spec.state_dim,
                &self.spec.angles,
                &vec![1.0; self.spec.angles.len()],
            )
            .expect("validated")
        })
    }

    /// `policy`'s predicted return (and, with `with_grad`, its gradient) under `model`: the
    /// setup's step layout, squashing, prior shift and start distributions.
    pub fn predicted_value(
        &self,
        policy: &P,
        model: MmModel<'_>,
        with_grad: bool,
    ) -> Result<ValueOut, LearnError> {
        self.predicted_value_from(policy, model, &self.prediction_starts, with_grad)
    }

    pub(crate) fn predicted_value_from(
        &self,
        policy: &P,
        model: MmModel<'_>,
        starts: &[(Vec<f64>, Mat<f64>)],
        with_grad: bool,
    ) -> Result<ValueOut, LearnError> {
        let pred = Predictor::new(
            &self.spec,
            policy,
            self.squash.as_ref(),
            model,
            self.prior_shift.as_deref(),
        )?;
        value(&pred, &self.ret, starts, with_grad)
    }

    /// The objective the policy optimiser sees, J and dJ/dq at its point `q = ψ / scales`:
    /// `J(scales ⊙ q)` and `scales ⊙ dJ/dψ`, with `candidate`'s parameters set to ψ. The same
    /// function of ψ whatever the scales; only the optimiser's steps change.
    pub(crate) fn scaled_value(
        &self,
        candidate: &mut P,
        model: MmModel<'_>,
        scales: &[f64],
        q: &[f64],
    ) -> Result<(f64, Vec<f64>), LearnError> {
        candidate.set_params(&unscale(q, scales))?;
        let out = self.predicted_value(candidate, model, true)?;
        let grad = out.grad.expect("value was asked for its gradient");
        Ok((out.j, grad.iter().zip(scales).map(|(g, s)| g * s).collect()))
    }

    /// The deterministic action of `policy` at a known observation.
    pub fn act(&self, policy: &P, trig: Option<&TrigAug>, t: usize, obs: &[f64]) -> Vec<f64> {
        let aug = augment(&self.spec, trig, obs, t);
        let x: Vec<f64> = self.spec.policy_inputs.iter().map(|&i| aug[i]).collect();
        let v = policy.action(&x);
        match &self.squash {
            Some(sq) => sq.apply(&v),
            None => v,
        }
    }

    /// The weighted immediate cost `w1 c(x_{t+1}) + w3 c_a(a_t)` of each step of a recorded
    /// roll-out (true states), undiscounted: what the prediction's
    /// [`crate::value::PredictedStep`] means are compared with. Always H entries: a roll-out
    /// the system ended early (a singular or runaway arm) pays its last step's cost for every
    /// step it did not run, as if it had stayed where it stopped, so a crash never records a
    /// cheaper return than running on would have.
    pub fn recorded_costs(&self, r: &Rollout) -> Vec<f64> {
        let mut costs = self.run_costs(r);
        if let Some(&last) = costs.last() {
            costs.resize(costs.len().max(self.ret.horizon), last);
        }
        costs
    }

    fn run_costs(&self, r: &Rollout) -> Vec<f64> {
        let trig = (!self.ret.cost_angles.is_empty()).then(|| {
            TrigAug::new(
                self.spec.state_dim,
                &self.ret.cost_angles,
                &vec![1.0; self.ret.cost_angles.len()],
            )
            .expect("validated")
        });
        (0..r.len())
            .map(|t| {
                let x = &r.true_states[t + 1];
                let mut xa = x.clone();
                if let Some(tr) = &trig {
                    xa.extend(tr.apply(x));
                }
                let c = self.ret.state_cost.as_ref().map_or(0.0, |c| c.eval(&xa));
                let ca = self
                    .ret
                    .energy
                    .as_ref()
                    .map_or(0.0, |(e, w)| w * e.eval(&r.actions[t]));
                self.ret.w_mean * c + ca
            })
            .collect()
    }

    /// The return of a recorded roll-out, as the predicted return counts it (discounted sum of
    /// [`Self::recorded_costs`]).
    pub fn recorded_return(&self, r: &Rollout) -> f64 {
        self.recorded_costs(r)
            .iter()
            .enumerate()
            .map(|(t, c)| self.ret.gamma.powi(t as i32 + 1) * c)
            .sum()
    }

    /// Run the whole loop on `env`: the initial roll-outs, then every update.
    pub fn run(
        self,
        env: &mut dyn Environment,
        observer: &mut dyn LoopObserver,
    ) -> Result<LoopOutcome<P>, LearnError> {
        self.check_against(env)?;
        let data = self.initial_rollouts(env, observer)?;
        self.continue_after_initial(data, env, observer)
    }

    /// As [`Self::run`], with the initial roll-outs recorded on `initial_env` and every
    /// update's on `env`. For a scripted initial roll-out that needs a setting the learned
    /// policy must not have (VILTA's search roll-out free of the reference-lead bound).
    /// Both must agree on state and action layout, step and horizon.
    pub fn run_with_initial_env(
        self,
        initial_env: &mut dyn Environment,
        env: &mut dyn Environment,
        observer: &mut dyn LoopObserver,
    ) -> Result<LoopOutcome<P>, LearnError> {
        let layout = |e: &dyn Environment| {
            (
                e.state_names(),
                e.action_names(),
                e.dt().to_bits(),
                e.horizon(),
            )
        };
        if layout(initial_env) != layout(env) {
            return Err(LearnError::Spec(
                "the initial roll-outs' environment differs from the updates' in its state or \
                 action layout, step or horizon"
                    .into(),
            ));
        }
        self.check_against(env)?;
        let data = self.initial_rollouts(initial_env, observer)?;
        self.continue_after_initial(data, env, observer)
    }

    fn initial_rollouts(
        &self,
        env: &mut dyn Environment,
        observer: &mut dyn LoopObserver,
    ) -> Result<Vec<Rollout>, LearnError> {
        // The first update trains the dynamics GP on these roll-outs alone; refused here,
        // before any roll-out runs, rather than by the GP after them.
        if self.initial_rollouts == 0 && self.episodes > 0 {
            return Err(LearnError::Spec(format!(
                "initial_rollouts: 0 leaves the first of {} policy updates no data to train \
                 the dynamics GP on; at least 1 is needed",
                self.episodes
            )));
        }
        let mut data: Vec<Rollout> = Vec::new();
        for i in 0..self.initial_rollouts {
            observer.phase(0, Phase::InitialRollout);
            let k = i as u64;
            let start = self
                .env_start
                .sample(derive_seed(self.seed, k, PURPOSE_START))?;
            let es = derive_seed(self.seed, k, PURPOSE_EXPLORE);
            let explore = &self.explore;
            let r = rollout(
                env,
                &start,
                derive_seed(self.seed, k, PURPOSE_NOISE),
                |t, obs| Ok(explore(es, t, obs)),
            )?;
            observer.rollout_done(0, &r, &self.recorded_costs(&r));
            data.push(r);
        }
        Ok(data)
    }

    fn continue_after_initial(
        self,
        data: Vec<Rollout>,
        env: &mut dyn Environment,
        observer: &mut dyn LoopObserver,
    ) -> Result<LoopOutcome<P>, LearnError> {
        let initial = data.clone();
        let state = LoopState {
            completed: 0,
            data,
            hyp: None,
            inducing: None,
            policy_params: self.policy.params(),
            episodes: Vec::new(),
        };
        observer.checkpoint(&state);
        let mut outcome = self.resume_checked(env, observer, state)?;
        outcome.initial = initial;
        Ok(outcome)
    }

    /// Continue the loop from a checkpoint (the state a [`LoopObserver::checkpoint`] received)
    /// up to `self.episodes` updates. Given the same set-up, the updates it runs are bit for
    /// bit those of an uninterrupted run.
    pub fn resume(
        self,
        env: &mut dyn Environment,
        observer: &mut dyn LoopObserver,
        state: LoopState,
    ) -> Result<LoopOutcome<P>, LearnError> {
        self.check_against(env)?;
        self.resume_checked(env, observer, state)
    }

    /// [`Self::resume`] once [`Self::check_against`] has passed (`run` checks before its
    /// initial roll-outs, so its updates need not check again).
    fn resume_checked(
        mut self,
        env: &mut dyn Environment,
        observer: &mut dyn LoopObserver,
        state: LoopState,
    ) -> Result<LoopOutcome<P>, LearnError> {
        let trig = self.trig();
        self.policy.set_params(&state.policy_params)?;
        let LoopState {
            completed,
            mut data,
            mut hyp,
            inducing,
            mut episodes,
            ..
        } = state;
        let mut inducing: Option<Mat<f64>> = match inducing {
            Some(rows) => Some(mat_from_rows(&rows, "checkpoint inducing inputs")?),
            None => None,
        };
        let mut rollouts = Vec::new();
        let mut predictions = Vec::new();
        for ep in completed + 1..=self.episodes {
            // Train the dynamics model.
            observer.phase(ep, Phase::Train);
            let t0 = Instant::now();
            let (inputs, targets) = training_set(&self.spec, &data, self.prior_shift.as_deref());
            let init = hyp
                .clone()
                .unwrap_or_else(|| initial_hyper(inputs.as_ref(), targets.as_ref()));
            let n_train = inputs.nrows();
            let (refit, report) = DynamicsModel::fit(
                inputs.clone(),
                targets.clone(),
                &init,
                inducing.as_ref().map(|m| m.as_ref()),
                &self.dynamics,
            )?;
            let (model, selection) = self.select_model(
                ep,
                refit,
                hyp.as_deref(),
                data.last(),
                (inputs, targets),
                inducing.as_ref(),
            )?;
            hyp = Some(model.hyp().to_vec());
            if model.is_sparse() {
                inducing = Some(model.inputs().to_owned());
            }
            let train_s = t0.elapsed().as_secs_f64();

            // Optimise the policy.
            observer.phase(ep, Phase::Optimise);
            let t0 = Instant::now();
            let mm = MmModel::dynamics(&model);
            let base = self.policy.clone();
            let mut candidate = base.clone();
            let scales = match self.optimiser.scale_params {
                Some(rule) => base.param_scales(rule),
                None => vec![1.0; base.n_params()],
            };
            // A point the prediction fails at is one the line search backs off from; the
            // first failure is kept, to name the cause if the start point itself fails.
            let mut first_failure: Option<LearnError> = None;
            let mut objective = |q: &[f64]| -> Option<(f64, Vec<f64>)> {
                match self.scaled_value(&mut candidate, mm, &scales, q) {
                    Ok((j, grad)) => {
                        observer.objective(ep, j);
                        Some((j, grad))
                    }
                    Err(e) => {
                        first_failure.get_or_insert(e);
                        None
                    }
                }
            };
            let q0: Vec<f64> = base
                .params()
                .iter()
                .zip(&scales)
                .map(|(p, s)| p / s)
                .collect();
            let start = objective(&q0);
            let j_start = start.as_ref().map_or(f64::NAN, |(j, _)| *j);
            let start_finite = start
                .as_ref()
                .is_some_and(|(j, g)| j.is_finite() && g.iter().all(|v| v.is_finite()));
            let opts = MinimizeOptions {
                max_iters: self.optimiser.length,
                grad_tol: 1e-8,
                rel_tol: 1e-10,
                memory: self.optimiser.memory,
                max_line_search_evals: Some(self.optimiser.mfepls),
                wolfe: self.optimiser.wolfe,
                max_slope_ratio: self.optimiser.max_slope_ratio,
            };
            // The optimiser's first evaluation is at q0: it gets the one made above rather than
            // a second value+gradient pass over the horizon.
            let mut at_start = start.map(|value| (q0.clone(), value));
            let mut objective_once_at_start = |q: &[f64]| match at_start.take() {
                Some((q_start, value)) if q == q_start.as_slice() => Some(value),
                _ => objective(q),
            };
            let result = minimize(&mut objective_once_at_start, q0, &opts);
            let result = result.ok_or_else(|| match first_failure.take() {
                Some(cause) => cause,
                None if start_finite => LearnError::Spec(format!(
                    "policy optimiser: the line search's Wolfe constants {:?} must satisfy \
                     0 < c1 < c2 < 1, and its maximum slope ratio {:?} must be positive",
                    self.optimiser.wolfe, self.optimiser.max_slope_ratio
                )),
                None => LearnError::NonFinite(format!(
                    "the predicted return ({j_start}) or its gradient at the policy update \
                     {ep} starts from"
                )),
            })?;
            self.policy.set_params(&unscale(&result.x, &scales))?;
            let optimise_s = t0.elapsed().as_secs_f64();
            let out = self.predicted_value(&self.policy, mm, false)?;
            let (predicted_mean, predicted_std) = self.ret.predicted_return(&out);
            observer.predicted(ep, &out);
            predictions.push(out);

            // Roll out: the first roll-out feeds the GP, further ones only test the policy.
            observer.phase(ep, Phase::Rollout);
            let k = (self.initial_rollouts + ep) as u64;
            let n_rollouts = self.rollouts_per_episode.max(1);
            let mut successes = 0usize;
            let mut first: Option<(Rollout, bool)> = None;
            for j in 0..n_rollouts {
                // The first roll-out keeps the master seed's streams, so runs with one
                // roll-out per update are unchanged by extra ones.
                let base = if j == 0 {
                    self.seed
                } else {
                    derive_seed(self.seed, k, PURPOSE_EXTRA_ROLLOUT + j as u64)
                };
                let start = self.env_start.sample(derive_seed(base, k, PURPOSE_START))?;
                let policy = &self.policy;
                let me = &self;
                let mut r = rollout(
                    env,
                    &start,
                    derive_seed(base, k, PURPOSE_NOISE),
                    |t, obs| Ok(me.act(policy, trig.as_ref(), t, obs)),
                )?;
                r.used_for_training = j == 0;
                let ok = (self.success)(&r);
                successes += usize::from(ok);
                observer.rollout_done(ep, &r, &self.recorded_costs(&r));
                if j == 0 {
                    first = Some((r, ok));
                } else {
                    rollouts.push(r);
                }
            }
            let (r, success) = first.expect("at least one roll-out per update");
            let record = EpisodeRecord {
                index: ep,
                predicted_return_mean: predicted_mean,
                predicted_return_std: predicted_std,
                recorded_return: self.recorded_return(&r),
                success,
                rollouts: n_rollouts,
                success_fraction: successes as f64 / n_rollouts as f64,
                interaction_s: r.len() as f64 * env.dt(),
                train_s,
                optimise_s,
                evaluations: result.evaluations,
                line_searches: result.iterations,
                slope_capped: self.optimiser.max_slope_ratio.map(|_| result.slope_capped),
                termination: termination_text(&result.termination),
                objective_start: j_start,
                objective_end: result.value,
                n_train,
                sparse: model.is_sparse(),
                cold_restarts: report.hyper().cold_restarts(),
                model_selection: selection,
            };
            tracing::info!(
                episode = ep,
                j = result.value,
                recorded = record.recorded_return,
                success = record.success,
                success_fraction = record.success_fraction,
                "policy update done"
            );
            observer.episode_done(&record);
            episodes.push(record);
            data.push(r.clone());
            rollouts.push(r);
            observer.checkpoint(&LoopState {
                completed: ep,
                data: data.clone(),
                hyp: hyp.clone(),
                inducing: inducing.as_ref().map(mat_rows),
                policy_params: self.policy.params(),
                episodes: episodes.clone(),
            });
        }
        Ok(LoopOutcome {
            initial: Vec::new(),
            episodes,
            rollouts,
            policy: self.policy,
            dynamics_hyp: hyp.unwrap_or_default(),
            predictions,
        })
    }
}

/// ψ = scale ⊙ q: the policy parameters at the optimiser's point `q`.
fn unscale(q: &[f64], scales: &[f64]) -> Vec<f64> {
    q.iter().zip(scales).map(|(q, s)| q * s).collect()
}

pub(crate) fn mat_rows(m: &Mat<f64>) -> Vec<Vec<f64>> {
    (0..m.nrows())
        .map(|i| (0..m.ncols()).map(|j| m[(i, j)]).collect())
        .collect()
}

fn mat_from_rows(rows: &[Vec<f64>], what: &str) -> Result<Mat<f64>, LearnError> {
    let n = rows.first().map_or(0, Vec::len);
    if let Some(i) = rows.iter().position(|r| r.len() != n) {
        return Err(LearnError::Spec(format!(
            "{what}: row {i} has {} entries, row 0 has {n}",
            rows[i].len()
        )));
    }
    Ok(Mat::from_fn(rows.len(), n, |i, j| rows[i][j]))
}

fn termination_text(t: &Termination) -> String {
    match t {
        Termination::GradientNorm => "gradient norm".into(),
        Termination::RelativeChange => "relative change".into(),
        Termination::MaxIterations => "line-search budget (Length)".into(),
        Termination::LineSearchFailed(m) => format!("line search failed: {m}"),
    }
}

#[cfg(test)]
mod tests;
