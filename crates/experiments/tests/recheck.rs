//! `vicpilco recheck` judges a recorded run's claims again with this build's checks: it
//! rewrites only a stale `thesis_reference`, refuses settings that are not the run's, and
//! every stored run (results/ and probes/) is current with this build, so that `vicpilco
//! acceptance` never tables an old judgement.

mod common;
#[path = "../../report/tests/common/stored_runs.rs"]
mod stored_runs;

use std::path::Path;
use stored_runs::{every_run, repo_dir, settings_file};
use vicpilco_experiments::recheck::recheck;
use vicpilco_experiments::ExperimentError;

fn read_json(path: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// A copy of the stored vilta seed 3 summary (complete, never inserting) in a scratch
/// directory, with its "3 consecutive" claim worded as builds before 773c412 wrote it.
fn stale_vilta_run(name: &str) -> (common::Scratch, serde_json::Value) {
    let dir = common::scratch("recheck", name);
    std::fs::create_dir_all(&dir).unwrap();
    let mut summary = read_json(&repo_dir("results/vilta-seed3/summary.json"));
    let claims = summary["thesis_reference"].as_array_mut().unwrap();
    let three = claims
        .iter_mut()
        .find(|c| c["id"] == "vilta_three_after_first")
        .expect("the stored vilta run makes the 3-consecutive claim");
    three["measured"] = "not yet".into();
    std::fs::write(
        dir.join("summary.json"),
        serde_json::to_vec_pretty(&summary).unwrap(),
    )
    .unwrap();
    (dir, summary)
}

#[test]
fn a_stale_claim_is_judged_again_and_nothing_else_changes() {
    let (dir, before) = stale_vilta_run("stale");
    let dry = recheck(&dir, None, false, true).unwrap();
    assert_eq!(dry.len(), 1, "{dry:?}");
    assert_eq!(
        read_json(&dir.join("summary.json")),
        before,
        "a dry run writes nothing"
    );

    let changes = recheck(&dir, None, false, false).unwrap();
    assert_eq!(changes, dry);
    let change = &changes[0];
    assert_eq!(change.id, "vilta_three_after_first");
    assert_eq!(change.before.as_ref().unwrap().measured, "not yet");
    let after = change.after.as_ref().unwrap();
    assert_eq!(
        after.measured, "never",
        "a complete run that never inserted"
    );
    assert_eq!(after.pass, Some(false));

    let mut rewritten = read_json(&dir.join("summary.json"));
    let claims = rewritten["thesis_reference"].take();
    let mut expected = before;
    expected["thesis_reference"] = serde_json::Value::Null;
    assert_eq!(rewritten, expected, "only thesis_reference may change");
    let three = claims
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["id"] == "vilta_three_after_first")
        .unwrap()
        .clone();
    assert_eq!(three["measured"], "never");

    assert!(
        recheck(&dir, None, false, false).unwrap().is_empty(),
        "a second recheck finds the summary current"
    );
}

#[test]
fn settings_that_are_not_the_runs_are_refused_with_the_key_that_differs() {
    let (dir, before) = stale_vilta_run("other-settings");
    let probe = repo_dir("probes/lead-state-y-ceiling/vilta.toml");
    let err = recheck(&dir, Some(&probe), false, false).unwrap_err();
    let text = err.to_string();
    assert!(matches!(err, ExperimentError::Recheck { .. }), "{text}");
    assert!(text.contains("summary.json"), "{text}");
    assert!(text.contains("differs"), "{text}");
    assert_eq!(read_json(&dir.join("summary.json")), before);

    let err = recheck(&dir, None, true, false).unwrap_err();
    assert!(err.to_string().contains("optimiser.length"), "{err}");
}

#[test]
fn a_missing_or_malformed_summary_is_an_error_that_names_the_file() {
    let dir = common::scratch("recheck", "malformed");
    std::fs::create_dir_all(&dir).unwrap();
    let err = recheck(&dir, None, false, false).unwrap_err();
    assert!(format!("{err:#}").contains("summary.json"), "{err:#}");
    std::fs::write(dir.join("summary.json"), "{\"experiment\": ").unwrap();
    let err = recheck(&dir, None, false, false).unwrap_err();
    assert!(matches!(err, ExperimentError::Recheck { .. }), "{err}");
    assert!(err.to_string().contains("summary.json"), "{err}");
}

#[test]
fn every_stored_run_is_judged_as_this_build_judges_it() {
    let runs = every_run();
    assert!(runs.len() > 30, "only {} stored runs found", runs.len());
    let stale: Vec<String> = runs
        .iter()
        .filter_map(|dir| {
            let changes = recheck(dir, settings_file(dir).as_deref(), false, true)
                .unwrap_or_else(|e| panic!("{}: {e:#}", dir.display()));
            (!changes.is_empty()).then(|| {
                let ids: Vec<&str> = changes.iter().map(|c| c.id.as_str()).collect();
                format!("{} ({})", dir.display(), ids.join(", "))
            })
        })
        .collect();
    assert!(
        stale.is_empty(),
        "stored runs judged by an older build (run scripts/recheck-stored):\n{}",
        stale.join("\n")
    );
}
