use std::path::PathBuf;
use vicpilco_experiments::RecordedRunOptions;

/// The default name of a run's directory under `runs/`: `<name>-seed<S>`, or
/// `<name>-quick-seed<S>` for a `--quick` run, which so never meets a full run's directory.
/// The commands that read a recorded run name their outputs after it.
pub fn default_run_name(name: &str, seed: u64, quick: bool) -> String {
    let quick = if quick { "-quick" } else { "" };
    format!("{name}{quick}-seed{seed}")
}

/// The recorded arm run a command reads (`rescore`, `evaluate`).
#[derive(clap::Args)]
pub struct RecordedRun {
    /// The recorded run's experiment (as given to `vicpilco run`).
    pub name: String,
    /// The recorded run's seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// The recorded run's directory (read only).
    #[arg(long, value_name = "DIR")]
    pub from: PathBuf,
    /// The recorded run was a --quick one.
    #[arg(long)]
    pub quick: bool,
}

impl RecordedRun {
    /// The library's options for this run, with its settings file and the output file.
    pub fn options(&self, config: Option<PathBuf>, out: PathBuf) -> RecordedRunOptions {
        RecordedRunOptions {
            seed: self.seed,
            from: self.from.clone(),
            config,
            out,
            quick: self.quick,
        }
    }

    /// Where a command's JSON lines go when no `--out` is given:
    /// `runs/<name>-seed<S>-<what>.jsonl`, or `runs/<name>-quick-seed<S>-<what>.jsonl` with
    /// `--quick` (as `run --quick` keeps its directory apart from the full run's).
    pub fn default_out(&self, what: &str) -> PathBuf {
        PathBuf::from(format!(
            "runs/{}-{what}.jsonl",
            default_run_name(&self.name, self.seed, self.quick)
        ))
    }
}
