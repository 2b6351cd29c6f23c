//! The Gaussian integral behind every saturating-cost moment:
//! `E[exp(−q(x))]` for `x ~ N(m, s)` and a positive semi-definite quadratic
//! `q(x) = Σ_k ½ (x_{J_k} − z_k)ᵀ W_k (x_{J_k} − z_k)` (a sum of one or more cost exponents,
//! each on its own subset `J_k` of the dimensions).
//!
//! Only the union `J` of the subsets matters, so everything below lives on `J`. Write
//! `W = Σ_k W_k` (embedded on `J`), `g = ∇q(m) = Σ_k W_k r_k`, `q₀ = q(m) = Σ_k ½ r_kᵀ W_k r_k`
//! with `r_k = m_{J_k} − z_k`, and `A = I + sW`. Completing the square,
//!
//! ```text
//! E[exp(−q(x))] = |A|^(−1/2) · exp(−q₀ + ½ gᵀ A⁻¹ s g) = |A|^(−1/2) · exp(−q₀ + ½ gᵀ s t),
//! t = A⁻ᵀ g = (I + W s)⁻¹ g.
//! ```
//!
//! For one term this is PILCO's `|I + sW|^(−1/2) exp(−½ rᵀ W (I + sW)⁻¹ r)`; the form with `g`,
//! `q₀` also covers sums whose combined `W` is singular (no combined target is needed).
//! Nothing needs `s⁻¹`, so singular `s` is fine. `A` is invertible for PSD `s`, `W` (its
//! eigenvalues are those of `I + s^{1/2} W s^{1/2}`, all ≥ 1), so `|A| > 0`.
//!
//! Derivatives (with `E` the value, `K = W A⁻¹ = (I + Ws)⁻¹ W`, symmetric):
//!
//! * `∂E/∂m = −E t`;
//! * `∂E/∂s = E (−½ K + ½ t tᵀ)` (entries of `s` independent; already symmetric);
//! * for the input-output term `t = K r` of a single term, with adjoint `t̄`:
//!   `m̄ += K t̄`, `s̄ += −(K t̄) tᵀ` (symmetrised by the caller).

use super::saturating::SaturatingCost;
use crate::GaussianBar;
use faer::linalg::solvers::Solve;
use faer::{Mat, MatRef};

/// The value and what the backward needs.
#[derive(Clone, Debug)]
pub(crate) struct GaussExp {
    /// The union `J` of the dimensions, sorted.
    pub dims: Vec<usize>,
    pub value: f64,
    /// `t = (I + W s)⁻¹ g` on `J`.
    pub t: Vec<f64>,
    /// `K = W (I + sW)⁻¹` on `J`, symmetrised.
    pub k: Mat<f64>,
}

impl GaussExp {
    /// `E[exp(−Σ_k q_k(x))]` for the given terms (a term may appear twice: `2 q_k`).
    pub fn new(m: &[f64], s: MatRef<'_, f64>, terms: &[&SaturatingCost]) -> Self {
        let mut dims: Vec<usize> = terms
            .iter()
            .flat_map(|c| c.dims().iter().copied())
            .collect();
        dims.sort_unstable();
        dims.dedup();
        let n = dims.len();
        let pos = |d: usize| dims.binary_search(&d).expect("dimension is in the union");

        let mut w = Mat::<f64>::zeros(n, n);
        let mut g = vec![0.0; n];
        let mut q0 = 0.0;
        for c in terms {
            let (cd, cw, cz) = (c.dims(), c.w(), c.target());
            let p: Vec<usize> = cd.iter().map(|&d| pos(d)).collect();
            let r: Vec<f64> = cd.iter().zip(cz).map(|(&d, z)| m[d] - z).collect();
            for a in 0..cd.len() {
                let mut wr = 0.0;
                for b in 0..cd.len() {
                    w[(p[a], p[b])] += cw[(a, b)];
                    wr += cw[(a, b)] * r[b];
                }
                g[p[a]] += wr;
                q0 += 0.5 * r[a] * wr;
            }
        }
        let s_j = Mat::from_fn(n, n, |a, b| s[(dims[a], dims[b])]);
        let mut amat = &s_j * &w;
        for a in 0..n {
            amat[(a, a)] += 1.0;
        }
        let lu = amat.partial_piv_lu();
        // |A| = ±Π U_aa, signed by the parity of the row pivoting (inversions; n = |J| is
        // small). The sign is kept: |A| ≥ 1 for PSD s and W (module docs; `SaturatingCost::new`
        // refuses any other W, and sums of PSD W_k are PSD), so |A| ≤ 0 means an indefinite s.
        // Neither this nor `CostSum::forward` can return an error, so |A|^(−1/2) is then NaN
        // for the caller's finiteness checks to report, where `abs` gave a finite, wrong cost.
        let (perm, _) = lu.P().arrays();
        let inversions: usize = (0..n)
            .map(|a| (a + 1..n).filter(|&b| perm[a] > perm[b]).count())
            .sum();
        let sign = if inversions.is_multiple_of(2) {
            1.0
        } else {
            -1.0
        };
        let det: f64 = sign * (0..n).map(|a| lu.U()[(a, a)]).product::<f64>();
        let gcol = MatRef::from_column_major_slice(&g, n, 1);
        let tcol = lu.solve_transpose(gcol);
        let t: Vec<f64> = (0..n).map(|a| tcol[(a, 0)]).collect();
        // K = W A⁻¹ = (A⁻ᵀ W)ᵀ; symmetric in exact arithmetic.
        let x = lu.solve_transpose(&w);
        let k = Mat::from_fn(n, n, |a, b| 0.5 * (x[(a, b)] + x[(b, a)]));
        let mut gst = 0.0;
        for a in 0..n {
            let mut st = 0.0;
            for b in 0..n {
                st += s_j[(a, b)] * t[b];
            }
            gst += g[a] * st;
        }
        let value = det.powf(-0.5) * (-q0 + 0.5 * gst).exp();
        Self { dims, value, t, k }
    }

    /// `out += ē · ∂E/∂(m, s)` (unsymmetrised accumulation; symmetric here anyway).
    pub fn add_grad(&self, ebar: f64, out: &mut GaussianBar) {
        if ebar == 0.0 {
            return;
        }
        let f = ebar * self.value;
        for (a, &da) in self.dims.iter().enumerate() {
            out.mean[da] -= f * self.t[a];
            for (b, &db) in self.dims.iter().enumerate() {
                out.cov[(da, db)] += f * 0.5 * (self.t[a] * self.t[b] - self.k[(a, b)]);
            }
        }
    }

    /// `out += t̄ · ∂t/∂(m, s)` for a single-term integral (`t = K r`); `tbar` is on `dims`.
    /// The covariance part is not symmetric; the caller symmetrises.
    pub fn add_t_grad(&self, tbar: &[f64], out: &mut GaussianBar) {
        let n = self.dims.len();
        for a in 0..n {
            let kt: f64 = (0..n).map(|b| self.k[(a, b)] * tbar[b]).sum();
            if kt == 0.0 {
                continue;
            }
            let da = self.dims[a];
            out.mean[da] += kt;
            for (b, &db) in self.dims.iter().enumerate() {
                out.cov[(da, db)] -= kt * self.t[b];
            }
        }
    }
}
