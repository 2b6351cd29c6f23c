//! `vicpilco acceptance DIR...`: issue 6's acceptance table over several runs (one per seed),
//! as Markdown on stdout or in a file.

use anyhow::Context;
use std::io::Write;
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
    /// Run directories written by `vicpilco run`, one per experiment and seed (any mix of
    /// experiments: each gets its own table).
    #[arg(required = true)]
    dirs: Vec<PathBuf>,
    /// Write the Markdown here instead of printing it.
    #[arg(long)]
    out: Option<PathBuf>,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let table = vicpilco_report::acceptance_markdown(&args.dirs)
        .context("building the acceptance table")?;
    match &args.out {
        Some(file) => {
            std::fs::write(file, table).with_context(|| format!("writing {}", file.display()))
        }
        // A closed pipe (`vicpilco acceptance ... | head`) is not an error.
        None => match std::io::stdout().lock().write_all(table.as_bytes()) {
            Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(e).context("printing"),
            _ => Ok(()),
        },
    }
}
