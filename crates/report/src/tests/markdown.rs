//! The Markdown report: its per-update, thesis and totals tables.

use super::{edit_json, edit_lines, html};
use crate::synthetic::{write_run, Kind, TempDir};
use crate::write_report;
use serde_json::Value;
use std::path::Path;

fn markdown(dir: &Path) -> String {
    std::fs::read_to_string(dir.join("report.md")).unwrap()
}

/// The Markdown rows of the table that follows `heading`, without header and rule.
fn md_rows<'a>(page: &'a str, heading: &str) -> Vec<Vec<&'a str>> {
    let start = page
        .find(heading)
        .unwrap_or_else(|| panic!("no {heading:?}"));
    page[start..]
        .lines()
        .skip_while(|l| !l.starts_with('|'))
        .take_while(|l| l.starts_with('|'))
        .skip(2)
        .map(|l| l.trim_matches('|').split(" | ").map(str::trim).collect())
        .collect()
}

/// The value of the Totals row whose label starts with `label` (the table has two columns).
fn totals_value(page: &str, label: &str) -> String {
    md_rows(page, "## Totals")
        .into_iter()
        .find(|r| r[0].starts_with(label))
        .inspect(|r| assert_eq!(r.len(), 2, "{r:?}"))
        .map(|r| r[1].to_string())
        .unwrap_or_else(|| panic!("no Totals row {label:?}"))
}

#[test]
fn markdown_report_has_a_row_per_update_and_every_claim() {
    let tmp = TempDir::new("md-vil");
    write_run(tmp.path(), Kind::Vil);
    let files = write_report(tmp.path()).unwrap();
    assert_eq!(files.markdown, tmp.path().join("report.md"));
    let page = markdown(tmp.path());
    assert!(page.starts_with("# vil-gic-rbf10 — seed 1\n"));

    let summary: Value =
        serde_json::from_str(&std::fs::read_to_string(tmp.path().join("summary.json")).unwrap())
            .unwrap();
    let eps = summary["episodes"].as_array().unwrap();
    let rows = md_rows(&page, "## Policy updates");
    assert_eq!(rows.len(), eps.len());
    let rollouts: Vec<Value> = std::fs::read_to_string(tmp.path().join("rollouts.jsonl"))
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    for (row, e) in rows.iter().zip(eps) {
        assert_eq!(row.len(), 14, "{row:?}");
        let r = rollouts
            .iter()
            .find(|r| r["episode"] == e["index"])
            .expect("a roll-out per update");
        let k_x: Vec<f64> = r["rollout"]["actions"]
            .as_array()
            .unwrap()
            .iter()
            .map(|a| a[0].as_f64().unwrap())
            .collect();
        let mean = k_x.iter().sum::<f64>() / k_x.len() as f64;
        let sd = (k_x.iter().map(|k| (k - mean).powi(2)).sum::<f64>() / k_x.len() as f64).sqrt();
        assert!(sd > 0.0, "the synthetic gains vary");
        assert_eq!(row[12], format!("{mean:.1} ± {sd:.1}"));
        let end = r["rollout"]["true_states"]
            .as_array()
            .unwrap()
            .last()
            .unwrap();
        assert_eq!(row[5], format!("{:.3}", end[1].as_f64().unwrap()));
        let model = match e.get("model_selection") {
            None => "–",
            Some(m) if m["kept_previous"].as_bool().unwrap() => "previous",
            Some(_) => "refit",
        };
        assert_eq!(row[11], model);
        assert_eq!(row[0], e["index"].to_string());
        assert_eq!(
            row[2],
            format!("{:.2}", e["recorded_return"].as_f64().unwrap())
        );
        assert_eq!(row[3], e["colour"].as_str().unwrap());
        assert_eq!(row[4], format!("{:.3}", e["final_x"].as_f64().unwrap()));
        let n = e["n_train"].as_u64().unwrap();
        let want = if e["sparse"].as_bool().unwrap() {
            format!("{n} (FITC)")
        } else {
            n.to_string()
        };
        assert_eq!(row[10], want);
    }

    let claims = md_rows(&page, "## Against the thesis");
    let verdicts: Vec<&str> = claims.iter().map(|r| r[3]).collect();
    assert_eq!(verdicts, ["pass", "fail", "undecided"]);
    assert_eq!(claims[1][2], "31.2");
    let rules: Vec<&str> = claims.iter().map(|r| r[4]).collect();
    assert_eq!(rules, ["3 of 5 seeds", "–", "–"]);

    let totals = md_rows(&page, "## Totals");
    let value = |k: &str| totals.iter().find(|r| r[0] == k).map(|r| r[1]).unwrap();
    assert_eq!(value("policy updates"), eps.len().to_string());
    assert_eq!(
        value("solved at"),
        "update 4 (first roll-outs of updates 2–4 all succeed)"
    );
    assert_eq!(
        value("mean wall time per update (s)"),
        format!("{:.1}", 1234.5 / eps.len() as f64)
    );
}

