//! The runs stored in the repository (results/README.md, probes/README.md), for the tests that
//! read them all (this crate's `results.rs`, and `recheck.rs` in vicpilco-experiments, which
//! includes this file with `#[path]`). `scripts/recheck-stored` walks the same layout:
//! `results/<experiment>-seed<S>/`, run with the shipped settings, and
//! `probes/<probe>/<experiment>-seed<S>/`, run with `probes/<probe>/<experiment>.toml` where
//! the probe has one (probes of more seeds of the shipped settings have none).

// Each including test uses its own part of this.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

/// A folder of the repository (both including crates sit at `crates/<name>`).
pub fn repo_dir(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(name)
}

/// The sub-folders of `dir`, sorted; none when `dir` does not exist.
pub fn folders(dir: &Path) -> Vec<PathBuf> {
    let mut dirs: Vec<PathBuf> = match std::fs::read_dir(dir) {
        Ok(entries) => entries
            .map(|e| e.expect("readable directory entry").path())
            .filter(|p| p.is_dir())
            .collect(),
        Err(_) => Vec::new(),
    };
    dirs.sort();
    dirs
}

/// The runs of `results/`.
pub fn result_runs() -> Vec<PathBuf> {
    folders(&repo_dir("results"))
}

/// Each probe's runs, as its own group (a probe may repeat a seed of results/).
pub fn probe_groups() -> Vec<Vec<PathBuf>> {
    folders(&repo_dir("probes"))
        .iter()
        .map(|probe| folders(probe))
        .collect()
}

/// Every stored run: results/, then each probe's.
pub fn every_run() -> Vec<PathBuf> {
    result_runs()
        .into_iter()
        .chain(probe_groups().into_iter().flatten())
        .collect()
}

/// The settings file a stored run was run with: its probe's `<experiment>.toml`, or `None`
/// for the shipped settings.
pub fn settings_file(run: &Path) -> Option<PathBuf> {
    if !run.starts_with(repo_dir("probes")) {
        return None;
    }
    let probe = run.parent()?;
    let name = run.file_name()?.to_string_lossy().into_owned();
    let experiment = name.rsplit_once("-seed").map_or(name.as_str(), |(e, _)| e);
    let config = probe.join(format!("{experiment}.toml"));
    config.is_file().then_some(config)
}
