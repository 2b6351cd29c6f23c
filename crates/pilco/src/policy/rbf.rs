//! The RBF-network policy (PILCO's `congp`): the mean of a GP with learnable pseudo-inputs
//! (centres), pseudo-targets and log length-scales, signal std fixed to 1 and noise std fixed
//! (SNR 100 by default, σ_n = 0.01), pushed through moment matching without model
//! uncertainty (`gp2`).
//!
//! Parameters in PILCO's `unwrap` order: `[hyp(:) ((D+2)·E); inputs(:) (N·D); targets(:) (N·E)]`,
//! each column-major; hyp column e is `[log ℓ_1..log ℓ_D, log σ_f, log σ_n]` for output e.
//! The σ_f and σ_n entries are kept in the vector (so it matches PILCO's) but are fixed: their
//! gradient is 0 and [`Policy::set_params`] resets them. The number of *learnable* parameters,
//! `N(D+E) + D·E` (thesis §4-3), is [`RbfPolicy::n_free_params`].

use super::{CentreScale, Policy};
use crate::error::{PilcoError, Result};
use crate::{GaussianBar, Moments, MomentsBar};
use faer::{Mat, MatRef};
use vicpilco_gp::moments::{backward, forward, MmCache, MmModel, MomentsAdjoint};
use vicpilco_gp::{GpModel, Hyper};

/// Signal-to-noise ratio PILCO fixes for its RBF policy.
pub const DEFAULT_SNR: f64 = 100.0;

/// PILCO's `congp`: an RBF network written as the posterior mean of a GP with N learnable
/// centres (pseudo-inputs, N×D), pseudo-targets (N×E) and per-output log length-scales, with
/// σ_f = 1 and σ_n = 1/snr fixed. Its [`Policy::params`] are PILCO's `unwrap` of
/// `{hyp, inputs, targets}`: `[hyp(:) ((D+2)·E); inputs(:) (N·D); targets(:) (N·E)]`, each
/// column-major, the fixed `log σ_f`, `log σ_n` entries of `hyp` included (with zero gradient).
#[derive(Clone, Debug)]
pub struct RbfPolicy {
    gp: GpModel,
    log_sn: f64,
}

impl RbfPolicy {
    /// `centres` N×D, `targets` N×E, `log_ls` D×E (column e for output e), noise std
    /// `1/snr` relative to the fixed signal std 1.
    pub fn new(
        centres: Mat<f64>,
        targets: Mat<f64>,
        log_ls: MatRef<'_, f64>,
        snr: f64,
    ) -> Result<Self> {
        if !(snr.is_finite() && snr > 0.0) {
            return Err(PilcoError::Invalid {
                what: "RBF policy signal-to-noise ratio".into(),
                detail: format!("{snr} must be > 0"),
            });
        }
        // Row d, column e is ℓ of input d for output e: another shape would index out of
        // bounds (too few columns) or be silently ignored (too many).
        if (log_ls.nrows(), log_ls.ncols()) != (centres.ncols(), targets.ncols()) {
            return Err(PilcoError::Shape {
                what: "RBF policy log length-scales log_ls".into(),
                expected: format!(
                    "{}×{} (one row per input, one column per output)",
                    centres.ncols(),
                    targets.ncols()
                ),
                got: format!("{}×{}", log_ls.nrows(), log_ls.ncols()),
            });
        }
        let log_sn = -snr.ln();
        let hyp = (0..targets.ncols())
            .map(|e| Hyper {
                log_ls: (0..log_ls.nrows()).map(|d| log_ls[(d, e)]).collect(),
                log_sf: 0.0,
                log_sn,
            })
            .collect();
        Ok(Self {
            gp: GpModel::new(centres, targets, hyp)?,
            log_sn,
        })
    }

    /// N, the number of basis functions.
    pub fn n_centres(&self) -> usize {
        self.gp.n()
    }

    /// Learnable parameters: `N(D+E) + D·E`.
    pub fn n_free_params(&self) -> usize {
        let (n, d, e) = (self.gp.n(), self.gp.input_dim(), self.gp.output_dim());
        n * (d + e) + d * e
    }

    /// The centres (PILCO's `inputs`), N×D: row i is the centre of basis function i.
    pub fn centres(&self) -> MatRef<'_, f64> {
        self.gp.inputs()
    }

    /// The pseudo-targets (PILCO's `targets`), N×E, column e for action e.
    pub fn targets(&self) -> MatRef<'_, f64> {
        self.gp.targets()
    }

    /// One [`Hyper`] per action: the learnable `log_ls` (D), and the fixed `log_sf = 0` and
    /// `log_sn = −ln snr`.
    pub fn hyp(&self) -> &[Hyper] {
        self.gp.hyp()
    }
}

impl Policy for RbfPolicy {
    type Cache = MmCache;

