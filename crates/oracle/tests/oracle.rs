//! Every case of every oracle kind (`VICPILCO_ORACLE_DIR`, default `../shared/oracle`) must
//! match the original PILCO MATLAB code at the oracle README's tolerance, and every stored
//! output array of a case must actually be compared.

use std::collections::BTreeSet;
use std::path::PathBuf;
use vicpilco_oracle::{checkers, default_dir, discover, Case};

/// The oracle directory, or `None` (with a notice) when the default one is absent outside CI.
fn oracle_dir() -> Option<PathBuf> {
    let explicit = std::env::var_os("VICPILCO_ORACLE_DIR").is_some();
    match locate(default_dir(), explicit, std::env::var_os("CI").is_some()) {
        Found::Dir(dir) => Some(dir),
        Found::Skip(msg) => {
            eprintln!("skipping: {msg}");
            None
        }
        Found::Fail(msg) => panic!("{msg}"),
    }
}

/// What [`locate`] decided.
#[derive(Debug)]
enum Found {
    Dir(PathBuf),
    Skip(String),
    Fail(String),
}

/// `dir` if it is a directory. A directory named in `VICPILCO_ORACLE_DIR` (`explicit`) that is
/// not there fails: whoever set it meant the tests to run, and a typo must not pass them all
/// unchecked. Only the default path may be absent, and only outside CI.
fn locate(dir: PathBuf, explicit: bool, ci: bool) -> Found {
    if dir.is_dir() {
        return Found::Dir(dir);
    }
    if explicit {
        return Found::Fail(format!(
            "VICPILCO_ORACLE_DIR={} is not a directory",
            dir.display()
        ));
    }
    let msg = format!(
        "oracle directory {} not found (set VICPILCO_ORACLE_DIR)",
        dir.display()
    );
    if ci {
        Found::Fail(msg)
    } else {
        Found::Skip(msg)
    }
}

#[test]
fn a_missing_oracle_directory_is_skipped_only_when_it_is_the_default_outside_ci() {
    let missing = std::env::temp_dir().join(format!("vicpilco-no-oracle-{}", std::process::id()));
    for ci in [false, true] {
        let found = locate(missing.clone(), true, ci);
        assert!(
            matches!(&found, Found::Fail(msg) if msg.starts_with("VICPILCO_ORACLE_DIR=")),
            "explicit, CI {ci}: {found:?}"
        );
    }
    let found = locate(missing.clone(), false, true);
    assert!(
        matches!(&found, Found::Fail(msg) if msg.contains("not found")),
        "{found:?}"
    );
    let found = locate(missing, false, false);
    assert!(
        matches!(&found, Found::Skip(msg) if msg.contains("not found")),
        "{found:?}"
    );
    let here = std::env::temp_dir();
    let found = locate(here.clone(), true, false);
    assert!(matches!(&found, Found::Dir(d) if *d == here), "{found:?}");
}

