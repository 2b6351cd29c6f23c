//! write_report on synthetic run directories of every kind, and on broken ones.

use crate::synthetic::{write_old_run, write_run, Kind, TempDir};
use crate::{write_report, ReportError};
use serde_json::Value;
use std::path::Path;

mod markdown;

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
        "class=\"na\">undecided",
        "swatch green",
        "swatch red",
        "205.8",
        // The same columns as report.md (tables.rs builds both).
        "<th>final x (m)</th>",
        "<th>max force (N)</th>",
        "<th>k_y mean ± std (N/m)</th>",
        "<th>initial roll-out&#39;s return</th>",
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
    // The start interval is listed once, as the setting; the summary's derived copy of it is not.
    assert!(
        page.contains("<td>start.y_range</td>"),
        "settings list the interval"
    );
    assert!(
        !page.contains("<td>start_y_range</td>"),
        "and not its derived copy"
    );
    // Yellow updates get the success-fraction column.
    assert!(page.contains("<th>success fraction</th>"));

    // Every roll-out after an update's first is drawn, with the return its costs sum to.
    let run = crate::data::Run::load(tmp.path()).unwrap();
    let others = crate::figures::other_rollout_returns(&run);
    assert_eq!(
        others.len(),
        run.summary.episodes.len() * 3,
        "3 more per update"
    );
    let rollouts = run.rollouts.as_ref().unwrap();
    let second_of_update_1 = rollouts.iter().filter(|r| r.episode == 1).nth(1).unwrap();
    let sum: f64 = second_of_update_1.costs.as_ref().unwrap().iter().sum();
    assert_eq!(others[0], (1.0, sum));
    assert!(caption_from(tmp.path(), "Predicted return (mean").contains("Small circles"));
}

/// The report page's text from `start` up to the next tag: a caption.
fn caption_from(dir: &Path, start: &str) -> String {
    let page = html(dir);
    let at = page
        .find(start)
        .unwrap_or_else(|| panic!("no {start:?} on the page"));
    let end = page[at..].find('<').map_or(page.len(), |n| at + n);
    page[at..end].to_string()
}

/// Gives a roll-out record a two-sample path per step: the step's midpoint and its end.
fn add_midpoint_paths(v: &mut Value) {
    let states = v["rollout"]["true_states"].as_array().unwrap().clone();
    let infos: Vec<Value> = states
        .windows(2)
        .map(|w| {
            let (a, b) = (&w[0], &w[1]);
            let mid = |j: usize| (a[j].as_f64().unwrap() + b[j].as_f64().unwrap()) / 2.0;
            serde_json::json!({"path": [[mid(0), mid(1)], [b[0], b[1]]]})
        })
        .collect();
    v["rollout"]["infos"] = infos.into();
}

/// The path [`add_midpoint_paths`] records, read back with each sample's time in steps.
fn assert_midpoint_path(states: &[Vec<f64>], path: &[crate::data::PathPoint]) {
    let point = |step: f64, s: &[f64]| crate::data::PathPoint {
        step,
        x: s[0],
        y: s[1],
    };
    assert_eq!(path.len(), 2 * states.len() - 1);
    assert_eq!(path[0], point(0.0, &states[0]));
    let mid: Vec<f64> = (0..2)
        .map(|j| (states[0][j] + states[1][j]) / 2.0)
        .collect();
    assert_eq!(path[1], point(0.5, &mid));
    assert_eq!(path[2], point(1.0, &states[1]));
    let k = states.len() - 1;
    assert_eq!(*path.last().unwrap(), point(k as f64, &states[k]));
}

