//! `vicpilco report DIR`: hands the run directory to `vicpilco_report::write_report` and lists
//! what it wrote.

use anyhow::Context;
use std::io::Write;
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
    /// Run directory written by `vicpilco run` (summary.json, rollouts.jsonl, ...).
    dir: PathBuf,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let files = vicpilco_report::write_report(&args.dir)
        .with_context(|| format!("writing the report of {}", args.dir.display()))?;
    let mut listing = format!("{}\n{}\n", files.html.display(), files.markdown.display());
    for f in &files.images {
        listing.push_str(&format!("{}\n", f.display()));
    }
    for n in &files.notes {
        listing.push_str(&format!("not shown: {n}\n"));
    }
    // `println!` panics when the reader has gone (`vicpilco report DIR | head`); the report is
    // written by then, so a closed pipe is not an error.
    match std::io::stdout().lock().write_all(listing.as_bytes()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(e).context("printing"),
        _ => Ok(()),
    }
}
