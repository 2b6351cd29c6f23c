//! `vicpilco --version` names the commit it was built from, the same one runs record.

#[test]
fn version_names_the_build_commit() {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_vicpilco"))
        .arg("--version")
        .output()
        .unwrap();
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert_eq!(
        text.trim(),
        format!("vicpilco {}", vicpilco_experiments::summary::VERSION_TEXT)
    );
    let commit = vicpilco_experiments::summary::BUILD_COMMIT;
    assert!(!commit.is_empty() && text.contains(&format!("(commit {commit})")));
}
