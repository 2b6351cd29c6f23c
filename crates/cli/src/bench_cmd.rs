use anyhow::Context;
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
    /// Workload name (only `w1` exists).
    workload: String,
    /// Workload file [default: w1.json in `VICPILCO_BENCH_DIR`, else in ../shared/bench beside
    /// the repository this binary was built from, as `cargo bench` reads it].
    #[arg(long)]
    file: Option<PathBuf>,
    /// Timed repetitions after one warm-up call (the median is reported).
    #[arg(long, default_value_t = 5)]
    reps: usize,
    /// Print `{"forward_s", "value_grad_s", "train_s", "J", ...}`.
    #[arg(long)]
    json: bool,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    anyhow::ensure!(
        args.workload == "w1",
        "unknown workload `{}` (known: w1)",
        args.workload
    );
    let file = args
        .file
        .unwrap_or_else(|| vicpilco_bench::default_dir().join("w1.json"));
    let w1 = vicpilco_bench::W1::load(&file).context("loading the benchmark workload")?;
    let t = w1.time(args.reps).map_err(|e| anyhow::anyhow!("{e}"))?;
    if args.json {
        println!("{}", serde_json::to_string(&t)?);
    } else {
        println!(
            "workload W1 ({}), median of {} after a warm-up, {} threads",
            file.display(),
            t.repetitions,
            t.threads
        );
        println!(
            "  forward (J over H = {}):   {:.3} s",
            w1.horizon, t.forward_s
        );
        println!("  value + gradient:           {:.3} s", t.value_grad_s);
        println!("  train 6 GPs (hypCurb):      {:.3} s", t.train_s);
        println!("  J = {:.10} (reference 92.6720698716)", t.j);
        println!(
            "  |dJ/d(inputs, targets)| = {:.8} (reference 149.55171269)",
            t.grad_norm_inputs_targets
        );
        println!(
            "  trained nlml + hypCurb penalty per output: {:?}",
            t.train_nlml
                .iter()
                .map(|v| (v * 10.0).round() / 10.0)
                .collect::<Vec<_>>()
        );
        if let Some(m) = t.peak_memory_mb {
            println!("  peak memory: {m:.0} MB");
        }
    }
    Ok(())
}
