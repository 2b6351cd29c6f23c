use crate::recorded::RecordedRun;
use anyhow::Context;
use std::path::PathBuf;
use vicpilco_experiments::evaluate::{evaluate, markdown_table, table_path, EvaluateOptions};

#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    run: RecordedRun,
    /// The run's settings, if not the shipped ones.
    #[arg(long, value_name = "FILE")]
    config: Option<PathBuf>,
    /// Updates whose policies to roll out, comma-separated (0: the untrained policy); default
    /// every update.
    #[arg(long, value_name = "LIST", value_delimiter = ',')]
    updates: Option<Vec<usize>>,
    /// Fresh starts per policy; default the config's `vilta.evaluation_starts` (20 for
    /// vilta-var).
    #[arg(long, value_name = "N")]
    starts: Option<usize>,
    /// JSON-lines file of the results, one line per update (must not exist); default
    /// runs/<name>-seed<S>-evaluate.jsonl. The printed table goes beside it, as FILE with the
    /// extension `md` (must not exist either).
    #[arg(long, value_name = "FILE")]
    out: Option<PathBuf>,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let run = args.run;
    let out = args.out.unwrap_or_else(|| run.default_out("evaluate"));
    let opts = EvaluateOptions {
        run: run.options(args.config, out.clone()),
        updates: args.updates,
        starts: args.starts,
    };
    let results =
        evaluate(&run.name, &opts).with_context(|| format!("evaluating {}", run.from.display()))?;
    print!("{}", markdown_table(&results));
    println!(
        "per start: {}; this table: {}",
        out.display(),
        table_path(&out).display()
    );
    Ok(())
}