#[test]
fn markdown_report_of_a_classic_run_has_no_arm_columns_and_escapes_pipes() {
    let tmp = TempDir::new("md-pendulum");
    write_run(tmp.path(), Kind::Pendulum);
    edit_json(&tmp.path().join("summary.json"), |v| {
        v["thesis_reference"][0]["claim"] = "a | b\nc".into();
    });
    write_report(tmp.path()).unwrap();
    let page = markdown(tmp.path());
    let rows = md_rows(&page, "## Policy updates");
    assert!(
        !rows.is_empty() && rows.iter().all(|r| r.len() == 8),
        "{rows:?}"
    );
    assert!(!page.contains("final x"));
    assert!(page.contains("| a \\| b c |"), "{page}");
}

#[test]
fn action_statistics_of_a_constant_gain_and_of_missing_components() {
    let r = crate::data::Rollout {
        episode: 1,
        costs: None,
        actions: vec![vec![252.5, 10.0], vec![252.5, 30.0]],
        true_states: Vec::new(),
        stopped_early: None,
        path: Vec::new(),
    };
    assert_eq!(r.action_mean_std(0), Some((252.5, 0.0)));
    assert_eq!(r.action_mean_std(1), Some((20.0, 10.0)));
    assert_eq!(r.action_mean_std(2), None);
    let empty = crate::data::Rollout {
        actions: Vec::new(),
        ..r
    };
    assert_eq!(empty.action_mean_std(0), None);
}

#[test]
fn totals_list_the_rollouts_the_system_ended_early() {
    let tmp = TempDir::new("ended-early");
    write_run(tmp.path(), Kind::Vil);
    let row = |page: &str| totals_value(page, "roll-outs the system ended early");
    write_report(tmp.path()).unwrap();
    assert_eq!(row(&markdown(tmp.path())), "none");

    let why = "simulation diverged at t = 4.1410 s: |q̇2| = 1.7690e2 rad/s";
    let episode = std::cell::Cell::new(None);
    edit_lines(&tmp.path().join("rollouts.jsonl"), |i, v| {
        if i == 2 {
            episode.set(v["episode"].as_u64());
            let infos = v["rollout"]["infos"].as_array_mut().unwrap();
            infos.push(serde_json::json!({"stopped_early": why}));
        }
    });
    write_report(tmp.path()).unwrap();
    // The reason's pipes are escaped, so the table keeps two columns.
    let escaped = why.replace('|', "\\|");
    let expected = format!("update {}, roll-out 1: {escaped}", episode.get().unwrap());
    assert_eq!(row(&markdown(tmp.path())), expected);
    assert!(html(tmp.path()).contains("roll-outs the system ended early"));
}

