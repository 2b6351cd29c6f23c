//! The normalised quadratic energy cost on actions (thesis eqs. 4-9, 4-10).
//!
//! `c_a(a) = aᵀ S⁻¹ a` with `S = diag(a_max,1², …, a_max,U²)`; a dimension is excluded from the
//! penalty by setting its entry of `S⁻¹` to 0 (used for the reference-action part of the
//! policy). Write `Λ = S⁻¹` (diagonal). For `a ~ N(μ, Σ)`:
//!
//! * `E[c_a] = tr(ΛΣ) + μᵀΛμ`;
//! * `Var[c_a] = 2 tr(ΛΣΛΣ) + 4 μᵀΛΣΛμ` (Gaussian quadratic form);
//! * `C = Σ⁻¹ Cov[a, c_a] = 2Λμ` (since `Cov[a, aᵀΛa] = 2ΣΛμ`).
//!
//! Derivatives: `∂E/∂μ = 2Λμ`, `∂E/∂Σ = Λ`, `∂Var/∂μ = 8ΛΣΛμ`,
//! `∂Var/∂Σ = 4ΛΣΛ + 4(Λμ)(Λμ)ᵀ`, `∂C/∂μ = 2Λ`.

use crate::error::{check_len, PilcoError, Result};
use crate::util::{assert_input, symmetrise};
use crate::{CostBar, CostMoments, GaussianBar};
use faer::{Mat, MatRef};

/// `aᵀ S⁻¹ a`, `S = diag(a_max²)`, with excludable dimensions.
#[derive(Clone, Debug)]
pub struct EnergyCost {
    /// Diagonal of `Λ = S⁻¹` (0 for excluded dimensions).
    lambda: Vec<f64>,
}

/// What [`EnergyCost::backward`] needs: `μ`, `Λμ` and `ΛΣΛ`.
#[derive(Clone, Debug)]
pub struct EnergyCache {
    mu: Vec<f64>,
    lam_mu: Vec<f64>,
    lsl: Mat<f64>,
}

impl EnergyCost {
    /// `a_max[i] > 0` is the amplitude of action i; `penalised[i] = false` excludes it.
    pub fn new(a_max: &[f64], penalised: &[bool]) -> Result<Self> {
        check_len(
            "energy cost: penalised flags (one per action)",
            a_max.len(),
            penalised.len(),
        )?;
        let mut lambda = Vec::with_capacity(a_max.len());
        for (i, (&a, &p)) in a_max.iter().zip(penalised).enumerate() {
            if !(a.is_finite() && a > 0.0) {
                return Err(PilcoError::Invalid {
                    what: format!("energy cost: a_max of action {i}"),
                    detail: format!("{a} is not a positive finite number"),
                });
            }
            lambda.push(if p { 1.0 / (a * a) } else { 0.0 });
        }
        Ok(Self { lambda })
    }

    /// Directly from the diagonal of `S⁻¹` (entries ≥ 0).
    pub fn from_inverse_diag(lambda: &[f64]) -> Result<Self> {
        if let Some(i) = lambda.iter().position(|l| !(l.is_finite() && *l >= 0.0)) {
            return Err(PilcoError::Invalid {
                what: format!("energy cost: S⁻¹ entry {i}"),
                detail: format!("{} is not a non-negative finite number", lambda[i]),
            });
        }
        Ok(Self {
            lambda: lambda.to_vec(),
        })
    }

    /// U, the length of the action `a`, excluded dimensions included.
    pub fn n_inputs(&self) -> usize {
        self.lambda.len()
    }

    /// The diagonal of `S⁻¹`.
    pub fn inverse_diag(&self) -> &[f64] {
        &self.lambda
    }

    /// The deterministic cost `aᵀ S⁻¹ a`.
    pub fn eval(&self, a: &[f64]) -> f64 {
        a.iter().zip(&self.lambda).map(|(x, l)| l * x * x).sum()
    }

    /// Mean, variance and `C` of `c_a` for `a ~ N(mu, sigma)` (eq. 4-10).
    pub fn forward(&self, mu: &[f64], sigma: MatRef<'_, f64>) -> (CostMoments, EnergyCache) {
        let n = self.lambda.len();
        assert_input("energy cost", n, mu, sigma);
        let l = &self.lambda;
        let lam_mu: Vec<f64> = (0..n).map(|i| l[i] * mu[i]).collect();
        let lsl = Mat::from_fn(n, n, |i, j| l[i] * sigma[(i, j)] * l[j]);
        let mut mean = 0.0;
        let mut tr2 = 0.0;
        let mut quad = 0.0;
        for i in 0..n {
            mean += l[i] * sigma[(i, i)] + mu[i] * lam_mu[i];
            for j in 0..n {
                tr2 += lsl[(i, j)] * sigma[(j, i)];
                quad += mu[i] * lsl[(i, j)] * mu[j];
            }
        }
        let var = 2.0 * tr2 + 4.0 * quad;
        let c = lam_mu.iter().map(|v| 2.0 * v).collect();
        (
            CostMoments { mean, var, v: c },
            EnergyCache {
                mu: mu.to_vec(),
                lam_mu,
                lsl,
            },
        )
    }

    /// Adjoints of `(E[c_a], Var[c_a], C)` → adjoints of `(μ, Σ)`.
    pub fn backward(&self, cache: &EnergyCache, bar: &CostBar) -> GaussianBar {
        let n = self.lambda.len();
        let l = &self.lambda;
        let EnergyCache { mu, lam_mu, lsl } = cache;
        let mut out = GaussianBar::zeros(n);
        for i in 0..n {
            let lslmu: f64 = (0..n).map(|j| lsl[(i, j)] * mu[j]).sum();
            out.mean[i] = 2.0 * bar.mean * lam_mu[i] + 8.0 * bar.var * lslmu;
            if let Some(cb) = &bar.v {
                out.mean[i] += 2.0 * l[i] * cb[i];
            }
            out.cov[(i, i)] += bar.mean * l[i];
            for j in 0..n {
                out.cov[(i, j)] += 4.0 * bar.var * (lsl[(i, j)] + lam_mu[i] * lam_mu[j]);
            }
        }
        symmetrise(&mut out.cov);
        out
    }
}
