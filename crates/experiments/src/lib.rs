//! # vicpilco-experiments: runnable learning experiments
//!
//! Each experiment builds a [`vicpilco_learn::outer::LoopSetup`] and a system, runs the PILCO
//! loop and keeps a run directory current ([`record`]):
//!
//! * `summary.json` — per policy update: predicted return (mean, std), recorded return,
//!   success (and the fraction of the update's roll-outs that succeeded, as a colour), timings;
//!   `solved_at_episode` (and the `solved_streak` it means); the settings; the thesis's
//!   numbers beside the run's ([`checks`]);
//! * `rollouts.jsonl` — every roll-out with its weighted cost per step, appended as recorded;
//! * `predictions.jsonl` — every update's long-term prediction (means, variances, costs);
//! * `policies.jsonl` — the parameters of the policy each update rolled out (episode 0: the
//!   untrained policy the first update starts from), in [`Policy::params`]' order;
//! * `checkpoint.json` — what `--resume` needs to continue bit for bit;
//! * `policy.json` — written when the run ends: the last update's policy parameters and
//!   dynamics hyper-parameters (the policy a `most-successful` run hands over is
//!   `policies.jsonl`'s at `final_eval.update`);
//! * `final_eval.jsonl` — runs with evaluation starts: the final policy from fresh starts
//!   (any update's policy: [`evaluate`]);
//! * `report.html`, `report.md` and the plots (PNG, SVG) — [`vicpilco_report`], rewritten
//!   after every update.
//!
//! Experiments: `pendulum` and `cartpole` (PILCO's swing-ups, [`classic`]), and the thesis's
//! peg-in-hole runs configured by `experiments/*.toml` ([`config`], [`arm`]). A system of your
//! own gets the same run directory from [`own::run_own`] (`examples/own_system.rs`).
//!
//! ## Example
//!
//! The shipped configs are compiled in. `vil-gic` is an alias of `vil-gic-rbf10`: an RBF policy
//! of 10 centres on (x, y, ẋ, ẏ) with two gains, n_ψ = N_c (n_π + m) + n_π m = 68, and a
//! dynamics GP on those four, time and the two gains (D = 7); VILTA's has 50 centres and four
//! actions (n_ψ = 416) and no time (D = 8). A key the schema does not know is an error that
//! names it:
//!
//! ```
//! use vicpilco_experiments::config::{parse, shipped};
//!
//! let (label, text) = shipped("vil-gic").expect("a shipped name");
//! assert_eq!(label, "vil-gic-rbf10");
//! let vil = parse(text, label)?;
//! assert_eq!((vil.n_params(), vil.gp_input_dim(), vil.horizon), (68, 7, 100));
//!
//! let (label, text) = shipped("vilta").expect("a shipped name");
//! let vilta = parse(text, label)?;
//! assert_eq!((vilta.n_params(), vilta.gp_input_dim(), vilta.n_actions()), (416, 8, 4));
//!
//! let misspelt = text.replace("[gp]", "[gp]\nlenghtscale_ceiling = 0.02");
//! let err = parse(&misspelt, "mine.toml").unwrap_err().to_string();
//! assert!(err.contains("mine.toml") && err.contains("lenghtscale_ceiling"), "{err}");
//! # Ok::<(), vicpilco_experiments::config::ConfigError>(())
//! ```

#![warn(missing_docs)]

pub mod arm;
pub mod checks;
pub mod classic;
pub mod config;
mod error;
pub mod evaluate;
pub mod own;
pub mod recheck;
pub mod record;
pub mod replay;
pub mod subnormals;
pub mod summary;
pub mod summary_config;

pub use error::ExperimentError;

use config::{ArmExperiment, FinalPolicy, PolicyKind};
use record::{
    open_jsonl, prepare_out, read_checkpoint, ClaimsOf, PredictionLabels, Recorder, RolloutExtras,
};
use std::path::{Path, PathBuf};
use std::time::Instant;
use summary::{write_json_atomic, RunSession, Summary};
use vicpilco_env::classic::{CartPoleScenario, PendulumScenario};
use vicpilco_env::Environment;
use vicpilco_learn::outer::LoopSetup;
use vicpilco_learn::record::{LoopObserver, LoopOutcome};
use vicpilco_pilco::policy::Policy;

