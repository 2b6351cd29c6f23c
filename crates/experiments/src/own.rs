//! A run directory for a system of your own: the learning loop of any
//! [`LoopSetup`] on any [`Environment`], recorded as the named experiments record theirs, so
//! checkpoints, `resume` and `vicpilco report` work for it too.

use crate::record::prepare_out;
use crate::summary::Summary;
use crate::{experiment_names, finish, subnormals, ExperimentError, RunMeta};
use crate::{RunOptions, QUICK_EPISODES};
use vicpilco_env::Environment;
use vicpilco_learn::outer::LoopSetup;
use vicpilco_learn::record::LoopObserver;
use vicpilco_pilco::policy::Policy;

/// Runs (or, with `opts.resume`, continues) `setup` on `env` and writes the run directory
/// `opts.out` as [`crate::run`] does: `summary.json`, the JSON-lines records, `checkpoint.json`
/// after every update, `policy.json`, and the report (`report.html`, `report.md`, plots).
///
/// * `name` is the run's experiment name in its files; the named experiments' names are
///   refused, so a report never mistakes the run for one of them.
/// * `settings` describes everything the run was set up with (it becomes `summary.json`'s
///   `config`). A resumed run must give the same: it is what tells a stopped run from another.
/// * `opts.seed` must equal `setup.seed` (the run's streams derive from it); `opts.episodes`,
///   if given, replaces `setup.episodes` (a resume may ask for more updates). `quick`,
///   `config` and `replay_from` select the named experiments' settings and runs, so they are
///   errors here.
///
/// A fresh run refuses a directory that already holds a run
/// ([`ExperimentError::RunExists`]). The run flushes subnormals to zero as the named runs do
/// when the global rayon pool has flushing threads: call [`subnormals::pool_flushes`] before
/// anything else starts the pool (building an RBF policy does); otherwise it keeps gradual
/// underflow (slower, the same numbers to 1e-300) and its summary's `sessions` say so.
pub fn run_own<P>(
    name: &str,
    mut setup: LoopSetup<P>,
    env: &mut dyn Environment,
    settings: serde_json::Value,
    opts: &RunOptions,
    observer: &mut dyn LoopObserver,
) -> Result<Summary, ExperimentError>
where
    P: Policy + Clone + Sync,
    P::Cache: Send,
{
    let refuse = |why: String| Err(ExperimentError::OwnRun(why));
    if experiment_names().contains(&name) {
        return refuse(format!(
            "`{name}` names a shipped experiment; give the run a name of its own"
        ));
    }
    if opts.quick {
        return refuse(format!(
            "`quick` applies the named experiments' smoke settings ({QUICK_EPISODES} updates); \
             set the setup's budget instead"
        ));
    }
    if opts.config.is_some() || opts.replay_from.is_some() {
        return refuse("`config` and `replay_from` apply to the named experiments only".into());
    }
    if opts.seed != setup.seed {
        return refuse(format!(
            "the run options' seed {} differs from the setup's {}",
            opts.seed, setup.seed
        ));
    }
    let _lock = prepare_out(opts)?;
    setup.episodes = opts.episodes.unwrap_or(setup.episodes);
    let meta = RunMeta {
        config: settings.clone(),
        identity: settings,
        controller: None,
        policy: format!(
            "{} ({} inputs, {} outputs)",
            std::any::type_name::<P>()
                .rsplit("::")
                .next()
                .unwrap_or("policy"),
            setup.policy.n_inputs(),
            setup.policy.n_outputs()
        ),
        n_params: setup.policy.n_params(),
        extras: None,
        claims: None,
    };
    let summary =
        subnormals::run_flushed(|| finish(name, opts, setup, env, None, observer, meta))?.0;
    vicpilco_report::write_report(&opts.out)?;
    Ok(summary)
}