    fn n_inputs(&self) -> usize {
        self.gp.input_dim()
    }

    fn n_outputs(&self) -> usize {
        self.gp.output_dim()
    }

    fn n_params(&self) -> usize {
        let (n, d, e) = (self.gp.n(), self.gp.input_dim(), self.gp.output_dim());
        (d + 2) * e + n * d + n * e
    }

    fn params(&self) -> Vec<f64> {
        let (n, d, e) = (self.gp.n(), self.gp.input_dim(), self.gp.output_dim());
        let mut p = Vec::with_capacity(self.n_params());
        for h in self.gp.hyp() {
            p.extend(h.to_pilco());
        }
        for c in 0..d {
            p.extend((0..n).map(|i| self.gp.inputs()[(i, c)]));
        }
        for c in 0..e {
            p.extend((0..n).map(|i| self.gp.targets()[(i, c)]));
        }
        p
    }

    /// Centres in units of the current length-scales (per input, the outputs' length-scales
    /// combined as `centres` says); everything else 1. Why: a centre's gradient grows like
    /// 1/ℓ², and with inputs in metres and ℓ ≈ 0.1 m an unscaled step throws centres metres
    /// away from every visited state, where the basis function and its gradient vanish for good.
    fn param_scales(&self, centres: CentreScale) -> Vec<f64> {
        let (n, d, e) = (self.gp.n(), self.gp.input_dim(), self.gp.output_dim());
        let mut scales = vec![1.0; self.n_params()];
        let off = (d + 2) * e;
        for c in 0..d {
            let log_ls = self.gp.hyp().iter().map(|h| h.log_ls[c]);
            let log_scale = match centres {
                CentreScale::GeometricMean => log_ls.sum::<f64>() / e as f64,
                CentreScale::Smallest => log_ls.fold(f64::INFINITY, f64::min),
            };
            scales[off + c * n..off + (c + 1) * n].fill(log_scale.exp());
        }
        scales
    }

    fn set_params(&mut self, p: &[f64]) -> Result<()> {
        let (n, d, e) = (self.gp.n(), self.gp.input_dim(), self.gp.output_dim());
        crate::error::check_len("RBF policy parameters", self.n_params(), p.len())?;
        crate::error::check_finite("RBF policy parameters", p)?;
        let hyp = (0..e)
            .map(|a| Hyper {
                log_ls: p[a * (d + 2)..a * (d + 2) + d].to_vec(),
                log_sf: 0.0,
                log_sn: self.log_sn,
            })
            .collect();
        let off = (d + 2) * e;
        let centres = Mat::from_fn(n, d, |i, c| p[off + c * n + i]);
        let off = off + n * d;
        let targets = Mat::from_fn(n, e, |i, c| p[off + c * n + i]);
        self.gp = GpModel::new(centres, targets, hyp)?;
        Ok(())
    }

    fn forward(&self, m: &[f64], s: MatRef<'_, f64>) -> Result<(Moments, Self::Cache)> {
        Ok(forward(&MmModel::mean_only(&self.gp), m, s)?)
    }

    fn backward(&self, cache: &Self::Cache, bar: &MomentsBar, p_bar: &mut [f64]) -> GaussianBar {
        let (n, d, e) = (self.gp.n(), self.gp.input_dim(), self.gp.output_dim());
        let zero_v = Mat::zeros(d, e);
        let v = bar.v.as_ref().unwrap_or(&zero_v);
        let ia = backward(
            &MmModel::mean_only(&self.gp),
            cache,
            MomentsAdjoint {
                mean: &bar.mean,
                cov: bar.cov.as_ref(),
                v: v.as_ref(),
            },
            true,
        )
        .expect("shapes were checked by the forward pass");
        let full = self
            .gp
            .chain_param_adjoint(ia.params.as_ref().expect("parameter adjoints requested"));
        for a in 0..e {
            // σ_f and σ_n are fixed: their entries get no gradient.
            for r in 0..d {
                p_bar[a * (d + 2) + r] += full.hyp[a][r];
            }
        }
        let off = (d + 2) * e;
        for c in 0..d {
            for i in 0..n {
                p_bar[off + c * n + i] += full.inputs[(i, c)];
            }
        }
        let off = off + n * d;
        for c in 0..e {
            for i in 0..n {
                p_bar[off + c * n + i] += full.targets[(i, c)];
            }
        }
        GaussianBar {
            mean: ia.m,
            cov: ia.s,
        }
    }

    /// Panics when `x` is not of length [`Policy::n_inputs`]: the trait's `action` cannot
    /// fail, and a truncated input would be a wrong action, not a usable one.
    fn action(&self, x: &[f64]) -> Vec<f64> {
        match self.gp.predict(x) {
            Ok((mean, _)) => mean,
            Err(e) => panic!("RBF policy action: {e}"),
        }
    }
}
