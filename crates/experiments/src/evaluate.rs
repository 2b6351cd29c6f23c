//! `vicpilco evaluate`: any update's policy of a recorded arm run, rolled out from fresh starts.
//!
//! The acceptance claims judge the final policy only, but a run's `policies.jsonl` keeps every
//! update's policy. Rolling each one out from the final evaluation's starts (the same starts
//! and noise for every policy, [`checks::fresh_start_rollouts`]) shows when a run found a
//! policy that generalises over the start interval and whether it kept it: the thesis says of
//! `vilta-var` that the hole is found "over the whole interval after 10 iterations" (§5-5-1),
//! while the claim is on the policy after 15.

use crate::checks;
use crate::config::{ArmExperiment, PolicyKind};
use crate::record::read_checkpoint;
use crate::{
    arm, arm_identity, recorded_arm_config, subnormals, ExperimentError, RecordedRunOptions,
};
use serde::{Deserialize, Serialize};
use vicpilco_env::Environment;
use vicpilco_learn::outer::LoopSetup;
use vicpilco_pilco::policy::Policy;

/// What `vicpilco evaluate` reads and writes.
#[derive(Clone, Debug)]
pub struct EvaluateOptions {
    /// The recorded run (the starts are drawn from its seed, as the final evaluation's are),
    /// its settings, which must be the run's, and the JSON-lines file of the results, one
    /// line per update.
    pub run: RecordedRunOptions,
    /// The updates whose policies to evaluate (0: the untrained policy); `None`: every one.
    pub updates: Option<Vec<usize>>,
    /// Fresh starts per policy; `None`: the config's `vilta.evaluation_starts`.
    pub starts: Option<usize>,
}

/// One fresh start's roll-out, summarised.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StartOutcome {
    /// The start's y (m), drawn from `start.y_range` (the config's start y without one).
    pub start_y: f64,
    /// The success test of the acceptance claims ([`arm::inserted`]).
    pub success: bool,
    /// The return the run would have recorded for this roll-out.
    pub recorded_return: f64,
    /// Where the peg ended (x, y) (m).
    pub final_position: [f64; 2],
    /// The largest contact force of the roll-out (N), as `summary.json`'s `max_force`.
    pub max_force: f64,
    /// Why the system ended the roll-out early, if it did.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stopped_early: Option<String>,
}

/// One update's policy from every fresh start.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct UpdateEvaluation {
    /// The update whose policy this is (0: the untrained policy).
    pub update: usize,
    /// Starts whose roll-out inserted.
    pub successes: usize,
    /// `successes` over the number of starts, in [0, 1].
    pub fraction: f64,
    /// Every start's outcome, in the same order (and with the same starts) for every update.
    pub starts: Vec<StartOutcome>,
}

/// Evaluate the chosen updates' policies of the recorded run `opts.run.from` of experiment `name`
/// from fresh starts; write one JSON line per update to `opts.run.out` as each is done, then
/// [`markdown_table`] of them to [`table_path`], and return them. The run's settings must
/// equal the config's (all but the number of updates), so the starts, the simulator and the
/// success test are the run's own; the line of the update whose policy the run handed over
/// (`final_eval.update` in its summary: the last one, or under `vilta.final_policy =
/// "most-successful"` the kept one) then repeats the run's `final_eval.jsonl`.
pub fn evaluate(
    name: &str,
    opts: &EvaluateOptions,
) -> Result<Vec<UpdateEvaluation>, ExperimentError> {
    let name = crate::config::canonical(name);
    let cfg = recorded_arm_config(name, opts.run.config.as_deref(), opts.run.quick, "evaluate")?;
    let bad = |message: String| ExperimentError::Evaluate {
        path: opts.run.from.clone(),
        message,
    };
    let n = match opts.starts {
        Some(0) => {
            return Err(bad(
                "--starts 0 leaves nothing to roll out: give N ≥ 1".into()
            ))
        }
        Some(n) => n,
        None => cfg
            .vilta
            .as_ref()
            .map(|v| v.evaluation_starts)
            .filter(|&n| n > 0)
            .ok_or_else(|| {
                bad(format!(
                    "`{name}` has no evaluation starts: give their number (--starts N)"
                ))
            })?,
    };
    let checkpoint = read_checkpoint(&opts.run.from, name, opts.run.seed, &arm_identity(&cfg)?)?;
    let completed = checkpoint.state.completed;
    let updates = match &opts.updates {
        None => (0..=completed).collect(),
        Some(u) => u.clone(),
    };
    if let Some(&u) = updates.iter().find(|&&u| u > completed) {
        return Err(ExperimentError::Evaluate {
            path: opts.run.from.clone(),
            message: format!("the run has updates 0 to {completed}, not update {u}"),
        });
    }
    // A missing or unreadable policy is this command's failure, not a replay's.
    let policies =
        crate::replay::read_policies(&opts.run.from, completed).map_err(|e| match e {
            ExperimentError::Replay { path, message } => {
                ExperimentError::Evaluate { path, message }
            }
            e => e,
        })?;
    let chosen: Vec<(usize, &[f64])> = updates.iter().map(|&u| (u, &policies[u][..])).collect();
    subnormals::run_flushed(|| match cfg.policy.kind {
        PolicyKind::Rbf => {
            let policy = arm::rbf_policy(&cfg, opts.run.seed)?;
            each_update(&cfg, policy, &chosen, n, opts)
        }
        PolicyKind::Linear => {
            let policy = arm::linear_policy(&cfg, opts.run.seed)?;
            each_update(&cfg, policy, &chosen, n, opts)
        }
    })
}

