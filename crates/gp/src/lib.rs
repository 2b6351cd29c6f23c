//! # vicpilco-gp: the Gaussian-process engine of PILCO
//!
//! Multi-output GP regression (E independent GPs on shared inputs) with a squared-exponential
//! ARD kernel, trained by maximising the log marginal likelihood (with PILCO's hypCurb penalty on
//! extreme hyper-parameters by default), exact or sparse (FITC, [`SparseGpModel`]), and
//! **moment matching**:
//! pushing a Gaussian input `x ~ N(m, s)` through the GP and returning the exact mean,
//! covariance and input-output covariance of the output, with reverse-mode derivatives.
//!
//! Start from [`GpModel`] (exact GP); [`DynamicsModel`] is the learner's model, which picks the
//! exact or the sparse GP by the size of its training set. This crate knows nothing of policies, costs,
//! environments or the CLI.
//!
//! ## Example
//!
//! Fit a GP to 40 samples of `sin x` (PILCO's first guess of the hyper-parameters, then the
//! penalised likelihood), predict at a known input, and push an uncertain input
//! `x ~ N(0.5, 0.3²)` through it. For `sin` the moments are known in closed form,
//! `E[sin x] = e^{−s/2} sin m` and `Var[sin x] = ½(1 − e^{−2s} cos 2m) − e^{−s} sin² m`, and
//! moment matching on the fitted GP reproduces them:
//!
//! ```
//! use faer::Mat;
//! use vicpilco_gp::moments::{forward, MmModel};
//! use vicpilco_gp::train::initial_hyper;
//! use vicpilco_gp::{train, GpModel, TrainOptions};
//!
//! let n = 40;
//! let x = Mat::from_fn(n, 1, |i, _| -3.0 + 6.0 * i as f64 / (n - 1) as f64);
//! let y = Mat::from_fn(n, 1, |i, _| x[(i, 0)].sin());
//! let start = initial_hyper(x.as_ref(), y.as_ref());
//! let (hyp, report) = train(x.as_ref(), y.as_ref(), &start, &TrainOptions::default())?;
//! assert!(report.outputs[0].objective.is_finite());
//! let gp = GpModel::new(x, y, hyp)?;
//!
//! let (mean, var) = gp.predict(&[0.5])?;
//! assert!((mean[0] - 0.5f64.sin()).abs() < 1e-3 && var[0] < 1e-4);
//!
//! let (m, s) = (0.5f64, 0.09f64);
//! let s_mat = Mat::from_fn(1, 1, |_, _| s);
//! let (out, _cache) = forward(&MmModel::with_uncertainty(&gp), &[m], s_mat.as_ref())?;
//! let exact_mean = (-s / 2.0).exp() * m.sin();
//! let exact_var =
//!     0.5 * (1.0 - (-2.0 * s).exp() * (2.0 * m).cos()) - (-s).exp() * m.sin().powi(2);
//! assert!((out.mean[0] - exact_mean).abs() < 1e-3);
//! assert!((out.cov[(0, 0)] - exact_var).abs() < 1e-3);
//! # Ok::<(), vicpilco_gp::GpError>(())
//! ```

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
