use thiserror::Error;

/// Invalid block definitions and failures of the blocks. Variants say *what* and *why*, so a
/// caller can print them unchanged.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum PilcoError {
    /// Shapes or lengths of a block's definition do not agree.
    #[error("{what}: expected {expected}, got {got}")]
    Shape {
        /// The definition part checked, e.g. `gSat scales (one per index)`.
        what: String,
        /// The required shape as text, e.g. `length 3` or `2×2 (one row per cost dimension)`.
        expected: String,
        /// The shape received, in the same form.
        got: String,
    },
    /// An index points outside the input vector.
    #[error("{what}: index {index} out of range for dimension {dim}")]
    Index {
        /// The index list checked, e.g. `gSat indices`.
        what: String,
        /// The first offending index (0-based).
        index: usize,
        /// The input dimension every index must lie below.
        dim: usize,
    },
    /// A value is outside its allowed range (e.g. `a_min ≥ a_max`, a non-finite weight).
    #[error("{what}: {detail}")]
    Invalid {
        /// The offending value, e.g. `saturation range 1` or `linear policy weights w`.
        what: String,
        /// What is wrong with it, quoting the value.
        detail: String,
    },
    /// The GP engine failed (used by policies built on it).
    #[error(transparent)]
    Gp(#[from] vicpilco_gp::GpError),
}

/// What every fallible constructor and setter of this crate returns.
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
