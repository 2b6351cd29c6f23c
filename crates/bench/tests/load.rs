//! `W1::load` checks the workload against its declared sizes: a malformed copy of `w1.json`
//! is an error naming the file and the field, never a panic when the problem is built.

use vicpilco_bench::{WorkloadError, W1};

/// The shipped workload as JSON, or `None` (with a notice) where the default `../shared/bench`
/// is absent outside CI. A directory named in `VICPILCO_BENCH_DIR` must hold it: whoever set
/// it meant these tests to run, and a typo must not pass them unchecked.
fn shipped_workload() -> Option<serde_json::Value> {
    let path = vicpilco_bench::default_dir().join("w1.json");
    let may_skip =
        std::env::var_os("CI").is_none() && std::env::var_os("VICPILCO_BENCH_DIR").is_none();
    match std::fs::read_to_string(&path) {
        Ok(text) => Some(serde_json::from_str(&text).unwrap()),
        Err(e) if may_skip => {
            eprintln!("skipping: {}: {e}", path.display());
            None
        }
        Err(e) => panic!("{}: {e}", path.display()),
    }
}

/// `workload` written to a fresh file, loaded.
/// `text` in a temporary file that is removed when the handle drops.
fn written(name: &str, text: &str) -> tempfile::NamedTempFile {
    let file = tempfile::Builder::new()
        .prefix(&format!("vicpilco-w1-{name}-"))
        .suffix(".json")
        .tempfile()
        .unwrap();
    std::fs::write(file.path(), text).unwrap();
    file
}

fn load_written(
    name: &str,
    workload: &serde_json::Value,
) -> (tempfile::NamedTempFile, Result<W1, WorkloadError>) {
    let file = written(name, &workload.to_string());
    let loaded = W1::load(file.path());
    (file, loaded)
}

#[test]
fn the_shipped_workload_loads_and_builds_its_problem() {
    let Some(workload) = shipped_workload() else {
        return;
    };
    let (_, loaded) = load_written("shipped", &workload);
    let w1 = loaded.unwrap();
    w1.problem().unwrap();
    w1.dynamics_gp().unwrap();
}

/// A change that spoils the workload.
type Spoil = fn(&mut serde_json::Value);

#[test]
fn a_malformed_workload_is_refused_naming_the_field() {
    let Some(workload) = shipped_workload() else {
        return;
    };
    let cases: [(&str, Spoil, &str); 4] = [
        (
            "ragged-x",
            |w| drop(w["X"][7].as_array_mut().unwrap().pop()),
            "`X`: expected 300×8, got row 7 has 7 entries",
        ),
        (
            "short-y",
            |w| drop(w["Y"].as_array_mut().unwrap().pop()),
            "`Y`: expected 300×6, got 299 rows",
        ),
        (
            "max-action",
            |w| w["max_action"] = serde_json::json!([1.0]),
            "`max_action`: expected 2 entries, got 1",
        ),
        (
            "cost-dims",
            |w| w["cost_dims"] = serde_json::json!([0, 6]),
            "`cost_dims`: state index 6",
        ),
    ];
    for (name, spoil, expected) in cases {
        let mut bad = workload.clone();
        spoil(&mut bad);
        let (path, loaded) = load_written(name, &bad);
        let err = loaded
            .err()
            .unwrap_or_else(|| panic!("{name}: loaded"))
            .to_string();
        assert!(
            err.starts_with(&path.path().display().to_string()),
            "{name}: {err}"
        );
        assert!(err.contains(expected), "{name}: {err}");
    }
}

/// JSON has no NaN or infinity, and a number beyond the f64 range is refused as it is parsed,
/// so every number of a loaded workload is finite.
#[test]
fn a_number_beyond_the_f64_range_is_a_parse_error() {
    let Some(workload) = shipped_workload() else {
        return;
    };
    let text = workload
        .to_string()
        .replacen("\"gamma\":1.0", "\"gamma\":1e400", 1);
    assert!(
        text.contains("1e400"),
        "the workload's gamma was not written as 1.0"
    );
    let file = written("huge", &text);
    let err = W1::load(file.path()).expect_err("refused").to_string();
    assert!(
        err.contains("not a valid workload: number out of range"),
        "{err}"
    );
}
