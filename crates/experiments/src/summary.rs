//! `summary.json`: what a run did, episode by episode.

use serde::{Deserialize, Serialize};
use std::path::Path;
use vicpilco_learn::record::EpisodeRecord;

/// One policy update as `summary.json` lists it: the loop's record plus what the task adds.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct EpisodeSummary {
    /// The loop's record of the update (returns, success, timings, model); its fields sit
    /// directly in this JSON object.
    #[serde(flatten)]
    pub record: EpisodeRecord,
    /// `green`: every roll-out of the update succeeded, `yellow`: some, `red`: none (the
    /// thesis's Figs. 5-6, 5-7, 5-12).
    pub colour: String,
    /// Arm runs, first roll-out: x at the end (m); `null` for the classic benchmarks.
    pub final_x: Option<f64>,
    /// Arm runs, first roll-out: the largest contact force |f| over its steps (N)
    /// ([`crate::arm::largest_force`]).
    pub max_force: Option<f64>,
    /// Arm runs, first roll-out: the start's y (m), drawn from `start.y_range` when set.
    pub start_y: Option<f64>,
}

impl std::ops::Deref for EpisodeSummary {
    type Target = EpisodeRecord;
    fn deref(&self) -> &EpisodeRecord {
        &self.record
    }
}

impl EpisodeSummary {
    /// Every roll-out of the update succeeded: the thesis's "inserting" update, and the one
    /// rule the claims count by.
    pub fn all_inserted(&self) -> bool {
        all_succeeded(self.success_fraction)
    }
}

fn all_succeeded(success_fraction: f64) -> bool {
    success_fraction >= 1.0
}

/// The colour of an update with this fraction of successful roll-outs.
pub fn colour(success_fraction: f64) -> &'static str {
    if all_succeeded(success_fraction) {
        "green"
    } else if success_fraction > 0.0 {
        "yellow"
    } else {
        "red"
    }
}

/// One of the thesis's claims next to what the run measured.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ThesisCheck {
    /// Stable name of the claim, the same in every run that makes it (the text may be reworded).
    #[serde(default)]
    pub id: String,
    /// The claim as checked, with its bar, e.g. `mean recorded return over updates 6-10 <= 75`.
    pub claim: String,
    /// What the thesis reports.
    pub thesis: String,
    /// What the run measured for the claim, as text (`n.a.` while it lacks the updates).
    pub measured: String,
    /// `None` when the run is too short to decide.
    pub pass: Option<bool>,
    /// How the seeds' verdicts combine into the claim's acceptance verdict (issue 6).
    /// Summaries written before this field existed read as `None`.
    #[serde(default)]
    pub across_seeds: Option<SeedRule>,
}

/// How many of a configuration's acceptance runs (one per seed) must pass a claim: `passing`
/// of `seeds` (issue 6, "How it is checked"); `passing == seeds` for "every run".
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct SeedRule {
    /// How many of the runs must pass, at least.
    pub passing: usize,
    /// Acceptance runs the claim is judged over, one per seed: seeds 1 to `seeds` (issue 6:
    /// seeds 1–5). Runs on other seeds are shown beside them but not counted.
    pub seeds: usize,
}

/// One invocation of a run: the first, then one per `--resume`. Which build computed which
/// updates, since a resumed run may continue with newer code.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunSession {
    /// The first policy update this session computed (1 for a fresh run). Updates before the
    /// first listed session ran with a build that did not record sessions.
    pub first_update: usize,
    /// The commit the binary was built from ("+dirty": with uncommitted changes; "unknown":
    /// built outside git).
    pub commit: String,
    /// "flushed to zero" or "gradual underflow" ([`crate::subnormals`]).
    pub subnormals: String,
    /// Start of the session, seconds since the Unix epoch.
    pub started_unix_s: u64,
}

impl RunSession {
    /// This process, starting at `first_update`.
    pub fn here(first_update: usize) -> RunSession {
        RunSession {
            first_update,
            commit: BUILD_COMMIT.to_string(),
            subnormals: crate::subnormals::mode_here().to_string(),
            started_unix_s: std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map_or(0, |d| d.as_secs()),
        }
    }
}

/// The commit this crate was built from (see `build.rs`).
pub const BUILD_COMMIT: &str = env!("VICPILCO_BUILD_COMMIT");

/// `vicpilco --version`: the crate version and the commit.
pub const VERSION_TEXT: &str = concat!(
    env!("CARGO_PKG_VERSION"),
    " (commit ",
    env!("VICPILCO_BUILD_COMMIT"),
    ")"
);

