//! Starting a run from a recorded run of another model-selection rule (`vicpilco run
//! --replay-from DIR`): the recorded run's updates stand for as long as this run's rule
//! chooses the same models ([`vicpilco_learn::replay`]), and the run continues from the first
//! update where the rules part, as if it had run from the start.

use crate::record::{lock_run_dir, refuse_recorded_run, PER_UPDATE_FILES};
use crate::record::{Checkpoint, CHECKPOINT_FORMAT};
use crate::summary::write_json_atomic;
use crate::ExperimentError;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use vicpilco_learn::data::Rollout;
use vicpilco_learn::outer::LoopSetup;
use vicpilco_learn::replay::ReplayedUpdate;
use vicpilco_learn::selection::ModelSelection;
use vicpilco_pilco::policy::Policy;

/// Where a run's first updates came from, in its `summary.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ReplaySource {
    /// The recorded run directory, as given on the machine that replayed it.
    pub run: String,
    /// The recorded run's return at each of its updates: what identifies it on another
    /// machine (against `results/*/summary.json`), where `run` names nothing.
    #[serde(default)]
    pub recorded_returns: Vec<f64>,
    /// Its model-selection rule.
    pub recorded_rule: ModelSelection,
    /// Its updates.
    pub recorded_updates: usize,
    /// Updates 1..=`agreed` are the recorded run's (this run's rule chooses alike on them).
    pub agreed: usize,
    /// Both rules' scores of every replayed update with a choice, the parting one last.
    pub updates: Vec<ReplayedUpdate>,
}

/// Replay the run in `source` under `setup` (this run's settings; `identity` as a checkpoint
/// holds them), write `out`'s checkpoint after the last update both rules agree on and its
/// per-update files (the caller's resume drops their lines after it), and return that
/// checkpoint. The source run must be of the same experiment and seed, with the same settings
/// but `gp.model_selection` (and the number of updates); `out` must not hold a run yet
/// ([`ExperimentError::RunExists`]). When `out` does not exist yet, graft makes it and returns
/// its lock too (on [`crate::record::LOCK_FILE`]), taken before anything is written into it,
/// for the caller to hold for the run (an existing `out` was locked by the caller).
pub fn graft<P>(
    source: &Path,
    experiment: &str,
    seed: u64,
    identity: &serde_json::Value,
    setup: &LoopSetup<P>,
    out: &Path,
    dt: f64,
) -> Result<(Checkpoint, Option<std::fs::File>), ExperimentError>
where
    P: Policy + Clone + Sync,
    P::Cache: Send,
{
    refuse_recorded_run(out)?;
    let (recorded, recorded_rule, policies) = open_source(source, experiment, seed, identity)?;
    let replay = setup
        .replay_selection(
            recorded_rule,
            &recorded.state,
            &policies,
            &mut |u: &ReplayedUpdate| {
                eprintln!(
                    "replayed update {:>2}: recorded rule {} ({:.1} vs {:.1}), this rule {} ({:.1} vs {:.1})",
                    u.update,
                    choice(u.recorded.kept_previous),
                    u.recorded.previous_score,
                    u.recorded.refit_score,
                    choice(u.other.kept_previous),
                    u.other.previous_score,
                    u.other.refit_score
                )
            },
        )
        .map_err(ExperimentError::from)?;
    // A second lock on the directory from this process would find it busy (locks belong to
    // open files), so only a directory made here is locked here.
    let made_here = !out.is_dir();
    std::fs::create_dir_all(out).map_err(|e| ExperimentError::Io {
        path: out.to_path_buf(),
        source: e,
    })?;
    let lock = made_here.then(|| lock_run_dir(out)).transpose()?;
    for file in PER_UPDATE_FILES {
        let from = source.join(file);
        std::fs::copy(&from, out.join(file)).map_err(|e| ExperimentError::Io {
            path: from,
            source: e,
        })?;
    }
    let agreed = replay.agreed;
    let mut summary = recorded.summary;
    // A run recorded under an alias continues under the name it stands for.
    summary.experiment = experiment.to_string();
    let recorded_returns = summary
        .episodes
        .iter()
        .map(|e| e.record.recorded_return)
        .collect();
    summary.episodes.truncate(agreed);
    for (e, record) in summary.episodes.iter_mut().zip(&replay.state.episodes) {
        e.record = record.clone();
    }
    summary.update_solved();
    summary.interaction_s = interaction_upto(source, agreed, dt)?;
    // The recorded run's time for the updates kept; this run's own sessions add theirs.
    summary.wall_s = summary
        .episodes
        .iter()
        .map(|e| e.record.train_s + e.record.optimise_s)
        .sum();
    let last = replay.state.data.last().filter(|_| agreed > 0);
    summary.final_gains = last.map(|r| crate::checks::gains_first_last(r, dt));
    summary.final_mean_gains = last.map(|r| crate::checks::mean_gains(&r.actions));
    summary.thesis_reference = Vec::new();
    summary.constant_gain_return = None;
    summary.constant_gain_inserted = None;
    summary.final_eval = None;
    summary.sessions.retain(|s| s.first_update <= agreed);
    summary.replayed_from = Some(ReplaySource {
        run: source.display().to_string(),
        recorded_returns,
        recorded_rule,
        recorded_updates: recorded.state.completed,
        agreed,
        updates: replay.updates,
    });
    let checkpoint = Checkpoint {
        format: CHECKPOINT_FORMAT,
        experiment: experiment.to_string(),
        seed,
        identity: identity.clone(),
        summary,
        state: replay.state,
    };
    let value = serde_json::to_value(&checkpoint).map_err(|e| ExperimentError::Write(e.into()))?;
    write_json_atomic(&out.join("checkpoint.json"), &value)?;
    Ok((checkpoint, lock))
}