/// The classic benchmarks (configured in code from PILCO's published scenarios).
pub const CLASSIC: &[&str] = &["pendulum", "cartpole"];

/// Names `vicpilco run` accepts: the classic benchmarks, the shipped configs and their aliases.
pub fn experiment_names() -> Vec<&'static str> {
    CLASSIC
        .iter()
        .copied()
        .chain(config::CONFIGS.iter().map(|(n, _)| *n))
        .chain(config::ALIASES.iter().map(|(a, _)| *a))
        .collect()
}

/// What the caller chooses about a run.
#[derive(Clone, Debug, Default)]
pub struct RunOptions {
    /// Master seed: every random stream of the run is derived from it and the episode
    /// ([`vicpilco_learn::outer::derive_seed`]), so seed and settings fix the run.
    pub seed: u64,
    /// The run directory, created if missing. A run that does not resume refuses one that
    /// already holds a run ([`ExperimentError::RunExists`]).
    pub out: PathBuf,
    /// Override the number of policy updates.
    pub episodes: Option<usize>,
    /// Smoke-test mode: [`QUICK_EPISODES`] updates with [`QUICK_LENGTH`] line searches each
    /// (an explicit `episodes` still wins).
    pub quick: bool,
    /// A config file to use instead of the shipped one (arm experiments).
    pub config: Option<PathBuf>,
    /// Continue the run in `out` from its `checkpoint.json`.
    pub resume: bool,
    /// Start from the recorded run in this directory (same experiment, seed and settings but
    /// `gp.model_selection`): keep its updates while this run's rule chooses as it did, and
    /// continue from the first update where the rules part ([`replay`]).
    pub replay_from: Option<PathBuf>,
}

/// Policy updates of a `--quick` run.
pub const QUICK_EPISODES: usize = 3;
/// Line searches per policy optimisation of a `--quick` run.
pub const QUICK_LENGTH: u64 = 5;

impl RunOptions {
    fn episodes_or(&self, default: usize) -> usize {
        self.episodes
            .unwrap_or(if self.quick { QUICK_EPISODES } else { default })
    }
}

/// The number of policy updates `run` will do with these options.
pub fn planned_updates(name: &str, opts: &RunOptions) -> Result<usize, ExperimentError> {
    let default = match load_config(name, opts.config.as_deref())? {
        Some(cfg) => cfg.episodes,
        None if name == "pendulum" => PendulumScenario::default().policy_updates,
        None => CartPoleScenario::default().policy_updates,
    };
    Ok(opts.episodes_or(default))
}

/// The arm config of a run (`--config` file, or the shipped one), `None` for the classic ones.
fn load_config(
    name: &str,
    config: Option<&Path>,
) -> Result<Option<ArmExperiment>, ExperimentError> {
    let shipped = |name: &str| -> Result<Option<ArmExperiment>, ExperimentError> {
        config::shipped(name)
            .map(|(file, text)| config::parse(text, &format!("experiments/{file}.toml")))
            .transpose()
            .map_err(Into::into)
    };
    Ok(match (config, name) {
        (Some(_), "pendulum" | "cartpole") => {
            return Err(ExperimentError::NotArm {
                name: name.to_string(),
                what: "--config",
            })
        }
        (Some(path), _) => {
            let cfg = config::load(path)?;
            // Any other name labels a variant of one's own.
            if let Some(theirs) = shipped(name)? {
                cfg.check_variant_of(name, &theirs, &path.display().to_string())?;
            }
            Some(cfg)
        }
        (None, "pendulum" | "cartpole") => None,
        (None, _) => {
            Some(shipped(name)?.ok_or_else(|| ExperimentError::Unknown(name.to_string()))?)
        }
    })
}

/// Run an experiment by name and write its run directory. The run flushes subnormal numbers to
/// zero ([`subnormals`]: up to 15× faster GP training, the same numbers above 1e-300).
pub fn run(
    name: &str,
    opts: &RunOptions,
    observer: &mut dyn LoopObserver,
) -> Result<Summary, ExperimentError> {
    let name = config::canonical(name);
    let cfg = load_config(name, opts.config.as_deref())?;
    if cfg.is_none() && opts.replay_from.is_some() {
        // The classic runs have one model-selection rule, so nothing to replay under another.
        return Err(ExperimentError::NotArm {
            name: name.to_string(),
            what: "--replay-from",
        });
    }
    let _lock = prepare_out(opts)?;
    subnormals::run_flushed(|| match (cfg, name) {
        (Some(cfg), _) => run_arm(name, cfg, opts, observer),
        (None, "pendulum") => run_classic(name, PendulumScenario::default(), opts, observer),
        (None, _) => run_classic(name, CartPoleScenario::default(), opts, observer),
    })
}