#[test]
fn totals_say_which_build_computed_which_updates() {
    let tmp = TempDir::new("sessions");
    write_run(tmp.path(), Kind::Vil);
    write_report(tmp.path()).unwrap();
    let code_row = |page: &str| totals_value(page, "code");
    assert_eq!(code_row(&markdown(tmp.path())), "not recorded");

    let summary = tmp.path().join("summary.json");
    let mut n = 0;
    edit_json(&summary, |v| {
        n = v["episodes"].as_array().unwrap().len();
        let session = |first: u64, commit: &str, mode: &str| {
            serde_json::json!({"first_update": first, "commit": commit, "subnormals": mode,
                               "started_unix_s": 1_800_000_000u64})
        };
        // Started by an older build, resumed at 2, stopped before finishing update 3,
        // resumed at 3 again.
        v["sessions"] = serde_json::json!([
            session(2, "aaa", "gradual underflow"),
            session(3, "bbb", "flushed to zero"),
            session(3, "ccc", "flushed to zero"),
        ]);
    });
    assert!(n >= 4, "the synthetic run has {n} updates");
    write_report(tmp.path()).unwrap();
    let expected = format!(
        "update 1: not recorded; update 2: aaa (gradual underflow); updates 3–{n}: ccc (flushed \
         to zero)"
    );
    assert_eq!(code_row(&markdown(tmp.path())), expected);
    assert!(html(tmp.path()).contains(&expected));
}

#[test]
fn totals_say_which_updates_a_run_took_from_a_recorded_run() {
    let tmp = TempDir::new("replayed");
    write_run(tmp.path(), Kind::Vil);
    write_report(tmp.path()).unwrap();
    let replay_row = |page: &str| totals_value(page, "updates from a recorded run");
    assert_eq!(replay_row(&markdown(tmp.path())), "–");
    edit_json(&tmp.path().join("summary.json"), |v| {
        v["replayed_from"] = serde_json::json!({
            "run": "runs/shipped", "recorded_rule": "last-rollout-states",
            "recorded_updates": 25, "agreed": 2, "updates": []
        });
    });
    write_report(tmp.path()).unwrap();
    let expected = "updates 1–2: the recorded run runs/shipped (rule last-rollout-states, 25 \
                    updates); this run's rule parts from it at update 3";
    assert_eq!(replay_row(&markdown(tmp.path())), expected);
    assert!(html(tmp.path()).contains("the recorded run runs/shipped (rule last-rollout-states"));
    assert!(html(tmp.path()).contains("parts from it at update 3"));
    // Its returns name the recorded run where the path does not.
    edit_json(&tmp.path().join("summary.json"), |v| {
        v["replayed_from"]["recorded_returns"] = serde_json::json!([64.0, 61.25, 59.94]);
    });
    write_report(tmp.path()).unwrap();
    assert!(replay_row(&markdown(tmp.path()))
        .starts_with("updates 1–2: the recorded run runs/shipped (rule last-rollout-states, 25 updates, final return 59.9);"));
}

#[test]
fn solved_at_says_what_solved_means_when_the_summary_records_the_streak() {
    let tmp = TempDir::new("md-solved");
    write_run(tmp.path(), Kind::Vil);
    let solved = |dir: &Path| {
        write_report(dir).unwrap();
        totals_value(&markdown(dir), "solved at")
    };
    edit_json(&tmp.path().join("summary.json"), |s| {
        s["solved_at_episode"] = Value::Null;
    });
    assert_eq!(
        solved(tmp.path()),
        "not solved (never 3 successive updates whose first roll-out succeeds)"
    );
    // A run asked for more updates than it has done has not ended: not solved yet.
    edit_json(&tmp.path().join("summary.json"), |s| {
        let done = s["episodes"].as_array().unwrap().len();
        s["config"]["episodes"] = (done + 1).into();
    });
    assert_eq!(
        solved(tmp.path()),
        "not yet (3 successive updates whose first roll-out succeeds)"
    );
    // Summaries written before the streak was recorded say only the update.
    edit_json(&tmp.path().join("summary.json"), |s| {
        s["solved_at_episode"] = 6.into();
        s.as_object_mut().unwrap().remove("solved_streak");
    });
    assert_eq!(solved(tmp.path()), "update 6");
}

