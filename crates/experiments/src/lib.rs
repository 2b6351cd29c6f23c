//! # vicpilco-experiments: runnable learning experiments
//!
//! Each experiment builds a [`vicpilco_learn::outer::LoopSetup`] and a system, runs the PILCO
//! loop and writes a run directory:
//!
//! * `summary.json` — per policy update: predicted return (mean, std), recorded return,
//!   success, interaction, training and optimisation time; `solved_at_episode`;
//! * `rollouts.json` — every roll-out (observations, actions, true states), so nothing a run
//!   recorded is lost.
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

fn finish(
    name: &str,
    opts: &RunOptions,
    setup: LoopSetup<RbfPolicy>,
    env: &mut dyn Environment,
    observer: &mut dyn LoopObserver,
    config: String,
) -> Result<Summary, ExperimentError> {
    let t0 = Instant::now();
    let dt = env.dt();
    let n_initial = setup.initial_rollouts;
    let n_params = setup.policy.n_free_params();
    let outcome = setup.run(env, observer)?;
    let interaction_s = outcome
        .initial
        .iter()
        .chain(&outcome.rollouts)
        .map(|r| r.len() as f64 * dt)
        .sum();
    let summary = Summary {
        experiment: name.to_string(),
        seed: opts.seed,
        policy: format!(
            "rbf ({} basis functions, {} inputs)",
            outcome.policy.n_centres(),
            outcome.policy.n_inputs()
        ),
        n_params,
        solved_at_episode: solved_at(&outcome.episodes),
        episodes: outcome.episodes,
        interaction_s,
        wall_s: t0.elapsed().as_secs_f64(),
        config: serde_json::json!({ "scenario": config, "initial_rollouts": n_initial }),
    };
    summary.write(&opts.out)?;
    let rollouts = serde_json::json!({
        "initial": outcome.initial,
        "learned": outcome.rollouts,
        "policy_params": outcome.policy.params(),
    });
    write_json_atomic(&opts.out.join("rollouts.json"), &rollouts)?;
    Ok(summary)
}
