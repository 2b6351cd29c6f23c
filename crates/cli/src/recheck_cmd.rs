//! `vicpilco recheck DIR...`: recorded arm runs' thesis claims judged again by this build's
//! checks, and rewritten in their summaries.

use anyhow::Context;
use std::path::PathBuf;
use vicpilco_experiments::recheck::recheck;
use vicpilco_experiments::summary::ThesisCheck;

#[derive(clap::Args)]
pub struct Args {
    /// Run directories (`vicpilco run`'s, or stored ones holding summary.json), all recorded
    /// with the same settings.
    #[arg(required = true)]
    dirs: Vec<PathBuf>,
    /// The runs' settings, if not the shipped ones of their experiment.
    #[arg(long, value_name = "FILE")]
    config: Option<PathBuf>,
    /// The runs were --quick ones.
    #[arg(long)]
    quick: bool,
    /// Print what would change, and write nothing.
    #[arg(long)]
    dry_run: bool,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    for dir in &args.dirs {
        let changes = recheck(dir, args.config.as_deref(), args.quick, args.dry_run)
            .with_context(|| format!("rechecking {}", dir.display()))?;
        if changes.is_empty() {
            println!("{}: current", dir.display());
            continue;
        }
        let verb = if args.dry_run {
            "would change"
        } else {
            "changed"
        };
        println!("{}: {} claim(s) {verb}", dir.display(), changes.len());
        for c in &changes {
            let reworded = match (&c.before, &c.after) {
                (Some(b), Some(a)) if b.measured == a.measured && b.pass == a.pass => {
                    " (its wording or acceptance rule only)"
                }
                _ => "",
            };
            println!(
                "  {}: {} -> {}{reworded}",
                c.id,
                judged(&c.before),
                judged(&c.after)
            );
        }
        if args.dry_run {
            continue;
        }
        // A run directory's report shows the claims too; a stored one (summary.json and
        // run.tar.xz only) cannot be redrawn without unpacking the run.
        if dir.join("rollouts.jsonl").exists() {
            vicpilco_report::write_report(dir)
                .with_context(|| format!("redrawing the report of {}", dir.display()))?;
        } else if dir.join("report.md").exists() {
            println!(
                "  report.md not redrawn: no rollouts.jsonl (unpack run.tar.xz and recheck there)"
            );
        }
    }
    Ok(())
}

/// A claim's judgement as the summary holds it: measured value and verdict.
fn judged(check: &Option<ThesisCheck>) -> String {
    match check {
        None => "(not made)".into(),
        Some(c) => format!(
            "{} ({})",
            c.measured,
            match c.pass {
                Some(true) => "pass",
                Some(false) => "fail",
                None => "undecided",
            }
        ),
    }
}
