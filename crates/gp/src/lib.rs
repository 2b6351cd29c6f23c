//! # vicpilco-gp: the Gaussian-process engine of PILCO
//!
//! Multi-output GP regression (E independent GPs on shared inputs) with a squared-exponential
//! ARD kernel, trained by maximising the log marginal likelihood, and **moment matching**:
//! pushing a Gaussian input `x ~ N(m, s)` through the GP and returning the exact mean,
//! covariance and input-output covariance of the output, with reverse-mode derivatives.
//!
//! Start from [`GpModel`] (exact GP). This crate knows nothing of policies, costs,
//! environments or the CLI.

#![warn(missing_docs)]

mod error;
pub mod fastexp;
pub mod fd;
pub mod kernel;
pub mod linalg;
mod model;
pub mod moments;
pub mod sparse;
pub mod train;

pub use error::{GpError, Result};
pub use kernel::{Hyper, Kernel, SquaredExponential};
pub use model::{validate_data, GpDataAdjoint, GpModel};
pub use sparse::{DynamicsModel, DynamicsOptions, DynamicsReport, SparseGpModel};
pub use train::{
    nlml, nlml_curb, train, HypCurb, NlmlEval, OutputReport, Termination, TrainOptions, TrainReport,
};
