//! # vicpilco-pilco: PILCO's small moment-matching blocks, built for reverse mode
//!
//! PILCO predicts a whole trial as a chain of Gaussians. Every link of that chain is a
//! *block* that maps a Gaussian input `x ~ N(m, s)` to the exact (or moment-matched) mean,
//! covariance and input-output term of its output. This crate holds the small blocks:
//!
//! | block | PILCO function | thesis | type |
//! |---|---|---|---|
//! | sine saturation `e·(9 sin x + sin 3x)/8` | `gSat` | eq. 4-22 | [`squash::SineSat`] |
//! | partial non-negative saturation (gains on `[a_min, a_max]`) | — | eq. 4-23 (corrected) | [`squash::PartialSat`] |
//! | trigonometric augmentation `(sin θ, cos θ)` | `gTrig` | — | [`squash::TrigAug`] |
//! | saturating cost(s) `1 − exp(−½(x−z)ᵀW(x−z))`, sums of them | `lossSat` | eq. 4-8 | [`cost::SaturatingCost`], [`cost::CostSum`] |
//! | normalised quadratic energy cost `aᵀS⁻¹a` | — | eqs. 4-9, 4-10 | [`cost::EnergyCost`] |
//! | linear policy `u = w x + b` | `conlin` | eq. 3-21 | [`policy::LinearPolicy`] |
//! | RBF policy: a GP's mean with learnable support points and targets | `conGP` | §4-3, eqs. 4-17, 4-18 | [`policy::RbfPolicy`] |
//!
//! ## Conventions (all blocks)
//!
//! * Input `x ~ N(m, s)`: `m` a slice of length D, `s` a symmetric D×D [`faer::Mat`].
//! * Output [`Moments`] (the GP crate's type): mean `M`, covariance `S` and
//!   `v = s⁻¹ Cov[x, y]`, D×E (PILCO's `C` for `gSat`, `gTrig`, `lossSat`; `V` for policies
//!   and GPs). Scalar-valued costs return [`CostMoments`].
//!   (`C`, `V` below both mean this term.)
//! * **Forward** returns the outputs and an opaque cache; **backward** is the vector-Jacobian
//!   product: it takes the adjoints of the outputs (`M̄, S̄, V̄` in [`MomentsBar`]; `V̄`
//!   optional) and returns the adjoints of the input distribution ([`GaussianBar`]).
//! * **Adjoint of a covariance input.** `s̄` is the plain gradient `∂f/∂s_kl` with the
//!   entries of `s` treated as independent, then symmetrised, `(G + Gᵀ)/2`. With this,
//!   `df = Σ_kl s̄_kl ds_kl` for every *symmetric* perturbation `ds`, which is all a covariance
//!   can undergo, and it is the form the oracle stores. Output adjoints `S̄` need not be
//!   symmetric: `S̄_ij` is the adjoint of the entry `S_ij` as computed.
//! * Policies additionally accumulate parameter adjoints into a caller-owned buffer in PILCO's
//!   flat `unwrap` order (see [`policy::Policy`]), so one backward sweep over a trajectory
//!   builds `dJ/dψ` without per-step allocations of parameter length.
//!
//! Shapes are validated by constructors (returning [`PilcoError`]). The policies' `forward`
//! checks its input too (an error naming it); the squashing and cost blocks, which run inside
//! the horizon's loop, treat an input of the wrong dimension as a programming error and panic
//! with a message.
//!
//! Every derivative here is checked against central finite differences
//! (`vicpilco_gp::fd`) and, for `gSat`, `gTrig`, `lossSat`, `conlin` and `conGP` (the RBF
//! policy), against the original
//! PILCO MATLAB code (`vicpilco-oracle`).
//!
//! ## Example
//!
//! Squash a policy's two raw outputs, a stiffness onto `[5, 250]` N/m and a reference
//! increment onto `±2.5` mm, for an uncertain raw output `x ~ N(m, s)`; check the stiffness's
//! mean against a quadrature of the deterministic map, and its derivative with respect to
//! `m₀` from the backward pass against a central difference of the forward pass:
//!
//! ```
//! use faer::Mat;
//! use vicpilco_pilco::squash::{PartialSat, SatRange};
//! use vicpilco_pilco::MomentsBar;
//!
//! let ranges = [
//!     SatRange::Bounded { a_min: 5.0, a_max: 250.0 },
//!     SatRange::Symmetric { a_max: 0.0025 },
//! ];
//! let sat = PartialSat::new(2, &[0, 1], &ranges)?;
//! let (m, sd) = ([0.4, -0.2], [0.3, 0.1]);
//! let s = Mat::from_fn(2, 2, |i, j| if i == j { sd[i] * sd[i] } else { 0.0 });
//! let (out, cache) = sat.forward(&m, s.as_ref());
//!
//! // E[k] by the midpoint rule over ±8 standard deviations of x₀.
//! let steps = 4000;
//! let width = 16.0 * sd[0] / steps as f64;
//! let quadrature: f64 = (0..steps)
//!     .map(|i| {
//!         let z = -8.0 + 16.0 * (i as f64 + 0.5) / steps as f64;
//!         let density = (-0.5 * z * z).exp() / (sd[0] * (2.0 * std::f64::consts::PI).sqrt());
//!         sat.apply(&[m[0] + sd[0] * z, m[1]])[0] * density * width
//!     })
//!     .sum();
//! assert!((out.mean[0] - quadrature).abs() < 1e-9 * 250.0);
//! assert!(out.mean[0] > 5.0 && out.mean[0] < 250.0);
//!
//! // Reverse mode: the adjoint of E[k] alone gives ∂E[k]/∂m.
//! let mut bar = MomentsBar::zeros(2);
//! bar.mean[0] = 1.0;
//! let grad = sat.backward(&cache, &bar);
//! let h = 1e-6;
//! let mean_k_at = |m0: f64| sat.forward(&[m0, m[1]], s.as_ref()).0.mean[0];
//! let central = (mean_k_at(m[0] + h) - mean_k_at(m[0] - h)) / (2.0 * h);
//! assert!((grad.mean[0] - central).abs() < 1e-6 * central.abs());
//! assert_eq!(grad.mean[1], 0.0);
//! # Ok::<(), vicpilco_pilco::PilcoError>(())
//! ```

