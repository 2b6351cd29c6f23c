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

#[derive(Debug, Error)]
#[non_exhaustive]
pub enum LearnError {
    #[error("prediction set-up: {0}")]
    Spec(String),
    #[error("non-finite prediction: {0}")]
    NonFinite(String),
    #[error(transparent)]
    Gp(#[from] vicpilco_gp::GpError),
    #[error(transparent)]
    Pilco(#[from] vicpilco_pilco::PilcoError),
    #[error("system: {0}")]
    Env(String),
}
