//! The saturating cost (PILCO's `lossSat`, thesis eq. 4-8) and sums of several of them.
//!
//! ## One cost
//!
//! On a subset `J` of the state dimensions, with width matrix `W` (symmetric PSD) and target
//! `z`, `c(x) = 1 − exp(−½ (x_J − z)ᵀ W (x_J − z))`. For `x ~ N(m, s)` and `r = m_J − z`:
//!
//! * `L = E[c] = 1 − |I + sW|^(−1/2) exp(−½ rᵀ W (I + sW)⁻¹ r)`;
//! * `S = Var[c] = |I + 2sW|^(−1/2) exp(−rᵀ W (I + 2sW)⁻¹ r) − (1 − L)²`, set to exactly 0
//!   when below 10⁻¹² (its derivatives are those of the unclamped formula, as in PILCO);
//! * `C = s⁻¹ Cov[x, c] = (1 − L) W (I + sW)⁻¹ r = ∂L/∂m` (zero outside `J`).
//!
//! (Here `s`, `I` are restricted to `J`.) The thesis writes the exponent as
//! `(s − s*)ᵀ S⁻¹ (s − s*)` without the ½; that is `W = 2 S⁻¹` in PILCO's form used here.
//!
//! ## A sum of costs
//!
//! The immediate cost of a step may be a sum `c = Σ_k c_k` of saturating costs on different
//! subsets, each with its own width and target (e.g. one on position, one on force). With
//! `e_k = 1 − c_k = exp(−q_k(x))`:
//!
//! * `E[c] = Σ_k (1 − E[e_k])`;
//! * `Var[c] = Σ_k Var[c_k] + 2 Σ_{k<l} Cov[c_k, c_l] = Σ_{k,l} E[e_k e_l] − (Σ_k E[e_k])²`,
//!   since `Cov[c_k, c_l] = Cov[e_k, e_l] = E[e_k e_l] − E[e_k] E[e_l]`;
//! * `E[e_k e_l] = E[exp(−(q_k + q_l)(x))]` is again a Gaussian integral of the same kind, with
//!   `W = W_k + W_l` embedded on `J_k ∪ J_l` and the targets combined through the gradient
//!   and value of `q_k + q_l` at `m` (see `gauss_exp`); for `k = l` it is the `2W` term of
//!   `lossSat`'s variance;
//! * `C = Σ_k C_k`.
//!
//! The variance of the sum is clamped like `lossSat`'s. A [`CostSum`] of one cost is exactly
//! `lossSat`.

use super::gauss_exp::GaussExp;
use crate::error::{check_finite, check_indices, check_len, PilcoError, Result};
use crate::util::{assert_input, symmetrise};
use crate::{CostBar, CostMoments, GaussianBar};
use faer::{Mat, MatRef};

/// Variances below this are returned as 0 (PILCO's `lossSat`).
pub const VAR_CLAMP: f64 = 1e-12;

/// One saturating cost `1 − exp(−½ (x_J − z)ᵀ W (x_J − z))`.
#[derive(Clone, Debug)]
pub struct SaturatingCost {
    dims: Vec<usize>,
    w: Mat<f64>,
    z: Vec<f64>,
}

impl SaturatingCost {
    /// A cost on the dimensions `dims` (distinct) of the state, with `|J|×|J|` width matrix
    /// `w` (symmetric positive semi-definite up to rounding, refused otherwise; the rounding
    /// is symmetrised away) and target `z`.
    pub fn new(dims: &[usize], w: MatRef<'_, f64>, z: &[f64]) -> Result<Self> {
        let n = dims.len();
        if w.nrows() != n || w.ncols() != n {
            return Err(PilcoError::Shape {
                what: "saturating cost width matrix W".into(),
                expected: format!("{n}×{n} (one row per cost dimension)"),
                got: format!("{}×{}", w.nrows(), w.ncols()),
            });
        }
        check_len("saturating cost target", n, z.len())?;
        check_finite("saturating cost target", z)?;
        let mut sorted = dims.to_vec();
        sorted.sort_unstable();
        if sorted.windows(2).any(|p| p[0] == p[1]) {
            return Err(PilcoError::Invalid {
                what: "saturating cost dimensions".into(),
                detail: format!("{dims:?} repeats a dimension"),
            });
        }
        let mut w = w.to_owned();
        for a in 0..n {
            for b in 0..n {
                if !w[(a, b)].is_finite() {
                    return Err(PilcoError::Invalid {
                        what: "saturating cost width matrix W".into(),
                        detail: format!("entry ({a}, {b}) is {}", w[(a, b)]),
                    });
                }
            }
            if w[(a, a)] < 0.0 {
                return Err(PilcoError::Invalid {
                    what: "saturating cost width matrix W".into(),
                    detail: format!("negative diagonal entry {} at {a}", w[(a, a)]),
                });
            }
        }
        check_symmetric_psd(&mut w)?;
        Ok(Self {
            dims: dims.to_vec(),
            w,
            z: z.to_vec(),
        })
    }

