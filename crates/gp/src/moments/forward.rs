//! Forward pass of moment matching: mean, covariance and input-output covariance.

use super::kernels::{block_forward, BlockOperands};
use super::small::{
    check_moment_input, mat_vec, mul, row_quad, scale_cols, spd_inverse_logdet, weighted_col_sum,
};
use crate::error::{GpError, Result};
use crate::kernel::Hyper;
use crate::model::GpModel;
use crate::sparse::{DynamicsModel, SparseGpModel};
use faer::{Mat, MatRef};
use rayon::prelude::*;

/// What replaces the model-uncertainty term of the covariance.
#[derive(Clone, Copy, Debug)]
pub enum Variance<'a> {
    /// One N×N matrix per output: `(K+σ_n²I)⁻¹` (full GP) or `K_mm⁻¹ − B⁻¹` (FITC). The
    /// latent-function variance `σ_f² − t tr(W L)` is added to the diagonal of S.
    Model(&'a [Mat<f64>]),
    /// No model uncertainty (the GP mean as a deterministic function); this constant is added
    /// to the diagonal of S instead (PILCO's gp2 uses 10⁻⁶).
    DiagonalJitter(f64),
}

/// The numbers moment matching needs from a GP: centres (training or inducing inputs), the
/// weights β, hyper-parameters per output, and the variance flavour.
#[derive(Clone, Copy, Debug)]
pub struct MmModel<'a> {
    /// N×D.
    pub centres: MatRef<'a, f64>,
    /// N×E.
    pub beta: MatRef<'a, f64>,
    /// Log hyper-parameters, one per output (E), each with D length-scales.
    pub hyp: &'a [Hyper],
    /// Model uncertainty (`W_a`, gp0/gp1) or a fixed diagonal instead (gp2).
    pub variance: Variance<'a>,
}

/// PILCO's gp2 jitter: added to the diagonal of the covariance of a deterministic GP mean.
pub const DETERMINISTIC_JITTER: f64 = 1e-6;

impl<'a> MmModel<'a> {
    /// Full GP with model uncertainty (PILCO gp0).
    pub fn with_uncertainty(gp: &'a GpModel) -> Self {
        Self {
            centres: gp.inputs(),
            beta: gp.beta(),
            hyp: gp.hyp(),
            variance: Variance::Model(gp.inv_k()),
        }
    }

    /// Sparse FITC GP with model uncertainty (PILCO gp1): the inducing inputs are the centres.
    pub fn sparse(gp: &'a SparseGpModel) -> Self {
        Self {
            centres: gp.inputs(),
            beta: gp.beta(),
            hyp: gp.hyp(),
            variance: Variance::Model(gp.inv_k()),
        }
    }

    /// A trained dynamics model, full or sparse, with model uncertainty.
    pub fn dynamics(model: &'a DynamicsModel) -> Self {
        match model {
            DynamicsModel::Full(gp) => Self::with_uncertainty(gp),
            DynamicsModel::Sparse(gp) => Self::sparse(gp),
        }
    }

    /// The GP mean only (PILCO gp2, the RBF-network form).
    pub fn mean_only(gp: &'a GpModel) -> Self {
        Self {
            centres: gp.inputs(),
            beta: gp.beta(),
            hyp: gp.hyp(),
            variance: Variance::DiagonalJitter(DETERMINISTIC_JITTER),
        }
    }

    /// Input dimension D (columns of the centres).
    pub fn input_dim(&self) -> usize {
        self.centres.ncols()
    }
    /// Number of outputs E (one [`Hyper`] each).
    pub fn output_dim(&self) -> usize {
        self.hyp.len()
    }
}

/// Predictive moments of the output.
#[derive(Clone, Debug)]
pub struct Moments {
    /// E.
    pub mean: Vec<f64>,
    /// E×E.
    pub cov: Mat<f64>,
    /// D×E, `s⁻¹ Cov[x, f(x)]`.
    pub v: Mat<f64>,
}

