//! Covariance functions.
//!
//! Hyper-parameters are stored as natural logarithms, the convention of PILCO and of the
//! oracle: `log ℓ_1..log ℓ_D` (length-scales), `log σ_f` (signal standard deviation),
//! `log σ_n` (noise standard deviation). The squared-exponential ARD kernel is
//!
//! `k(x, x') = σ_f² exp(-½ (x-x')ᵀ Λ⁻¹ (x-x'))`, `Λ = diag(ℓ_1², …, ℓ_D²)`,
//!
//! and training adds `σ_n² I`. Moment matching at uncertain inputs has a closed form only for
//! this kernel, so the moment-matching code takes [`Hyper`] directly; training and plain
//! prediction go through the [`Kernel`] trait so that other stationary kernels (Matérn) can be
//! added without touching their callers.

use crate::error::{GpError, Result};
use faer::{Mat, MatMut, MatRef};
use serde::{Deserialize, Serialize};

/// Log hyper-parameters of one output: ARD length-scales, signal and noise standard deviation.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Hyper {
    /// `log ℓ_d`, one per input dimension (D); ℓ_d is in the units of input d.
    pub log_ls: Vec<f64>,
    /// `log σ_f`; σ_f is the signal standard deviation, in the units of the output.
    pub log_sf: f64,
    /// `log σ_n`; σ_n is the noise standard deviation, in the units of the output.
    pub log_sn: f64,
}

impl Hyper {
    /// From PILCO's column layout `[log ℓ_1..log ℓ_D, log σ_f, log σ_n]`; fewer than 2
    /// entries is [`GpError::Shape`].
    pub fn from_pilco(col: &[f64]) -> Result<Self> {
        let Some(d) = col.len().checked_sub(2) else {
            return Err(GpError::Shape {
                what: "PILCO hyper-parameter column [log ℓ_1..log ℓ_D, log σ_f, log σ_n]".into(),
                expected: "at least 2 entries (log σ_f and log σ_n)".into(),
                got: format!("{} entries", col.len()),
            });
        };
        Ok(Self {
            log_ls: col[..d].to_vec(),
            log_sf: col[d],
            log_sn: col[d + 1],
        })
    }

    /// PILCO's column layout `[log ℓ_1..log ℓ_D, log σ_f, log σ_n]`.
    pub fn to_pilco(&self) -> Vec<f64> {
        let mut v = self.log_ls.clone();
        v.push(self.log_sf);
        v.push(self.log_sn);
        v
    }

    /// Input dimension D: the number of length-scales.
    pub fn dim(&self) -> usize {
        self.log_ls.len()
    }

    /// Signal variance σ_f².
    pub fn sf2(&self) -> f64 {
        (2.0 * self.log_sf).exp()
    }

    /// Noise variance σ_n².
    pub fn sn2(&self) -> f64 {
        (2.0 * self.log_sn).exp()
    }

    /// `1/ℓ_d²` for every input dimension (the diagonal of Λ⁻¹).
    pub fn inv_ls2(&self) -> Vec<f64> {
        self.log_ls.iter().map(|l| (-2.0 * l).exp()).collect()
    }

    /// Whether no log hyper-parameter is NaN or ±inf; [`crate::validate_data`] and the
    /// likelihood reject the set otherwise.
    pub fn is_finite(&self) -> bool {
        self.log_sf.is_finite()
            && self.log_sn.is_finite()
            && self.log_ls.iter().all(|v| v.is_finite())
    }
}

/// A stationary covariance function with ARD length-scales and a signal variance.
pub trait Kernel: Send + Sync + std::fmt::Debug {
    /// `k(a, b)` (no noise).
    fn eval(&self, h: &Hyper, a: &[f64], b: &[f64]) -> f64;

    /// `K(X, X)` (no noise), N×N.
    fn gram(&self, h: &Hyper, x: MatRef<'_, f64>) -> Mat<f64> {
        let n = x.nrows();
        let rows: Vec<Vec<f64>> = (0..n).map(|i| row(x, i)).collect();
        let mut k = Mat::zeros(n, n);
        for i in 0..n {
            for j in 0..=i {
                let v = self.eval(h, &rows[i], &rows[j]);
                k[(i, j)] = v;
                k[(j, i)] = v;
            }
        }
        k
    }

    /// `K(X, X)` (no noise) written into `out` (N×N), for loops that reuse one buffer.
    fn gram_into(&self, h: &Hyper, x: MatRef<'_, f64>, mut out: MatMut<'_, f64>) {
        out.copy_from(self.gram(h, x));
    }

    /// `K(X1, X2)`, N1×N2.
    fn cross(&self, h: &Hyper, x1: MatRef<'_, f64>, x2: MatRef<'_, f64>) -> Mat<f64> {
        let r1: Vec<Vec<f64>> = (0..x1.nrows()).map(|i| row(x1, i)).collect();
        let r2: Vec<Vec<f64>> = (0..x2.nrows()).map(|i| row(x2, i)).collect();
        Mat::from_fn(x1.nrows(), x2.nrows(), |i, j| self.eval(h, &r1[i], &r2[j]))
    }

