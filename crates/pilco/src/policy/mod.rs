//! Policies: maps from a Gaussian input `x ~ N(m, s)` to a Gaussian action with mean,
//! covariance and `V = s⁻¹ Cov[x, u]`, plus a reverse-mode backward for the input **and** the
//! parameters.
//!
//! The learning loop chains hundreds of policy calls per predicted trajectory and needs
//! `dJ/dψ` from one backward sweep, so the backward *accumulates* the parameter adjoints into
//! a caller-owned buffer (one per trajectory) instead of returning a fresh vector per step.
//!
//! The policy sees its own input vector: choosing which state dimensions (and optionally time)
//! enter it, and any squashing of the output ([`crate::squash`]), happen outside the policy.

mod linear;
mod rbf;

pub use linear::{LinearCache, LinearPolicy};
pub use rbf::{RbfPolicy, DEFAULT_SNR};

use crate::{GaussianBar, Moments, MomentsBar, Result};
use faer::MatRef;
use serde::{Deserialize, Serialize};

/// Which length-scale an RBF centre coordinate is measured in when the optimiser searches over
/// scaled parameters ([`Policy::param_scales`]). The centres are shared by all outputs while
/// each output has its own length-scales, so one value per input has to be chosen.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum CentreScale {
    /// The geometric mean over the outputs: every output's steps are equally (mis)sized.
    #[default]
    GeometricMean,
    /// The smallest over the outputs: a unit step moves a centre by at most one length-scale
    /// of the output with the narrowest basis functions, so no step can carry the centres
    /// out of that output's reach (where its basis functions and their gradient vanish).
    Smallest,
}

/// A policy on Gaussian inputs, with reverse-mode derivatives.
///
/// Implemented by [`LinearPolicy`] (PILCO's `conlin`); the RBF policy (PILCO's `congp`, a
/// deterministic GP using the GP crate's `gp2` moment matching) implements it too.
pub trait Policy {
    /// What [`Policy::backward`] needs from [`Policy::forward`].
    type Cache: Send + Sync;

    /// D, the length of the policy input.
    fn n_inputs(&self) -> usize;

    /// E, the number of (unsquashed) actions.
    fn n_outputs(&self) -> usize;

    /// P, the number of learnable parameters.
    fn n_params(&self) -> usize;

    /// The parameters as a flat vector in PILCO's `unwrap` order: the fields of the
    /// parameter struct in alphabetical order, each array vectorised column-major (for the
    /// linear policy `[b; w(:)]`).
    fn params(&self) -> Vec<f64>;

    /// Set the parameters from a flat vector in the order of [`Policy::params`].
    fn set_params(&mut self, p: &[f64]) -> Result<()>;

    /// Mean `M` (E), covariance `S` (E×E) and `V = s⁻¹Cov[x, u]` (D×E) of the action for
    /// `x ~ N(m, s)`, and the cache for the backward. An `m` or `s` not of D entries is an
    /// error, not a panic.
    fn forward(&self, m: &[f64], s: MatRef<'_, f64>) -> Result<(Moments, Self::Cache)>;

    /// Vector-Jacobian product. Given the adjoints of `(M, S, V)` (`bar.v` is `V̄`), **add**
    /// `∂f/∂p` to `p_bar` (length P, same order as [`Policy::params`]) and return the adjoints
    /// of `(m, s)` (`s̄` symmetrised, see the crate docs).
    fn backward(&self, cache: &Self::Cache, bar: &MomentsBar, p_bar: &mut [f64]) -> GaussianBar;

    /// The deterministic (unsquashed) action for a known input `x`. Panics unless `x` has
    /// length [`Policy::n_inputs`]: this cannot fail otherwise, and its caller (the learning
    /// loop's `act`) builds `x` from a layout checked against the policy before a run.
    fn action(&self, x: &[f64]) -> Vec<f64>;

    /// A typical size of each parameter (same order as [`Policy::params`]), for an optimiser
    /// that should see every parameter on a comparable scale: it may search over `p / scale`
    /// instead of `p`. The policy itself is unchanged. `centres` says which length-scale
    /// measures a centre (policies without centres ignore it). Default: all ones (PILCO's raw
    /// parameters).
    fn param_scales(&self, centres: CentreScale) -> Vec<f64> {
        let _ = centres;
        vec![1.0; self.n_params()]
    }
}
