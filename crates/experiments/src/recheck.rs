//! `vicpilco recheck`: a recorded arm run's thesis claims judged again by this build's checks.
//!
//! `summary.json` keeps the claims ([`Summary::thesis_reference`]) as judged when the run
//! ended. When a check's rule or wording changes afterwards (the vilta insertion claims came to
//! say "never" for a complete run, where earlier builds wrote "not yet"), stored runs keep the
//! old judgement and `vicpilco acceptance` tables it. This judges them again from the summary's
//! own per-update records and final evaluation: nothing is rolled out or refitted, and only
//! `thesis_reference` is rewritten; every recorded number stays as it was.

use crate::checks;
use crate::summary::{write_json_atomic, Summary, ThesisCheck};
use crate::summary_config::arm_settings;
use crate::{arm_identity, recorded_arm_config, ExperimentError};
use std::path::Path;
use vicpilco_report::difference::first_difference;

/// One claim whose judgement this build changes.
#[derive(Clone, Debug, PartialEq)]
pub struct ClaimChange {
    /// The claim's stable id.
    pub id: String,
    /// As stored (`None`: the stored summary does not make this claim).
    pub before: Option<ThesisCheck>,
    /// As this build judges it (`None`: this build no longer makes it).
    pub after: Option<ThesisCheck>,
}

/// Judge the run in `dir` again under its settings (`config`, or the shipped ones of the
/// summary's experiment; `quick` for a `--quick` run) and, unless `dry_run`, rewrite
/// `thesis_reference` in its `summary.json`. Returns the claims whose judgement changes (none
/// when the stored one is current); the file is left untouched when there are none.
pub fn recheck(
    dir: &Path,
    config: Option<&Path>,
    quick: bool,
    dry_run: bool,
) -> Result<Vec<ClaimChange>, ExperimentError> {
    let path = dir.join("summary.json");
    let bad = |message: String| ExperimentError::Recheck {
        path: path.clone(),
        message,
    };
    let text = std::fs::read_to_string(&path).map_err(|e| ExperimentError::Io {
        path: path.clone(),
        source: e,
    })?;
    let mut stored: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| bad(e.to_string()))?;
    let summary: Summary = serde_json::from_value(stored.clone())
        .map_err(|e| bad(format!("not a run summary: {e}")))?;
    let cfg = recorded_arm_config(&summary.experiment, config, quick, "recheck")?;
    let recorded = arm_settings(&summary.config).map_err(|e| {
        bad(format!(
            "its `config` is not one this build reads ({e}); it cannot be judged under today's \
             settings"
        ))
    })?;
    if let Some(diff) = first_difference(
        &arm_identity(&recorded)?,
        &arm_identity(&cfg)?,
        String::new(),
    ) {
        return Err(bad(format!(
            "recorded with different settings: {diff} (give the run's own --config, and --quick \
             for a --quick run)"
        )));
    }
    let judged = checks::thesis_checks(&summary.experiment, &cfg, cfg.episodes, &summary);
    let changes = differences(&summary.thesis_reference, &judged);
    if !changes.is_empty() && !dry_run {
        stored["thesis_reference"] =
            serde_json::to_value(&judged).map_err(|e| ExperimentError::Write(e.into()))?;
        write_json_atomic(&path, &stored)?;
    }
    Ok(changes)
}

/// The claims that differ between `stored` and `judged`, matched by id, in `judged`'s order
/// and then the stored claims no longer made.
fn differences(stored: &[ThesisCheck], judged: &[ThesisCheck]) -> Vec<ClaimChange> {
    let find = |list: &[ThesisCheck], id: &str| list.iter().find(|c| c.id == id).cloned();
    let mut out: Vec<ClaimChange> = judged
        .iter()
        .filter(|j| find(stored, &j.id).as_ref() != Some(*j))
        .map(|j| ClaimChange {
            id: j.id.clone(),
            before: find(stored, &j.id),
            after: Some(j.clone()),
        })
        .collect();
    out.extend(
        stored
            .iter()
            .filter(|s| find(judged, &s.id).is_none())
            .map(|s| ClaimChange {
                id: s.id.clone(),
                before: Some(s.clone()),
                after: None,
            }),
    );
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn claim(id: &str, measured: &str, pass: Option<bool>) -> ThesisCheck {
        ThesisCheck {
            id: id.into(),
            claim: format!("claim {id}"),
            thesis: "thesis".into(),
            measured: measured.into(),
            pass,
            across_seeds: None,
        }
    }

    #[test]
    fn differences_match_claims_by_id() {
        let stored = [
            claim("a", "not yet", Some(false)),
            claim("b", "12.6", Some(true)),
            claim("gone", "x", None),
        ];
        let judged = [
            claim("b", "12.6", Some(true)),
            claim("a", "never", Some(false)),
            claim("new", "y", None),
        ];
        let changes = differences(&stored, &judged);
        let ids: Vec<&str> = changes.iter().map(|c| c.id.as_str()).collect();
        assert_eq!(ids, ["a", "new", "gone"]);
        assert_eq!(changes[0].before.as_ref().unwrap().measured, "not yet");
        assert_eq!(changes[0].after.as_ref().unwrap().measured, "never");
        assert!(changes[1].before.is_none());
        assert!(changes[2].after.is_none());
        assert!(differences(&judged, &judged).is_empty());
    }
}
