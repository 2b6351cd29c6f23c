//! `--replay-from` and `vicpilco rescore` on the quick vil-gic run of `main.rs`.

use super::{read, summary_without_timings};
use vicpilco_experiments::summary::Summary;
use vicpilco_experiments::{rescore, run, RecordedRunOptions, RunOptions};
use vicpilco_learn::replay::ReplayedUpdate;
use vicpilco_learn::selection::ModelSelection;

/// Whether the run directory was locked (by another open file: the run's own lock) at the
/// first update the loop ran.
struct LockSeenDuringRun {
    dir: std::path::PathBuf,
    busy: Option<bool>,
}

impl vicpilco_learn::record::LoopObserver for LockSeenDuringRun {
    fn phase(&mut self, _episode: usize, _phase: vicpilco_learn::record::Phase) {
        if self.busy.is_none() {
            let lock = self.dir.join(vicpilco_experiments::record::LOCK_FILE);
            let file = std::fs::OpenOptions::new().write(true).open(lock).unwrap();
            let busy = matches!(file.try_lock(), Err(std::fs::TryLockError::WouldBlock));
            self.busy = Some(busy);
        }
    }
}

/// `--replay-from`: a run of `full`'s rule replays and keeps every update of it; another rule
/// keeps them up to where it chooses differently and runs the rest itself; a record the replay
/// does not rebuild, changed settings and an occupied directory are errors.
pub(crate) fn replaying_a_run_keeps_its_updates_while_the_rules_agree(
    base: &std::path::Path,
    full: &std::path::Path,
    opts: &dyn Fn(&std::path::Path, Option<usize>, bool) -> RunOptions,
) {
    let from_full = |out: &std::path::Path, config: Option<std::path::PathBuf>| RunOptions {
        replay_from: Some(full.to_path_buf()),
        config,
        ..opts(out, None, false)
    };
    let same = base.join("replayed-same-rule");
    run("vil-gic", &from_full(&same, None), &mut ()).expect("replay under the same rule");
    let mut v = summary_without_timings(&same);
    let source = v.as_object_mut().unwrap().remove("replayed_from").unwrap();
    assert_eq!(source["agreed"], 3);
    assert_eq!(source["recorded_updates"], 3);
    assert_eq!(source["recorded_rule"], "last-rollout");
    let full_summary = summary_without_timings(full);
    let full_returns: Vec<f64> = full_summary["episodes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| e["recorded_return"].as_f64().unwrap())
        .collect();
    assert_eq!(source["recorded_returns"], serde_json::json!(full_returns));
    let updates = source["updates"].as_array().unwrap();
    assert_eq!(updates.len(), 2, "updates 2 and 3 choose a model");
    for u in updates {
        assert_eq!(u["recorded"], u["other"]);
    }
    assert_eq!(v, full_summary);
    for file in ["rollouts.jsonl", "predictions.jsonl", "policies.jsonl"] {
        assert!(read(&full.join(file)) == read(&same.join(file)), "{file}");
    }

    // A replay that goes on past the recorded updates runs in the directory it made, holding
    // its lock as any run does (a resume beside it is refused).
    let longer = base.join("replayed-longer");
    let mut probe = LockSeenDuringRun {
        dir: longer.clone(),
        busy: None,
    };
    let opts_longer = RunOptions {
        replay_from: Some(full.to_path_buf()),
        ..opts(&longer, Some(4), false)
    };
    let summary = run("vil-gic", &opts_longer, &mut probe).expect("replay and one more update");
    assert_eq!(summary.episodes.len(), 4);
    assert_eq!(summary.replayed_from.as_ref().unwrap().agreed, 3);
    assert_eq!(probe.busy, Some(true), "the replaying run holds its lock");

    // The state score: kept updates carry its scores, and from the first update where it
    // parts from the recorded choice the run is its own.
    let text = vicpilco_experiments::config::shipped("vil-gic").unwrap().1;
    let rule = "model_selection = \"last-rollout\"";
    assert!(text.contains(rule));
    let states = base.join("states.toml");
    let states_rule = "model_selection = \"last-rollout-states\"";
    std::fs::write(&states, text.replace(rule, states_rule)).unwrap();
    let other = base.join("replayed-state-rule");
    let summary = run("vil-gic", &from_full(&other, Some(states.clone())), &mut ())
        .expect("replay under the state score");
    let source = summary.replayed_from.as_ref().unwrap();
    assert_eq!(summary.episodes.len(), 3);
    let parted = source.agreed < 3;
    let agreeing = &source.updates[..source.updates.len() - usize::from(parted)];
    for u in agreeing {
        assert_eq!(u.recorded.kept_previous, u.other.kept_previous);
        let kept = &summary.episodes[u.update - 1].model_selection;
        assert_eq!(kept.as_ref(), Some(&u.other));
    }
    if parted {
        let last = source.updates.last().unwrap();
        assert_eq!(last.update, source.agreed + 1);
        assert_ne!(last.recorded.kept_previous, last.other.kept_previous);
    }
    let sessions = &summary.sessions;
    assert_eq!(sessions.last().unwrap().first_update, source.agreed + 1);

    // Rescoring follows the recorded choices through every update and judges each under
    // every rule: the recorded rule's verdicts are the recorded ones, and up to the state
    // rule's parting its verdicts are those its replay found.
    let verdicts = base.join("rescored").join("verdicts.jsonl");
    let rescore_opts = RecordedRunOptions {
        seed: 1,
        from: full.to_path_buf(),
        config: Some(states.clone()),
        out: verdicts.clone(),
        quick: true,
    };
    let rescored = rescore("vil-gic", &rescore_opts).expect("rescore");
    let recorded: Summary = serde_json::from_str(&read(&full.join("summary.json"))).unwrap();
    assert_eq!(
        rescored.iter().map(|u| u.update).collect::<Vec<_>>(),
        [2, 3]
    );
    for u in &rescored {
        let rules: Vec<_> = u.every_rule.iter().map(|v| v.rule).collect();
        assert_eq!(rules, ModelSelection::COMPARING);
        let by_rule = |r| u.every_rule.iter().find(|v| v.rule == r).unwrap().choice;
        let record = recorded.episodes[u.update - 1].model_selection.unwrap();
        assert_eq!(by_rule(ModelSelection::LastRollout), record);
        assert_eq!(u.recorded, record);
        assert_eq!(by_rule(ModelSelection::LastRolloutStates), u.other);
    }
    for (r, s) in rescored.iter().zip(&source.updates) {
        assert_eq!(r, s);
    }
    let lines: Vec<ReplayedUpdate> = read(&verdicts)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines, rescored);
    let err = rescore("vil-gic", &rescore_opts).unwrap_err().to_string();
    assert!(err.contains("verdicts.jsonl"), "{err}");
    let classic = RecordedRunOptions {
        config: None,
        ..rescore_opts.clone()
    };
    let err = rescore("pendulum", &classic).unwrap_err().to_string();
    assert!(err.contains("not an arm experiment"), "{err}");

    // Errors: the directory already holds a run; settings other than the rule differ; the
    // record's scores are not what the replay computes.
    let err = run("vil-gic", &from_full(&same, None), &mut ())
        .unwrap_err()
        .to_string();
    assert!(err.contains("already holds a run"), "{err}");
    let changed = base.join("changed-and-rule.toml");
    std::fs::write(
        &changed,
        text.replace(rule, states_rule)
            .replace("w_std = -0.25", "w_std = -0.5"),
    )
    .unwrap();
    let err = run(
        "vil-gic",
        &from_full(&base.join("x"), Some(changed)),
        &mut (),
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("cost.w_std"), "{err}");
    let tampered = base.join("tampered-source");
    std::fs::create_dir_all(&tampered).unwrap();
    for file in ["rollouts.jsonl", "predictions.jsonl", "policies.jsonl"] {
        std::fs::copy(full.join(file), tampered.join(file)).unwrap();
    }
    let mut cp: serde_json::Value =
        serde_json::from_str(&read(&full.join("checkpoint.json"))).unwrap();
    let score = &mut cp["state"]["episodes"][1]["model_selection"]["refit_score"];
    *score = serde_json::json!(score.as_f64().unwrap() * (1.0 + 1e-6));
    std::fs::write(tampered.join("checkpoint.json"), cp.to_string()).unwrap();
    let err = run(
        "vil-gic",
        &RunOptions {
            replay_from: Some(tampered),
            ..opts(&base.join("y"), None, false)
        },
        &mut (),
    )
    .unwrap_err()
    .to_string();
    assert!(
        err.contains("update 2") && err.contains("does not rebuild"),
        "{err}"
    );
}