/// A run optimised over several start distributions (vilta-var) shows, beside each update's
/// roll-out, the predicted return of the start nearest that roll-out's start, not summary.json's
/// (the first start's).
#[test]
fn a_k_start_run_sets_the_nearest_starts_prediction_beside_the_roll_out() {
    let tmp = TempDir::new("md-k-starts");
    write_run(tmp.path(), Kind::ViltaVar);
    // Three starts: the recorded prediction as recorded at start (line % 3), with doubled costs
    // so that its return differs from the summary's, and moved 0.5 m off in y at the others.
    edit_lines(&tmp.path().join("predictions.jsonl"), |line, v| {
        let own = v["starts"][0].clone();
        let shifted = |dy: f64, cost_scale: f64| -> Value {
            let mut s = own.clone();
            for step in s.as_array_mut().unwrap() {
                let y = step["mean"][1].as_f64().unwrap();
                step["mean"][1] = (y + dy).into();
                for key in ["weighted_cost_mean", "weighted_cost_std"] {
                    let c = step[key].as_f64().unwrap();
                    step[key] = (c * cost_scale).into();
                }
            }
            s
        };
        let nearest = line % 3;
        v["starts"] = (0..3)
            .map(|k| {
                if k == nearest {
                    shifted(0.0, 2.0)
                } else {
                    shifted(0.5 * (k as f64 - 0.9), 1.0)
                }
            })
            .collect();
    });
    write_report(tmp.path()).unwrap();
    let page = markdown(tmp.path());
    assert!(page.contains("predicted (mean ± 1σ; start nearest the roll-out)"));
    let predictions: Vec<Value> = std::fs::read_to_string(tmp.path().join("predictions.jsonl"))
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    let summary: Value =
        serde_json::from_str(&std::fs::read_to_string(tmp.path().join("summary.json")).unwrap())
            .unwrap();
    let rows = md_rows(&page, "## Policy updates");
    let mut seen = std::collections::BTreeSet::new();
    for (row, e) in rows.iter().zip(summary["episodes"].as_array().unwrap()) {
        let line = predictions
            .iter()
            .position(|p| p["episode"] == e["index"])
            .unwrap();
        let (p, nearest) = (&predictions[line], line % 3);
        seen.insert(nearest);
        let sum = |key: &str| -> f64 {
            p["starts"][nearest]
                .as_array()
                .unwrap()
                .iter()
                .map(|s| s[key].as_f64().unwrap())
                .sum()
        };
        let (mean, std) = (sum("weighted_cost_mean"), sum("weighted_cost_std"));
        assert_ne!(
            format!("{mean:.2}"),
            format!("{:.2}", e["predicted_return_mean"].as_f64().unwrap())
        );
        assert_eq!(
            row[1],
            format!("{mean:.2} ± {std:.2} (start {} of 3)", nearest + 1)
        );
    }
    assert_eq!(seen.len(), 3, "every start is the nearest somewhere");
    assert!(html(tmp.path()).contains("from the start nearest the first roll-out"));

    // Older predictions without step costs: the first start's return, as summary.json has
    // it, and the cell says which start that is.
    edit_lines(&tmp.path().join("predictions.jsonl"), |_, v| {
        for start in v["starts"].as_array_mut().unwrap() {
            for step in start.as_array_mut().unwrap() {
                let step = step.as_object_mut().unwrap();
                step.remove("weighted_cost_mean");
                step.remove("weighted_cost_std");
            }
        }
    });
    write_report(tmp.path()).unwrap();
    let page = markdown(tmp.path());
    let rows = md_rows(&page, "## Policy updates");
    for (row, e) in rows.iter().zip(summary["episodes"].as_array().unwrap()) {
        let (mean, std) = (
            e["predicted_return_mean"].as_f64().unwrap(),
            e["predicted_return_std"].as_f64().unwrap(),
        );
        assert_eq!(row[1], format!("{mean:.2} ± {std:.2} (start 1 of 3)"));
    }
}
