use anyhow::Context;
use std::path::PathBuf;
use vicpilco_learn::selection::ModelSelection;

#[derive(clap::Args)]
pub struct Args {
    /// The recorded run's experiment (as given to `vicpilco run`).
    name: String,
    /// The recorded run's seed.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// The recorded run's directory (read only).
    #[arg(long, value_name = "DIR")]
    from: PathBuf,
    /// The run's settings, if not the shipped ones (its gp.model_selection may differ from the
    /// run's: that rule is reported as `other`).
    #[arg(long, value_name = "FILE")]
    config: Option<PathBuf>,
    /// JSON-lines file of the verdicts, one line per update (must not exist); default
    /// runs/<name>-seed<S>-rescore.jsonl.
    #[arg(long, value_name = "FILE")]
    out: Option<PathBuf>,
    /// The recorded run was a --quick one.
    #[arg(long)]
    quick: bool,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let out = args.out.unwrap_or_else(|| {
        PathBuf::from(format!(
            "runs/{}-seed{}-rescore.jsonl",
            args.name, args.seed
        ))
    });
    let opts = vicpilco_experiments::RescoreOptions {
        seed: args.seed,
        from: args.from.clone(),
        config: args.config,
        out: out.clone(),
        quick: args.quick,
    };
    let updates = vicpilco_experiments::rescore(&args.name, &opts)
        .with_context(|| format!("rescoring {}", args.from.display()))?;
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
