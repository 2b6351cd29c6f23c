//! The one error type of the crate's public functions.

use crate::{config, experiment_names, summary};
use std::path::PathBuf;

/// Why a run, a resume, a replay, `rescore`, `evaluate` or `recheck` failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ExperimentError {
    /// A name that is neither a classic benchmark nor a shipped config or alias, given without
    /// `--config`; holds the name.
    #[error("unknown experiment `{0}` (known: {known})", known = experiment_names().join(", "))]
    Unknown(String),
    /// A command that reads a recorded arm run was given a classic benchmark.
    #[error("`{name}` is not an arm experiment: {what} needs one")]
    NotArm {
        /// The experiment name given.
        name: String,
        /// The command that needs an arm run: `rescore`, `evaluate` or `recheck`.
        what: &'static str,
    },
    /// The arm config could not be read, parsed or validated.
    #[error(transparent)]
    Config(#[from] config::ConfigError),
    /// The learning loop, or a roll-out outside it, failed: model fit, prediction, policy
    /// optimisation, start sampling or the simulator during a roll-out.
    #[error(transparent)]
    Learn(#[from] vicpilco_learn::LearnError),
    /// A policy, cost or saturation could not be built from the settings, or a recorded
    /// parameter vector does not fit the policy.
    #[error(transparent)]
    Pilco(#[from] vicpilco_pilco::PilcoError),
    /// The GP engine failed outside the loop, e.g. factoring the start covariance that the
    /// classic policies' initial centres are drawn from.
    #[error(transparent)]
    Gp(#[from] vicpilco_gp::GpError),
    /// The simulator or the OU exploration refused its configuration (a failure during a
    /// roll-out arrives as `Learn`).
    #[error(transparent)]
    Env(#[from] vicpilco_env::EnvError),
    /// A JSON file of the run directory could not be written.
    #[error(transparent)]
    Write(#[from] summary::WriteError),
    /// The path only: the I/O error is the source, which `{:#}` prints after it.
    #[error("{}", path.display())]
    Io {
        /// The file or directory the failed operation was on.
        path: PathBuf,
        /// The I/O error (`AlreadyExists` for an output `evaluate` will not overwrite).
        source: std::io::Error,
    },
    /// A run that does not resume (a fresh one, or `--replay-from`) was pointed at a directory
    /// that already holds a run: starting over would discard what that run recorded.
    #[error(
        "{} already holds {held} ({file}): continue it with --resume (same experiment and \
         seed; --episodes N for more updates), or give another --out; delete the directory to \
         start it afresh",
        dir.display()
    )]
    RunExists {
        /// The run directory.
        dir: PathBuf,
        /// The first of the run's files found there, e.g. `checkpoint.json`.
        file: &'static str,
        /// Which run, from its checkpoint ("a run of `vil-sic`, seed 2, 25 updates done"),
        /// or "a run" when there is none to read.
        held: String,
    },
    /// Another process is running in the directory (it holds [`crate::record::LOCK_FILE`]'s lock).
    #[error(
        "{} is in use by another vicpilco process (a run still going there): wait for it to \
         end or stop it, then --resume",
        dir.display()
    )]
    RunBusy {
        /// The run directory.
        dir: PathBuf,
    },
    /// [`crate::own::run_own`] was given options or a name that belong to the named experiments, or
    /// a seed other than its setup's.
    #[error("run of a system of your own: {0}")]
    OwnRun(String),
    /// A run's checkpoint cannot be continued or read back (`--resume`, and `rescore`,
    /// `evaluate` and `--replay-from` on a recorded run): none, unreadable, or of another
    /// experiment, seed or setting.
    #[error("cannot continue from {path}: {message}")]
    Resume {
        /// `checkpoint.json`, or the JSON-lines file with a bad line.
        path: PathBuf,
        /// What does not match or cannot be read, e.g. the first setting that differs.
        message: String,
    },
    /// A recorded run that `--replay-from` or `rescore` cannot replay under these settings.
    #[error("cannot replay the recorded run {path}: {message}")]
    Replay {
        /// The recorded run's file that is malformed, incomplete or does not match
        /// (`checkpoint.json`, or a JSON-lines file).
        path: PathBuf,
        /// What is wrong with it, e.g. a bad line or the first setting that differs.
        message: String,
    },
    /// A recorded run whose policies `evaluate` cannot roll out as asked.
    #[error("cannot evaluate the recorded run {path}: {message}")]
    Evaluate {
        /// The recorded run's directory, or the file of its policies.
        path: PathBuf,
        /// What is wrong, e.g. an update the run does not have or no evaluation starts.
        message: String,
    },
    /// A recorded run whose claims `recheck` cannot judge again under the settings given.
    #[error("cannot recheck {path}: {message}")]
    Recheck {
        /// The run's `summary.json`.
        path: PathBuf,
        /// What is wrong, e.g. the first setting that differs from the run's.
        message: String,
    },
    /// The report (`report.html`, `report.md`, plots) could not be written from the run
    /// directory.
    #[error(transparent)]
    Report(#[from] vicpilco_report::ReportError),
}
