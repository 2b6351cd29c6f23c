//! The thesis experiments' settings: one TOML file per run in `experiments/` (embedded in the
//! binary, so `vicpilco run vil-gic` works from any directory; `--config FILE` reads another).
//!
//! Every struct denies unknown keys, and [`ArmExperiment::validate`] checks ranges after
//! parsing; both kinds of error name the file and the key. Values the thesis does not give are
//! marked "ours" in the TOML files and in the report.

use serde::{Deserialize, Serialize};
use std::path::Path;
use vicpilco_env::arm::ControllerKind;
use vicpilco_learn::selection::ModelSelection;

mod validate;
pub use vicpilco_pilco::policy::CentreScale;

/// The shipped configs: (name, file text). `vil-gic` is an alias of `vil-gic-rbf10`.
pub const CONFIGS: &[(&str, &str)] = &[
    (
        "vil-gic-lin",
        include_str!("../../../../experiments/vil-gic-lin.toml"),
    ),
    (
        "vil-gic-rbf10",
        include_str!("../../../../experiments/vil-gic-rbf10.toml"),
    ),
    (
        "vil-gic-rbf25",
        include_str!("../../../../experiments/vil-gic-rbf25.toml"),
    ),
    (
        "vil-sic",
        include_str!("../../../../experiments/vil-sic.toml"),
    ),
    ("vilta", include_str!("../../../../experiments/vilta.toml")),
    (
        "vilta-var",
        include_str!("../../../../experiments/vilta-var.toml"),
    ),
];

/// Names that stand for another config.
pub const ALIASES: &[(&str, &str)] = &[("vil-gic", "vil-gic-rbf10")];

/// The name an alias stands for (`vil-gic` → `vil-gic-rbf10`), any other name unchanged. Runs
/// record this name, so a run started under an alias resumes, replays and pools in `acceptance`
/// with those started under the name itself.
pub fn canonical(name: &str) -> &str {
    ALIASES
        .iter()
        .find(|(alias, _)| *alias == name)
        .map_or(name, |(_, target)| target)
}

/// A bad config: which file, which key, what is wrong.
#[derive(Debug, thiserror::Error)]
pub enum ConfigError {
    /// The text is not TOML, or has an unknown key, a missing one or a value of the wrong type.
    #[error("{file}: {message}")]
    Parse {
        /// The file's label: the path as given, or `experiments/<name>.toml` when shipped.
        file: String,
        /// The TOML parser's error, with line and column.
        message: String,
    },
    /// A value out of range or against a cross-field rule ([`ArmExperiment::validate`]).
    #[error("{file}: `{key}` {message}")]
    Invalid {
        /// The file's label, as in `Parse`.
        file: String,
        /// Dotted key of the first bad value, indexed in arrays, e.g. `policy.lengthscales[2]`.
        key: String,
        /// The rule broken and the value given, e.g. `must be a finite number > 0, got -1`.
        message: String,
    },
    /// The path only: the I/O error is the source, which `{:#}` prints after it.
    #[error("{path}")]
    Read {
        /// The config file, as given.
        path: String,
        /// Why it could not be read.
        source: std::io::Error,
    },
}

/// VIL: stiffness along the given plan; VILTA: stiffness and reference velocities.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Task {
    /// `"vil"` (§5-4): the policy sets (k_x, k_y), m = 2; the reference follows the given
    /// min-jerk plan through the hole.
    Vil,
    /// `"vilta"` (§5-5): the policy sets (k_x, k_y, Δx_ref, Δy_ref), m = 4, with the hole's
    /// position unknown; needs `[vilta]`, `initial.scan` and `policy.delta_max`.
    Vilta,
}

/// Policy family.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum PolicyKind {
    /// `"linear"`: a = sat(A s + b) on the policy inputs s; n_ψ = m (n_π + 1).
    Linear,
    /// `"rbf"`: a deterministic GP (RBF network) of `policy.n_basis` Gaussian basis functions
    /// with learnable centres, pseudo-targets and length-scales, then saturated (§4-3).
    Rbf,
}

