use thiserror::Error;

/// Everything that can go wrong in the GP engine. Variants carry *where* and *what*, so a
/// caller can print them to a user unchanged.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum GpError {
    /// A data matrix holds NaN or ±inf.
    #[error("{what}: non-finite value {value} at row {row}, column {col}")]
    NonFinite {
        what: String,
        row: usize,
        col: usize,
        value: f64,
    },
    /// Shapes of inputs do not agree.
    #[error("{what}: expected {expected}, got {got}")]
    Shape {
        what: String,
        expected: String,
        got: String,
    },
    /// A matrix that must be positive definite is not, even after the allowed jitter.
    #[error(
        "{what}: not positive definite (Cholesky failed at pivot {pivot}, after jitter {jitter:e})"
    )]
    NotPositiveDefinite {
        what: String,
        pivot: usize,
        jitter: f64,
    },
    /// A computation produced NaN/inf from finite inputs.
    #[error("{what}: numerical breakdown ({detail})")]
    Numerical { what: String, detail: String },
    /// The optimiser failed.
    #[error("optimiser: {0}")]
    Optimiser(String),
}

pub type Result<T> = std::result::Result<T, GpError>;