    /// `Σ_ij G_ij ∂K_ij/∂θ` for θ = (log ℓ_1..log ℓ_D, log σ_f), given `K = K(X,X)` (no
    /// noise) and a symmetric N×N weight `G`: the contraction every likelihood gradient needs.
    fn gram_grad_contract(
        &self,
        h: &Hyper,
        x: MatRef<'_, f64>,
        k: MatRef<'_, f64>,
        g: MatRef<'_, f64>,
    ) -> Vec<f64>;
}

/// The squared-exponential (Gaussian) kernel with ARD length-scales.
#[derive(Clone, Copy, Debug, Default)]
pub struct SquaredExponential;

impl Kernel for SquaredExponential {
    fn eval(&self, h: &Hyper, a: &[f64], b: &[f64]) -> f64 {
        let mut q = 0.0;
        for ((ai, bi), l) in a.iter().zip(b).zip(&h.log_ls) {
            let d = (ai - bi) * (-l).exp();
            q += d * d;
        }
        h.sf2() * (-0.5 * q).exp()
    }

    fn gram(&self, h: &Hyper, x: MatRef<'_, f64>) -> Mat<f64> {
        let mut k = Mat::zeros(x.nrows(), x.nrows());
        self.gram_into(h, x, k.as_mut());
        k
    }

    fn gram_into(&self, h: &Hyper, x: MatRef<'_, f64>, mut k: MatMut<'_, f64>) {
        let (n, d) = (x.nrows(), x.ncols());
        assert_eq!((k.nrows(), k.ncols()), (n, n), "gram_into: output size");
        let il: Vec<f64> = h.log_ls.iter().map(|l| (-l).exp()).collect();
        // Scale once so the pair loop is a plain squared distance.
        let xs: Vec<f64> = (0..n)
            .flat_map(|i| (0..d).map(move |c| (i, c)))
            .map(|(i, c)| x[(i, c)] * il[c])
            .collect();
        let sf2 = h.sf2();
        let log_sf2 = 2.0 * h.log_sf;
        // Column j below the diagonal: exponents first, then one vectorised exp over the
        // contiguous run (σ_f² exp(−q/2) = exp(2 log σ_f − q/2)), then mirrored.
        let mut col = vec![0.0; n];
        for j in 0..n {
            let xj = &xs[j * d..(j + 1) * d];
            let below = &mut col[j + 1..];
            for (v, xi) in below.iter_mut().zip(xs[(j + 1) * d..].chunks_exact(d)) {
                let q: f64 = xi.iter().zip(xj).map(|(a, b)| (a - b) * (a - b)).sum();
                *v = log_sf2 - 0.5 * q;
            }
            crate::fastexp::exp_in_place(below);
            k[(j, j)] = sf2;
            for (i, v) in below.iter().enumerate() {
                k[(j + 1 + i, j)] = *v;
                k[(j, j + 1 + i)] = *v;
            }
        }
    }

    fn gram_grad_contract(
        &self,
        h: &Hyper,
        x: MatRef<'_, f64>,
        k: MatRef<'_, f64>,
        g: MatRef<'_, f64>,
    ) -> Vec<f64> {
        let (n, d) = (x.nrows(), x.ncols());
        let il2 = h.inv_ls2();
        // ∂K_ij/∂log ℓ_c = K_ij (x_ic - x_jc)² / ℓ_c²;  ∂K_ij/∂log σ_f = 2 K_ij.
        // Rows copied once to contiguous memory; G and K read down their columns (the upper
        // triangle, equal to the lower one for symmetric G), so the pair loop has no strided
        // or bounds-checked access.
        let xr: Vec<f64> = (0..n)
            .flat_map(|i| (0..d).map(move |c| (i, c)))
            .map(|(i, c)| x[(i, c)])
            .collect();
        let mut acc = vec![0.0; d];
        let mut diag_sum = 0.0;
        for i in 0..n {
            diag_sum += g[(i, i)] * k[(i, i)];
            let xi = &xr[i * d..(i + 1) * d];
            let pairs = g.col(i).iter().zip(k.col(i).iter()).take(i);
            for ((gv, kv), xj) in pairs.zip(xr.chunks_exact(d)) {
                let w = 2.0 * gv * kv;
                diag_sum += w;
                for ((a, p), q) in acc.iter_mut().zip(xi).zip(xj) {
                    let dx = p - q;
                    *a += w * dx * dx;
                }
            }
        }
        let mut out: Vec<f64> = acc.iter().zip(&il2).map(|(a, l)| a * l).collect();
        out.push(2.0 * diag_sum);
        out
    }
}

/// Row `i` of a matrix as a vector.
pub fn row(x: MatRef<'_, f64>, i: usize) -> Vec<f64> {
    (0..x.ncols()).map(|c| x[(i, c)]).collect()
}