    /// `J`: the state dimensions the cost sees, in the order of the rows of `W` and of `z`.
    pub fn dims(&self) -> &[usize] {
        &self.dims
    }

    /// `W` (|J|×|J|), symmetrised at construction; row a belongs to `dims()[a]`.
    pub fn w(&self) -> &Mat<f64> {
        &self.w
    }

    /// The target `z` (|J|), entry a for state dimension `dims()[a]`.
    pub fn target(&self) -> &[f64] {
        &self.z
    }

    /// The deterministic cost `c(x)`.
    pub fn eval(&self, x: &[f64]) -> f64 {
        let r: Vec<f64> = self
            .dims
            .iter()
            .zip(&self.z)
            .map(|(&d, z)| x[d] - z)
            .collect();
        let n = r.len();
        let mut q = 0.0;
        for a in 0..n {
            for b in 0..n {
                q += r[a] * self.w[(a, b)] * r[b];
            }
        }
        1.0 - (-0.5 * q).exp()
    }
}

/// Relative rounding (of `max |W|`) tolerated in W's asymmetry and negative eigenvalues: a
/// width built as `A Aᵀ` or `2 S⁻¹` is PSD only up to a few ulps.
const PSD_TOL: f64 = 1e-10;

/// Refuse a W that is not symmetric PSD, then symmetrise it. Why: the Gaussian integral
/// `E[exp(−½ xᵀWx)]` is finite only for PSD W (with an indefinite W it diverges, yet
/// `|I + sW|^(−1/2)` would still give a finite, wrong number).
fn check_symmetric_psd(w: &mut Mat<f64>) -> Result<()> {
    let n = w.nrows();
    let scale = (0..n)
        .flat_map(|a| (0..n).map(move |b| (a, b)))
        .fold(0.0f64, |acc, (a, b)| acc.max(w[(a, b)].abs()));
    let tol = PSD_TOL * scale;
    let invalid = |detail: String| PilcoError::Invalid {
        what: "saturating cost width matrix W".into(),
        detail,
    };
    for a in 0..n {
        for b in 0..a {
            if (w[(a, b)] - w[(b, a)]).abs() > tol {
                return Err(invalid(format!(
                    "not symmetric: entry ({a}, {b}) is {} but ({b}, {a}) is {}",
                    w[(a, b)],
                    w[(b, a)]
                )));
            }
        }
    }
    symmetrise(w);
    if n == 0 {
        return Ok(());
    }
    let eig = w
        .self_adjoint_eigenvalues(faer::Side::Lower)
        .map_err(|e| invalid(format!("eigenvalues did not converge ({e:?})")))?;
    // Sorted ascending: the first is the smallest.
    if eig[0] < -tol {
        return Err(invalid(format!(
            "not positive semi-definite: smallest eigenvalue {:e}",
            eig[0]
        )));
    }
    Ok(())
}

/// The sum of several saturating costs on a D-dimensional state (PILCO's `lossSat` for one).
#[derive(Clone, Debug)]
pub struct CostSum {
    d: usize,
    costs: Vec<SaturatingCost>,
}

/// What [`CostSum::backward`] needs.
#[derive(Clone, Debug)]
pub struct CostSumCache {
    /// `E[e_k]` per cost.
    singles: Vec<GaussExp>,
    /// `E[e_k e_l]` for `k ≤ l`, row by row.
    pairs: Vec<(usize, usize, GaussExp)>,
    /// `Var[c]` before clamping.
    var_unclamped: f64,
}

impl CostSumCache {
    /// The variance before the 10⁻¹² clamp.
    pub fn var_unclamped(&self) -> f64 {
        self.var_unclamped
    }

    /// `E[c_k]` of each cost of the sum.
    pub fn means(&self) -> Vec<f64> {
        self.singles.iter().map(|g| 1.0 - g.value).collect()
    }
}

