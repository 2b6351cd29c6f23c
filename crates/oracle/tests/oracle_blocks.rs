//! Every case of the small-block kinds (`gSat`, `gTrig`, `lossSat`, `conlin`) in the oracle
//! directory passes, and every stored output and derivative array of each case is compared.

use std::collections::BTreeSet;
use vicpilco_oracle::{checkers, default_dir, discover, Case};

const KINDS: [&str; 4] = ["gSat", "gTrig", "lossSat", "conlin"];

/// Input fields of these kinds (everything else in a case file is an output to compare).
const INPUTS: [&str; 16] = [
    "kind", "case", "seed", "d", "I", "i_1based", "e", "m", "s", "D", "E", "w", "b", "P", "z", "W",
];

#[test]
fn every_small_block_case_passes_and_every_array_is_compared() {
    let dir = default_dir();
    if !dir.is_dir() {
        let msg = format!(
            "oracle directory {} not found (set VICPILCO_ORACLE_DIR)",
            dir.display()
        );
        if std::env::var_os("CI").is_some() {
            panic!("{msg}");
        }
        eprintln!("skipping the oracle block cases: {msg}");
        return;
    }
    let found = discover(&dir).expect("oracle directory readable");
    let all = checkers();
    let mut failures = Vec::new();
    let mut n_cases = 0;
    for kind in KINDS {
        let files = found
            .get(kind)
            .unwrap_or_else(|| panic!("no {kind} cases in {}", dir.display()));
        assert!(!files.is_empty(), "no {kind} cases");
        let checker = all
            .iter()
            .find(|c| c.kind() == kind)
            .unwrap_or_else(|| panic!("no checker for {kind}"));
        for f in files {
            n_cases += 1;
            let case = Case::load(f).unwrap();
            let comparisons = checker
                .check(&case)
                .unwrap_or_else(|e| panic!("{kind}/{}: {e}", case.name));
            for c in &comparisons {
                if !c.passed() {
                    failures.push(format!(
                        "{kind}/{}: {} rel err {:.3e} > {:.0e}",
                        case.name, c.field, c.rel_err, c.tol
                    ));
                }
            }
            let compared: BTreeSet<&str> = comparisons.iter().map(|c| c.field.as_str()).collect();
            let text = std::fs::read_to_string(f).unwrap();
            let json: serde_json::Value = serde_json::from_str(&text).unwrap();
            for key in json.as_object().unwrap().keys() {
                if !INPUTS.contains(&key.as_str()) {
                    assert!(
                        compared.contains(key.as_str()),
                        "{kind}/{}: stored array `{key}` is not compared",
                        case.name
                    );
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    eprintln!("{n_cases} small-block oracle cases passed");
}
