//! `vicpilco evaluate` rolls out a recorded run's policies from the final evaluation's starts:
//! on the final policy it repeats `final_eval.jsonl`, it reads each update's policy from
//! `policies.jsonl`, and it refuses what it cannot do with an error that names why.

mod common;

use std::path::{Path, PathBuf};
use vicpilco_experiments::evaluate::{evaluate, markdown_table, EvaluateOptions};
use vicpilco_experiments::{run, ExperimentError, RecordedRunOptions, RunOptions};

fn scratch(name: &str) -> common::Scratch {
    common::scratch("evaluate", name)
}

/// A vilta-var run of the initial search roll-out only: its final policy is the untrained one
/// (update 0), evaluated from 20 fresh starts, with no GP fit or optimisation to pay for.
fn initial_only_run(dir: &Path) {
    let opts = RunOptions {
        seed: 4,
        out: dir.to_path_buf(),
        episodes: Some(0),
        ..Default::default()
    };
    run("vilta-var", &opts, &mut ()).expect("vilta-var with 0 updates");
}

fn options(from: &Path, out: PathBuf) -> EvaluateOptions {
    EvaluateOptions {
        run: RecordedRunOptions {
            seed: 4,
            from: from.to_path_buf(),
            config: None,
            quick: false,
            out,
        },
        updates: None,
        starts: None,
    }
}

#[test]
fn the_final_policy_repeats_the_final_evaluation_and_each_update_reads_its_own_policy() {
    let base = scratch("repeat");
    let run_dir = base.join("run");
    initial_only_run(&run_dir);
    let final_eval = common::json_lines(&run_dir.join("final_eval.jsonl"));
    assert_eq!(final_eval.len(), 20);

    let out = base.join("every-update.jsonl");
    let results = evaluate("vilta-var", &options(&run_dir, out.clone())).unwrap();
    assert_eq!(results.len(), 1, "updates 0 to 0");
    let written = common::json_lines(&out);
    assert_eq!(written.len(), 1);
    assert_eq!(written[0]["update"], 0);
    let table = std::fs::read_to_string(base.join("every-update.md")).unwrap();
    assert_eq!(table, markdown_table(&results));
    let rows: Vec<&str> = table.lines().skip(2).collect();
    assert_eq!(rows.len(), 1, "{table}");
    assert!(
        rows[0].starts_with(&format!("| 0 | {} of 20 |", results[0].successes)),
        "{table}"
    );
    let u = &results[0];
    assert_eq!(u.starts.len(), 20);
    for (mine, recorded) in u.starts.iter().zip(&final_eval) {
        let states = recorded["rollout"]["true_states"].as_array().unwrap();
        let last = states.last().unwrap();
        assert_eq!(mine.start_y, recorded["start_y"].as_f64().unwrap());
        assert_eq!(mine.success, recorded["success"].as_bool().unwrap());
        assert_eq!(mine.final_position[0], last[0].as_f64().unwrap());
        assert_eq!(mine.final_position[1], last[1].as_f64().unwrap());
        assert!(mine.recorded_return.is_finite() && mine.recorded_return > 0.0);
        assert!(mine.max_force.is_finite() && mine.max_force >= 0.0);
    }
    assert!(
        (0.1..=0.3).contains(&u.starts[0].start_y),
        "{}",
        u.starts[0].start_y
    );
    assert_eq!(u.successes, u.starts.iter().filter(|s| s.success).count());
    assert_eq!(u.fraction, u.successes as f64 / 20.0);

    // Another policy written for update 0 is the one rolled out: the same starts end elsewhere.
    let policies = run_dir.join("policies.jsonl");
    let mut line: serde_json::Value =
        serde_json::from_str(std::fs::read_to_string(&policies).unwrap().trim()).unwrap();
    for p in line["params"].as_array_mut().unwrap() {
        *p = serde_json::json!(p.as_f64().unwrap() + 0.5);
    }
    std::fs::write(&policies, format!("{line}\n")).unwrap();
    let other = evaluate(
        "vilta-var",
        &EvaluateOptions {
            updates: Some(vec![0]),
            starts: Some(3),
            ..options(&run_dir, base.join("changed.jsonl"))
        },
    )
    .unwrap();
    assert_eq!(other[0].starts.len(), 3);
    for (changed, first) in other[0].starts.iter().zip(&u.starts) {
        assert_eq!(
            changed.start_y, first.start_y,
            "the starts do not depend on the policy"
        );
        assert_ne!(changed.final_position, first.final_position);
    }
}

