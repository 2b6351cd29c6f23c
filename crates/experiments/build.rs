//! Records the commit the crate is built from, so every run can say which code produced each
//! of its updates (`summary.json`'s `sessions`). Without git (a source tarball) it is
//! "unknown"; uncommitted changes to tracked files add "+dirty".

use std::process::Command;

fn git(args: &[&str]) -> Option<String> {
    let out = Command::new("git").args(args).output().ok()?;
    out.status
        .success()
        .then(|| String::from_utf8_lossy(&out.stdout).trim().to_string())
}

fn main() {
    let commit = git(&["rev-parse", "--short=12", "HEAD"]);
    // Without optional locks `status` does not write its refreshed index back: a written index
    // is a file this script watches, and would rebuild the crate once more on the next build.
    let dirty = git(&[
        "--no-optional-locks",
        "status",
        "--porcelain",
        "--untracked-files=no",
    ])
    .is_some_and(|s| !s.is_empty());
    let label = match commit {
        Some(c) if dirty => format!("{c}+dirty"),
        Some(c) => c,
        None => "unknown".into(),
    };
    println!("cargo:rustc-env=VICPILCO_BUILD_COMMIT={label}");
    // Rebuild the label when HEAD moves or the index changes (commits, checkouts, staging).
    if let Some(dir) = git(&["rev-parse", "--absolute-git-dir"]) {
        for file in ["HEAD", "index"] {
            let path = std::path::Path::new(&dir).join(file);
            if path.exists() {
                println!("cargo:rerun-if-changed={}", path.display());
            }
        }
        if let Some(r) = git(&["symbolic-ref", "-q", "HEAD"]) {
            let path = std::path::Path::new(&dir).join(r);
            if path.exists() {
                println!("cargo:rerun-if-changed={}", path.display());
            }
        }
    }
    // ... and when a source file changes, so "+dirty" stays true.
    for dir in [
        "../../crates",
        "../../experiments",
        "../../Cargo.toml",
        "../../Cargo.lock",
    ] {
        println!("cargo:rerun-if-changed={dir}");
    }
}