#![warn(missing_docs)]

pub mod cost;
mod error;
pub mod policy;
pub mod squash;
mod util;

pub use error::{PilcoError, Result};

use faer::Mat;

/// Mean `mean` (E), covariance `cov` (E×E) and input-output term `v = s⁻¹ Cov[x, y]` (D×E;
/// PILCO's `C` for `gSat`/`gTrig`, `V` for policies and GPs) of a block's output `y` for
/// `x ~ N(m, s)`. The same type as the GP moment matching returns, so blocks chain freely.
pub use vicpilco_gp::moments::Moments;

/// Adjoints of a block's outputs (`M̄`, `S̄`, `V̄`/`C̄`); `v = None` means `V̄ = 0`.
#[derive(Clone, Debug)]
pub struct MomentsBar {
    /// `M̄` (E): adjoint of the output mean.
    pub mean: Vec<f64>,
    /// `S̄` (E×E): `S̄_ij` is the adjoint of the entry `S_ij` as computed (need not be symmetric).
    pub cov: Mat<f64>,
    /// `V̄` / `C̄` (D×E): adjoint of `v = s⁻¹ Cov[x, y]`; `None` when nothing depends on `v`.
    pub v: Option<Mat<f64>>,
}

impl MomentsBar {
    /// All-zero adjoints for a block with E outputs (`V̄ = None`).
    pub fn zeros(e: usize) -> Self {
        Self {
            mean: vec![0.0; e],
            cov: Mat::zeros(e, e),
            v: None,
        }
    }
}

/// Adjoints of an input Gaussian: `m̄` and the symmetrised `s̄` (see the crate docs).
#[derive(Clone, Debug)]
pub struct GaussianBar {
    /// `m̄` (D): `∂f/∂m`.
    pub mean: Vec<f64>,
    /// `s̄` (D×D): `∂f/∂s` with the entries of `s` independent, symmetrised `(G + Gᵀ)/2`.
    pub cov: Mat<f64>,
}

impl GaussianBar {
    /// All-zero adjoints of a D-dimensional input: the start of an accumulation, or of a unit
    /// adjoint with one entry set.
    pub fn zeros(d: usize) -> Self {
        Self {
            mean: vec![0.0; d],
            cov: Mat::zeros(d, d),
        }
    }
}

/// Mean, variance and input-output term of a scalar cost `c(x)` for `x ~ N(m, s)`.
#[derive(Clone, Debug)]
pub struct CostMoments {
    /// `E[c]`.
    pub mean: f64,
    /// `Var[c]` (for saturating costs clamped to 0 below 1e-12, as PILCO's `lossSat`).
    pub var: f64,
    /// `s⁻¹ Cov[x, c]`, length D (PILCO's `C`; equals `∂E[c]/∂m`).
    pub v: Vec<f64>,
}

/// Adjoints of a scalar cost's outputs; `v = None` means zero.
#[derive(Clone, Debug, Default)]
pub struct CostBar {
    /// Adjoint of `E[c]`.
    pub mean: f64,
    /// Adjoint of `Var[c]`; for saturating costs it acts on the unclamped variance.
    pub var: f64,
    /// `C̄` (D): adjoint of `s⁻¹ Cov[x, c]`; `None` when nothing depends on it.
    pub v: Option<Vec<f64>>,
}
