//! write_report on synthetic run directories of every kind, and on broken ones.

use crate::synthetic::{write_old_run, write_run, Kind, TempDir};
use crate::{write_report, ReportError};
use serde_json::Value;
use std::path::Path;

fn stems(files: &crate::ReportFiles) -> Vec<String> {
    files
        .images
        .iter()
        .filter(|p| p.extension().is_some_and(|e| e == "png"))
        .filter_map(|p| p.file_stem().map(|s| s.to_string_lossy().into_owned()))
        .collect()
}

/// Width and height of a PNG that must decode.
fn png_size(path: &Path) -> (u32, u32) {
    let file = std::fs::File::open(path).expect("open png");
    let reader = png::Decoder::new(std::io::BufReader::new(file))
        .read_info()
        .expect("png header");
    let info = reader.info();
    (info.width, info.height)
}

fn edit_json(path: &Path, f: impl FnOnce(&mut Value)) {
    let mut v: Value = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    f(&mut v);
    std::fs::write(path, v.to_string()).unwrap();
}

fn edit_lines(path: &Path, f: impl Fn(usize, &mut Value)) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut out = String::new();
    for (i, l) in text.lines().enumerate() {
        let mut v: Value = serde_json::from_str(l).unwrap();
        f(i, &mut v);
        out.push_str(&v.to_string());
        out.push('\n');
    }
    std::fs::write(path, out).unwrap();
}

fn html(dir: &Path) -> String {
    std::fs::read_to_string(dir.join("report.html")).unwrap()
}

#[test]
fn vil_run_gets_every_plot_but_final_eval() {
    let tmp = TempDir::new("vil");
    write_run(tmp.path(), Kind::Vil);
    let files = write_report(tmp.path()).unwrap();
    assert_eq!(
        stems(&files),
        [
            "returns",
            "policy",
            "prediction_first",
            "cost_first",
            "prediction_last",
            "cost_last",
            "paths"
        ]
    );
    assert!(files.notes.is_empty(), "{:?}", files.notes);
    for p in &files.images {
        assert!(
            std::fs::metadata(p).unwrap().len() > 1000,
            "{}",
            p.display()
        );
    }
    // Two actions: one row of policy panels; six states: three rows of prediction panels.
    assert_eq!(png_size(&tmp.path().join("policy.png")), (1400, 480));
    assert_eq!(
        png_size(&tmp.path().join("prediction_last.png")),
        (1400, 1200)
    );
    let svg = std::fs::read_to_string(tmp.path().join("returns.svg")).unwrap();
    assert!(svg.starts_with("<svg") && svg.contains("policy update"));

    let page = html(tmp.path());
    assert_eq!(page.matches("data:image/png;base64,").count(), 7);
    for want in [
        "vil-gic-rbf10 — seed 1",
        "geometry.wall_x",
        "class=\"pass\">PASS",
        "class=\"fail\">FAIL",
        "class=\"na\">n.a.",
        "swatch green",
        "swatch red",
        "205.8",
    ] {
        assert!(page.contains(want), "report lacks {want:?}");
    }
}

#[test]
fn vilta_policy_has_a_panel_per_action() {
    let tmp = TempDir::new("vilta");
    write_run(tmp.path(), Kind::Vilta);
    let files = write_report(tmp.path()).unwrap();
    assert!(files.notes.is_empty(), "{:?}", files.notes);
    // Four actions: k_x, k_y above dx_ref, dy_ref.
    assert_eq!(png_size(&tmp.path().join("policy.png")), (1400, 960));
}

#[test]
fn vilta_var_adds_final_eval_and_yellow_updates() {
    let tmp = TempDir::new("vilta-var");
    write_run(tmp.path(), Kind::ViltaVar);
    let files = write_report(tmp.path()).unwrap();
    let stems = stems(&files);
    assert_eq!(stems.last().map(String::as_str), Some("final_eval"));
    assert!(stems.iter().any(|s| s == "paths"));
    assert!(files.notes.is_empty(), "{:?}", files.notes);
    let page = html(tmp.path());
    assert!(page.contains("swatch yellow"));
    assert!(page.contains("start_y_range"));
}

/// With `final_eval.update` (`vilta.final_policy`) the policy plot and the final evaluation are
/// of that update, also when it is not the last; a named update without a prediction falls
/// back to the last with a note.
#[test]
fn the_final_policy_plots_show_the_update_the_final_evaluation_chose() {
    let tmp = TempDir::new("vilta-var-chosen");
    write_run(tmp.path(), Kind::ViltaVar);
    let summary = tmp.path().join("summary.json");
    edit_json(
        &summary,
        |v| {
            v["final_eval"] =
                serde_json::json!({"starts": 20, "successes": 17, "fraction": 0.85, "update": 3})
        },
    );
    let files = write_report(tmp.path()).unwrap();
    assert!(files.notes.is_empty(), "{:?}", files.notes);
    let page = html(tmp.path());
    assert!(page.contains("Final policy (update 3)"), "policy caption");
    assert!(
        page.contains(&crate::html::esc(
            "update 3's, chosen by vilta.final_policy"
        )),
        "final_eval caption"
    );
    assert!(!page.contains("Final policy (update 5)"));

    edit_json(&summary, |v| {
        v["final_eval"]["update"] = serde_json::json!(9)
    });
    let files = write_report(tmp.path()).unwrap();
    assert!(
        files
            .notes
            .iter()
            .any(|n| n.contains("no prediction of update 9")),
        "{:?}",
        files.notes
    );
    assert!(html(tmp.path()).contains("Final policy (update 5)"));
}