#[derive(Clone, Debug)]
pub(super) struct OutputCache {
    pub inv_ls2: Vec<f64>,
    /// `(s + Λ)⁻¹`.
    pub a: Mat<f64>,
    /// `q_i` (N).
    pub q: Vec<f64>,
    /// `log k(x_i, m)` (N).
    pub log_k: Vec<f64>,
    /// `Σ_i β_i q_i ν_i` (D).
    pub u: Vec<f64>,
}

#[derive(Clone, Debug)]
pub(super) struct PairCache {
    pub a: usize,
    pub b: usize,
    /// `Λ_a⁻¹ + Λ_b⁻¹` (diagonal).
    pub lam: Vec<f64>,
    /// `R⁻¹`.
    pub r_inv: Mat<f64>,
    /// `T = ½ R⁻¹ s` (symmetric).
    pub t_mat: Mat<f64>,
    /// `|R|^{-1/2}`.
    pub t: f64,
}

/// What the backward pass needs from the forward pass (O(E²D² + E N D) numbers).
#[derive(Clone, Debug)]
pub struct MmCache {
    /// N×D, `x_i − m`.
    pub(super) nu: Mat<f64>,
    pub(super) outputs: Vec<OutputCache>,
    pub(super) pairs: Vec<PairCache>,
    pub(super) mean: Vec<f64>,
}

/// Moment matching: the moments of `f(x)` for `x ~ N(m, s)`.
pub fn forward(model: &MmModel<'_>, m: &[f64], s: MatRef<'_, f64>) -> Result<(Moments, MmCache)> {
    let (n, d, e) = (model.centres.nrows(), model.input_dim(), model.output_dim());
    check_moment_input(model, m, s)?;
    let nu = Mat::from_fn(n, d, |i, k| model.centres[(i, k)] - m[k]);

    let mut outputs = Vec::with_capacity(e);
    let mut mean = vec![0.0; e];
    let mut v = Mat::zeros(d, e);
    for (a, h) in model.hyp.iter().enumerate() {
        let inv_ls2 = h.inv_ls2();
        let sl = Mat::from_fn(d, d, |i, j| {
            s[(i, j)] + if i == j { 1.0 / inv_ls2[i] } else { 0.0 }
        });
        let (amat, logdet_sl) = spd_inverse_logdet(sl.as_ref(), "s + Λ in moment matching")?;
        let logdet_l: f64 = -inv_ls2.iter().map(|v| v.ln()).sum::<f64>();
        let c = h.sf2() * (-0.5 * (logdet_sl - logdet_l)).exp();
        let quad = row_quad(nu.as_ref(), amat.as_ref());
        let q: Vec<f64> = quad.iter().map(|qq| c * (-0.5 * qq).exp()).collect();
        let w: Vec<f64> = (0..n).map(|i| model.beta[(i, a)] * q[i]).collect();
        mean[a] = w.iter().sum();
        let u = weighted_col_sum(nu.as_ref(), &w);
        let va = mat_vec(amat.as_ref(), &u);
        for k in 0..d {
            v[(k, a)] = va[k];
        }
        let log_sf2 = 2.0 * h.log_sf;
        let log_k = (0..n)
            .map(|i| {
                log_sf2
                    - 0.5
                        * (0..d)
                            .map(|k| inv_ls2[k] * nu[(i, k)] * nu[(i, k)])
                            .sum::<f64>()
            })
            .collect();
        outputs.push(OutputCache {
            inv_ls2,
            a: amat,
            q,
            log_k,
            u,
        });
    }

    let pair_ids: Vec<(usize, usize)> = (0..e).flat_map(|a| (0..=a).map(move |b| (a, b))).collect();
    let pair_results: Vec<Result<(PairCache, f64)>> = pair_ids
        .par_iter()
        .map(|&(a, b)| {
            let pc = pair_cache(s, &outputs, a, b)?;
            let blk = PairBlock::new(&nu, &outputs, &pc);
            let (sum_beta, trace) = blk.forward_sums(model, a, b);
            let mut sab = pc.t * sum_beta;
            if a == b {
                match model.variance {
                    Variance::Model(_) => sab += model.hyp[a].sf2() - pc.t * trace,
                    Variance::DiagonalJitter(j) => sab += j,
                }
            }
            Ok((pc, sab))
        })
        .collect();
    let mut cov = Mat::zeros(e, e);
    let mut pairs = Vec::with_capacity(pair_ids.len());
    for r in pair_results {
        let (pc, sab) = r?;
        let (a, b) = (pc.a, pc.b);
        let val = sab - mean[a] * mean[b];
        cov[(a, b)] = val;
        cov[(b, a)] = val;
        pairs.push(pc);
    }
    if let Some((i, j)) = (0..e)
        .flat_map(|i| (0..e).map(move |j| (i, j)))
        .find(|&(i, j)| !cov[(i, j)].is_finite())
    {
        return Err(GpError::Numerical {
            what: "moment-matched covariance".into(),
            detail: format!("entry ({i}, {j}) is {}", cov[(i, j)]),
        });
    }
    let cache = MmCache {
        nu,
        outputs,
        pairs,
        mean: mean.clone(),
    };
    Ok((Moments { mean, cov, v }, cache))
}

