//! Checks vicpilco's numbers against reference values computed by the original PILCO MATLAB
//! code (`../shared/oracle`, see its README). Every case file of every kind found in the
//! directory is loaded, so new cases are picked up without code changes. Kinds with no
//! checker yet are reported as skipped, never as passed.

#![warn(missing_docs)]

mod case;
mod compare;
mod kinds;

pub use case::{Case, Tensor};
pub use compare::{compare, Class, Comparison, Tolerance};
pub use kinds::checkers;

use rayon::prelude::*;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use thiserror::Error;

/// Why the oracle directory or one case could not be checked. Every variant names the
/// directory or case file, so the message can be printed unchanged. A case that loads but
/// disagrees with vicpilco is no error: it is a failing [`Comparison`].
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum OracleError {
    /// The directory or one of its `<kind>/` folders cannot be listed, or it holds no kind
    /// folder at all.
    #[error("oracle directory {path}: {detail}")]
    Dir {
        /// The directory that failed.
        path: PathBuf,
        /// The I/O error's message, or what is missing.
        detail: String,
    },
    /// The path only: the I/O error is the source, which `{:#}` prints after it.
    #[error("{}", path.display())]
    Io {
        /// The case file that could not be read.
        path: PathBuf,
        /// The read error.
        source: std::io::Error,
    },
    /// A case file is not JSON, or its top level is not an object.
    #[error("{path}: not valid JSON: {detail}")]
    Parse {
        /// The case file.
        path: PathBuf,
        /// `serde_json`'s message (with line and column), or `top level is not a JSON object`.
        detail: String,
    },
    /// A field a checker needs is missing or has the wrong type or shape (e.g. a vector where
    /// a matrix is expected, a ragged array, a 0 in a `*_1based` index set).
    #[error("{path}: field `{field}`: {detail}")]
    Field {
        /// The case file.
        path: PathBuf,
        /// The JSON key; for a [`Case::sub`] the key inside the nested object (e.g. `dSds`).
        field: String,
        /// What is wrong: `missing`, `expected a matrix, shape [3]`, ….
        detail: String,
    },
    /// vicpilco returned an error for the case's inputs (a constructor or forward pass refused
    /// them), or the sizes of what it built disagree with the case's (`D`, `P`).
    #[error("{path}: vicpilco refused the case: {detail}")]
    Compute {
        /// The case file.
        path: PathBuf,
        /// vicpilco's error message, or which sizes disagree.
        detail: String,
    },
}

/// A checker computes one kind of case with vicpilco and compares every stored output.
pub trait KindChecker: Sync {
    /// The `<kind>/` folder it checks, named after the PILCO function (`gp0`, `gSat`, …).
    fn kind(&self) -> &'static str;
    /// Rebuild `case`'s inputs in vicpilco, compute and compare every array the case stores.
    /// `Err` when a field cannot be read or vicpilco refuses the inputs; an empty vector is
    /// counted as a failure by [`check_files`].
    fn check(&self, case: &Case) -> Result<Vec<Comparison>, OracleError>;
}

/// The outcome of all cases of one kind.
#[derive(Clone, Debug, Default)]
pub struct KindReport {
    /// Case files found, including skipped and unloadable ones.
    pub cases: usize,
    /// Cases that compared at least one array and whose every [`Comparison`] passed.
    pub passed: usize,
    /// Largest [`Comparison::rel_err`] over all arrays of all cases (0 when nothing was
    /// compared); `+∞` when a case failed to load or compute, or an array's shape disagreed.
    pub max_rel_err: f64,
    /// No checker exists for this kind yet.
    pub skipped: bool,
    /// One line per failing case and array (or load error).
    pub failures: Vec<String>,
}

/// The oracle directory tests use: `VICPILCO_ORACLE_DIR`, else `../shared/oracle` beside the
/// repository root.
pub fn default_dir() -> PathBuf {
    if let Some(d) = std::env::var_os("VICPILCO_ORACLE_DIR") {
        return PathBuf::from(d);
    }
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/oracle")
}

/// Every `<kind>/*.json` under `dir`, grouped by kind (sorted, deterministic).
pub fn discover(dir: &Path) -> Result<BTreeMap<String, Vec<PathBuf>>, OracleError> {
    let entries = std::fs::read_dir(dir).map_err(|e| OracleError::Dir {
        path: dir.to_path_buf(),
        detail: e.to_string(),
    })?;
    let mut out = BTreeMap::new();
    for entry in entries.flatten() {
        let p = entry.path();
        if !p.is_dir() {
            continue;
        }
        let kind = entry.file_name().to_string_lossy().to_string();
        let mut files: Vec<PathBuf> = std::fs::read_dir(&p)
            .map_err(|e| OracleError::Dir {
                path: p.clone(),
                detail: e.to_string(),
            })?
            .flatten()
            .map(|e| e.path())
            .filter(|f| f.extension().is_some_and(|x| x == "json"))
            .collect();
        // A kind whose cases went missing must not read as a kind that passes.
        if files.is_empty() {
            return Err(OracleError::Dir {
                path: p,
                detail: "holds no case files (*.json)".into(),
            });
        }
        files.sort();
        out.insert(kind, files);
    }
    if out.is_empty() {
        return Err(OracleError::Dir {
            path: dir.to_path_buf(),
            detail: "holds no <kind>/ folders of case files".into(),
        });
    }
    Ok(out)
}

/// Run one kind's checker over the given files.
pub fn check_files(checker: &dyn KindChecker, files: &[PathBuf]) -> KindReport {
    let results: Vec<(String, Result<Vec<Comparison>, OracleError>)> = files
        .par_iter()
        .map(|f| {
            let name = f
                .file_stem()
                .unwrap_or_default()
                .to_string_lossy()
                .to_string();
            (name, Case::load(f).and_then(|c| checker.check(&c)))
        })
        .collect();
    let mut report = KindReport {
        cases: files.len(),
        ..Default::default()
    };
    for (name, result) in results {
        match result {
            Ok(comparisons) => {
                let mut ok = !comparisons.is_empty();
                for c in &comparisons {
                    report.max_rel_err = report.max_rel_err.max(c.rel_err);
                    if !c.passed() {
                        ok = false;
                        report.failures.push(format!(
                            "{name}: {} rel err {:.3e} > tol {:.0e}",
                            c.field, c.rel_err, c.tol
                        ));
                    }
                }
                if comparisons.is_empty() {
                    report
                        .failures
                        .push(format!("{name}: nothing was compared"));
                }
                report.passed += ok as usize;
            }
            Err(e) => {
                report.max_rel_err = f64::INFINITY;
                report.failures.push(format!("{name}: {e}"));
            }
        }
    }
    report
}

/// Check every kind found under `dir`.
pub fn check_dir(dir: &Path) -> Result<BTreeMap<String, KindReport>, OracleError> {
    let found = discover(dir)?;
    let all = checkers();
    Ok(found
        .into_iter()
        .map(|(kind, files)| {
            let report = match all.iter().find(|c| c.kind() == kind) {
                Some(c) => check_files(*c, &files),
                None => KindReport {
                    cases: files.len(),
                    skipped: true,
                    ..Default::default()
                },
            };
            (kind, report)
        })
        .collect())
}
