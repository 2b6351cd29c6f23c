//! The PILCO outer loop: initial roll-outs, then repeat {train the dynamics GP (warm start);
//! optimise the policy on the predicted return; roll it out on the system; record}.
//!
//! The loop owns every side effect (progress, logging) through a [`LoopObserver`]; GP
//! training, policy optimisation and roll-outs know nothing of them. Randomness is derived
//! from the master seed per (episode, purpose), so an episode can be reproduced alone.

use crate::data::{augment, initial_hyper, training_set, Rollout};
use crate::step::{Predictor, StepSpec};
use crate::value::{value, ReturnSpec, ValueOut};
use crate::LearnError;
use faer::Mat;
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use std::time::Instant;
use vicpilco_env::Environment;
use vicpilco_gp::linalg::Chol;
use vicpilco_gp::moments::MmModel;
use vicpilco_gp::train::{minimize, MinimizeOptions, Termination};
use vicpilco_gp::{DynamicsModel, DynamicsOptions, Hyper};
use vicpilco_pilco::policy::Policy;
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
}

/// What the loop does between roll-outs, reported to an observer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Phase {
    InitialRollout,
    Train,
    Optimise,
    Rollout,
}

/// Progress hooks; every method has a no-op default.
pub trait LoopObserver {
    fn phase(&mut self, _episode: usize, _phase: Phase) {}
    fn objective(&mut self, _episode: usize, _j: f64) {}
    fn episode_done(&mut self, _record: &EpisodeRecord) {}
    /// Every roll-out as soon as it is recorded (initial ones with `episode` 0).
    fn rollout_done(&mut self, _episode: usize, _rollout: &Rollout) {}
}

impl LoopObserver for () {}

/// Exploration for the initial roll-outs: `(seed, t, observation) → action`.
pub type ExplorePolicy = Box<dyn Fn(u64, usize, &[f64]) -> Vec<f64> + Send + Sync>;

/// Whether a roll-out achieved the task.
pub type SuccessTest = Box<dyn Fn(&Rollout) -> bool + Send + Sync>;

/// One learning problem: the prediction layout, cost, budgets and the system's start
/// distribution. `P` is the policy type.
pub struct LoopSetup<P> {
    pub spec: StepSpec,
    pub squash: Option<PartialSat>,
    pub ret: ReturnSpec,
    /// Start distributions the predicted return is averaged over (K).
    pub prediction_starts: Vec<(Vec<f64>, Mat<f64>)>,
    /// Distribution the system's real start states are drawn from.
    pub env_start: (Vec<f64>, Mat<f64>),
    /// Known prior mean of the GP targets per step (H rows of D0), if any.
    pub prior_shift: Option<Vec<Vec<f64>>>,
    pub dynamics: DynamicsOptions,
    pub optimiser: OptimiserOptions,
    /// Roll-outs with the exploration policy before learning.
    pub initial_rollouts: usize,
    /// Policy updates, one roll-out each.
    pub episodes: usize,
    pub policy: P,
    /// The initial roll-outs' actions: `(seed, t, observation) → action`.
    pub explore: ExplorePolicy,
    /// Did a roll-out succeed?
    pub success: SuccessTest,
    pub seed: u64,
}

/// What was recorded for one policy update.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct EpisodeRecord {
    /// 1-based policy update.
    pub index: usize,
    /// `Σ_t γ^t (w1 E[c] + w3 E[c_a])` predicted for the optimised policy (no exploration
    /// term).
    pub predicted_return_mean: f64,
    /// `Σ_t γ^t w1 std[c_t]`: the spread of the return if step costs are perfectly
    /// correlated (ours: moment matching gives no cross-step covariances).
    pub predicted_return_std: f64,
    /// The same weighted cost evaluated on the recorded (true) states and actions.
    pub recorded_return: f64,
    pub success: bool,
    /// System time of the roll-out, seconds.
    pub interaction_s: f64,
    pub train_s: f64,
    pub optimise_s: f64,
    /// Value+gradient evaluations of the policy optimisation.
    pub evaluations: usize,
    pub line_searches: u64,
    pub termination: String,
    /// The objective J (with the exploration term) before and after optimisation.
    pub objective_start: f64,
    pub objective_end: f64,
    /// Training points of the dynamics model, and whether it was sparse.
    pub n_train: usize,
    pub sparse: bool,
}

/// Everything the loop produced.
pub struct LoopOutcome<P> {
    pub initial: Vec<Rollout>,
    pub episodes: Vec<EpisodeRecord>,
    pub rollouts: Vec<Rollout>,
    pub policy: P,
    pub dynamics_hyp: Vec<Hyper>,
    /// Per policy update, the long-term prediction of the optimised policy under that
    /// update's dynamics model (for predicted-vs-recorded plots).
    pub predictions: Vec<ValueOut>,
}

