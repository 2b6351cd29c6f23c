//! # vicpilco-experiments: runnable learning experiments
//!
//! Each experiment builds a [`vicpilco_learn::outer::LoopSetup`] and a system, runs the PILCO
//! loop and writes a run directory:
//!
//! * `summary.json` — per policy update: predicted return (mean, std), recorded return,
//!   success, interaction, training and optimisation time; `solved_at_episode`;
//! * `rollouts.jsonl` — every roll-out (observations, actions, true states), one JSON line each,
//!   appended as it is recorded, so nothing a run recorded is lost if it stops early;
//! * `policy.json` — the final policy parameters and dynamics hyper-parameters.
//!
//! Experiments: `pendulum` and `cartpole` (PILCO's swing-ups, [`classic`]); `vil-gic` (the
//! thesis's VIL experiment with the GIC controller and an RBF policy, [`vil`]; settings only
//! in code so far — the TOML configs and the other thesis runs are open work).

pub mod classic;
pub mod summary;
pub mod vil;

use std::path::PathBuf;
use std::time::Instant;
use summary::{solved_at, write_json_atomic, Summary};
use vicpilco_env::classic::{CartPoleScenario, PendulumScenario};
use vicpilco_env::Environment;
use vicpilco_learn::outer::{LoopObserver, LoopSetup};
use vicpilco_pilco::policy::{Policy, RbfPolicy};

#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ExperimentError {
    #[error("unknown experiment `{0}` (known: {known})", known = EXPERIMENTS.join(", "))]
    Unknown(String),
    #[error(transparent)]
    Learn(#[from] vicpilco_learn::LearnError),
    #[error(transparent)]
    Pilco(#[from] vicpilco_pilco::PilcoError),
    #[error(transparent)]
    Gp(#[from] vicpilco_gp::GpError),
    #[error(transparent)]
    Env(#[from] vicpilco_env::EnvError),
    #[error(transparent)]
    Write(#[from] summary::WriteError),
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
}

/// Names `vicpilco run` accepts.
pub const EXPERIMENTS: &[&str] = &["pendulum", "cartpole", "vil-gic"];

/// What the caller chooses about a run.
#[derive(Clone, Debug)]
pub struct RunOptions {
    pub seed: u64,
    pub out: PathBuf,
    /// Override the number of policy updates.
    pub episodes: Option<usize>,
    /// Smoke-test mode: [`QUICK_EPISODES`] updates with [`QUICK_LENGTH`] line searches each
    /// (an explicit `episodes` still wins).
    pub quick: bool,
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

/// Run an experiment by name and write its run directory.
pub fn run(
    name: &str,
    opts: &RunOptions,
    observer: &mut dyn LoopObserver,
) -> Result<Summary, ExperimentError> {
    std::fs::create_dir_all(&opts.out).map_err(|e| ExperimentError::Io {
        path: opts.out.clone(),
        source: e,
    })?;
    match name {
        "pendulum" => run_classic(name, PendulumScenario::default(), opts, observer),
        "cartpole" => run_classic(name, CartPoleScenario::default(), opts, observer),
        "vil-gic" => {
            let mut st = vil::VilSettings::default();
            st.episodes = opts.episodes_or(st.episodes);
            if opts.quick {
                st.opt_length = QUICK_LENGTH;
            }
            let config = format!("{st:#?}");
            let (setup, mut env) = vil::setup(&st, opts.seed)?;
            finish(name, opts, setup, &mut env, observer, config)
        }
        other => Err(ExperimentError::Unknown(other.to_string())),
    }
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
        + Send
        + Sync
        + 'static,
{
    scn.policy_updates = opts.episodes_or(scn.policy_updates);
    if opts.quick {
        scn.opt_length = QUICK_LENGTH as usize;
    }
    let config = format!("{scn:#?}");
    let (setup, mut env) = classic::setup(scn, opts.seed)?;
    finish(name, opts, setup, &mut env, observer, config)
}

/// Keeps the run directory current while the loop runs: every roll-out is appended to
/// `rollouts.jsonl` when it is recorded and `summary.json` is rewritten after every policy
/// update, so a run that stops early loses nothing it recorded. Forwards to the caller's
/// observer.
struct Recorder<'a> {
    inner: &'a mut dyn LoopObserver,
    summary: Summary,
    dir: PathBuf,
    dt: f64,
    started: Instant,
    rollouts: std::fs::File,
    error: Option<ExperimentError>,
}

impl Recorder<'_> {
    fn record(&mut self, result: Result<(), ExperimentError>) {
        if let Err(e) = result {
            tracing::error!("{e}");
            self.error.get_or_insert(e);
        }
    }
}

impl LoopObserver for Recorder<'_> {
    fn phase(&mut self, episode: usize, phase: vicpilco_learn::outer::Phase) {
        self.inner.phase(episode, phase)
    }
    fn objective(&mut self, episode: usize, j: f64) {
        self.inner.objective(episode, j)
    }
    fn rollout_done(&mut self, episode: usize, rollout: &vicpilco_learn::data::Rollout) {
        use std::io::Write;
        self.summary.interaction_s += rollout.len() as f64 * self.dt;
        let line = serde_json::json!({ "episode": episode, "rollout": rollout });
        let path = self.dir.join("rollouts.jsonl");
        let result = writeln!(self.rollouts, "{line}")
            .and_then(|()| self.rollouts.flush())
            .map_err(|e| ExperimentError::Io { path, source: e });
        self.record(result);
        self.inner.rollout_done(episode, rollout)
    }
    fn episode_done(&mut self, record: &vicpilco_learn::outer::EpisodeRecord) {
        self.summary.episodes.push(record.clone());
        self.summary.solved_at_episode = solved_at(&self.summary.episodes);
        self.summary.wall_s = self.started.elapsed().as_secs_f64();
        let result = self.summary.write(&self.dir).map_err(ExperimentError::from);
        self.record(result);
        self.inner.episode_done(record)
    }
}

fn finish(
    name: &str,
    opts: &RunOptions,
    setup: LoopSetup<RbfPolicy>,
    env: &mut dyn Environment,
    observer: &mut dyn LoopObserver,
    config: String,
) -> Result<Summary, ExperimentError> {
    let path = opts.out.join("rollouts.jsonl");
    let rollouts =
        std::fs::File::create(&path).map_err(|e| ExperimentError::Io { path, source: e })?;
    let mut recorder = Recorder {
        inner: observer,
        summary: Summary {
            experiment: name.to_string(),
            seed: opts.seed,
            policy: format!(
                "rbf ({} basis functions, {} inputs)",
                setup.policy.n_centres(),
                setup.policy.n_inputs()
            ),
            n_params: setup.policy.n_free_params(),
            episodes: Vec::new(),
            solved_at_episode: None,
            interaction_s: 0.0,
            wall_s: 0.0,
            config: serde_json::json!({ "scenario": config, "initial_rollouts": setup.initial_rollouts }),
        },
        dir: opts.out.clone(),
        dt: env.dt(),
        started: Instant::now(),
        rollouts,
        error: None,
    };
    let outcome = setup.run(env, &mut recorder)?;
    if let Some(e) = recorder.error {
        return Err(e);
    }
    let mut summary = recorder.summary;
    summary.wall_s = recorder.started.elapsed().as_secs_f64();
    summary.write(&opts.out)?;
    let policy = serde_json::json!({
        "policy": summary.policy,
        "params": outcome.policy.params(),
        "dynamics_hyp": outcome.dynamics_hyp,
    });
    write_json_atomic(&opts.out.join("policy.json"), &policy)?;
    Ok(summary)
}