/// One thesis run (§5-4 to §5-6).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ArmExperiment {
    /// `"vil"` or `"vilta"` ([`Task`]): what the policy controls, and so which keys are
    /// required or refused.
    pub task: Task,
    /// Impedance law: `gic` or `sic`.
    pub controller: ControllerKind,
    /// Policy updates after the initial roll-out (VIL: Table 5-4, N = 25).
    pub episodes: usize,
    /// Learning steps H per episode (100: T = 10 s, §5-2-2, at Table 5-1's Δt); the return is
    /// undiscounted.
    pub horizon: usize,
    /// Length Δt of a learning step (s) (Table 5-1: 0.1); each action is held over one step.
    pub dt: f64,
    /// `[policy]`: family, stiffness limits and initial parameters (Tables 5-2, 5-6).
    pub policy: PolicyConfig,
    /// `[cost]`: the saturating costs and the return's weights (Tables 5-3, 5-5).
    pub cost: CostConfig,
    /// `[optimiser]`: the L-BFGS policy search of each update (Table 5-4).
    pub optimiser: OptimiserConfig,
    /// `[gp]`: the dynamics GP's inputs, prior mean, sparse approximation and fits (Table 5-1).
    pub gp: GpConfig,
    /// `[start]`: where real roll-outs start, and the prediction's start distribution(s).
    pub start: StartConfig,
    /// Initial (exploration) roll-out.
    pub initial: InitialConfig,
    /// VILTA only.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub vilta: Option<ViltaConfig>,
    /// The simulated sensors' noise (§5-2: 0.1° per encoder, 0.1°/s per tachometer, 0.1 N per
    /// force axis). Every shipped config keeps it on; `false` is a diagnostic (ours) that
    /// shows how much of a run's behaviour the measurement noise in the GP's inputs and
    /// targets causes (EXPERIMENTS.md, "Runs without sensor noise").
    #[serde(default = "on", skip_serializing_if = "is_on")]
    pub sensor_noise: bool,
}

fn on() -> bool {
    true
}

fn is_on(b: &bool) -> bool {
    *b
}

/// `[policy]`: the policy family, the saturation of its actions and its initial parameters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PolicyConfig {
    /// `"linear"` or `"rbf"` ([`PolicyKind`]); `n_basis`, `lengthscales` and `snr` are required
    /// with `"rbf"` and refused with `"linear"`.
    pub kind: PolicyKind,
    /// RBF basis functions N_c (RBF only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub n_basis: Option<usize>,
    /// Lower end of the stiffness range [k_min, k_max] of the partial non-negative saturation
    /// (N/m) (eq. 4-23; Table 5-2: 5); also the OU profiles' lower limit.
    pub k_min: f64,
    /// Upper end of that range (N/m): 250 under GIC (Table 5-2), 500 under SIC (§5-4-2). Also
    /// the energy cost's scale S = diag(k_max²) and the OU profiles' upper limit.
    pub k_max: f64,
    /// VILTA: |Δx_ref|, |Δy_ref| limit per `delta_tick` (m) (Table 5-6: 0.0025).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub delta_max: Option<f64>,
    /// Initial RBF length-scales on (x, y, ẋ, ẏ) (ours).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lengthscales: Option<[f64; 4]>,
    /// Std of the initial pseudo-targets (RBF) or weights (linear) (ours, PILCO: 0.1).
    pub init_std: f64,
    /// RBF signal-to-noise ratio σ_f/σ_n (SNR 100: noise 0.01²).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub snr: Option<f64>,
    /// VILTA, RBF (ours, off unless set): the initial policy's reference increments are the
    /// search roll-out's at each centre (the centres lie on its path), not `init_std · randn`,
    /// so the first optimisation starts from a policy that moves towards the wall. The gains'
    /// pseudo-targets stay random. See EXPERIMENTS.md, twenty-second session.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub init_from_scan: bool,
}

/// `[cost]`: the saturating position and force costs and the weights of the return, relative
/// to w1 = 1 on the saturating costs' mean (Tables 5-3, 5-5).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CostConfig {
    /// Which of `"x"`, `"y"` the position cost measures (1 or 2, distinct): both for VIL
    /// (Table 5-3); x only for VILTA, whose hole position is unknown (Table 5-5).
    pub position_dims: Vec<String>,
    /// The position cost's target (m), one entry per `position_dims` entry: the end of the
    /// hole, (0.75, 0.20) for VIL and x = 0.80 in VILTA's shifted scene.
    pub position_target: Vec<f64>,
    /// Width of the saturating position cost (m) (Tables 5-3, 5-5: 0.05).
    pub position_width: f64,
    /// Width (N) of the saturating cost on (f_x, f_y), target 0 (Tables 5-3, 5-5: 20).
    pub force_width: f64,
    /// Ours, off unless set: the width (N) of a second saturating cost on (f_x, f_y), target 0,
    /// wider than `force_width`. The thesis's 20 N cost is flat at 1 beyond about 60 N, so a
    /// policy that presses a wall with 150 N or crashes into it with 500 N gets no gradient
    /// towards pressing less (EXPERIMENTS.md, sixteenth session). Like the other saturating
    /// costs it also enters the summed cost whose std `w_std` weighs.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub force_width_far: Option<f64>,
    /// w2: weight of std of the summed saturating costs (negative: exploration).
    pub w_std: f64,
    /// w3: weight of the energy cost of (k_x, k_y), S = diag(k_max²).
    pub w_energy: f64,
}