#[test]
fn pendulum_run_has_no_arm_plots() {
    let tmp = TempDir::new("pendulum");
    write_run(tmp.path(), Kind::Pendulum);
    let files = write_report(tmp.path()).unwrap();
    let stems = stems(&files);
    assert!(!stems.iter().any(|s| s == "paths" || s == "final_eval"));
    assert_eq!(stems.len(), 6);
    assert_eq!(png_size(&tmp.path().join("policy.png")), (1000, 480));
    assert_eq!(
        png_size(&tmp.path().join("prediction_first.png")),
        (1400, 400)
    );
}

#[test]
fn old_format_run_gets_the_returns_plot_and_notes() {
    let tmp = TempDir::new("old");
    write_old_run(tmp.path());
    let files = write_report(tmp.path()).unwrap();
    assert_eq!(stems(&files), ["returns"]);
    let notes = files.notes.join("\n");
    assert!(notes.contains("rollouts.json"), "{notes}");
    assert!(notes.contains("no predictions.jsonl"), "{notes}");
    assert!(notes.contains("initial_return"), "{notes}");
    let page = html(tmp.path());
    assert!(page.contains("has no thesis_reference"));
    assert!(page.contains("not solved"));
    // Old summaries have only `success`: red squares and green circles, no yellow.
    assert!(page.contains("swatch red") && page.contains("swatch green"));
    assert!(!page.contains("swatch yellow"));
}

#[test]
fn missing_optional_fields_skip_parts_with_notes() {
    let tmp = TempDir::new("partial");
    write_run(tmp.path(), Kind::Vil);
    edit_lines(&tmp.path().join("predictions.jsonl"), |i, v| {
        if i == 0 {
            for step in v["starts"][0].as_array_mut().unwrap() {
                step.as_object_mut().unwrap().remove("weighted_cost_mean");
            }
        }
    });
    edit_lines(&tmp.path().join("rollouts.jsonl"), |_, v| {
        v.as_object_mut().unwrap().remove("costs");
    });
    edit_json(&tmp.path().join("summary.json"), |v| {
        for e in v["episodes"].as_array_mut().unwrap() {
            e.as_object_mut().unwrap().remove("colour");
        }
        v.as_object_mut().unwrap().remove("initial_return");
    });
    let files = write_report(tmp.path()).unwrap();
    let stems = stems(&files);
    assert!(!stems.iter().any(|s| s == "cost_first"));
    assert!(stems.iter().any(|s| s == "cost_last"));
    let notes = files.notes.join("\n");
    assert!(notes.contains("no cost_first plot"), "{notes}");
    assert!(notes.contains("no recorded costs"), "{notes}");
    assert!(notes.contains("initial_return"), "{notes}");
    assert!(html(tmp.path()).contains("no recorded costs"));
}

#[test]
fn summary_without_episodes_still_reports() {
    let tmp = TempDir::new("empty");
    write_run(tmp.path(), Kind::Vil);
    edit_json(&tmp.path().join("summary.json"), |v| {
        v["episodes"] = Value::Array(vec![])
    });
    std::fs::write(tmp.path().join("predictions.jsonl"), "").unwrap();
    let files = write_report(tmp.path()).unwrap();
    assert_eq!(stems(&files), ["paths"]);
    let notes = files.notes.join("\n");
    assert!(notes.contains("no policy updates yet"), "{notes}");
    assert!(notes.contains("predictions.jsonl is empty"), "{notes}");
}

#[test]
fn missing_summary_names_the_file() {
    let tmp = TempDir::new("nosummary");
    let err = write_report(tmp.path()).unwrap_err();
    assert!(matches!(err, ReportError::Read { .. }));
    assert!(err.to_string().contains("summary.json"), "{err}");
}

