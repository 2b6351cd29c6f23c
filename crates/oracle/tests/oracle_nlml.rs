//! Every `nlml/*.json` case of the oracle directory (`VICPILCO_ORACLE_DIR`, default
//! `../shared/oracle`) must pass.

use vicpilco_oracle::{check_files, checkers, default_dir, discover};

#[test]
fn every_nlml_case_matches_pilco() {
    let dir = default_dir();
    if !dir.is_dir() {
        let msg = format!(
            "oracle directory {} not found (set VICPILCO_ORACLE_DIR)",
            dir.display()
        );
        if std::env::var_os("CI").is_some() {
            panic!("{msg}");
        }
        eprintln!("NOTICE: {msg}; skipping the nlml oracle test outside CI");
        return;
    }
    let found = discover(&dir).expect("readable oracle directory");
    let files = found
        .get("nlml")
        .unwrap_or_else(|| panic!("{} holds no nlml/ cases", dir.display()));
    assert!(!files.is_empty(), "no nlml cases in {}", dir.display());
    let all = checkers();
    let checker = all
        .iter()
        .find(|c| c.kind() == "nlml")
        .expect("an nlml checker is registered");
    let report = check_files(*checker, files);
    for f in &report.failures {
        eprintln!("FAIL {f}");
    }
    eprintln!(
        "nlml: {}/{} cases passed, max rel err {:.3e}",
        report.passed, report.cases, report.max_rel_err
    );
    assert_eq!(report.passed, report.cases, "{:#?}", report.failures);
}
