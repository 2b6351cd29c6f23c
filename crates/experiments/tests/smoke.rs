//! A cut-down learning run (2 policy updates of the pendulum swing-up) writes every file,
//! records every episode with finite numbers, and the same seed reproduces it exactly.

use vicpilco_experiments::{run, RunOptions};

fn run_once(dir: &std::path::Path, seed: u64) -> serde_json::Value {
    let opts = RunOptions {
        seed,
        out: dir.to_path_buf(),
        episodes: Some(2),
        quick: false,
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
    let _ = std::fs::remove_dir_all(&base);
}

#[test]
fn unknown_experiment_is_an_error_naming_it() {
    let opts = RunOptions {
        seed: 1,
        out: std::env::temp_dir().join("vicpilco-unknown"),
        episodes: Some(1),
        quick: false,
    };
    let err = run("swing-a-cat", &opts, &mut ()).unwrap_err().to_string();
    assert!(
        err.contains("swing-a-cat") && err.contains("pendulum"),
        "{err}"
    );
}

/// `vicpilco run vil-gic --quick`: three short policy updates on the arm, every file written.
#[test]
fn vil_gic_quick_run_writes_its_summary() {
    let dir = std::env::temp_dir().join(format!("vicpilco-vil-quick-{}", std::process::id()));
    let opts = RunOptions {
        seed: 1,
        out: dir.clone(),
        episodes: None,
        quick: true,
    };
    let summary = run("vil-gic", &opts, &mut ()).expect("vil-gic quick run");
    assert_eq!(summary.episodes.len(), vicpilco_experiments::QUICK_EPISODES);
    for e in &summary.episodes {
        assert!(
            e.line_searches <= vicpilco_experiments::QUICK_LENGTH,
            "{e:?}"
        );
        assert!(e.recorded_return.is_finite() && e.recorded_return > 0.0);
        assert!(e.objective_end <= e.objective_start);
    }
    assert!(dir.join("summary.json").is_file() && dir.join("rollouts.jsonl").is_file());
    let _ = std::fs::remove_dir_all(&dir);
}