/// The recorded run in `source`, checked to be of `experiment` and `seed` with `identity`'s
/// settings but `gp.model_selection`: its final checkpoint, its rule and its policies.
fn open_source(
    source: &Path,
    experiment: &str,
    seed: u64,
    identity: &serde_json::Value,
) -> Result<(Checkpoint, ModelSelection, Vec<Vec<f64>>), ExperimentError> {
    let bad = |message: String| ExperimentError::Replay {
        path: source.join("checkpoint.json"),
        message,
    };
    let recorded = crate::record::read_checkpoint_unchecked(source)?;
    let same_experiment =
        crate::config::canonical(&recorded.experiment) == crate::config::canonical(experiment);
    if !same_experiment || recorded.seed != seed {
        return Err(bad(format!(
            "a run of `{}` with seed {}, not `{experiment}` with seed {seed}",
            recorded.experiment, recorded.seed
        )));
    }
    let rule_of = |identity: &serde_json::Value| {
        serde_json::from_value::<ModelSelection>(identity["gp"]["model_selection"].clone())
            .map_err(|e| bad(format!("gp.model_selection: {e}")))
    };
    let recorded_rule = rule_of(&recorded.identity)?;
    let (mut a, mut b) = (recorded.identity.clone(), identity.clone());
    a["gp"]["model_selection"] = serde_json::Value::Null;
    b["gp"]["model_selection"] = serde_json::Value::Null;
    if let Some(diff) = vicpilco_report::difference::first_difference(&a, &b, String::new()) {
        return Err(bad(format!(
            "written with different settings: {diff} (only gp.model_selection may{})",
            diff.quick_hint("is replayed")
        )));
    }
    let policies = read_policies(source, recorded.state.completed)?;
    Ok((recorded, recorded_rule, policies))
}