/// SplitMix64 of (master seed, episode, purpose): independent streams without stored state.
pub fn derive_seed(master: u64, episode: u64, purpose: u64) -> u64 {
    let mut z = master
        ^ episode.wrapping_mul(0x9E37_79B9_7F4A_7C15)
        ^ purpose.wrapping_mul(0xD1B5_4A32_D192_ED03);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

const PURPOSE_START: u64 = 1;
const PURPOSE_NOISE: u64 = 2;
const PURPOSE_EXPLORE: u64 = 3;

/// A draw from `N(m, s)` (s may be singular: zero-variance dimensions stay at the mean).
pub fn sample_gaussian(m: &[f64], s: &Mat<f64>, seed: u64) -> Result<Vec<f64>, LearnError> {
    let d = m.len();
    // A deterministic start (zero covariance) has no Cholesky factor to draw with.
    if (0..d).all(|i| (0..d).all(|j| s[(i, j)] == 0.0)) {
        return Ok(m.to_vec());
    }
    let mut rng = rand::rngs::ChaCha8Rng::seed_from_u64(seed);
    let z: Vec<f64> = (0..d).map(|_| StandardNormal.sample(&mut rng)).collect();
    let chol = Chol::with_jitter(s.as_ref(), "start-state covariance", Default::default())?;
    let l = chol.l();
    Ok((0..d)
        .map(|i| m[i] + (0..=i).map(|k| l[(i, k)] * z[k]).sum::<f64>())
        .collect())
}

/// Run one episode on the system with `act(t, observation) → action`.
pub fn rollout(
    env: &mut dyn Environment,
    start: &[f64],
    seed: u64,
    mut act: impl FnMut(usize, &[f64]) -> Result<Vec<f64>, LearnError>,
) -> Result<Rollout, LearnError> {
    let first = env
        .reset(start, seed)
        .map_err(|e| LearnError::Env(e.to_string()))?;
    let mut r = Rollout {
        observations: vec![first],
        actions: Vec::new(),
        true_states: vec![start.to_vec()],
        infos: Vec::new(),
        used_for_training: true,
    };
    for t in 0..env.horizon() {
        let a = act(t, r.observations.last().expect("non-empty"))?;
        let step = env
            .step(&a)
            .map_err(|e| LearnError::Env(format!("step {t}: {e}")))?;
        r.actions.push(a);
        r.observations.push(step.observation);
        r.true_states.push(step.info.true_state.clone());
        r.infos.push(step.info);
        if step.done {
            break;
        }
    }
    Ok(r)
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

    /// The weighted cost of a recorded roll-out (true states), as the predicted return
    /// counts it.
    pub fn recorded_return(&self, r: &Rollout) -> f64 {
        let trig = (!self.ret.cost_angles.is_empty()).then(|| {
            TrigAug::new(
                self.spec.state_dim,
                &self.ret.cost_angles,
                &vec![1.0; self.ret.cost_angles.len()],
            )
            .expect("validated")
        });
        let mut total = 0.0;
        for t in 0..r.len() {
            let disc = self.ret.gamma.powi(t as i32 + 1);
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
            total += disc * (self.ret.w_mean * c + ca);
        }
        total
    }

    fn predicted(&self, out: &ValueOut) -> (f64, f64) {
        let traj = &out.trajectories[0];
        let w3 = self.ret.energy.as_ref().map_or(0.0, |(_, w)| *w);
        let mut mean = 0.0;
        let mut std = 0.0;
        for (t, s) in traj.iter().enumerate() {
            let disc = self.ret.gamma.powi(t as i32 + 1);
            mean += disc * (self.ret.w_mean * s.cost_mean + w3 * s.energy_mean);
            std += disc * self.ret.w_mean * s.cost_var.max(0.0).sqrt();
        }
        (mean, std)
    }

    /// Run the whole loop on `env`.
    pub fn run(
        mut self,
        env: &mut dyn Environment,
        observer: &mut dyn LoopObserver,
    ) -> Result<LoopOutcome<P>, LearnError> {
        let trig = self.trig();
        let mut data: Vec<Rollout> = Vec::new();
        for i in 0..self.initial_rollouts {
            observer.phase(0, Phase::InitialRollout);
            let k = i as u64;
            let start = sample_gaussian(
                &self.env_start.0,
                &self.env_start.1,
                derive_seed(self.seed, k, PURPOSE_START),
            )?;
            let es = derive_seed(self.seed, k, PURPOSE_EXPLORE);
            let explore = &self.explore;
            let r = rollout(
                env,
                &start,
                derive_seed(self.seed, k, PURPOSE_NOISE),
                |t, obs| Ok(explore(es, t, obs)),
            )?;
            observer.rollout_done(0, &r);
            data.push(r);
        }
        let initial = data.clone();
        let mut hyp: Option<Vec<Hyper>> = None;
        let mut inducing: Option<Mat<f64>> = None;
        let mut episodes = Vec::with_capacity(self.episodes);
        let mut rollouts = Vec::with_capacity(self.episodes);
        let mut predictions = Vec::with_capacity(self.episodes);
        for ep in 1..=self.episodes {
            // Train the dynamics model.
            observer.phase(ep, Phase::Train);
            let t0 = Instant::now();
            let (inputs, targets) = training_set(&self.spec, &data, self.prior_shift.as_deref());
            let init = hyp
                .clone()
                .unwrap_or_else(|| initial_hyper(&inputs, &targets));
            let n_train = inputs.nrows();
            let (model, _report) = DynamicsModel::fit(
                inputs,
                targets,
                &init,
                inducing.as_ref().map(|m| m.as_ref()),
                &self.dynamics,
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
            let mut objective = |p: &[f64]| -> Option<(f64, Vec<f64>)> {
                candidate.set_params(p).ok()?;
                let pred = Predictor::new(
                    &self.spec,
                    &candidate,
                    self.squash.as_ref(),
                    mm,
                    self.prior_shift.as_deref(),
                )
                .ok()?;
                let out = value(&pred, &self.ret, &self.prediction_starts, true).ok()?;
                observer.objective(ep, out.j);
                Some((out.j, out.grad?))
            };
            let p0 = base.params();
            let j_start = objective(&p0).map_or(f64::NAN, |(j, _)| j);
            let opts = MinimizeOptions {
                max_iters: self.optimiser.length,
                grad_tol: 1e-8,
                rel_tol: 1e-10,
                memory: self.optimiser.memory,
                max_line_search_evals: Some(self.optimiser.mfepls),
            };
            let result = minimize(&mut objective, p0, &opts).ok_or_else(|| {
                LearnError::NonFinite("the predicted return at the current policy".into())
            })?;
            self.policy.set_params(&result.x)?;
            let optimise_s = t0.elapsed().as_secs_f64();
            let pred = Predictor::new(
                &self.spec,
                &self.policy,
                self.squash.as_ref(),
                mm,
                self.prior_shift.as_deref(),
            )?;
            let out = value(&pred, &self.ret, &self.prediction_starts, false)?;
            let (predicted_mean, predicted_std) = self.predicted(&out);
            predictions.push(out);

            // Roll out.
            observer.phase(ep, Phase::Rollout);
            let k = (self.initial_rollouts + ep) as u64;
            let start = sample_gaussian(
                &self.env_start.0,
                &self.env_start.1,
                derive_seed(self.seed, k, PURPOSE_START),
            )?;
            let policy = &self.policy;
            let me = &self;
            let r = rollout(
                env,
                &start,
                derive_seed(self.seed, k, PURPOSE_NOISE),
                |t, obs| Ok(me.act(policy, trig.as_ref(), t, obs)),
            )?;
            let record = EpisodeRecord {
                index: ep,
                predicted_return_mean: predicted_mean,
                predicted_return_std: predicted_std,
                recorded_return: self.recorded_return(&r),
                success: (self.success)(&r),
                interaction_s: r.len() as f64 * env.dt(),
                train_s,
                optimise_s,
                evaluations: result.evaluations,
                line_searches: result.iterations,
                termination: termination_text(&result.termination),
                objective_start: j_start,
                objective_end: result.value,
                n_train,
                sparse: model.is_sparse(),
            };
            tracing::info!(
                episode = ep,
                j = result.value,
                recorded = record.recorded_return,
                success = record.success,
                "policy update done"
            );
            observer.rollout_done(ep, &r);
            observer.episode_done(&record);
            episodes.push(record);
            data.push(r.clone());
            rollouts.push(r);
        }
        Ok(LoopOutcome {
            initial,
            episodes,
            rollouts,
            policy: self.policy,
            dynamics_hyp: hyp.unwrap_or_default(),
            predictions,
        })
    }
}

fn termination_text(t: &Termination) -> String {
    match t {
        Termination::GradientNorm => "gradient norm".into(),
        Termination::RelativeChange => "relative change".into(),
        Termination::MaxIterations => "line-search budget (Length)".into(),
        Termination::LineSearchFailed(m) => format!("line search failed: {m}"),
    }
}
