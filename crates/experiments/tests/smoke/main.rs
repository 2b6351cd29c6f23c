//! Cut-down learning runs: 2 policy updates of the pendulum swing-up write every file, record
//! every episode with finite numbers, and the same seed reproduces them exactly; `vil-gic
//! --quick` on the arm resumes bit for bit, and its replay and rescore are in `replay.rs`.

mod replay;

use vicpilco_experiments::summary::Summary;
use vicpilco_experiments::{run, ExperimentError, RunOptions};

fn run_once(dir: &std::path::Path, seed: u64) -> serde_json::Value {
    let opts = RunOptions {
        seed,
        out: dir.to_path_buf(),
        episodes: Some(2),
        quick: false,
        ..Default::default()
    };
    let summary = run("pendulum", &opts, &mut ()).expect("pendulum run");
    assert_eq!(summary.episodes.len(), 2);
    for e in &summary.episodes {
        assert!(e.predicted_return_mean.is_finite() && e.recorded_return.is_finite());
        assert!(
            e.predicted_return_mean > 0.0 && e.predicted_return_mean <= 40.0,
            "{e:?}"
        );
        assert!(e.evaluations > 0 && e.optimise_s > 0.0);
        // The optimiser keeps the best point it saw, so it never ends above its start.
        assert!(e.objective_end <= e.objective_start, "{e:?}");
    }
    let text = std::fs::read_to_string(dir.join("summary.json")).expect("summary.json written");
    let lines =
        std::fs::read_to_string(dir.join("rollouts.jsonl")).expect("rollouts.jsonl written");
    assert_eq!(
        lines.lines().count(),
        3,
        "one initial and two learned roll-outs"
    );
    assert!(dir.join("policy.json").is_file());
    serde_json::from_str(&text).unwrap()
}

#[test]
fn pendulum_two_updates_write_a_reproducible_summary() {
    let base = std::env::temp_dir().join(format!("vicpilco-smoke-{}", std::process::id()));
    let (a, b) = (base.join("a"), base.join("b"));
    let sa = run_once(&a, 7);
    let sb = run_once(&b, 7);
    for key in [
        "experiment",
        "seed",
        "n_params",
        "solved_at_episode",
        "interaction_s",
    ] {
        assert!(sa.get(key).is_some(), "summary.json lacks {key}");
    }
    assert_eq!(
        sa["solved_streak"],
        vicpilco_experiments::summary::SOLVED_STREAK,
        "a report needs the streak to say what solved means"
    );
    let numbers = |s: &serde_json::Value| -> Vec<(f64, f64, bool)> {
        s["episodes"]
            .as_array()
            .unwrap()
            .iter()
            .map(|e| {
                (
                    e["predicted_return_mean"].as_f64().unwrap(),
                    e["recorded_return"].as_f64().unwrap(),
                    e["success"].as_bool().unwrap(),
                )
            })
            .collect()
    };
    assert_eq!(numbers(&sa), numbers(&sb), "same seed, different result");

    // A fresh run into a directory that holds one refuses before writing anything.
    let recorded = std::fs::read(a.join("rollouts.jsonl")).unwrap();
    let again = RunOptions {
        seed: 8,
        out: a.clone(),
        episodes: Some(2),
        ..Default::default()
    };
    let err = run("pendulum", &again, &mut ()).unwrap_err();
    assert!(
        matches!(
            err,
            ExperimentError::RunExists {
                file: "checkpoint.json",
                ..
            }
        ),
        "{err}"
    );
    assert!(err.to_string().contains("--resume"), "{err}");
    assert!(
        err.to_string()
            .contains("a run of `pendulum`, seed 7, 2 updates done"),
        "{err}"
    );
    assert_eq!(std::fs::read(a.join("rollouts.jsonl")).unwrap(), recorded);

    // While another process runs in the directory (holding its lock), a resume is refused
    // before it touches a file.
    let summary_before = std::fs::read(a.join("summary.json")).unwrap();
    let holder = std::fs::OpenOptions::new()
        .write(true)
        .open(a.join(vicpilco_experiments::record::LOCK_FILE))
        .expect("a run leaves its lock file");
    holder.lock().unwrap();
    let busy = RunOptions {
        seed: 7,
        out: a.clone(),
        episodes: Some(3),
        resume: true,
        ..Default::default()
    };
    let err = run("pendulum", &busy, &mut ()).unwrap_err();
    assert!(matches!(err, ExperimentError::RunBusy { .. }), "{err}");
    assert_eq!(
        std::fs::read(a.join("summary.json")).unwrap(),
        summary_before
    );
    drop(holder);

    // A resume asking for fewer updates than the run has cannot undo them: refused, and the
    // record (sessions and wall time included) is left as it was.
    let fewer = RunOptions {
        seed: 7,
        out: a.clone(),
        episodes: Some(1),
        resume: true,
        ..Default::default()
    };
    let err = run("pendulum", &fewer, &mut ()).unwrap_err().to_string();
    assert!(
        err.contains("already has 2 policy updates") && err.contains("--episodes 1"),
        "{err}"
    );
    assert_eq!(
        std::fs::read(a.join("summary.json")).unwrap(),
        summary_before
    );
    assert_eq!(std::fs::read(a.join("rollouts.jsonl")).unwrap(), recorded);
    let _ = std::fs::remove_dir_all(&base);
}

