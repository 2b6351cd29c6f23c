//! Checks vicpilco's numbers against reference values computed by the original PILCO MATLAB
//! code (`../shared/oracle`, see its README). Every case file of every kind found in the
//! directory is loaded, so new cases are picked up without code changes. Kinds with no
//! checker yet are reported as skipped, never as passed.

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

#[derive(Debug, Error)]
#[non_exhaustive]
pub enum OracleError {
    #[error("oracle directory {path}: {detail}")]
    Dir { path: PathBuf, detail: String },
    /// The path only: the I/O error is the source, which `{:#}` prints after it.
    #[error("{}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: not valid JSON: {detail}")]
    Parse { path: PathBuf, detail: String },
    #[error("{path}: field `{field}`: {detail}")]
    Field {
        path: PathBuf,
        field: String,
        detail: String,
    },
    #[error("{path}: vicpilco refused the case: {detail}")]
    Compute { path: PathBuf, detail: String },
}

/// A checker computes one kind of case with vicpilco and compares every stored output.
pub trait KindChecker: Sync {
    fn kind(&self) -> &'static str;
    fn check(&self, case: &Case) -> Result<Vec<Comparison>, OracleError>;
}

/// The outcome of all cases of one kind.
#[derive(Clone, Debug, Default)]
pub struct KindReport {
    pub cases: usize,
    pub passed: usize,
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