/// The run summary written to `DIR/summary.json`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Summary {
    /// The experiment's name: the one an alias stands for ([`crate::config::canonical`]; runs
    /// made before 2026-12-07 and not continued since keep `vil-gic` as given).
    pub experiment: String,
    /// The run's master seed ([`crate::RunOptions::seed`]).
    pub seed: u64,
    /// Impedance law of arm runs (`gic`, `sic`); `null` otherwise.
    pub controller: Option<String>,
    /// The policy's structure, e.g. `rbf (10 basis functions, 4 inputs)` or `linear (4 inputs)`.
    pub policy: String,
    /// Learnable policy parameters.
    pub n_params: usize,
    /// Recorded return of the first initial (exploration) roll-out.
    pub initial_return: Option<f64>,
    /// One entry per completed policy update, in order (index 1 first).
    pub episodes: Vec<EpisodeSummary>,
    /// The first policy update at which the success test had held for the last
    /// [`SOLVED_STREAK`] consecutive updates; `null` if never.
    pub solved_at_episode: Option<usize>,
    /// The [`SOLVED_STREAK`] that `solved_at_episode` used, written so that a report can say
    /// what "solved" means; absent in summaries written before it was recorded (all used 3).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub solved_streak: Option<usize>,
    /// Cumulative system time of all roll-outs (initial ones included), seconds.
    pub interaction_s: f64,
    /// Wall time of the whole run, seconds.
    pub wall_s: f64,
    /// The settings the run used (every number, ours marked in the docs).
    pub config: serde_json::Value,
    /// The thesis's numbers for this experiment beside the run's.
    pub thesis_reference: Vec<ThesisCheck>,
    /// VIL runs: the recorded return of one roll-out with constant gains
    /// ([`crate::checks::CONSTANT_GAIN`]) on the same simulator.
    pub constant_gain_return: Option<f64>,
    /// Whether that constant-gain roll-out inserted (the success test of the learning runs).
    #[serde(default)]
    pub constant_gain_inserted: Option<bool>,
    /// Runs with evaluation starts: the final policy from fresh starts.
    pub final_eval: Option<FinalEval>,
    /// Arm runs: mean (k_x, k_y) of the last learned roll-out over its first and its last
    /// [`crate::checks::GAIN_WINDOW_S`] seconds.
    pub final_gains: Option<[[f64; 2]; 2]>,
    /// Arm runs: mean (k_x, k_y) of the last learned roll-out over the whole episode, the
    /// number the thesis compares between SIC and GIC (§5-4-2).
    #[serde(default)]
    pub final_mean_gains: Option<[f64; 2]>,
    /// Every invocation of the run, in order; empty in summaries written before this field.
    #[serde(default)]
    pub sessions: Vec<RunSession>,
    /// A run started with `--replay-from`: the recorded run its first updates are, and the
    /// replay's verdicts ([`crate::replay`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub replayed_from: Option<crate::replay::ReplaySource>,
}

/// The final policy from fresh starts (`final_eval.jsonl` holds the roll-outs).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FinalEval {
    /// Fresh starts the policy was rolled out from (`vilta.evaluation_starts`).
    pub starts: usize,
    /// Roll-outs that inserted ([`crate::arm::inserted`]).
    pub successes: usize,
    /// `successes / starts`, in [0, 1]; the claim `fresh_starts_insert` needs ≥ 0.8.
    pub fraction: f64,
    /// The update whose policy was evaluated (`vilta.final_policy`); absent in summaries
    /// written before the rule, which evaluated the last update's.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub update: Option<usize>,
}

/// Consecutive successful updates that count as "solved".
pub const SOLVED_STREAK: usize = 3;

/// The update at which the last [`SOLVED_STREAK`] updates all succeeded, if any.
pub fn solved_at<E: std::ops::Deref<Target = EpisodeRecord>>(episodes: &[E]) -> Option<usize> {
    let mut streak = 0;
    for e in episodes {
        streak = if e.success { streak + 1 } else { 0 };
        if streak >= SOLVED_STREAK {
            return Some(e.index);
        }
    }
    None
}

