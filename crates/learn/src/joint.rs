//! The joint Gaussian of one prediction step, grown by appending block outputs, and its
//! reverse-mode counterpart.
//!
//! A block reads the marginal of variables `I` of the joint `z ~ N(μ, Σ)` and returns the
//! mean `M`, covariance `S` and `C = Σ_II⁻¹ Cov[z_I, y]` of its output `y`. Appending `y`
//! gives (thesis eq. 4-6, PILCO's `propagated`)
//!
//! ```text
//! μ' = [μ; M],   Σ' = [[Σ, Σ_{:,I} C], [(Σ_{:,I} C)ᵀ, S]],
//! ```
//!
//! so every cross-covariance with earlier variables is kept. The reverse step takes the
//! adjoint `(μ̄', Σ̄')` of the extended joint and returns the block's output adjoints
//! `M̄ = μ̄'_new`, `S̄ = Σ̄'_new,new`, `C̄ = Σ_{I,:} X̄` with `X̄ = Σ̄'_{:,new} + Σ̄'ᵀ_{new,:}`,
//! while `Σ̄_{:,I} += X̄ Cᵀ`; the block's own backward then adds its input adjoints.

use faer::{Mat, MatRef};
use vicpilco_pilco::{GaussianBar, Moments, MomentsBar};

/// A Gaussian over all variables of a prediction step so far.
#[derive(Clone, Debug)]
pub struct Joint {
    /// μ: one mean per variable, in the order appended (the starting Gaussian's first).
    pub mean: Vec<f64>,
    /// Σ: their covariance, `dim()`×`dim()` and symmetric.
    pub cov: Mat<f64>,
}

impl Joint {
    /// The joint of the starting Gaussian `N(mean, cov)` alone (a step's state); blocks are
    /// appended after it.
    pub fn new(mean: Vec<f64>, cov: Mat<f64>) -> Self {
        Self { mean, cov }
    }

    /// Number of variables so far, the starting ones included.
    pub fn dim(&self) -> usize {
        self.mean.len()
    }

    /// Mean and covariance of the variables `idx`.
    pub fn marginal(&self, idx: &[usize]) -> (Vec<f64>, Mat<f64>) {
        let m = idx.iter().map(|&i| self.mean[i]).collect();
        let s = Mat::from_fn(idx.len(), idx.len(), |a, b| self.cov[(idx[a], idx[b])]);
        (m, s)
    }

    /// Append a block's output computed from the marginal of `idx`; returns the indices of
    /// the new variables.
    pub fn append(&mut self, idx: &[usize], out: &Moments) -> Vec<usize> {
        let (n, k) = (self.dim(), out.mean.len());
        debug_assert_eq!(out.v.nrows(), idx.len());
        debug_assert_eq!(out.v.ncols(), k);
        let mut cov = Mat::zeros(n + k, n + k);
        for j in 0..n {
            for i in 0..n {
                cov[(i, j)] = self.cov[(i, j)];
            }
        }
        for i in 0..n {
            for c in 0..k {
                let v: f64 = idx
                    .iter()
                    .enumerate()
                    .map(|(a, &ia)| self.cov[(i, ia)] * out.v[(a, c)])
                    .sum();
                cov[(i, n + c)] = v;
                cov[(n + c, i)] = v;
            }
        }
        for a in 0..k {
            for b in 0..k {
                cov[(n + a, n + b)] = out.cov[(a, b)];
            }
        }
        self.mean.extend_from_slice(&out.mean);
        self.cov = cov;
        (n..n + k).collect()
    }

    /// Append variables with known values (zero variance, uncorrelated), e.g. time.
    pub fn append_constant(&mut self, values: &[f64]) -> Vec<usize> {
        let k = values.len();
        let out = Moments {
            mean: values.to_vec(),
            cov: Mat::zeros(k, k),
            v: Mat::zeros(0, k),
        };
        self.append(&[], &out)
    }
}

/// Adjoint of a [`Joint`]: `μ̄` and `Σ̄` (entries treated as independent; not necessarily
/// symmetric until [`JointBar::into_gaussian_bar`]).
#[derive(Clone, Debug)]
pub struct JointBar {
    /// μ̄: the adjoint of each entry of [`Joint::mean`], same indexing.
    pub mean: Vec<f64>,
    /// Σ̄: the adjoint of each entry of [`Joint::cov`], `(i, j)` and `(j, i)` separately.
    pub cov: Mat<f64>,
}

impl JointBar {
    /// Zero adjoints of a joint of `n` variables: where a reverse sweep starts accumulating.
    pub fn zeros(n: usize) -> Self {
        Self {
            mean: vec![0.0; n],
            cov: Mat::zeros(n, n),
        }
    }

    /// Variables still covered; each [`JointBar::pop_append`] removes its block's outputs.
    pub fn dim(&self) -> usize {
        self.mean.len()
    }

    /// Add the adjoint of a marginal over `idx`.
    pub fn add_marginal(&mut self, idx: &[usize], bar: &GaussianBar) {
        for (a, &ia) in idx.iter().enumerate() {
            self.mean[ia] += bar.mean[a];
            for (b, &ib) in idx.iter().enumerate() {
                self.cov[(ia, ib)] += bar.cov[(a, b)];
            }
        }
    }

    /// Reverse of [`Joint::append`]: `joint` is the joint *after* the append (its leading
    /// block is the joint before), `idx` the block's input variables and `c` its `C`.
    /// Shrinks `self` to the dimension before the append and returns the block's output
    /// adjoints; the caller then adds the block's input adjoints with
    /// [`JointBar::add_marginal`].
    pub fn pop_append(&mut self, joint: &Joint, idx: &[usize], c: MatRef<'_, f64>) -> MomentsBar {
        let k = c.ncols();
        let n = self.dim() - k;
        let mean_bar = self.mean[n..].to_vec();
        let cov_bar = Mat::from_fn(k, k, |a, b| self.cov[(n + a, n + b)]);
        // X̄ (n×k): adjoint of Σ_{:,I} C, both triangles.
        let xbar = Mat::from_fn(n, k, |i, a| self.cov[(i, n + a)] + self.cov[(n + a, i)]);
        // C̄ = Σ_{I,:} X̄
        let c_bar = Mat::from_fn(idx.len(), k, |p, a| {
            (0..n).map(|i| joint.cov[(idx[p], i)] * xbar[(i, a)]).sum()
        });
        let mut cov = Mat::from_fn(n, n, |i, j| self.cov[(i, j)]);
        // Σ̄_{:,I} += X̄ Cᵀ
        for (p, &ip) in idx.iter().enumerate() {
            for i in 0..n {
                let v: f64 = (0..k).map(|a| xbar[(i, a)] * c[(p, a)]).sum();
                cov[(i, ip)] += v;
            }
        }
        self.mean.truncate(n);
        self.cov = cov;
        MomentsBar {
            mean: mean_bar,
            cov: cov_bar,
            v: Some(c_bar),
        }
    }

    /// The adjoint of the leading `n` variables as a [`GaussianBar`] with symmetrised `s̄`.
    pub fn into_gaussian_bar(self) -> GaussianBar {
        let n = self.dim();
        let cov = Mat::from_fn(n, n, |i, j| 0.5 * (self.cov[(i, j)] + self.cov[(j, i)]));
        GaussianBar {
            mean: self.mean,
            cov,
        }
    }
}
