//! Check (k), CLI part: `vicpilco sim` writes every file and reports the insertion; a bad
//! stiffness exits non-zero with a message naming the stiffness.

use std::process::Command;

fn vicpilco() -> Command {
    Command::new(env!("CARGO_BIN_EXE_vicpilco"))
}

#[test]
fn sim_writes_files_and_inserts() {
    let dir = std::env::temp_dir().join(format!("vicpilco-cli-sim-{}", std::process::id()));
    let out = vicpilco()
        .args([
            "sim",
            "--controller",
            "gic",
            "--stiffness",
            "const:250,250",
            "--seed",
            "1",
            "--out",
        ])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "stderr: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    for f in ["trace.csv", "steps.csv", "summary.json", "plot.png"] {
        assert!(dir.join(f).is_file(), "missing {f}");
    }
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["inserted"], serde_json::Value::Bool(true));
    assert!(summary["final_x"].as_f64().unwrap() >= 0.745);
    assert!(String::from_utf8_lossy(&out.stdout).contains("inserted: true"));
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn sim_rejects_negative_stiffness() {
    let dir = std::env::temp_dir().join(format!("vicpilco-cli-bad-{}", std::process::id()));
    let out = vicpilco()
        .args([
            "sim",
            "--controller",
            "gic",
            "--stiffness",
            "const:-5,100",
            "--out",
        ])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("stiffness"), "stderr: {err}");
    assert!(err.contains("-5"), "stderr: {err}");
    assert!(!dir.exists());
}

#[test]
fn sim_rejects_unknown_controller() {
    let out = vicpilco()
        .args([
            "sim",
            "--controller",
            "pid",
            "--stiffness",
            "const:5,5",
            "--out",
            "/nonexistent",
        ])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("unknown controller"));
}