impl CostSum {
    /// `d` state dimensions; every cost's dimensions must lie below `d`.
    pub fn new(d: usize, costs: Vec<SaturatingCost>) -> Result<Self> {
        if costs.is_empty() {
            return Err(PilcoError::Invalid {
                what: "cost sum".into(),
                detail: "holds no cost".into(),
            });
        }
        for (k, c) in costs.iter().enumerate() {
            check_indices(&format!("dimensions of cost {k}"), &c.dims, d)?;
        }
        Ok(Self { d, costs })
    }

    /// One cost on all `d` dimensions: PILCO's `lossSat(m, s, z, W)`.
    pub fn loss_sat(w: MatRef<'_, f64>, z: &[f64]) -> Result<Self> {
        let d = z.len();
        let dims: Vec<usize> = (0..d).collect();
        Self::new(d, vec![SaturatingCost::new(&dims, w, z)?])
    }

    /// D, the length of the state `x` the costs are evaluated on.
    pub fn n_inputs(&self) -> usize {
        self.d
    }

    /// The summands `c_k`, in the order given to [`CostSum::new`].
    pub fn costs(&self) -> &[SaturatingCost] {
        &self.costs
    }

    /// The deterministic cost `Σ_k c_k(x)`.
    pub fn eval(&self, x: &[f64]) -> f64 {
        self.costs.iter().map(|c| c.eval(x)).sum()
    }

    /// Mean, (clamped) variance and `C` of the summed cost for `x ~ N(m, s)`.
    pub fn forward(&self, m: &[f64], s: MatRef<'_, f64>) -> (CostMoments, CostSumCache) {
        assert_input("saturating cost", self.d, m, s);
        let n = self.costs.len();
        let singles: Vec<GaussExp> = self
            .costs
            .iter()
            .map(|c| GaussExp::new(m, s, &[c]))
            .collect();
        let mut pairs = Vec::with_capacity(n * (n + 1) / 2);
        for k in 0..n {
            for l in k..n {
                let g = GaussExp::new(m, s, &[&self.costs[k], &self.costs[l]]);
                pairs.push((k, l, g));
            }
        }
        let sum_q: f64 = singles.iter().map(|g| g.value).sum();
        let mean = n as f64 - sum_q;
        let second: f64 = pairs
            .iter()
            .map(|(k, l, g)| if k == l { g.value } else { 2.0 * g.value })
            .sum();
        let var_unclamped = second - sum_q * sum_q;
        let var = if var_unclamped < VAR_CLAMP {
            0.0
        } else {
            var_unclamped
        };
        let mut c = vec![0.0; self.d];
        for g in &singles {
            for (a, &da) in g.dims.iter().enumerate() {
                c[da] += g.value * g.t[a];
            }
        }
        (
            CostMoments { mean, var, v: c },
            CostSumCache {
                singles,
                pairs,
                var_unclamped,
            },
        )
    }

    /// Adjoints of `(E[c], Var[c], C)` → adjoints of `(m, s)`. The variance adjoint acts on
    /// the unclamped variance.
    pub fn backward(&self, cache: &CostSumCache, bar: &CostBar) -> GaussianBar {
        let mut out = GaussianBar::zeros(self.d);
        let sum_q: f64 = cache.singles.iter().map(|g| g.value).sum();
        // Var = Σ_{k,l} E[e_k e_l] − (Σ_k E[e_k])²; E[c] = n − Σ_k E[e_k].
        let q_bar_common = -bar.mean - 2.0 * bar.var * sum_q;
        for g in &cache.singles {
            let mut q_bar = q_bar_common;
            if let Some(cb) = &bar.v {
                // C = Σ_k E[e_k] t_k
                let tbar: Vec<f64> = g.dims.iter().map(|&d| g.value * cb[d]).collect();
                q_bar += g
                    .dims
                    .iter()
                    .zip(&g.t)
                    .map(|(&d, t)| cb[d] * t)
                    .sum::<f64>();
                g.add_t_grad(&tbar, &mut out);
            }
            g.add_grad(q_bar, &mut out);
        }
        if bar.var != 0.0 {
            for (k, l, g) in &cache.pairs {
                let w = if k == l { 1.0 } else { 2.0 };
                g.add_grad(w * bar.var, &mut out);
            }
        }
        symmetrise(&mut out.cov);
        out
    }
}
