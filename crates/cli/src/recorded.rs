use std::path::PathBuf;

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
    /// Where a command's JSON lines go when no --out is given: runs/<name>-seed<S>-<what>.jsonl.
    pub fn default_out(&self, what: &str) -> PathBuf {
        PathBuf::from(format!("runs/{}-seed{}-{what}.jsonl", self.name, self.seed))
    }
}
