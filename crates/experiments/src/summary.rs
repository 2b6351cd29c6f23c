//! `summary.json`: what a run did, episode by episode.

use serde::Serialize;
use std::path::Path;
use vicpilco_learn::outer::EpisodeRecord;

/// The run summary written to `DIR/summary.json`.
#[derive(Clone, Debug, Serialize)]
pub struct Summary {
    pub experiment: String,
    pub seed: u64,
    pub policy: String,
    /// Learnable policy parameters.
    pub n_params: usize,
    pub episodes: Vec<EpisodeRecord>,
    /// The first policy update at which the success test had held for the last
    /// [`SOLVED_STREAK`] consecutive updates; `null` if never.
    pub solved_at_episode: Option<usize>,
    /// Cumulative system time of all roll-outs (initial ones included), seconds.
    pub interaction_s: f64,
    /// Wall time of the whole run, seconds.
    pub wall_s: f64,
    /// The settings the run used (every number, ours marked in the docs).
    pub config: serde_json::Value,
}

/// Consecutive successful updates that count as "solved".
pub const SOLVED_STREAK: usize = 3;

/// The update at which the last [`SOLVED_STREAK`] updates all succeeded, if any.
pub fn solved_at(episodes: &[EpisodeRecord]) -> Option<usize> {
    let mut streak = 0;
    for e in episodes {
        streak = if e.success { streak + 1 } else { 0 };
        if streak >= SOLVED_STREAK {
            return Some(e.index);
        }
    }
    None
}

#[derive(Debug, thiserror::Error)]
pub enum WriteError {
    #[error("{path}: {source}")]
    Io {
        path: String,
        source: std::io::Error,
    },
    #[error("{what} is {value}: refusing to write it as JSON null")]
    NonFinite { what: String, value: f64 },
    #[error("serialising {0}")]
    Json(#[from] serde_json::Error),
}

impl Summary {
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
    let io = |e: std::io::Error| WriteError::Io {
        path: path.display().to_string(),
        source: e,
    };
    let tmp = path.with_extension("json.tmp");
    std::fs::write(&tmp, serde_json::to_vec_pretty(value)?).map_err(io)?;
    std::fs::rename(&tmp, path).map_err(io)
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
            interaction_s: 4.0,
            train_s: 0.1,
            optimise_s: 1.0,
            evaluations: 10,
            line_searches: 5,
            termination: "test".into(),
            objective_start: 2.0,
            objective_end: 1.0,
            n_train: 40,
            sparse: false,
        }
    }

    #[test]
    fn solved_needs_three_consecutive_successes() {
        let flags = [false, true, true, false, true, true, true, true];
        let eps: Vec<_> = flags
            .iter()
            .enumerate()
            .map(|(i, &s)| ep(i + 1, s))
            .collect();
        assert_eq!(solved_at(&eps), Some(7));
        assert_eq!(solved_at(&eps[..6]), None);
    }

    #[test]
    fn non_finite_numbers_are_refused() {
        let mut e = ep(1, true);
        e.recorded_return = f64::NAN;
        let s = Summary {
            experiment: "x".into(),
            seed: 1,
            policy: "rbf".into(),
            n_params: 3,
            episodes: vec![e],
            solved_at_episode: None,
            interaction_s: 0.0,
            wall_s: 0.0,
            config: serde_json::Value::Null,
        };
        let dir = std::env::temp_dir();
        assert!(matches!(s.write(&dir), Err(WriteError::NonFinite { .. })));
    }
}