/// Why a JSON file of the run directory (`summary.json`, a checkpoint, a JSON line) was not
/// written.
#[derive(Debug, thiserror::Error)]
pub enum WriteError {
    /// The path only: the I/O error is the source, which `{:#}` prints after it.
    #[error("{path}")]
    Io {
        /// The file being written; the failed step may be on its `.json.tmp` sibling.
        path: String,
        /// The error of the failed create, write, sync or rename.
        source: std::io::Error,
    },
    /// A NaN or ±∞, which JSON cannot hold: refused rather than written as `null`.
    #[error("{what} is {value}: refusing to write it as JSON null")]
    NonFinite {
        /// Where the number is, e.g. `episode 3 recorded_return`.
        what: String,
        /// The offending value: NaN, +∞ or −∞.
        value: f64,
    },
    /// serde_json could not serialise the value.
    #[error("serialising {0}")]
    Json(#[from] serde_json::Error),
}

impl Summary {
    /// The summary of a run before its first update: what identifies it, nothing measured.
    pub fn new(
        experiment: &str,
        seed: u64,
        controller: Option<String>,
        policy: &str,
        n_params: usize,
        config: serde_json::Value,
    ) -> Summary {
        Summary {
            experiment: experiment.to_string(),
            seed,
            controller,
            policy: policy.to_string(),
            n_params,
            initial_return: None,
            episodes: Vec::new(),
            solved_at_episode: None,
            solved_streak: Some(SOLVED_STREAK),
            interaction_s: 0.0,
            wall_s: 0.0,
            config,
            thesis_reference: Vec::new(),
            constant_gain_return: None,
            constant_gain_inserted: None,
            final_eval: None,
            final_gains: None,
            final_mean_gains: None,
            sessions: Vec::new(),
            replayed_from: None,
        }
    }

    /// Recomputes `solved_at_episode` from the episodes, and records the streak it used.
    pub fn update_solved(&mut self) {
        self.solved_at_episode = solved_at(&self.episodes);
        self.solved_streak = Some(SOLVED_STREAK);
    }

    fn check_finite(&self) -> Result<(), WriteError> {
        let bad = |what: String, value: f64| Err(WriteError::NonFinite { what, value });
        for e in &self.episodes {
            for (name, v) in [
                ("predicted_return_mean", e.predicted_return_mean),
                ("predicted_return_std", e.predicted_return_std),
                ("recorded_return", e.recorded_return),
                ("objective_end", e.objective_end),
            ] {
                if !v.is_finite() {
                    return bad(format!("episode {} {name}", e.index), v);
                }
            }
        }
        Ok(())
    }

    /// Write `summary.json` atomically (temporary file, then rename).
    pub fn write(&self, dir: &Path) -> Result<(), WriteError> {
        self.check_finite()?;
        write_json_atomic(&dir.join("summary.json"), &serde_json::to_value(self)?)
    }
}

/// Write pretty JSON to `path` through a temporary file in the same directory and a rename,
/// so an interrupted write never leaves a truncated file.
pub fn write_json_atomic(path: &Path, value: &serde_json::Value) -> Result<(), WriteError> {
    let bytes = serde_json::to_vec_pretty(value)?;
    vicpilco_report::atomic::write_atomic(path, &bytes).map_err(|e| WriteError::Io {
        path: path.display().to_string(),
        source: e,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ep(index: usize, success: bool) -> EpisodeRecord {
        EpisodeRecord {
            index,
            predicted_return_mean: 1.0,
            predicted_return_std: 0.1,
            recorded_return: 1.0,
            success,
            rollouts: 1,
            success_fraction: if success { 1.0 } else { 0.0 },
            interaction_s: 4.0,
            train_s: 0.1,
            optimise_s: 1.0,
            evaluations: 10,
            line_searches: 5,
            slope_capped: None,
            termination: "test".into(),
            objective_start: 2.0,
            objective_end: 1.0,
            n_train: 40,
            sparse: false,
            cold_restarts: 0,
            model_selection: None,
        }
    }

    #[test]
    fn solved_needs_three_consecutive_successes() {
        let flags = [false, true, true, false, true, true, true, true];
        let eps: Vec<_> = flags
            .iter()
            .enumerate()
            .map(|(i, &s)| Box::new(ep(i + 1, s)))
            .collect();
        assert_eq!(solved_at(&eps), Some(7));
        assert_eq!(solved_at(&eps[..6]), None);
    }

    #[test]
    fn non_finite_numbers_are_refused() {
        let mut e = ep(1, true);
        e.recorded_return = f64::NAN;
        let s = Summary {
            episodes: vec![EpisodeSummary {
                record: e,
                colour: "green".into(),
                final_x: None,
                max_force: None,
                start_y: None,
            }],
            ..Summary::new("x", 1, None, "rbf", 3, serde_json::Value::Null)
        };
        let dir = std::env::temp_dir();
        assert!(matches!(s.write(&dir), Err(WriteError::NonFinite { .. })));
    }
}