#[test]
fn what_evaluate_cannot_do_is_an_error_naming_why() {
    let base = scratch("errors");
    let run_dir = base.join("run");
    initial_only_run(&run_dir);
    // The error with its causes, as the CLI prints it.
    let message = |r: Result<_, ExperimentError>| {
        let e = r.map(|_| ()).unwrap_err();
        let mut text = e.to_string();
        let mut cause = std::error::Error::source(&e);
        while let Some(c) = cause {
            text.push_str(&format!(": {c}"));
            cause = c.source();
        }
        text
    };

    let beyond = EvaluateOptions {
        updates: Some(vec![0, 3]),
        ..options(&run_dir, base.join("beyond.jsonl"))
    };
    let m = message(evaluate("vilta-var", &beyond));
    assert!(m.contains("updates 0 to 0, not update 3"), "{m}");
    assert!(
        !base.join("beyond.jsonl").exists(),
        "nothing written for a bad request"
    );

    let out = base.join("once.jsonl");
    evaluate("vilta-var", &options(&run_dir, out.clone())).unwrap();
    let m = message(evaluate("vilta-var", &options(&run_dir, out.clone())));
    assert!(
        m.contains("once.jsonl") && m.contains("give another --out"),
        "an earlier result is not overwritten: {m}"
    );
    assert_eq!(common::json_lines(&out).len(), 1);
    std::fs::write(base.join("table-taken.md"), "kept").unwrap();
    let m = message(evaluate(
        "vilta-var",
        &options(&run_dir, base.join("table-taken.jsonl")),
    ));
    assert!(
        m.contains("table-taken.md") && m.contains("give another --out"),
        "{m}"
    );
    assert!(
        !base.join("table-taken.jsonl").exists(),
        "nothing written beside a table that exists"
    );
    assert_eq!(
        std::fs::read_to_string(base.join("table-taken.md")).unwrap(),
        "kept"
    );

    let m = message(evaluate(
        "vilta",
        &EvaluateOptions {
            starts: Some(2),
            ..options(&run_dir, base.join("vilta.jsonl"))
        },
    ));
    assert!(m.contains("vilta-var") && m.contains("not `vilta`"), "{m}");

    let m = message(evaluate(
        "vilta",
        &options(&run_dir, base.join("none.jsonl")),
    ));
    assert!(m.contains("--starts"), "{m}");
    let m = message(evaluate(
        "vilta-var",
        &EvaluateOptions {
            starts: Some(0),
            ..options(&run_dir, base.join("zero.jsonl"))
        },
    ));
    assert!(m.contains("--starts 0 leaves nothing"), "{m}");

    let m = message(evaluate(
        "pendulum",
        &options(&run_dir, base.join("p.jsonl")),
    ));
    assert!(m.contains("not an arm experiment"), "{m}");

    std::fs::write(run_dir.join("policies.jsonl"), "").unwrap();
    let m = message(evaluate(
        "vilta-var",
        &options(&run_dir, base.join("gone.jsonl")),
    ));
    assert!(
        m.contains("cannot evaluate") && m.contains("no policy of update 0"),
        "{m}"
    );
}

/// `vilta.final_policy = "most-successful"` hands over the policy of the latest update whose own
/// roll-outs inserted most often; the rule acts after learning only, so a finished run takes
/// it on `--resume` and its final evaluation is then that update's `vicpilco evaluate` line.
#[test]
fn the_most_successful_rule_evaluates_the_best_update_also_of_a_finished_run() {
    let base = scratch("most-successful");
    let run_dir = base.join("run");
    let shipped = vicpilco_experiments::config::shipped("vilta-var")
        .unwrap()
        .1;
    let rule_line = "final_policy = \"most-successful\"";
    assert!(shipped.contains(rule_line), "vilta-var ships the rule");
    let last_config = base.join("last.toml");
    std::fs::create_dir_all(&base).unwrap();
    std::fs::write(
        &last_config,
        shipped.replace(rule_line, "final_policy = \"last\""),
    )
    .unwrap();
    let opts = RunOptions {
        seed: 4,
        out: run_dir.clone(),
        episodes: Some(2),
        quick: true,
        config: Some(last_config),
        ..Default::default()
    };
    let summary = run("vilta-var", &opts, &mut ()).expect("2 quick updates");
    assert_eq!(summary.final_eval.as_ref().unwrap().update, Some(2));

    // As if update 1's roll-outs had all inserted (a quick run's seldom do): the rule now
    // prefers update 1 to the last.
    let checkpoint = run_dir.join("checkpoint.json");
    let mut c: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&checkpoint).unwrap()).unwrap();
    c["summary"]["episodes"][0]["success_fraction"] = serde_json::json!(1.0);
    c["summary"]["episodes"][1]["success_fraction"] = serde_json::json!(0.75);
    std::fs::write(&checkpoint, c.to_string()).unwrap();
    let resumed = run(
        "vilta-var",
        &RunOptions {
            config: None,
            resume: true,
            ..opts
        },
        &mut (),
    )
    .expect("the finished run resumed under the shipped rule");
    let final_eval = resumed.final_eval.unwrap();
    assert_eq!(final_eval.update, Some(1));
    assert_eq!(resumed.episodes.len(), 2, "no update added");
    assert!(resumed.config["ours"]
        .as_array()
        .unwrap()
        .contains(&serde_json::json!("vilta.final_policy")));

    let quick_update = |u: usize| {
        let mut o = options(&run_dir, base.join(format!("update-{u}.jsonl")));
        o.run.quick = true;
        o.updates = Some(vec![u]);
        evaluate("vilta-var", &o).unwrap()
    };
    let mut evaluated = quick_update(1);
    let update_1 = evaluated.remove(0);
    assert_eq!(update_1.successes, final_eval.successes);
    let recorded = common::json_lines(&run_dir.join("final_eval.jsonl"));
    assert_eq!(recorded.len(), update_1.starts.len());
    let mut differs_from_last = false;
    let last = quick_update(2);
    for ((mine, line), other) in update_1.starts.iter().zip(&recorded).zip(&last[0].starts) {
        let states = line["rollout"]["true_states"].as_array().unwrap();
        let end = states.last().unwrap();
        assert_eq!(mine.final_position[0], end[0].as_f64().unwrap());
        assert_eq!(mine.final_position[1], end[1].as_f64().unwrap());
        differs_from_last |= other.final_position != mine.final_position;
    }
    assert!(
        differs_from_last,
        "update 2's policy would have ended elsewhere"
    );
}
