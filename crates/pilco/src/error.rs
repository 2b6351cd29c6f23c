use thiserror::Error;

/// Invalid block definitions and failures of the blocks. Variants say *what* and *why*, so a
/// caller can print them unchanged.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum PilcoError {
    /// Shapes or lengths of a block's definition do not agree.
    #[error("{what}: expected {expected}, got {got}")]
    Shape {
        what: String,
        expected: String,
        got: String,
    },
    /// An index points outside the input vector.
    #[error("{what}: index {index} out of range for dimension {dim}")]
    Index {
        what: String,
        index: usize,
        dim: usize,
    },
    /// A value is outside its allowed range (e.g. `a_min ≥ a_max`, a non-finite weight).
    #[error("{what}: {detail}")]
    Invalid { what: String, detail: String },
    /// The GP engine failed (used by policies built on it).
    #[error(transparent)]
    Gp(#[from] vicpilco_gp::GpError),
}

pub type Result<T> = std::result::Result<T, PilcoError>;

pub(crate) fn check_len(what: &str, expected: usize, got: usize) -> Result<()> {
    if expected == got {
        Ok(())
    } else {
        Err(PilcoError::Shape {
            what: what.into(),
            expected: format!("length {expected}"),
            got: format!("length {got}"),
        })
    }
}

pub(crate) fn check_indices(what: &str, idx: &[usize], dim: usize) -> Result<()> {
    match idx.iter().find(|&&i| i >= dim) {
        Some(&index) => Err(PilcoError::Index {
            what: what.into(),
            index,
            dim,
        }),
        None => Ok(()),
    }
}

pub(crate) fn check_finite(what: &str, v: &[f64]) -> Result<()> {
    match v.iter().position(|x| !x.is_finite()) {
        Some(i) => Err(PilcoError::Invalid {
            what: what.into(),
            detail: format!("entry {i} is {}", v[i]),
        }),
        None => Ok(()),
    }
}