#[test]
fn malformed_fields_are_named() {
    let tmp = TempDir::new("malformed");
    write_run(tmp.path(), Kind::Vil);
    let summary = tmp.path().join("summary.json");
    edit_json(&summary, |v| {
        v["episodes"][1]["recorded_return"] = "65.5".into()
    });
    let err = write_report(tmp.path()).unwrap_err().to_string();
    assert!(err.contains("summary.json"), "{err}");
    assert!(err.contains("episodes[1].recorded_return"), "{err}");

    write_run(tmp.path(), Kind::Vil);
    edit_json(&summary, |v| {
        v.as_object_mut().unwrap().remove("seed");
    });
    let err = write_report(tmp.path()).unwrap_err();
    assert!(
        matches!(&err, ReportError::Missing { field, .. } if field == "seed"),
        "{err}"
    );

    write_run(tmp.path(), Kind::Vil);
    edit_json(&summary, |v| v["episodes"][0]["colour"] = "blue".into());
    let err = write_report(tmp.path()).unwrap_err().to_string();
    assert!(
        err.contains("episodes[0].colour") && err.contains("\"blue\""),
        "{err}"
    );

    write_run(tmp.path(), Kind::Vil);
    edit_lines(&tmp.path().join("rollouts.jsonl"), |i, v| {
        if i == 1 {
            v["rollout"]["true_states"][4][1] = Value::Bool(true);
        }
    });
    let err = write_report(tmp.path()).unwrap_err().to_string();
    assert!(err.contains("rollouts.jsonl"), "{err}");
    assert!(err.contains("line 2: rollout.true_states[4][1]"), "{err}");

    write_run(tmp.path(), Kind::Vil);
    edit_lines(&tmp.path().join("predictions.jsonl"), |i, v| {
        if i == 2 {
            v["starts"][0][7]["var"].as_array_mut().unwrap().pop();
        }
    });
    let err = write_report(tmp.path()).unwrap_err().to_string();
    assert!(err.contains("predictions.jsonl"), "{err}");
    assert!(err.contains("line 3: starts[0][7]"), "{err}");

    write_run(tmp.path(), Kind::Vil);
    edit_lines(&tmp.path().join("predictions.jsonl"), |i, v| {
        if i == 1 {
            v["action_bounds"][1] = serde_json::json!([250.0, 5.0]);
        }
    });
    let err = write_report(tmp.path()).unwrap_err().to_string();
    assert!(
        err.contains("line 2: action_bounds") && err.contains("[lowest, highest]"),
        "{err}"
    );

    write_run(tmp.path(), Kind::Vil);
    edit_json(&summary, |v| {
        v["config"]["geometry"]
            .as_object_mut()
            .unwrap()
            .remove("hole_r");
    });
    let err = write_report(tmp.path()).unwrap_err();
    assert!(
        matches!(&err, ReportError::Missing { field, .. } if field == "config.geometry.hole_r"),
        "{err}"
    );

    write_run(tmp.path(), Kind::Vil);
    std::fs::write(&summary, "{ not json").unwrap();
    let err = write_report(tmp.path()).unwrap_err();
    assert!(matches!(err, ReportError::Json { .. }), "{err}");
}

#[test]
fn a_cut_off_last_line_is_ignored_but_a_bad_middle_line_is_not() {
    let tmp = TempDir::new("cutoff");
    write_run(tmp.path(), Kind::Vil);
    let path = tmp.path().join("rollouts.jsonl");
    let mut text = std::fs::read_to_string(&path).unwrap();
    text.push_str("{\"episode\": 7, \"rollout\": {\"actions\": [[1");
    std::fs::write(&path, &text).unwrap();
    let files = write_report(tmp.path()).unwrap();
    assert!(files.notes.join("\n").contains("incomplete last line 8"));

    std::fs::write(&path, format!("{{oops\n{text}\n")).unwrap();
    let err = write_report(tmp.path()).unwrap_err();
    assert!(
        matches!(&err, ReportError::Json { location, .. } if location == "line 1"),
        "{err}"
    );
}

#[test]
fn strings_from_the_run_are_escaped() {
    let tmp = TempDir::new("escape");
    write_run(tmp.path(), Kind::Pendulum);
    edit_json(&tmp.path().join("summary.json"), |v| {
        v["experiment"] = "<script>alert('x')</script>".into();
        v["thesis_reference"][0]["claim"] = "return < 20 & \"fast\"".into();
        v["config"]["note"] = "<b>bold</b>".into();
    });
    write_report(tmp.path()).unwrap();
    let page = html(tmp.path());
    assert!(!page.contains("<script>") && !page.contains("<b>bold"));
    assert!(page.contains("&lt;script&gt;alert(&#39;x&#39;)&lt;/script&gt;"));
    assert!(page.contains("return &lt; 20 &amp; &quot;fast&quot;"));
}

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
            format!("{:.1}", e["recorded_return"].as_f64().unwrap())
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
    assert_eq!(value("solved at"), "update 4");
    assert_eq!(
        value("mean wall time per update (s)"),
        format!("{:.0}", 1234.5 / eps.len() as f64)
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
    let row = |page: &str| {
        md_rows(page, "## Totals")
            .into_iter()
            .find(|r| r[0] == "roll-outs the system ended early")
            .inspect(|r| assert_eq!(r.len(), 2, "{r:?}"))
            .map(|r| r[1].to_string())
            .expect("an ended-early row")
    };
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
    let code_row = |page: &str| {
        md_rows(page, "## Totals")
            .into_iter()
            .find(|r| r[0].starts_with("code"))
            .map(|r| r[1].to_string())
            .expect("a code row")
    };
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
    let replay_row = |page: &str| {
        md_rows(page, "## Totals")
            .into_iter()
            .find(|r| r[0].starts_with("updates from a recorded run"))
            .map(|r| r[1].to_string())
            .expect("a replay row")
    };
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
