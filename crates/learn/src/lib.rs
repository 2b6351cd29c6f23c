//! # vicpilco-learn: long-term prediction, the expected return and its policy gradient
//!
//! * [`joint`]: the joint Gaussian of a step, grown block by block, and its adjoint;
//! * [`step`]: one prediction step (state → policy → squashing → GP → next state), forward and
//!   backward;
//! * [`value`]: the expected return over a horizon and `dJ/dψ` by one reverse sweep;
//! * [`data`]: roll-outs and the GP training set built from them;
//! * [`outer`]: the learning loop over an [`vicpilco_env::Environment`], with checkpoints;
//! * [`selection`]: which dynamics model an update optimises on (PILCO's refit or ours);
//! * [`replay`]: where another selection rule would have parted from a recorded run;
//! * [`start`]: start distributions of the real episodes.

#![warn(missing_docs)]

pub mod data;
pub mod joint;
pub mod outer;
pub mod record;
pub mod replay;
pub mod selection;
pub mod start;
pub mod step;
pub mod value;

use thiserror::Error;

/// Why a prediction, a model fit, a replay or the learning loop failed.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum LearnError {
    /// Parts that do not fit together: out-of-range indices, mismatched dimensions, inverted
    /// bounds, no start distribution, an incomplete checkpoint or replay record. The text
    /// names the field or record at fault.
    #[error("prediction set-up: {0}")]
    Spec(String),
    /// A prediction came out NaN or infinite: an immediate cost (the text names the 1-based
    /// step) or the return at the policy an optimisation starts from.
    #[error("non-finite prediction: {0}")]
    NonFinite(String),
    /// Training a GP, factorising a covariance or moment matching through a GP failed.
    #[error(transparent)]
    Gp(#[from] vicpilco_gp::GpError),
    /// A policy, squashing or cost block rejected its definition, input or parameters.
    #[error(transparent)]
    Pilco(#[from] vicpilco_pilco::PilcoError),
    /// The system refused a reset or a step; the text is its error, prefixed `step t:` (0-based)
    /// for a step.
    #[error("system: {0}")]
    Env(String),
}
