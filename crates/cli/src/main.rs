//! `vicpilco`: the command-line edge. Library crates return typed errors; this file turns them
//! into messages and exit codes.

// The argument structs' doc comments are the terminal's `--help` text, where placeholders such
// as `runs/<name>-seed<S>` read as written; rustdoc would take them for HTML tags.
#![allow(rustdoc::invalid_html_tags)]

mod acceptance_cmd;
mod bench_cmd;
#[cfg(test)]
mod doc_commands;
mod evaluate_cmd;
mod oracle_cmd;
mod recheck_cmd;
mod recorded;
mod report_cmd;
mod rescore_cmd;
mod run_cmd;
mod sim_cmd;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "vicpilco",
    version = vicpilco_experiments::summary::VERSION_TEXT,
    about = "Learn variable impedance control from a handful of trials (PILCO with GP dynamics models)"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run a learning experiment: PILCO's pendulum or cart-pole swing-up, or one of the
    /// thesis's peg-in-hole experiments (VIL with GIC or SIC, VILTA).
    ///
    /// Random initial roll-out(s), then per policy update: train the GP dynamics model, optimise
    /// the policy on the predicted return, roll it out. Keeps DIR current after every update:
    /// summary.json (per update: predicted and recorded return, success, interaction, training
    /// and optimisation time; the thesis's numbers beside the run's), rollouts.jsonl,
    /// predictions.jsonl and policies.jsonl (every roll-out, long-term prediction and policy,
    /// appended as recorded), checkpoint.json (for --resume), and the plots, report.html and
    /// report.md. When the run ends it adds policy.json (the last update's policy and dynamics
    /// hyper-parameters; under vilta.final_policy = "most-successful" the policy handed over is
    /// policies.jsonl's line of summary.json's final_eval.update).
    Run(run_cmd::Args),
    /// Check vicpilco's maths against reference values from the original PILCO MATLAB code.
    ///
    /// Loads every case file under DIR (one folder per kind: gp0, gp1, ...), recomputes each
    /// with vicpilco, and prints one row per kind: cases, cases passed, largest relative error.
    /// Kinds vicpilco cannot compute yet are listed as skipped. Exits non-zero if any case fails.
    Oracle(oracle_cmd::Args),
    /// Time a fixed benchmark workload (../shared/bench): forward prediction of the expected
    /// return, value + gradient w.r.t. every policy parameter, and GP training.
    ///
    /// Prints medians over repetitions after a warm-up, the return J (which must equal the
    /// workload's reference), and with --json `{"forward_s", "value_grad_s", "train_s", "J"}`
    /// so other PILCO implementations can be timed side by side on the same numbers.
    Bench(bench_cmd::Args),
    /// Simulate one 10 s peg-in-hole episode of the planar 3-DOF arm under impedance control.
    ///
    /// The arm follows the thesis's min-jerk plan (approach the wall, slide to the hole, insert)
    /// with the given stiffness per 0.1 s step. Writes trace.csv (per control tick), steps.csv
    /// (per step), summary.json (inserted, final x, max |f|, wall time, real-time factor) and
    /// plot.png into DIR.
    Sim(sim_cmd::Args),
    /// Plot a run directory and write a self-contained HTML report (and its tables as Markdown).
    ///
    /// Writes returns, policy, prediction_first/_last, cost_first/_last and, for arm runs,
    /// paths and final_eval as PNG and SVG, report.html (settings, per-update results, the
    /// thesis comparison, totals, every plot inlined) and report.md (its tables as Markdown).
    /// Missing optional files or fields skip a plot with a note instead of failing.
    Report(report_cmd::Args),
    /// Issue 6's acceptance table: each thesis claim over the seeds given, and its verdict.
    ///
    /// Reads DIR/summary.json of every run (one per experiment and seed), lists per experiment
    /// each claim's measured value and pass/fail per seed, how many seeds pass and the verdict
    /// under the claim's rule (3 of 5 seeds, or every run, over seeds 1–5; runs on other seeds
    /// are shown and counted apart, never in the verdict). vil-sic's "mean k_y above GIC's" is
    /// decided against a vil-gic run of the same seed when one is given.
    Acceptance(acceptance_cmd::Args),
    /// Score a recorded arm run's model choices under every model-selection rule.
    ///
    /// Replays the run's model fits update by update along its own choices (no policy
    /// optimisation; it checks that every replayed score equals the recorded one) and writes,
    /// per update with a choice, each rule's scores of the refit and of the previous
    /// hyper-parameters and its choice, as JSON lines. Prints, per rule, the updates where it
    /// chooses otherwise. Past a rule's first such update, its verdicts are on the recorded
    /// models, not on those of its own run (`vicpilco run --replay-from` makes that run).
    Rescore(rescore_cmd::Args),
    /// Roll out any update's policy of a recorded arm run from fresh starts.
    ///
    /// Reads the run's policies.jsonl and rolls each chosen update's policy out from the final
    /// evaluation's starts (the same starts and sensor noise for every policy; the results of
    /// the update whose policy the run handed over, final_eval.jsonl's, repeat that file).
    /// Writes one JSON line per update
    /// (each start's y, success, return, end position, largest force) and prints how many
    /// starts insert per update.
    Evaluate(evaluate_cmd::Args),
    /// Judge recorded arm runs' thesis claims again with this build's checks.
    ///
    /// A summary keeps the claims as judged when its run ended; after a check's rule or
    /// wording changes, stored runs keep the old judgement, which `acceptance` tables. This
    /// judges each run again from its summary's per-update records and final evaluation
    /// (nothing is rolled out or refitted), after checking that the settings given are the
    /// run's, and rewrites only `thesis_reference` (and the report, in a full run directory).
    /// Prints each claim that changes.
    Recheck(recheck_cmd::Args),
}

fn main() -> ExitCode {
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env()
                .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("warn")),
        )
        .with_writer(std::io::stderr)
        .init();
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Run(args) => run_cmd::run(args).map(|()| ExitCode::SUCCESS),
        Command::Oracle(args) => oracle_cmd::run(args),
        Command::Bench(args) => bench_cmd::run(args).map(|()| ExitCode::SUCCESS),
        Command::Sim(args) => sim_cmd::run(args),
        Command::Report(args) => report_cmd::run(args).map(|()| ExitCode::SUCCESS),
        Command::Acceptance(args) => acceptance_cmd::run(args).map(|()| ExitCode::SUCCESS),
        Command::Rescore(args) => rescore_cmd::run(args).map(|()| ExitCode::SUCCESS),
        Command::Evaluate(args) => evaluate_cmd::run(args).map(|()| ExitCode::SUCCESS),
        Command::Recheck(args) => recheck_cmd::run(args).map(|()| ExitCode::SUCCESS),
    };
    match result {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::from(2)
        }
    }
}
