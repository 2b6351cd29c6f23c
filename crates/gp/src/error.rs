use thiserror::Error;

/// Everything that can go wrong in the GP engine. Variants carry *where* and *what*, so a
/// caller can print them to a user unchanged.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum GpError {
    /// A data matrix holds NaN or ±inf.
    #[error("{what}: non-finite value {value} at row {row}, column {col}")]
    NonFinite {
        /// Which data, e.g. `"GP training inputs"`.
        what: String,
        /// 0-based row of the first offending entry (for a vector: its index).
        row: usize,
        /// 0-based column of that entry (0 for a vector).
        col: usize,
        /// The offending value: NaN, +inf or −inf.
        value: f64,
    },
    /// Shapes of inputs do not agree.
    #[error("{what}: expected {expected}, got {got}")]
    Shape {
        /// Which argument, e.g. `"GP training targets"`.
        what: String,
        /// The shape required, in words, e.g. `"300 rows (one per input)"`.
        expected: String,
        /// The shape given, in the same words.
        got: String,
    },
    /// A matrix that must be positive definite is not, even after the allowed jitter.
    #[error(
        "{what}: not positive definite (Cholesky failed at pivot {pivot}, after jitter {jitter:e})"
    )]
    NotPositiveDefinite {
        /// Which matrix, e.g. `"K + sn2 I of output 2"`.
        what: String,
        /// 0-based index of the non-positive pivot in the last attempted factorisation.
        pivot: usize,
        /// Largest diagonal jitter tried (absolute; 0 when no jitter was allowed).
        jitter: f64,
    },
    /// A computation produced NaN/inf from finite inputs. Also raised for non-finite
    /// hyper-parameters, a non-positive FITC Γ, a negative variance in a moment-matching input
    /// covariance beyond propagation's cancellation (a small fraction of the input's scale),
    /// and parameter adjoints asked of a moment-matching flavour with model
    /// uncertainty.
    #[error("{what}: numerical breakdown ({detail})")]
    Numerical {
        /// Which quantity, e.g. `"FITC diagonal Γ"`, `"nlml"`.
        what: String,
        /// What went wrong, with the offending entry or values where known.
        detail: String,
    },
    /// The optimiser failed.
    #[error("optimiser: {0}")]
    Optimiser(String),
}

/// [`std::result::Result`] with [`GpError`]: what every fallible function of this crate returns.
pub type Result<T> = std::result::Result<T, GpError>;