pub(super) fn pair_cache(
    s: MatRef<'_, f64>,
    outputs: &[OutputCache],
    a: usize,
    b: usize,
) -> Result<PairCache> {
    let d = s.nrows();
    let lam: Vec<f64> = (0..d)
        .map(|k| outputs[a].inv_ls2[k] + outputs[b].inv_ls2[k])
        .collect();
    // R = s Λ' + I = (s + Λ'⁻¹) Λ', so R⁻¹ = Λ'⁻¹ (s + Λ'⁻¹)⁻¹ and T = ½R⁻¹s is exactly
    // symmetric when formed as ½(Λ'⁻¹ − Λ'⁻¹ Q⁻¹ Λ'⁻¹), Q = s + Λ'⁻¹.
    let q = Mat::from_fn(d, d, |i, j| {
        s[(i, j)] + if i == j { 1.0 / lam[i] } else { 0.0 }
    });
    let (q_inv, logdet_q) = spd_inverse_logdet(q.as_ref(), "s + (Λa⁻¹+Λb⁻¹)⁻¹ in moment matching")?;
    let logdet_r = logdet_q + lam.iter().map(|v| v.ln()).sum::<f64>();
    let r_inv = Mat::from_fn(d, d, |i, j| q_inv[(i, j)] / lam[i]);
    let t_mat = Mat::from_fn(d, d, |i, j| {
        0.5 * (if i == j { 1.0 / lam[i] } else { 0.0 } - q_inv[(i, j)] / (lam[i] * lam[j]))
    });
    Ok(PairCache {
        a,
        b,
        lam,
        r_inv,
        t_mat,
        t: (-0.5 * logdet_r).exp(),
    })
}

/// The operands of the N×N block of one output pair:
/// `L_ij = exp(r_i + c_j + P_ij)` with `r_i = log k_a(x_i) + 𝒜_iᵀT𝒜_i`,
/// `c_j = log k_b(x_j) + ℬ_jᵀTℬ_j`, `P = 2𝒜Tℬᵀ`, `𝒜 = ν Λ_a⁻¹`, `ℬ = ν Λ_b⁻¹`. The block
/// itself is formed column by column in [`super::kernels`] and never stored.
pub(super) struct PairBlock {
    pub scaled_a: Mat<f64>,
    pub scaled_b: Mat<f64>,
    /// `2𝒜T`, column-major.
    a_hat: Vec<f64>,
    /// `ℬ`, row-major.
    b_rows: Vec<f64>,
    /// `𝒜`, column-major (for the parameter adjoints).
    pub a_cols: Vec<f64>,
    row: Vec<f64>,
    col: Vec<f64>,
}