/// What a run is, for its summary and checkpoint.
pub(crate) struct RunMeta<'a> {
    /// Every setting, for `summary.json`.
    config: serde_json::Value,
    /// The settings a resumed run must share (all but the number of updates).
    identity: serde_json::Value,
    controller: Option<String>,
    policy: String,
    n_params: usize,
    extras: Option<RolloutExtras>,
    claims: Option<ClaimsOf<'a>>,
}

/// A classic swing-up with the run options applied to its PILCO scenario.
fn run_classic<P, const N: usize>(
    name: &str,
    mut scn: vicpilco_env::classic::Scenario<P>,
    opts: &RunOptions,
    observer: &mut dyn LoopObserver,
) -> Result<Summary, ExperimentError>
where
    P: vicpilco_env::classic::ClassicSystem
        + vicpilco_env::classic::Dynamics<N>
        + serde::Serialize
        + Send
        + Sync
        + 'static,
{
    if opts.quick {
        scn.opt_length = QUICK_LENGTH as usize;
    }
    let identity = serde_json::to_value(vicpilco_env::classic::Scenario {
        policy_updates: 0,
        ..scn.clone()
    })
    .map_err(|e| ExperimentError::Write(e.into()))?;
    scn.policy_updates = opts.episodes_or(scn.policy_updates);
    let config = serde_json::json!({ "scenario": format!("{scn:#?}") });
    let (setup, mut env) = classic::setup(scn, opts.seed)?;
    let meta = RunMeta {
        config,
        identity,
        controller: None,
        policy: format!(
            "rbf ({} basis functions, {} inputs)",
            setup.policy.n_centres(),
            setup.policy.n_inputs()
        ),
        n_params: setup.policy.n_free_params(),
        extras: None,
        claims: None,
    };
    let summary = finish(name, opts, setup, &mut env, None, observer, meta)?.0;
    vicpilco_report::write_report(&opts.out)?;
    Ok(summary)
}

/// (final x, largest |f|, start y) of an arm roll-out.
fn arm_extras(r: &vicpilco_learn::data::Rollout) -> (f64, f64, f64) {
    let final_x = r.true_states.last().map_or(f64::NAN, |s| s[0]);
    let max_force = arm::largest_force(r);
    let start_y = r.true_states.first().map_or(f64::NAN, |s| s[1]);
    (final_x, max_force, start_y)
}

/// The learning loop of an arm experiment with `policy`: its environment (and the search
/// roll-out's, when that differs), the run, and the checks that need the loop's outcome.
fn learn_on_arm<P>(
    name: &str,
    cfg: &ArmExperiment,
    policy: P,
    opts: &RunOptions,
    observer: &mut dyn LoopObserver,
    meta: RunMeta<'_>,
) -> Result<Summary, ExperimentError>
where
    P: Policy + Clone + Sync,
    P::Cache: Send,
{
    let (setup, mut env) = arm::setup(cfg, policy, opts.seed)?;
    let mut search = arm::search_env(cfg)?;
    let search_env = search.as_mut().map(|e| e as &mut dyn Environment);
    let (summary, outcome) = finish(name, opts, setup, &mut env, search_env, observer, meta)?;
    checks::after_run(cfg, summary, &outcome, opts)
}