/// A run stopped during its initial roll-out leaves `rollouts.jsonl` alone; a fresh run there
/// refuses too, naming it, as does a replay into it.
#[test]
fn the_initial_roll_out_is_summarised_and_reported_before_the_first_update() {
    use vicpilco_learn::record::{LoopObserver, Phase};
    struct AtFirstUpdate<'a>(&'a std::path::Path, bool);
    impl LoopObserver for AtFirstUpdate<'_> {
        fn phase(&mut self, episode: usize, phase: Phase) {
            if (episode, phase) != (1, Phase::Train) {
                return;
            }
            let text = std::fs::read_to_string(self.0.join("summary.json"))
                .expect("summary.json written after the initial roll-out");
            let summary: Summary = serde_json::from_str(&text).unwrap();
            assert!(summary.episodes.is_empty(), "{summary:?}");
            assert!(summary.initial_return.is_some_and(f64::is_finite));
            assert!(self.0.join("report.html").is_file());
            self.1 = true;
        }
    }
    let dir = tempfile::tempdir().unwrap();
    let opts = RunOptions {
        seed: 3,
        out: dir.path().to_path_buf(),
        episodes: Some(1),
        ..Default::default()
    };
    let mut observer = AtFirstUpdate(dir.path(), false);
    run("pendulum", &opts, &mut observer).expect("pendulum run");
    assert!(observer.1, "update 1 never began training");
}