fn each_update<P: Policy + Clone + Sync>(
    cfg: &ArmExperiment,
    policy: P,
    chosen: &[(usize, &[f64])],
    n: usize,
    opts: &EvaluateOptions,
) -> Result<Vec<UpdateEvaluation>, ExperimentError> {
    use std::io::Write;
    let (setup, mut env) = arm::setup(cfg, policy, opts.run.seed)?;
    // Both paths are checked before the first roll-out, so an existing table fails at once
    // rather than after minutes of roll-outs. The table itself is created only once every
    // update is done, so an evaluation that fails part-way leaves its JSON lines and no
    // empty table beside them.
    let table_path = table_path(&opts.run.out);
    if let Some(taken) = [&opts.run.out, &table_path]
        .into_iter()
        .find(|p| p.exists())
    {
        return Err(crate::record::already_exists(taken));
    }
    let mut file = crate::record::create_new(&opts.run.out)?;
    let mut policy = setup.policy.clone();
    let mut results = Vec::with_capacity(chosen.len());
    for &(update, params) in chosen {
        policy.set_params(params)?;
        let result = evaluate_policy(&setup, &mut env, &policy, update, n, opts.run.seed)?;
        let line = serde_json::to_string(&result).map_err(|e| ExperimentError::Write(e.into()))?;
        writeln!(file, "{line}").map_err(|e| ExperimentError::Io {
            path: opts.run.out.clone(),
            source: e,
        })?;
        results.push(result);
    }
    crate::record::create_new(&table_path)?
        .write_all(markdown_table(&results).as_bytes())
        .map_err(|e| ExperimentError::Io {
            path: table_path,
            source: e,
        })?;
    Ok(results)
}

/// Where [`evaluate`] writes its table: the JSON-lines path with the extension `md`.
pub fn table_path(jsonl: &std::path::Path) -> std::path::PathBuf {
    jsonl.with_extension("md")
}

/// One row per update: how many starts insert, the mean recorded return, and the start
/// positions y0 of the starts that fail.
pub fn markdown_table(results: &[UpdateEvaluation]) -> String {
    let mut table = String::from(
        "| update | inserted | mean return | starts that fail (y0, m) |\n|---|---|---|---|\n",
    );
    for u in results {
        let n = u.starts.len();
        let mean = u.starts.iter().map(|s| s.recorded_return).sum::<f64>() / n as f64;
        let failing: Vec<String> = u
            .starts
            .iter()
            .filter(|s| !s.success)
            .map(|s| format!("{:.3}", s.start_y))
            .collect();
        let failing = if failing.len() == n {
            "all".to_string()
        } else if failing.is_empty() {
            "none".to_string()
        } else {
            failing.join(", ")
        };
        table.push_str(&format!(
            "| {} | {} of {n} | {mean:.1} | {failing} |\n",
            u.update, u.successes
        ));
    }
    table
}

fn evaluate_policy<P: Policy + Clone + Sync>(
    setup: &LoopSetup<P>,
    env: &mut dyn Environment,
    policy: &P,
    update: usize,
    n: usize,
    seed: u64,
) -> Result<UpdateEvaluation, ExperimentError> {
    let starts: Vec<StartOutcome> = checks::fresh_start_rollouts(setup, env, policy, seed, n)?
        .into_iter()
        .map(|(start_y, r)| {
            let last = r.true_states.last().map_or([f64::NAN; 2], |s| [s[0], s[1]]);
            StartOutcome {
                start_y,
                success: arm::inserted(&r),
                recorded_return: setup.recorded_return(&r),
                final_position: last,
                max_force: arm::largest_force(&r),
                stopped_early: r.infos.iter().find_map(|i| i.stopped_early.clone()),
            }
        })
        .collect();
    let successes = starts.iter().filter(|s| s.success).count();
    Ok(UpdateEvaluation {
        update,
        successes,
        fraction: successes as f64 / n as f64,
        starts,
    })
}
