//! `vicpilco report DIR`: hands the run directory to `vicpilco_report::write_report` and lists
//! what it wrote.

use anyhow::Context;
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
    /// Run directory written by `vicpilco run` (summary.json, rollouts.jsonl, ...).
    dir: PathBuf,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let files = vicpilco_report::write_report(&args.dir)
        .with_context(|| format!("writing the report of {}", args.dir.display()))?;
    println!("{}", files.html.display());
    for f in &files.images {
        println!("{}", f.display());
    }
    for n in &files.notes {
        println!("not shown: {n}");
    }
    Ok(())
}
