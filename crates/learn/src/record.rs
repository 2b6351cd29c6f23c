//! What the outer loop reports and keeps: the progress hooks of a [`LoopObserver`], the record
//! of each policy update, the finished run ([`LoopOutcome`]) and the state between updates
//! that a stopped run resumes from ([`LoopState`]).

use crate::data::Rollout;
use crate::selection::SelectionRecord;
use crate::value::ValueOut;
use vicpilco_gp::Hyper;

/// What the loop does between roll-outs, reported to an observer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Phase {
    /// One initial roll-out with the exploration policy (reported once per roll-out, with
    /// episode 0).
    InitialRollout,
    /// Fitting the dynamics GP to the training roll-outs so far, and with a comparing
    /// [`crate::selection::ModelSelection`] choosing between the refit and the previous
    /// hyper-parameters.
    Train,
    /// Optimising the policy on the predicted return.
    Optimise,
    /// Running the optimised policy on the system: every roll-out of the update.
    Rollout,
}

/// Progress hooks; every method has a no-op default.
pub trait LoopObserver {
    /// `phase` of policy update `episode` begins (episode 0: the initial roll-outs).
    fn phase(&mut self, _episode: usize, _phase: Phase) {}
    /// Each evaluation of the objective `j` (J, exploration term included) while update
    /// `episode` optimises its policy, line-search trial points included. A point whose
    /// prediction fails has no J and is not reported: the line search backs off from it (if
    /// the start point fails, the update fails with that cause).
    fn objective(&mut self, _episode: usize, _j: f64) {}
    /// Update `record.index` is finished: optimised, rolled out and recorded (before its
    /// [`LoopObserver::checkpoint`]).
    fn episode_done(&mut self, _record: &EpisodeRecord) {}
    /// Every roll-out as soon as it is recorded (initial ones with `episode` 0), with its
    /// weighted immediate cost per step ([`crate::outer::LoopSetup::recorded_costs`]).
    fn rollout_done(&mut self, _episode: usize, _rollout: &Rollout, _costs: &[f64]) {}
    /// The long-term prediction of the policy an update optimised.
    fn predicted(&mut self, _episode: usize, _prediction: &ValueOut) {}
    /// Everything needed to continue after an update, handed over once it is complete (the
    /// initial roll-outs count as update 0).
    fn checkpoint(&mut self, _state: &LoopState) {}
}

impl LoopObserver for () {}

/// What was recorded for one policy update.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct EpisodeRecord {
    /// 1-based policy update.
    pub index: usize,
    /// `Σ_t γ^t (w1 E[c] + w3 E[c_a])` predicted for the optimised policy (no exploration
    /// term), from the first of the set-up's prediction starts only: with several (K > 1)
    /// the optimised objective averages them, but a roll-out starts from one state.
    pub predicted_return_mean: f64,
    /// `Σ_t γ^t w1 std[c_t]`: the spread of the return if step costs are perfectly
    /// correlated (ours: moment matching gives no cross-step covariances).
    pub predicted_return_std: f64,
    /// The same weighted cost evaluated on the recorded (true) states and actions.
    pub recorded_return: f64,
    /// The success test on the first roll-out.
    pub success: bool,
    /// Roll-outs after this update (at least 1); only the first adds to the GP's data.
    pub rollouts: usize,
    /// Fraction of those roll-outs that passed the success test, in [0, 1].
    pub success_fraction: f64,
    /// System time of the roll-out, seconds.
    pub interaction_s: f64,
    /// Wall-clock seconds of training the dynamics model, model selection included.
    pub train_s: f64,
    /// Wall-clock seconds of the policy optimisation.
    pub optimise_s: f64,
    /// Value+gradient evaluations of the policy optimisation.
    pub evaluations: usize,
    /// L-BFGS iterations (one line search each), at most
    /// [`crate::outer::OptimiserOptions::length`].
    pub line_searches: u64,
    /// Line searches whose first trial step PILCO's maximum slope ratio shortened
    /// ([`crate::outer::OptimiserOptions::max_slope_ratio`]); `None` when the rule was off.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub slope_capped: Option<usize>,
    /// Why the optimiser stopped: `gradient norm`, `relative change`,
    /// `line-search budget (Length)` or `line search failed: …`.
    pub termination: String,
    /// The objective J (with the exploration term) before optimisation.
    pub objective_start: f64,
    /// J at the policy the optimisation returned (the policy rolled out).
    pub objective_end: f64,
    /// Training points (recorded transitions) of the dynamics model.
    pub n_train: usize,
    /// Whether the model was the sparse FITC GP (more training points than
    /// [`vicpilco_gp::DynamicsOptions::sparse_threshold`]).
    pub sparse: bool,
    /// Outputs whose hyper-parameters came from the cold restart rather than the warm start
    /// (0 when the restart is off).
    #[serde(default)]
    pub cold_restarts: usize,
    /// With a comparing [`crate::selection::ModelSelection`]: the rule's score of the refitted
    /// model and of the previous hyper-parameters (lower is better), and whether the previous
    /// ones were kept.
    /// `None` when no selection was made (PILCO's rule, or the first update).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub model_selection: Option<SelectionRecord>,
}

/// Everything the loop produced.
pub struct LoopOutcome<P> {
    /// The initial roll-outs with the exploration policy (empty after
    /// [`crate::outer::LoopSetup::resume`]).
    pub initial: Vec<Rollout>,
    /// One record per policy update, in order; after a resume, the checkpoint's first.
    pub episodes: Vec<EpisodeRecord>,
    /// Every roll-out of the updates this call ran, update by update; within an update the
    /// extra test roll-outs come before the first (training) one.
    pub rollouts: Vec<Rollout>,
    /// The policy with the last update's parameters.
    pub policy: P,
    /// Hyper-parameters, one per GP output, of the last update's dynamics model (the chosen
    /// one); empty if no update has run.
    pub dynamics_hyp: Vec<Hyper>,
    /// Per policy update, the long-term prediction of the optimised policy under that
    /// update's dynamics model (for predicted-vs-recorded plots).
    pub predictions: Vec<ValueOut>,
}

/// The loop between updates: enough to continue a stopped run bit for bit (every random
/// stream is derived from the master seed and the episode, so no generator state is kept).
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct LoopState {
    /// Updates completed (0: only the initial roll-outs).
    pub completed: usize,
    /// The GP's training roll-outs, in order.
    pub data: Vec<Rollout>,
    /// Dynamics hyper-parameters of the model the last update chose: its refit, or under a
    /// comparing [`crate::selection::ModelSelection`] possibly the previous ones kept (the
    /// next fit's warm start either way).
    pub hyp: Option<Vec<Hyper>>,
    /// Inducing inputs of the last sparse fit, rows (the next sparse fit's warm start).
    pub inducing: Option<Vec<Vec<f64>>>,
    /// The current policy's parameters.
    pub policy_params: Vec<f64>,
    /// The records of updates 1..=`completed`.
    pub episodes: Vec<EpisodeRecord>,
}