/// `[optimiser]`: the L-BFGS search over the policy parameters at each update (Table 5-4).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OptimiserConfig {
    /// Line searches per policy update (PILCO "Length").
    pub length: u64,
    /// Function evaluations per line search (MFEPLS).
    pub mfepls: u64,
    /// L-BFGS memory (ours).
    pub memory: usize,
    /// Optimise the RBF centres in units of the policy's length-scales (ours; the policy and
    /// the objective are unchanged, only the optimiser's steps). `false`, the default, is
    /// PILCO's search over the raw parameters, where centres in metres with ℓ ≈ 0.1 m are
    /// thrown out of the workspace by the first steps.
    #[serde(default)]
    pub scale_params: bool,
    /// With `scale_params`, which of the outputs' length-scales measures a centre coordinate
    /// (ours): `"geometric-mean"` (the default) or `"smallest"`, which keeps every step within
    /// one length-scale of the narrowest output (see EXPERIMENTS.md, "The RBF policy's k_x
    /// output dies").
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub centre_scale: Option<CentreScale>,
    /// PILCO's maximum slope ratio (Table 5-4's MSR = 100): each line search after the first
    /// first tries a step whose predicted decrease is at most `msr` times the previous search's
    /// achieved one (`vicpilco_gp::train::MinimizeOptions::max_slope_ratio`). Absent: no cap,
    /// every line search first tries L-BFGS's step 1, as every stored run was made.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub msr: Option<f64>,
}

/// Where the relative targets' prior mean comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum PriorMean {
    /// The reference trajectory's increment over each step (§4-1-2).
    Reference,
    /// Zero.
    Zero,
}

/// `[gp]`: the dynamics GP's inputs and prior mean, its sparse approximation and the fit of its
/// hyper-parameters at each update (Table 5-1, §5-6-1).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GpConfig {
    /// Time as a GP input (VIL: yes; VILTA: no).
    pub time_input: bool,
    /// The relative targets' prior mean ([`PriorMean`]): `"reference"` for VIL (§4-1-2);
    /// VILTA, which has no given reference, requires `"zero"`.
    pub prior_mean: PriorMean,
    /// Full GP up to this many points, FITC above.
    pub sparse_threshold: usize,
    /// Inducing inputs of the FITC approximation (Table 5-1: N_ii = 300; §5-6-1).
    pub n_inducing: usize,
    /// Above the sparse threshold the hyper-parameters are fitted on a random subset of this
    /// many points (ours: all of up to 2600 points would cost O(N³) per evaluation).
    pub hyper_points: usize,
    /// Line searches per hyper-parameter fit.
    pub line_searches: u64,
    /// Also fit the hyper-parameters from PILCO's first guess on the current data and keep the
    /// better fit per output (ours; PILCO only warm-starts from the previous fit, which kept
    /// the arm's velocity model at a length-scale of the sensor noise, EXPERIMENTS.md).
    pub cold_restart: bool,
    /// Per GP input (x, y, ẋ, ẏ, \[ℓ_x, ℓ_y,\] \[f_x, f_y,\] \[t,\] actions), a length-scale
    /// floor: training adds a wall penalty below about half of it
    /// (`vicpilco_gp::train::floor_penalty`; 0 = free). Ours, not PILCO's: a length-scale at
    /// an input's sensor-noise scale fits the noise (EXPERIMENTS.md, "Why an update drops an
    /// inserting policy": measured, it did not help).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lengthscale_floor: Option<Vec<f64>>,
    /// Per GP input, in `lengthscale_floor`'s order, a length-scale ceiling: training adds a
    /// wall penalty above about twice it (`vicpilco_gp::train::ceiling_penalty`; 0 = free).
    /// Ours, not PILCO's: the VILTA runs that press the face below the hole fit x-dynamics
    /// models whose y length-scale (3.6-5 m, or 7-11 cm) smears the 1 cm channel away, so the
    /// model sees no gain in moving along the face (EXPERIMENTS.md, twenty-sixth session).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lengthscale_ceiling: Option<Vec<f64>>,
    /// Also feed the measured contact forces (f_x, f_y) to the dynamics GP, after (x, y, ẋ, ẏ).
    /// Ours, not the thesis's (its inputs are the motion states only, eq. 4-3/4-5, because
    /// "the forces follow from the states, gains and reference"). Under VILTA the reference is
    /// the integral of the policy's increments, a state the GP does not see, so a force that
    /// ramps up while the peg is held still looks like noise to it; the last force makes the
    /// ramp predictable (EXPERIMENTS.md, "Force inputs for VILTA").
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub force_inputs: bool,
    /// How each update picks its model's hyper-parameters: `"likelihood"` (the default,
    /// PILCO's: the refit), `"last-rollout"` (ours: the refit or the previous update's
    /// hyper-parameters, whichever predicts the newest roll-out's return better) or
    /// `"last-rollout-states"` (ours: the same choice on the roll-out's predicted states),
    /// `"last-rollout-states-robust"` (ours: on the states with a Student-t density per
    /// entry), `"last-rollout-states-huber"` (ours, vil-sic's: on the states with a Huber
    /// density per entry) or `"last-rollout-crps"` (ours: on the return by its continuous
    /// ranked probability score; `vicpilco_learn::selection::ModelSelection`).
    #[serde(default, skip_serializing_if = "is_likelihood")]
    pub model_selection: ModelSelection,
}

