//! `run_to_dir`: the files `vicpilco sim` writes.

use vicpilco_env::arm::run::{run_to_dir, SimOptions, StiffnessSource};
use vicpilco_env::arm::ControllerKind;

#[test]
fn writes_all_files() {
    let out = std::env::var_os("VICPILCO_PLOT_DIR")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| {
            std::env::temp_dir().join(format!("vicpilco-run-{}", std::process::id()))
        });
    for (name, controller, stiffness) in [
        (
            "gic_const",
            ControllerKind::Gic,
            StiffnessSource::Const([250.0, 250.0]),
        ),
        ("sic_ou", ControllerKind::Sic, StiffnessSource::Ou(4)),
    ] {
        let dir = out.join(name);
        let opts = SimOptions {
            controller,
            stiffness,
            ..SimOptions::default()
        };
        let s = run_to_dir(&opts, &dir).unwrap();
        eprintln!(
            "{name}: inserted {}, final x {:.4}, max |f| {:.1} N, real-time factor {:.0}",
            s.inserted, s.final_x, s.max_abs_f, s.real_time_factor
        );
        for f in ["trace.csv", "steps.csv", "summary.json", "plot.png"] {
            let len = std::fs::metadata(dir.join(f)).unwrap().len();
            assert!(len > 1000, "{f}: {len} bytes");
        }
        let trace = std::fs::read_to_string(dir.join("trace.csv")).unwrap();
        assert_eq!(trace.lines().count(), 1 + 10_000);
        let steps = std::fs::read_to_string(dir.join("steps.csv")).unwrap();
        assert_eq!(steps.lines().count(), 1 + 1 + 100);
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap())
                .unwrap();
        assert_eq!(json["inserted"].as_bool(), Some(s.inserted));
        assert!(json["real_time_factor"].as_f64().unwrap() > 0.0);
    }
    if std::env::var_os("VICPILCO_PLOT_DIR").is_none() {
        std::fs::remove_dir_all(&out).ok();
    }
}

/// A runaway arm is not a quiet failure to insert: the summary says why and when the episode
/// ended, and the step that ended it is flagged in steps.csv.
#[test]
fn a_diverged_episode_says_so_in_its_files() {
    let dir = std::env::temp_dir().join(format!("vicpilco-diverged-{}", std::process::id()));
    let opts = SimOptions {
        controller: ControllerKind::Sic,
        stiffness: StiffnessSource::Const([1e6, 1e6]),
        ..SimOptions::default()
    };
    let s = run_to_dir(&opts, &dir).unwrap();
    let why = s
        .stopped_early
        .as_deref()
        .expect("a runaway ends the episode early");
    assert!(why.starts_with("simulation diverged at t = "), "{why}");
    assert!(s.steps < s.config.horizon);
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    assert_eq!(json["stopped_early"].as_str(), Some(why));
    let steps = std::fs::read_to_string(dir.join("steps.csv")).unwrap();
    let mut lines = steps.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = header.iter().position(|&h| h == "diverged").unwrap();
    let flags: Vec<&str> = lines.map(|l| l.split(',').nth(col).unwrap()).collect();
    assert_eq!(flags.last(), Some(&"1"));
    assert!(flags[1..flags.len() - 1].iter().all(|&f| f == "0"));
    // A run to the horizon has no reason.
    let calm = run_to_dir(&SimOptions::default(), &dir).unwrap();
    assert!(calm.stopped_early.is_none());
    std::fs::remove_dir_all(&dir).ok();
}
