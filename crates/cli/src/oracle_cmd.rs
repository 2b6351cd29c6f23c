use anyhow::Context;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(clap::Args)]
pub struct Args {
    /// Directory holding the oracle case folders [default: `VICPILCO_ORACLE_DIR`, else
    /// ../shared/oracle beside the repository this binary was built from, as the tests read
    /// it].
    #[arg(long)]
    dir: Option<PathBuf>,
    /// Print `{"kinds": {"<kind>": {"cases", "passed", "max_rel_err"}}}` instead of a table.
    #[arg(long)]
    json: bool,
}

pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let dir = args.dir.unwrap_or_else(vicpilco_oracle::default_dir);
    let reports = vicpilco_oracle::check_dir(&dir)
        .with_context(|| format!("checking the oracle cases in {}", dir.display()))?;
    let failed = reports.values().any(|r| r.passed < r.cases && !r.skipped);
    if args.json {
        let kinds: serde_json::Map<String, serde_json::Value> = reports
            .iter()
            .map(|(kind, r)| {
                let mut v = serde_json::json!({
                    "cases": r.cases,
                    "passed": r.passed,
                    // JSON has no infinity: a case that could not be computed reports null.
                    "max_rel_err": if r.max_rel_err.is_finite() && !r.skipped { serde_json::json!(r.max_rel_err) } else { serde_json::Value::Null },
                });
                if r.skipped {
                    v["skipped"] = serde_json::Value::Bool(true);
                }
                (kind.clone(), v)
            })
            .collect();
        println!("{}", serde_json::json!({ "kinds": kinds }));
    } else {
        println!(
            "{:<10} {:>6} {:>7} {:>12}  status",
            "kind", "cases", "passed", "max_rel_err"
        );
        for (kind, r) in &reports {
            let status = if r.skipped {
                "skipped (not implemented yet)"
            } else if r.passed == r.cases {
                "ok"
            } else {
                "FAILED"
            };
            let err = if r.skipped {
                "-".to_string()
            } else {
                format!("{:.2e}", r.max_rel_err)
            };
            println!(
                "{kind:<10} {:>6} {:>7} {err:>12}  {status}",
                r.cases, r.passed
            );
        }
        for (kind, r) in &reports {
            for f in &r.failures {
                eprintln!("{kind}: {f}");
            }
        }
    }
    Ok(if failed {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    })
}