/// A thesis experiment on the arm.
fn run_arm(
    name: &str,
    mut cfg: ArmExperiment,
    opts: &RunOptions,
    observer: &mut dyn LoopObserver,
) -> Result<Summary, ExperimentError> {
    if opts.quick {
        cfg.optimiser.length = QUICK_LENGTH;
    }
    let identity = arm_identity(&cfg)?;
    let planned = cfg.episodes;
    cfg.episodes = opts.episodes_or(cfg.episodes);
    let config = summary_config::arm_summary_config(&cfg)?;
    let meta = |policy: String| RunMeta {
        config: config.clone(),
        identity: identity.clone(),
        controller: Some(cfg.controller.to_string()),
        policy,
        n_params: cfg.n_params(),
        extras: Some(arm_extras),
        claims: Some(Box::new(|s: &Summary| {
            checks::thesis_checks(name, &cfg, planned, s)
        })),
    };
    let mut summary = match cfg.policy.kind {
        PolicyKind::Rbf => {
            let policy = arm::rbf_policy(&cfg, opts.seed)?;
            let desc = format!(
                "rbf ({} basis functions, {} inputs)",
                policy.n_centres(),
                policy.n_inputs()
            );
            learn_on_arm(name, &cfg, policy, opts, observer, meta(desc))?
        }
        PolicyKind::Linear => {
            let policy = arm::linear_policy(&cfg, opts.seed)?;
            let desc = format!("linear ({} inputs)", policy.n_inputs());
            learn_on_arm(name, &cfg, policy, opts, observer, meta(desc))?
        }
    };
    summary.thesis_reference = checks::thesis_checks(name, &cfg, planned, &summary);
    summary.write(&opts.out)?;
    vicpilco_report::write_report(&opts.out)?;
    Ok(summary)
}

/// The settings a resumed or replayed arm run must share with its record: all but the number
/// of updates and `vilta.final_policy`, which acts only after the last update.
pub(crate) fn arm_identity(cfg: &ArmExperiment) -> Result<serde_json::Value, ExperimentError> {
    let mut shared = ArmExperiment {
        episodes: 0,
        ..cfg.clone()
    };
    if let Some(v) = shared.vilta.as_mut() {
        v.final_policy = FinalPolicy::Last;
    }
    serde_json::to_value(shared).map_err(|e| ExperimentError::Write(e.into()))
}

/// A recorded arm run that a command reads (`rescore`, `evaluate`), and the file it writes.
#[derive(Clone, Debug)]
pub struct RecordedRunOptions {
    /// The recorded run's seed.
    pub seed: u64,
    /// The recorded run's directory (read only).
    pub from: PathBuf,
    /// The run's settings (`--config` file, or the shipped ones). `rescore` accepts a
    /// `gp.model_selection` other than the run's: it names the rule reported as `other`.
    pub config: Option<PathBuf>,
    /// The JSON-lines file the command writes, one line per update (must not exist).
    pub out: PathBuf,
    /// The recorded run was a `--quick` one (its settings are then the quick ones).
    pub quick: bool,
}

/// The settings of a recorded arm run that `what` reads: the `config` file or the shipped
/// ones, with a `--quick` run's optimiser budget when `quick`.
pub(crate) fn recorded_arm_config(
    name: &str,
    config: Option<&Path>,
    quick: bool,
    what: &'static str,
) -> Result<ArmExperiment, ExperimentError> {
    let mut cfg = load_config(name, config)?.ok_or_else(|| ExperimentError::NotArm {
        name: name.to_string(),
        what,
    })?;
    if quick {
        cfg.optimiser.length = QUICK_LENGTH;
    }
    Ok(cfg)
}

/// Every comparing model-selection rule's verdict at each update of the recorded arm run
/// `opts.from`, replayed along its own choices ([`replay::rescore`]); a cheap way to compare
/// rules on recorded runs (the model fits only, no policy optimisation), in the same
/// floating-point mode as the run ([`subnormals`]).
pub fn rescore(
    name: &str,
    opts: &RecordedRunOptions,
) -> Result<Vec<vicpilco_learn::replay::ReplayedUpdate>, ExperimentError> {
    let name = config::canonical(name);
    let cfg = recorded_arm_config(name, opts.config.as_deref(), opts.quick, "rescore")?;
    let identity = arm_identity(&cfg)?;
    subnormals::run_flushed(|| match cfg.policy.kind {
        PolicyKind::Rbf => {
            let (setup, _) = arm::setup(&cfg, arm::rbf_policy(&cfg, opts.seed)?, opts.seed)?;
            replay::rescore(&opts.from, name, opts.seed, &identity, &setup, &opts.out)
        }
        PolicyKind::Linear => {
            let (setup, _) = arm::setup(&cfg, arm::linear_policy(&cfg, opts.seed)?, opts.seed)?;
            replay::rescore(&opts.from, name, opts.seed, &identity, &setup, &opts.out)
        }
    })
}