fn is_likelihood(s: &ModelSelection) -> bool {
    *s == ModelSelection::Likelihood
}

/// `[start]`: the real roll-outs' start state and the long-term prediction's Gaussian start
/// distribution(s).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StartConfig {
    /// Start state (x, y, ẋ, ẏ, f_x, f_y).
    pub state: [f64; 6],
    /// Std of the prediction's start distribution (ours).
    pub prediction_std: [f64; 6],
    /// Real starts draw y uniformly from this interval (vilta-var).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub y_range: Option<[f64; 2]>,
    /// Prediction start means' y, one start distribution each (K), averaged (vilta-var).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub prediction_y: Option<Vec<f64>>,
}

/// `[initial]`: the exploration roll-out before the first update (OU stiffness profiles; for
/// VILTA also the scan that sets the reference increments).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InitialConfig {
    /// Ornstein–Uhlenbeck stiffness profile: mean-reversion rate θ (1/s) (see
    /// [`vicpilco_env::arm::OuParams`]).
    pub ou_theta: f64,
    /// VILTA: the scan's via points (t, x, y), min-jerk between them, sent as per-tick Δ.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scan: Option<Vec<[f64; 3]>>,
    /// VILTA (ours, off unless set): jitter added to the scan's reference position.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scan_jitter: Option<ScanJitter>,
}

/// A zero-mean Ornstein–Uhlenbeck perturbation of the scan's reference position, one per axis,
/// clipped to ±3 std. Without it the scan's increments are a function of the state along its
/// path, and the first dynamics model cannot tell what the Δ actions do (EXPERIMENTS.md,
/// fifteenth session).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScanJitter {
    /// Stationary standard deviation per axis (m).
    pub std: f64,
    /// Mean-reversion rate θ (1/s); the increments' correlation time is about 1/θ.
    pub theta: f64,
}