/// Replay the recorded run in `source` (as [`graft`] does) through all its updates along its
/// own choices, append every comparing rule's verdict at each update with a choice to `out`
/// as a JSON line ([`ReplayedUpdate`]) as soon as it is known, and return them. `setup`'s own
/// rule is reported as `other`. Refuses to overwrite `out`.
pub fn rescore<P>(
    source: &Path,
    experiment: &str,
    seed: u64,
    identity: &serde_json::Value,
    setup: &LoopSetup<P>,
    out: &Path,
) -> Result<Vec<ReplayedUpdate>, ExperimentError>
where
    P: Policy + Clone + Sync,
    P::Cache: Send,
{
    use std::io::Write;
    let (recorded, recorded_rule, policies) = open_source(source, experiment, seed, identity)?;
    let io_err = |e: std::io::Error| ExperimentError::Io {
        path: out.to_path_buf(),
        source: e,
    };
    let mut file = crate::record::create_new(out)?;
    let mut written: Result<(), ExperimentError> = Ok(());
    let updates = setup
        .rescore_run(
            recorded_rule,
            &recorded.state,
            &policies,
            &mut |u: &ReplayedUpdate| {
                let verdicts: Vec<String> = u
                    .every_rule
                    .iter()
                    .map(|v| {
                        let margin = v.choice.previous_score - v.choice.refit_score;
                        format!(
                            "{} {} ({margin:+.1})",
                            v.rule,
                            choice(v.choice.kept_previous)
                        )
                    })
                    .collect();
                eprintln!(
                    "update {:>2}: recorded {}; {}",
                    u.update,
                    choice(u.recorded.kept_previous),
                    verdicts.join(", ")
                );
                written = serde_json::to_string(u)
                    .map_err(|e| ExperimentError::Write(e.into()))
                    .and_then(|line| writeln!(file, "{line}").map_err(io_err));
                written.is_ok()
            },
        )
        .map_err(ExperimentError::from)?;
    written?;
    Ok(updates)
}

fn choice(kept_previous: bool) -> &'static str {
    if kept_previous {
        "keeps"
    } else {
        "refits"
    }
}

/// `policies.jsonl`'s parameters of updates 0..=`completed`, in order.
pub(crate) fn read_policies(
    dir: &Path,
    completed: usize,
) -> Result<Vec<Vec<f64>>, ExperimentError> {
    let path = dir.join("policies.jsonl");
    let mut policies: Vec<Option<Vec<f64>>> = vec![None; completed + 1];
    for (i, line) in read_lines(&path)?.iter().enumerate() {
        #[derive(Deserialize)]
        struct Line {
            episode: usize,
            params: Vec<f64>,
        }
        let l: Line = serde_json::from_str(line).map_err(|e| source_err(&path, i, e))?;
        if let Some(slot) = policies.get_mut(l.episode) {
            *slot = Some(l.params);
        }
    }
    policies
        .into_iter()
        .enumerate()
        .map(|(u, p)| {
            p.ok_or_else(|| ExperimentError::Replay {
                path: path.clone(),
                message: format!("no policy of update {u}"),
            })
        })
        .collect()
}

/// System time of the roll-outs in `rollouts.jsonl` up to update `upto`.
fn interaction_upto(dir: &Path, upto: usize, dt: f64) -> Result<f64, ExperimentError> {
    let path = dir.join("rollouts.jsonl");
    let mut total = 0.0;
    for (i, line) in read_lines(&path)?.iter().enumerate() {
        #[derive(Deserialize)]
        struct Line {
            episode: usize,
            rollout: Rollout,
        }
        let l: Line = serde_json::from_str(line).map_err(|e| source_err(&path, i, e))?;
        if l.episode <= upto {
            total += l.rollout.len() as f64 * dt;
        }
    }
    Ok(total)
}

fn read_lines(path: &PathBuf) -> Result<Vec<String>, ExperimentError> {
    let text = std::fs::read_to_string(path).map_err(|e| ExperimentError::Io {
        path: path.clone(),
        source: e,
    })?;
    Ok(text
        .lines()
        .filter(|l| !l.trim().is_empty())
        .map(str::to_string)
        .collect())
}

fn source_err(path: &Path, line: usize, e: serde_json::Error) -> ExperimentError {
    ExperimentError::Replay {
        path: path.to_path_buf(),
        message: format!("line {}: {e}", line + 1),
    }
}