/// Run (or resume) the loop with a [`Recorder`] and write the final files.
pub(crate) fn finish<P>(
    name: &str,
    opts: &RunOptions,
    setup: LoopSetup<P>,
    env: &mut dyn Environment,
    initial_env: Option<&mut dyn Environment>,
    observer: &mut dyn LoopObserver,
    meta: RunMeta<'_>,
) -> Result<(Summary, LoopOutcome<P>), ExperimentError>
where
    P: Policy + Clone + Sync,
    P::Cache: Send,
{
    // A replaying run's directory is made (and locked) by graft; the lock is held to the end.
    let mut _graft_lock = None;
    let checkpoint = match (&opts.replay_from, opts.resume) {
        (_, true) => Some(read_checkpoint(&opts.out, name, opts.seed, &meta.identity)?),
        (Some(source), false) => {
            let (checkpoint, lock) = replay::graft(
                source,
                name,
                opts.seed,
                &meta.identity,
                &setup,
                &opts.out,
                env.dt(),
            )?;
            _graft_lock = lock;
            Some(checkpoint)
        }
        (None, false) => None,
    };
    let keep = checkpoint.as_ref().map(|c| c.state.completed);
    // Equal is allowed: it redoes only what follows the last update (the final evaluation,
    // the summary and the report), e.g. under another `vilta.final_policy`.
    if let Some(done) = keep.filter(|&done| opts.resume && setup.episodes < done) {
        return Err(ExperimentError::Resume {
            path: opts.out.join("checkpoint.json"),
            message: format!(
                "the run already has {done} policy updates and --episodes {} would learn none \
                 (updates are not undone): give --episodes above {done} to continue, or {done} \
                 to redo only the final evaluation and the report",
                setup.episodes
            ),
        });
    }
    let rollouts = open_jsonl(&opts.out.join("rollouts.jsonl"), keep)?;
    let predictions = open_jsonl(&opts.out.join("predictions.jsonl"), keep)?;
    let policies = open_jsonl(&opts.out.join("policies.jsonl"), keep)?;
    let mut summary = match &checkpoint {
        Some(c) => Summary {
            config: meta.config.clone(),
            // A run recorded under an alias continues under the name it stands for.
            experiment: name.to_string(),
            ..c.summary.clone()
        },
        None => Summary::new(
            name,
            opts.seed,
            meta.controller.clone(),
            &meta.policy,
            meta.n_params,
            meta.config.clone(),
        ),
    };
    summary
        .sessions
        .push(RunSession::here(keep.map_or(1, |done| done + 1)));
    let labels = PredictionLabels {
        dt: env.dt(),
        state_names: env.state_names(),
        action_names: env.action_names(),
        action_bounds: setup
            .squash
            .as_ref()
            .map(|sq| sq.ranges().iter().map(|r| r.bounds()).collect()),
        w_mean: setup.ret.w_mean,
        w_energy: setup.ret.energy.as_ref().map_or(0.0, |(_, w)| *w),
    };
    let mut recorder = Recorder {
        inner: observer,
        wall_before: summary.wall_s,
        summary,
        dir: opts.out.clone(),
        dt: env.dt(),
        labels,
        extras: meta.extras,
        identity: meta.identity,
        claims: meta.claims,
        started: Instant::now(),
        rollouts,
        predictions,
        policies,
        current: None,
        error: None,
    };
    let outcome = match checkpoint {
        Some(c) => setup.resume(env, &mut recorder, c.state)?,
        None => match initial_env {
            Some(initial_env) => setup.run_with_initial_env(initial_env, env, &mut recorder)?,
            None => setup.run(env, &mut recorder)?,
        },
    };
    if let Some(e) = recorder.error {
        return Err(e);
    }
    let mut summary = recorder.summary;
    summary.wall_s = recorder.wall_before + recorder.started.elapsed().as_secs_f64();
    summary.write(&opts.out)?;
    let policy = serde_json::json!({
        "policy": summary.policy,
        "params": outcome.policy.params(),
        "dynamics_hyp": outcome.dynamics_hyp,
    });
    write_json_atomic(&opts.out.join("policy.json"), &policy)?;
    Ok((summary, outcome))
}