/// `[vilta]`: required by VILTA runs and refused by VIL ones: the shifted scene, the Δ actions'
/// tick, roll-outs per iteration, the final evaluation and the reference's lead.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ViltaConfig {
    /// The VIL scene moved by this much in x (m) (issue: +0.05).
    pub geometry_shift_x: f64,
    /// Controller tick the Δ actions refer to (s) (thesis: 5 ms).
    pub delta_tick: f64,
    /// Roll-outs per iteration; only the first adds GP data.
    pub rollouts_per_iteration: usize,
    /// Fresh starts the final policy is evaluated on (0: none).
    pub evaluation_starts: usize,
    /// Where the reference integration starts: `"start"` (issue 5: the whole episode from the
    /// start pose) or `"measured"` (ours: at each step from the measured position, which keeps
    /// the reference from drifting into a surface; see EXPERIMENTS.md).
    #[serde(
        default,
        skip_serializing_if = "vicpilco_env::arm::ReferenceOrigin::is_start"
    )]
    pub reference: vicpilco_env::arm::ReferenceOrigin,
    /// Largest lead (m) of the reference over the measured TCP position on each axis (ours;
    /// absent: unbounded, as issue 5). See `ActionMode::Vilta::max_lead` and EXPERIMENTS.md.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_lead: Option<f64>,
    /// Whether `max_lead` also bounds the initial search roll-out (the default). `false`
    /// (ours) records the search without the bound and only the learned policy's roll-outs
    /// with it: the bound slows only increments that push the lead out, so a jittered scan
    /// under it ratchets its reference back from the wall and never inserts (probe
    /// `scan-jitter-lead`, EXPERIMENTS.md).
    #[serde(default = "on", skip_serializing_if = "is_on")]
    pub max_lead_in_search: bool,
    /// The reference's lead over the TCP, (x_v − x, y_v − y), as two more state entries that
    /// the dynamics GP takes as inputs and predicts (relative targets, zero prior) and the
    /// policy takes as inputs (ours; absent: the state, D = 8). See [`LeadState`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lead_state: Option<LeadState>,
    /// Which update's policy the run hands over and evaluates from the fresh starts:
    /// `"last"` (PILCO, the default) or `"most-successful"` (ours). It acts after learning
    /// only, so it is not part of a run's identity and a finished run can be evaluated again
    /// under the other rule with `--resume`.
    #[serde(default, skip_serializing_if = "FinalPolicy::is_last")]
    pub final_policy: FinalPolicy,
}

/// `vilta.lead_state` (ours). The integrated reference x_v is a state the GP and policy
/// never see, so a policy cannot tell a reference running on into a wall from one at rest and
/// the model cannot tell the force it causes (EXPERIMENTS.md, "Force inputs for VILTA" and the
/// twenty-fifth session). With the lead in the state the transition is Markov in what is
/// observed: the GP gets D = 10 inputs and E = 8 targets, the policy n_π = 6 inputs.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LeadState {
    /// Std (m) of each lead entry of the prediction's start distribution; the reference starts
    /// at the start pose, so the start's lead is 0.
    pub prediction_std: f64,
    /// Initial RBF policy length-scale (m) on each lead input: required with an RBF policy,
    /// refused with a linear one, which has no length-scales.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub policy_lengthscale: Option<f64>,
    /// Stiffness k₀ (N/m) of a linear prior mean on the measured contact forces:
    /// f_{t+1} = k₀ · ℓ_t + GP (ours; absent: the zero prior). Against a surface the
    /// controller's quasi-static force is k · ℓ; with the zero prior the force model falls
    /// back to 0 at leads beyond its data, so a reference driven a metre into the face looks
    /// free (probe `lead-state-scan-deep-jitter`, seed 1). k₀ makes such leads look costly
    /// instead; in free space the GP learns the −k₀ · ℓ it adds.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub force_prior_stiffness: Option<f64>,
}

/// Which policy of a run is its result (`vilta.final_policy`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum FinalPolicy {
    /// The last update's policy.
    #[default]
    Last,
    /// The policy of the update whose own roll-outs inserted most often, the latest of equals
    /// (ours). The learner can tell: it records whether each of its roll-outs inserted. A
    /// jammed insertion and standing still both cost about 1 per step, so the cost alone does
    /// not keep the learner from trading an inserting policy for a worse one
    /// (EXPERIMENTS.md, twenty-second session); this rule keeps the best it has seen.
    MostSuccessful,
}

impl FinalPolicy {
    /// The default (serialised configs omit it).
    pub fn is_last(&self) -> bool {
        *self == FinalPolicy::Last
    }
}

/// `(label, text)` of a shipped config: its name (an alias resolved to the name it stands for)
/// and its TOML text.
pub fn shipped(name: &str) -> Option<(&'static str, &'static str)> {
    let name = canonical(name);
    CONFIGS.iter().find(|(n, _)| *n == name).copied()
}

/// Parse and validate a config text; `file` labels errors.
pub fn parse(text: &str, file: &str) -> Result<ArmExperiment, ConfigError> {
    let cfg: ArmExperiment = toml::from_str(text).map_err(|e| ConfigError::Parse {
        file: file.to_string(),
        message: e.to_string(),
    })?;
    cfg.validate(file)?;
    Ok(cfg)
}

/// Read, parse and validate a config file.
pub fn load(path: &Path) -> Result<ArmExperiment, ConfigError> {
    let text = std::fs::read_to_string(path).map_err(|e| ConfigError::Read {
        path: path.display().to_string(),
        source: e,
    })?;
    parse(&text, &path.display().to_string())
}