/// A roll-out whose every step recorded a within-step path is drawn along it, and the caption
/// says which roll-outs were; a malformed sample is an error naming it.
#[test]
fn paths_follow_the_within_step_samples_when_every_step_has_them() {
    let tmp = TempDir::new("within-step-paths");
    write_run(tmp.path(), Kind::Vilta);
    write_report(tmp.path()).unwrap();
    let caption = |dir: &Path| caption_from(dir, "TCP x–y path of every roll-out");
    assert!(caption(tmp.path()).contains(
        "joining the states at the ends of the steps (the run recorded no within-step path)"
    ));

    let rollouts = tmp.path().join("rollouts.jsonl");
    edit_lines(&rollouts, |i, v| {
        if i > 0 {
            add_midpoint_paths(v);
        }
    });
    let run = crate::data::Run::load(tmp.path()).unwrap();
    let all = run.rollouts.as_deref().unwrap();
    assert!(all[0].path.is_empty());
    for r in &all[1..] {
        assert_midpoint_path(&r.true_states, &r.path);
    }
    write_report(tmp.path()).unwrap();
    let n = all.len();
    assert!(
        caption(tmp.path()).contains(&format!("sampled within each step (1 of {n} roll-outs")),
        "{}",
        caption(tmp.path())
    );

    edit_lines(&rollouts, |i, v| {
        if i == 2 {
            v["rollout"]["infos"][3]["path"][1] = serde_json::json!([0.7]);
        }
    });
    let err = write_report(tmp.path()).unwrap_err().to_string();
    assert!(err.contains("line 3: rollout.infos[3].path[1]"), "{err}");
}

/// The fresh starts' y(t) follows their within-step paths as the paths plot does, and its
/// caption says so.
#[test]
fn final_eval_follows_the_within_step_samples() {
    let tmp = TempDir::new("final-eval-within-step");
    write_run(tmp.path(), Kind::ViltaVar);
    write_report(tmp.path()).unwrap();
    let caption = |dir: &Path| caption_from(dir, "from fresh start positions");
    assert!(caption(tmp.path()).contains("at the ends of the steps (the run recorded no"));

    let evals = tmp.path().join("final_eval.jsonl");
    edit_lines(&evals, |_, v| add_midpoint_paths(v));
    let run = crate::data::Run::load(tmp.path()).unwrap();
    let all = run.final_eval.as_deref().unwrap();
    for e in all {
        assert_midpoint_path(&e.true_states, &e.path);
    }
    write_report(tmp.path()).unwrap();
    assert!(
        caption(tmp.path()).contains("y(t) of each roll-out, sampled within each step, green"),
        "{}",
        caption(tmp.path())
    );

    edit_lines(&evals, |i, v| {
        if i == 1 {
            v["rollout"]["infos"][0]["path"] = serde_json::json!([[0.5, "y"]]);
        }
    });
    let err = write_report(tmp.path()).unwrap_err().to_string();
    assert!(err.contains("line 2: rollout.infos[0].path[0]"), "{err}");
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
    // The end-of-run predictions show the handed-over policy too, and the returns plot marks it.
    let last = caption_from(tmp.path(), "Long-term prediction of the final policy");
    assert!(
        last.contains(&crate::html::esc(
            "(update 3, the final evaluation's choice; the last update is 5)"
        )),
        "{last}"
    );
    let cost = caption_from(tmp.path(), "Immediate cost of the final policy");
    assert!(cost.contains("update 3"), "{cost}");
    let returns = caption_from(tmp.path(), "Predicted return (mean");
    assert!(returns.contains("Dashed line: update 3"), "{returns}");
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
fn settings_show_floats_without_rounding_noise() {
    let tmp = TempDir::new("settings-floats");
    write_run(tmp.path(), Kind::Vil);
    edit_json(&tmp.path().join("summary.json"), |v| {
        v["config"]["geometry"]["wall_x"] = serde_json::json!(0.7 - 0.05);
        v["config"]["start"]["prediction_std"] = serde_json::json!([0.002, 1e-300, 0.1 + 0.2]);
    });
    write_report(tmp.path()).unwrap();
    let page = html(tmp.path());
    assert!(
        page.contains("<td>geometry.wall_x</td><td>0.65</td>"),
        "wall_x"
    );
    assert!(
        page.contains("<td>start.prediction_std</td><td>[0.002, 1e-300, 0.3]</td>"),
        "prediction_std"
    );
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
