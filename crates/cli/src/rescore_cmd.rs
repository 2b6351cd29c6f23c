use crate::recorded::RecordedRun;
use anyhow::Context;
use std::path::PathBuf;
use vicpilco_learn::selection::ModelSelection;

#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    run: RecordedRun,
    /// The run's settings, if not the shipped ones (its gp.model_selection may differ from the
    /// run's: that rule is reported as `other`).
    #[arg(long, value_name = "FILE")]
    config: Option<PathBuf>,
    /// JSON-lines file of the verdicts, one line per update (must not exist); default
    /// runs/<name>-seed<S>-rescore.jsonl.
    #[arg(long, value_name = "FILE")]
    out: Option<PathBuf>,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let run = args.run;
    let out = args.out.unwrap_or_else(|| run.default_out("rescore"));
    let opts = run.options(args.config, out.clone());
    let updates = vicpilco_experiments::rescore(&run.name, &opts)
        .with_context(|| format!("rescoring {}", run.from.display()))?;
    println!("rule: updates where it chooses otherwise than the recorded run");
    for rule in ModelSelection::COMPARING {
        let parting: Vec<String> = updates
            .iter()
            .filter(|u| {
                u.every_rule
                    .iter()
                    .any(|v| v.rule == rule && v.choice.kept_previous != u.recorded.kept_previous)
            })
            .map(|u| u.update.to_string())
            .collect();
        println!(
            "  {rule}: {}",
            if parting.is_empty() {
                "none".to_string()
            } else {
                parting.join(", ")
            }
        );
    }
    println!("verdicts: {}", out.display());
    Ok(())
}