impl ArmExperiment {
    /// Learnable policy parameters n_ψ = N_c (n_π + m) + n_π m (RBF, §4-3) or m (n_π + 1)
    /// (linear), with n_π inputs and m outputs.
    pub fn n_params(&self) -> usize {
        let (n_in, m) = (self.n_policy_inputs(), self.n_actions());
        match self.policy.kind {
            PolicyKind::Rbf => self.policy.n_basis.unwrap_or(0) * (n_in + m) + n_in * m,
            PolicyKind::Linear => m * (n_in + 1),
        }
    }

    /// Keys whose values are ours rather than the thesis's (they are marked "ours" in the TOML
    /// files too; the simulator's own choices are listed in crates/env/README.md).
    pub fn ours_keys(&self) -> Vec<&'static str> {
        let mut keys = vec![
            "optimiser.memory",
            "policy.init_std",
            "start.prediction_std",
            "initial.ou_theta",
            "gp.hyper_points",
            "gp.cold_restart",
        ];
        if self.policy.kind == PolicyKind::Rbf {
            keys.extend(["policy.lengthscales", "optimiser.scale_params"]);
            if self.optimiser.centre_scale.is_some() {
                keys.push("optimiser.centre_scale");
            }
        }
        if self.gp.lengthscale_floor.is_some() {
            keys.push("gp.lengthscale_floor");
        }
        if self.gp.lengthscale_ceiling.is_some() {
            keys.push("gp.lengthscale_ceiling");
        }
        if self.gp.force_inputs {
            keys.push("gp.force_inputs");
        }
        if self.gp.model_selection != ModelSelection::Likelihood {
            keys.push("gp.model_selection");
        }
        if self.policy.init_from_scan {
            keys.push("policy.init_from_scan");
        }
        if !self.sensor_noise {
            keys.push("sensor_noise");
        }
        if self.vilta.as_ref().is_some_and(|v| !v.reference.is_start()) {
            keys.push("vilta.reference");
        }
        if self.vilta.as_ref().is_some_and(|v| v.max_lead.is_some()) {
            keys.push("vilta.max_lead");
        }
        if self.vilta.as_ref().is_some_and(|v| !v.max_lead_in_search) {
            keys.push("vilta.max_lead_in_search");
        }
        if self.lead_state().is_some() {
            keys.push("vilta.lead_state");
        }
        if self
            .vilta
            .as_ref()
            .is_some_and(|v| !v.final_policy.is_last())
        {
            keys.push("vilta.final_policy");
        }
        if self.controller == ControllerKind::Sic && self.policy.kind == PolicyKind::Rbf {
            keys.push("policy.n_basis");
        }
        if self.cost.force_width_far.is_some() {
            keys.push("cost.force_width_far");
        }
        if self.task == Task::Vilta {
            keys.extend(["episodes", "start.state", "initial.scan"]);
            if self.start.prediction_y.is_some() {
                keys.push("start.prediction_y");
            }
            if self.initial.scan_jitter.is_some() {
                keys.push("initial.scan_jitter");
            }
        }
        keys
    }

    /// D of the dynamics GP: the policy inputs, the forces if `gp.force_inputs`, time if
    /// `gp.time_input`, and the actions.
    pub fn gp_input_dim(&self) -> usize {
        self.n_policy_inputs()
            + 2 * usize::from(self.gp.force_inputs)
            + usize::from(self.gp.time_input)
            + self.n_actions()
    }

    /// `vilta.lead_state`, if set.
    pub fn lead_state(&self) -> Option<&LeadState> {
        self.vilta.as_ref().and_then(|v| v.lead_state.as_ref())
    }

    /// Entries of the learner's state: (x, y, ẋ, ẏ, f_x, f_y), plus the reference's lead
    /// with `vilta.lead_state`.
    pub fn state_dim(&self) -> usize {
        use vicpilco_env::arm::{LEAD_NAMES, STATE_NAMES};
        STATE_NAMES.len() + LEAD_NAMES.len() * usize::from(self.lead_state().is_some())
    }

    /// n_π: (x, y, ẋ, ẏ), plus the reference's lead with `vilta.lead_state`.
    pub fn n_policy_inputs(&self) -> usize {
        4 + vicpilco_env::arm::LEAD_NAMES.len() * usize::from(self.lead_state().is_some())
    }

    /// Actions: (k_x, k_y) or (k_x, k_y, Δx_ref, Δy_ref).
    pub fn n_actions(&self) -> usize {
        match self.task {
            Task::Vil => 2,
            Task::Vilta => 4,
        }
    }
}