impl PairBlock {
    pub fn new(nu: &Mat<f64>, outputs: &[OutputCache], pc: &PairCache) -> Self {
        let (n, d) = (nu.nrows(), nu.ncols());
        let scaled_a = scale_cols(nu.as_ref(), &outputs[pc.a].inv_ls2);
        let scaled_b = scale_cols(nu.as_ref(), &outputs[pc.b].inv_ls2);
        let qa = row_quad(scaled_a.as_ref(), pc.t_mat.as_ref());
        let qb = row_quad(scaled_b.as_ref(), pc.t_mat.as_ref());
        let row = (0..n).map(|i| outputs[pc.a].log_k[i] + qa[i]).collect();
        let col = (0..n).map(|j| outputs[pc.b].log_k[j] + qb[j]).collect();
        let at = mul(scaled_a.as_ref(), pc.t_mat.as_ref());
        // Flat column-major copies for the kernels, column by column (contiguous in faer).
        let col_of = |m: &Mat<f64>, k: usize| -> Vec<f64> {
            m.col(k)
                .try_as_col_major()
                .expect("fresh matrix is column-major")
                .as_slice()
                .to_vec()
        };
        let mut a_hat = Vec::with_capacity(n * d);
        let mut a_cols = Vec::with_capacity(n * d);
        for k in 0..d {
            a_hat.extend(col_of(&at, k).iter().map(|v| 2.0 * v));
            a_cols.extend(col_of(&scaled_a, k));
        }
        let mut b_rows = vec![0.0; n * d];
        for k in 0..d {
            for (j, v) in col_of(&scaled_b, k).into_iter().enumerate() {
                b_rows[j * d + k] = v;
            }
        }
        Self {
            scaled_a,
            scaled_b,
            a_hat,
            b_rows,
            a_cols,
            row,
            col,
        }
    }

    pub fn operands<'a>(
        &'a self,
        beta_a: &'a [f64],
        beta_b: &'a [f64],
        w: Option<&'a Mat<f64>>,
    ) -> BlockOperands<'a> {
        let w = w.map(|w| {
            let stride = w.col_stride() as usize;
            // An empty W (N = 0, which `validate_data` refuses but a hand-built `MmModel` can
            // still hold) has no storage to span: `ncols − 1` would wrap to a huge length.
            let Some(last_col) = w.ncols().checked_sub(1).filter(|_| w.nrows() > 0) else {
                return (&[][..], stride);
            };
            let len = stride * last_col + w.nrows();
            debug_assert!(stride >= w.nrows(), "a Mat's columns do not overlap");
            // SAFETY: a Mat's columns are contiguous with this stride; the slice covers
            // exactly its storage from the first to the last element.
            (
                unsafe { std::slice::from_raw_parts(w.as_ptr(), len) },
                stride,
            )
        });
        BlockOperands {
            n: self.row.len(),
            d: self.scaled_a.ncols(),
            a_hat: &self.a_hat,
            b: &self.b_rows,
            row: &self.row,
            col: &self.col,
            beta_a,
            beta_b,
            w,
            symmetric: false,
        }
    }

    /// `Σ_ij β_ai L_ij β_bj`, and for a diagonal pair with model variance `Σ_ij W_ij L_ij` in
    /// the same sweep (0 otherwise).
    fn forward_sums(&self, model: &MmModel<'_>, a: usize, b: usize) -> (f64, f64) {
        let n = self.row.len();
        let beta_a: Vec<f64> = (0..n).map(|i| model.beta[(i, a)]).collect();
        let beta_b: Vec<f64> = (0..n).map(|i| model.beta[(i, b)]).collect();
        let w = match (a == b, model.variance) {
            (true, Variance::Model(w)) => Some(&w[a]),
            _ => None,
        };
        let mut ops = self.operands(&beta_a, &beta_b, w);
        ops.symmetric = a == b;
        block_forward(&ops)
    }
}