/// `inputs`: the fields of this kind that are inputs; every other field is an output that
/// must be compared.
fn check_kind(kind: &str, inputs: &[&str]) {
    let Some(dir) = oracle_dir() else { return };
    let found = discover(&dir).expect("oracle directory readable");
    let files = found
        .get(kind)
        .unwrap_or_else(|| panic!("no `{kind}` cases in {}", dir.display()));
    assert!(
        !files.is_empty(),
        "no `{kind}` case files in {}",
        dir.display()
    );
    let checker = checkers()
        .into_iter()
        .find(|c| c.kind() == kind)
        .unwrap_or_else(|| panic!("no checker for `{kind}`"));
    let mut failures = Vec::new();
    let mut worst = 0.0f64;
    for f in files {
        let case = Case::load(f).unwrap();
        let comparisons = checker
            .check(&case)
            .unwrap_or_else(|e| panic!("{kind}/{}: {e}", case.name));
        for c in &comparisons {
            worst = worst.max(c.rel_err);
            if !c.passed() {
                failures.push(format!(
                    "{kind}/{}: {} rel err {:.3e} > {:.0e}",
                    case.name, c.field, c.rel_err, c.tol
                ));
            }
        }
        // Nested objects (`prop1`) count as compared when any of their arrays is.
        let compared: BTreeSet<&str> = comparisons
            .iter()
            .map(|c| c.field.split('.').next().unwrap_or_default())
            .collect();
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(f).unwrap()).unwrap();
        for key in json.as_object().unwrap().keys() {
            if !inputs.contains(&key.as_str()) && !["kind", "case", "seed"].contains(&key.as_str())
            {
                assert!(
                    compared.contains(key.as_str()),
                    "{kind}/{}: stored output `{key}` is not compared",
                    case.name
                );
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    eprintln!("{kind}: {} cases, max rel err {worst:.2e}", files.len());
}

const GP_INPUTS: &[&str] = &["D", "E", "N", "inputs", "targets", "hyp", "m", "s"];

#[test]
fn gp0_matches_pilco() {
    check_kind("gp0", GP_INPUTS);
}

#[test]
fn gp1_matches_pilco() {
    check_kind(
        "gp1",
        &[
            "D", "E", "N", "inputs", "targets", "hyp", "m", "s", "M_induce", "induce",
        ],
    );
}

#[test]
fn nlml_matches_pilco() {
    check_kind(
        "nlml",
        &[
            "D",
            "N",
            "inputs",
            "targets",
            "hyp",
            "curb_power",
            "curb_ls",
            "curb_snr",
            "curb_std",
        ],
    );
}

#[test]
fn every_kind_in_the_directory_has_a_checker() {
    let Some(dir) = oracle_dir() else { return };
    let reports = vicpilco_oracle::check_dir(&dir).expect("oracle directory readable");
    let skipped: Vec<&String> = reports
        .iter()
        .filter(|(_, r)| r.skipped)
        .map(|(k, _)| k)
        .collect();
    assert!(skipped.is_empty(), "kinds without a checker: {skipped:?}");
}

#[test]
fn gp2_matches_pilco() {
    check_kind("gp2", GP_INPUTS);
}

#[test]
fn gsat_matches_pilco() {
    check_kind("gSat", &["d", "I", "i_1based", "e", "m", "s"]);
}

#[test]
fn gtrig_matches_pilco() {
    check_kind("gTrig", &["d", "I", "i_1based", "e", "m", "s"]);
}

#[test]
fn loss_sat_matches_pilco() {
    check_kind("lossSat", &["D", "z", "W", "m", "s"]);
}

#[test]
fn conlin_matches_pilco() {
    check_kind("conlin", &["D", "E", "w", "b", "m", "s", "P"]);
}

#[test]
fn congp_matches_pilco() {
    check_kind(
        "congp",
        &["D", "E", "N", "hyp", "inputs", "targets", "m", "s", "P"],
    );
}

#[test]
fn value_matches_pilco() {
    check_kind(
        "value",
        &[
            "policy_type",
            "D0",
            "U",
            "H",
            "gamma",
            "angi_1based",
            "dyni_1based",
            "poli_1based",
            "difi_1based",
            "maxU",
            "dyn_inputs",
            "dyn_targets",
            "dyn_hyp",
            "policy_nc",
            "policy_hyp",
            "policy_inputs",
            "policy_targets",
            "policy_w",
            "policy_b",
            "cost_z",
            "cost_W",
            "m0",
            "S0",
            "P",
        ],
    );
}

/// A case file damaged in a field's shape is an error naming the field, never a panic (one bad
/// file must not take the whole run with it); a kind folder with no case files is an error,
/// not a kind that passes.
#[test]
fn malformed_cases_are_errors_naming_the_field() {
    let Some(dir) = oracle_dir() else { return };
    let found = discover(&dir).expect("oracle directory readable");
    let scratch = std::env::temp_dir().join(format!("vicpilco-oracle-bad-{}", std::process::id()));
    std::fs::create_dir_all(&scratch).unwrap();
    fn longer(v: &serde_json::Value) -> serde_json::Value {
        let mut a = v.as_array().unwrap().clone();
        a.push(serde_json::json!(0.1));
        serde_json::Value::Array(a)
    }
    type Damage = fn(&serde_json::Value) -> serde_json::Value;
    let damages: [(&str, &str, Damage); 9] = [
        ("congp", "hyp", |_| serde_json::json!([[0.5]])),
        ("gp0", "hyp", |_| serde_json::json!([[0.5]])),
        ("nlml", "hyp", |_| serde_json::json!([0.5])),
        ("gSat", "m", longer),
        ("gTrig", "m", longer),
        ("conlin", "m", longer),
        // Stored outputs symmetrised before the comparison: these panicked on an assert.
        ("gp0", "dSds", |_| serde_json::json!([[0.5, 0.5]])),
        ("gp1", "dMds", |_| serde_json::json!([0.5])),
        // The start of a whole prediction: this panicked inside the first step.
        ("value", "m0", longer),
    ];
    for (kind, field, damage) in damages {
        let original = &found[kind][0];
        let mut json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(original).unwrap()).unwrap();
        json[field] = damage(&json[field]);
        let file = scratch.join(format!("{kind}.json"));
        std::fs::write(&file, json.to_string()).unwrap();
        let checker = checkers().into_iter().find(|c| c.kind() == kind).unwrap();
        let err = Case::load(&file)
            .and_then(|case| checker.check(&case))
            .err()
            .unwrap_or_else(|| panic!("{kind}: a damaged `{field}` passed"));
        assert!(
            err.to_string()
                .contains(&format!(": field `{field}`: expected")),
            "{kind}: {err}"
        );
    }
    let empty = scratch.join("empty");
    std::fs::create_dir_all(empty.join("gp0")).unwrap();
    let err = discover(&empty).unwrap_err().to_string();
    assert!(err.contains("holds no case files"), "{err}");
    std::fs::remove_dir_all(&scratch).ok();
}