#[test]
fn a_directory_with_any_record_file_is_not_started_over() {
    let dir = std::env::temp_dir().join(format!("vicpilco-partial-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("rollouts.jsonl"), "").unwrap();
    let fresh = RunOptions {
        seed: 1,
        out: dir.clone(),
        quick: true,
        ..Default::default()
    };
    let err = run("vil-gic", &fresh, &mut ()).unwrap_err().to_string();
    assert!(
        err.contains("already holds a run (rollouts.jsonl)"),
        "{err}"
    );
    let replay = RunOptions {
        replay_from: Some(dir.join("elsewhere")),
        ..fresh
    };
    let err = run("vil-gic", &replay, &mut ()).unwrap_err().to_string();
    assert!(
        err.contains("already holds a run (rollouts.jsonl)"),
        "{err}"
    );
    // A replay of a run that is not there, or a resume of a directory that is not there, is
    // refused without leaving a folder behind.
    let nowhere = dir.join("nowhere");
    for opts in [
        RunOptions {
            out: nowhere.clone(),
            ..replay.clone()
        },
        RunOptions {
            out: nowhere.clone(),
            replay_from: None,
            resume: true,
            ..replay
        },
    ] {
        assert!(run("vil-gic", &opts, &mut ()).is_err());
        assert!(!nowhere.exists(), "{} was made", nowhere.display());
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn unknown_experiment_is_an_error_naming_it() {
    let opts = RunOptions {
        seed: 1,
        out: std::env::temp_dir().join("vicpilco-unknown"),
        episodes: Some(1),
        quick: false,
        ..Default::default()
    };
    let err = run("swing-a-cat", &opts, &mut ()).unwrap_err().to_string();
    assert!(
        err.contains("swing-a-cat") && err.contains("pendulum"),
        "{err}"
    );
}

fn read(path: &std::path::Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// summary.json without the wall-clock timings, which differ between any two runs, and
/// without the list of sessions (a resumed run has one more by design).
fn summary_without_timings(dir: &std::path::Path) -> serde_json::Value {
    let mut v: serde_json::Value = serde_json::from_str(&read(&dir.join("summary.json"))).unwrap();
    v.as_object_mut().unwrap().remove("wall_s");
    v.as_object_mut().unwrap().remove("sessions");
    for e in v["episodes"].as_array_mut().unwrap() {
        let e = e.as_object_mut().unwrap();
        e.remove("train_s");
        e.remove("optimise_s");
    }
    // The time bar's measured value is a wall time too.
    for c in v["thesis_reference"].as_array_mut().unwrap() {
        if c["claim"].as_str().unwrap().contains("wall time") {
            c.as_object_mut().unwrap().remove("measured");
            c.as_object_mut().unwrap().remove("pass");
        }
    }
    v
}

/// Reads `summary.json`'s claim ids and verdicts as each update ends, as a user watching a run
/// (or stopping it) would find them.
struct ClaimsAfterEachUpdate {
    dir: std::path::PathBuf,
    seen: Vec<Vec<(String, Option<bool>)>>,
}

impl vicpilco_learn::record::LoopObserver for ClaimsAfterEachUpdate {
    fn episode_done(&mut self, _record: &vicpilco_learn::record::EpisodeRecord) {
        let v: serde_json::Value =
            serde_json::from_str(&read(&self.dir.join("summary.json"))).unwrap();
        let claims = v["thesis_reference"].as_array().unwrap().iter();
        self.seen.push(
            claims
                .map(|c| (c["id"].as_str().unwrap().to_string(), c["pass"].as_bool()))
                .collect(),
        );
    }
}

/// `vicpilco run vil-gic --quick`: three short policy updates on the arm write every file; a
/// run stopped after update 1 and resumed ends with the same files, timings excepted.
#[test]
fn vil_gic_quick_run_writes_every_file_and_resumes_bit_for_bit() {
    let base = std::env::temp_dir().join(format!("vicpilco-vil-quick-{}", std::process::id()));
    let (full, split) = (base.join("full"), base.join("split"));
    let opts = |out: &std::path::Path, episodes: Option<usize>, resume: bool| RunOptions {
        seed: 1,
        out: out.to_path_buf(),
        episodes,
        quick: true,
        resume,
        ..Default::default()
    };
    let mut watch = ClaimsAfterEachUpdate {
        dir: full.clone(),
        seen: Vec::new(),
    };
    let summary = run("vil-gic", &opts(&full, None, false), &mut watch).expect("vil-gic quick run");
    assert_eq!(summary.episodes.len(), vicpilco_experiments::QUICK_EPISODES);
    // An alias records the name it stands for, so its runs resume and pool as that name's.
    assert_eq!(summary.experiment, "vil-gic-rbf10");
    // A run stopped after any update already lists every claim; those its updates cannot
    // decide yet (here: all of them, three updates being too few) stay open.
    assert_eq!(watch.seen.len(), vicpilco_experiments::QUICK_EPISODES);
    let ids: Vec<&str> = summary
        .thesis_reference
        .iter()
        .map(|c| c.id.as_str())
        .collect();
    for seen in &watch.seen {
        assert_eq!(seen.iter().map(|c| c.0.as_str()).collect::<Vec<_>>(), ids);
        for (id, pass) in seen {
            assert!(pass.is_none(), "{id}: {pass:?}");
        }
    }
    for e in &summary.episodes {
        assert!(
            e.line_searches <= vicpilco_experiments::QUICK_LENGTH,
            "{e:?}"
        );
        assert!(e.recorded_return.is_finite() && e.recorded_return > 0.0);
        assert!(e.objective_end <= e.objective_start);
        assert!(["green", "yellow", "red"].contains(&e.colour.as_str()));
        assert!(e.final_x.is_some_and(|x| x > 0.5) && e.max_force.is_some());
        // The model is chosen on the newest roll-out once a policy has made one.
        match &e.model_selection {
            None => assert_eq!(e.index, 1, "{e:?}"),
            Some(s) => {
                assert!(e.index >= 2 && s.refit_score.is_finite() && s.previous_score.is_finite());
                assert_eq!(s.kept_previous, s.previous_score < s.refit_score);
            }
        }
    }
    assert_eq!(summary.n_params, 68);
    assert!(summary.initial_return.is_some() && summary.constant_gain_return.is_some());
    assert!(summary.constant_gain_inserted.is_some());
    assert!(!summary.thesis_reference.is_empty());
    assert_eq!(summary.config["subnormals"], "flushed to zero");
    for file in [
        "summary.json",
        "checkpoint.json",
        "policy.json",
        "report.html",
        "report.md",
        "returns.png",
        "returns.svg",
        "policy.png",
        "prediction_last.png",
        "cost_last.png",
        "paths.png",
    ] {
        assert!(full.join(file).is_file(), "{file} missing");
    }
    assert_eq!(read(&full.join("rollouts.jsonl")).lines().count(), 4);
    let predictions = read(&full.join("predictions.jsonl"));
    assert_eq!(predictions.lines().count(), 3);
    for line in predictions.lines() {
        let v: serde_json::Value = serde_json::from_str(line).unwrap();
        // The stiffness range of the shipped vil-gic config, which the report's band stops at.
        assert_eq!(
            v["action_bounds"],
            serde_json::json!([[5.0, 250.0], [5.0, 250.0]])
        );
    }
    // The untrained policy and the three updates' policies; the last is policy.json's.
    let policies: Vec<serde_json::Value> = read(&full.join("policies.jsonl"))
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(policies.len(), 4);
    let last: serde_json::Value = serde_json::from_str(&read(&full.join("policy.json"))).unwrap();
    assert_eq!(policies[3]["episode"], 3);
    assert_eq!(policies[3]["params"], last["params"]);
    assert_ne!(policies[2]["params"], last["params"]);

    run("vil-gic", &opts(&split, Some(1), false), &mut ()).expect("first part");
    // Settings other than the number of updates must match.
    let changed = base.join("changed.toml");
    let text = vicpilco_experiments::config::shipped("vil-gic").unwrap().1;
    std::fs::write(&changed, text.replace("w_std = -0.25", "w_std = -0.5")).unwrap();
    let err = run(
        "vil-gic",
        &RunOptions {
            config: Some(changed),
            ..opts(&split, None, true)
        },
        &mut (),
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("cost.w_std"), "{err}");
    // Stopped while appending update 2's roll-out: the cut-off line is dropped on resume.
    let mut rollouts = std::fs::OpenOptions::new()
        .append(true)
        .open(split.join("rollouts.jsonl"))
        .unwrap();
    std::io::Write::write_all(&mut rollouts, b"{\"costs\":[1.0,0.9").unwrap();
    // A run recorded under the alias itself (as runs were before they recorded the name it
    // stands for), resumed under that name: it continues, and records the name.
    let checkpoint = split.join("checkpoint.json");
    let mut cp: serde_json::Value = serde_json::from_str(&read(&checkpoint)).unwrap();
    cp["experiment"] = "vil-gic".into();
    cp["summary"]["experiment"] = "vil-gic".into();
    std::fs::write(&checkpoint, cp.to_string()).unwrap();
    run("vil-gic-rbf10", &opts(&split, None, true), &mut ()).expect("resumed part");

    assert_eq!(
        summary_without_timings(&full),
        summary_without_timings(&split)
    );
    // Each invocation is listed with the first update it computed and the build that ran it.
    let sessions = |dir: &std::path::Path| -> Vec<(u64, String, String)> {
        let v: serde_json::Value = serde_json::from_str(&read(&dir.join("summary.json"))).unwrap();
        v["sessions"]
            .as_array()
            .unwrap()
            .iter()
            .map(|s| {
                assert!(s["started_unix_s"].as_u64().unwrap() > 1_600_000_000);
                (
                    s["first_update"].as_u64().unwrap(),
                    s["commit"].as_str().unwrap().to_string(),
                    s["subnormals"].as_str().unwrap().to_string(),
                )
            })
            .collect()
    };
    let this_build = (
        vicpilco_experiments::summary::BUILD_COMMIT.to_string(),
        "flushed to zero".to_string(),
    );
    let at = |first: u64| (first, this_build.0.clone(), this_build.1.clone());
    assert_eq!(sessions(&full), [at(1)]);
    assert_eq!(sessions(&split), [at(1), at(2)]);
    assert!(!this_build.0.is_empty());
    for file in [
        "rollouts.jsonl",
        "predictions.jsonl",
        "policies.jsonl",
        "policy.json",
    ] {
        assert!(
            read(&full.join(file)) == read(&split.join(file)),
            "{file} differs after resume"
        );
    }
    replay::replaying_a_run_keeps_its_updates_while_the_rules_agree(&base, &full, &opts);
    let _ = std::fs::remove_dir_all(&base);
}

#[test]
fn resuming_without_a_checkpoint_is_an_error_naming_the_file() {
    let dir = std::env::temp_dir().join(format!("vicpilco-no-checkpoint-{}", std::process::id()));
    let opts = RunOptions {
        seed: 1,
        out: dir.clone(),
        quick: true,
        resume: true,
        ..Default::default()
    };
    let err = run("vil-gic", &opts, &mut ()).unwrap_err().to_string();
    assert!(err.contains("checkpoint.json"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `optimiser.scale_params` changes the optimiser's steps, not the objective: the first
/// update starts from the same predicted return with and without it, and ends elsewhere.
#[test]
fn scaling_the_policy_parameters_keeps_the_objective_and_changes_the_search() {
    let base = std::env::temp_dir().join(format!("vicpilco-scaled-{}", std::process::id()));
    let text = vicpilco_experiments::config::shipped("vil-gic").unwrap().1;
    assert!(text.contains("scale_params = true"));
    let raw = base.join("raw.toml");
    std::fs::create_dir_all(&base).unwrap();
    std::fs::write(
        &raw,
        text.replace("scale_params = true", "scale_params = false"),
    )
    .unwrap();
    let first_update = |name: &str, config: Option<std::path::PathBuf>| {
        let opts = RunOptions {
            seed: 3,
            out: base.join(name),
            episodes: Some(1),
            quick: true,
            config,
            ..Default::default()
        };
        let summary = run("vil-gic", &opts, &mut ()).expect("vil-gic quick run");
        let e = &summary.episodes[0];
        (e.objective_start, e.objective_end)
    };
    let (start_scaled, end_scaled) = first_update("scaled", None);
    let (start_raw, end_raw) = first_update("raw", Some(raw));
    assert!(
        (start_scaled - start_raw).abs() <= 1e-9 * start_raw.abs(),
        "{start_scaled} vs {start_raw}"
    );
    assert!(end_scaled.is_finite() && end_raw.is_finite());
    assert!(end_scaled != end_raw, "both searches ended at {end_raw}");
    let _ = std::fs::remove_dir_all(&base);
}
