//! Backward pass (vector-Jacobian product) of moment matching.
//!
//! Given adjoints `(M̄, S̄, V̄)` of the outputs, returns `(m̄, s̄)` and optionally the adjoints
//! of the model's parameters. The derivation follows the forward pass step by step; the
//! notation is that of [`super`] plus, per output pair, `Φ_ij = ∂f/∂E_ij` for the exponent
//! `E_ij = r_i + c_j + P_ij` of the block `L = exp(E)`:
//!
//! * `Φ = t L ∘ (G β_a β_bᵀ − δ_ab S̄_aa W_a)`, `G = S̄_ab + S̄_ba` (`S̄_aa` when a = b);
//! * `T̄ = 𝒜ᵀdiag(rowsum Φ)𝒜 + ℬᵀdiag(colsum Φ)ℬ + 2𝒜ᵀΦℬ`;
//! * `T = ½R⁻¹s` gives `s̄ += ½ R⁻ᵀ T̄ (I − 2TΛ')` and `t = |R|^{-1/2}` gives
//!   `s̄ −= ½ (ΣΦ) R⁻ᵀΛ'`;
//! * the mean part, with `A = (s+Λ)⁻¹`, `g_i = β_i q_i (M̄ + (AV̄)ᵀν_i)`:
//!   `s̄ −= A Ā A + ½ (Σg) A`, `Ā = V̄ uᵀ − ½ Σ_i g_i ν_iν_iᵀ`.

use super::forward::{MmCache, MmModel, PairBlock, Variance};
use super::kernels::block_backward;
use super::small::{mat_vec, mul, mul_tn, weighted_col_sum, weighted_gram};
use crate::error::{GpError, Result};
use faer::{Mat, MatRef};
use rayon::prelude::*;

/// Adjoints of the moment-matching outputs.
#[derive(Clone, Copy, Debug)]
pub struct MomentsAdjoint<'a> {
    /// E.
    pub mean: &'a [f64],
    /// E×E.
    pub cov: MatRef<'a, f64>,
    /// D×E.
    pub v: MatRef<'a, f64>,
}

/// Adjoints of the model's own numbers (for a GP mean used as an RBF policy).
#[derive(Clone, Debug)]
pub struct ParamAdjoint {
    /// N×D, w.r.t. the centres (training or inducing inputs) where they enter the moment
    /// formulas directly (not through β).
    pub centres: Mat<f64>,
    /// N×E, w.r.t. β.
    pub beta: Mat<f64>,
    /// D×E, w.r.t. log length-scales (not through β).
    pub log_ls: Mat<f64>,
    /// E, w.r.t. log σ_f (not through β).
    pub log_sf: Vec<f64>,
}

/// Adjoints of the Gaussian input, and optionally of the model parameters.
#[derive(Clone, Debug)]
pub struct InputAdjoint {
    /// D, `m̄ = ∂f/∂m` for the input mean.
    pub m: Vec<f64>,
    /// D×D, symmetrised.
    pub s: Mat<f64>,
    /// `Some` exactly when [`backward`] was called with `with_params`.
    pub params: Option<ParamAdjoint>,
}

struct PairGrad {
    s_bar: Mat<f64>,
    nu_sum: Vec<f64>,
    params: Option<PairParamGrad>,
}

struct PairParamGrad {
    nu: Mat<f64>,
    beta_a: Vec<f64>,
    beta_b: Vec<f64>,
    inv_ls2_a: Vec<f64>,
    inv_ls2_b: Vec<f64>,
    log_sf_each: f64,
}

/// Vector-Jacobian product of [`super::forward`]. With `with_params`, also the adjoints of
/// centres, β, log length-scales and log σ_f; that is only offered for the deterministic
/// flavour ([`Variance::DiagonalJitter`]), the one whose parameters are learned.
pub fn backward(
    model: &MmModel<'_>,
    cache: &MmCache,
    adj: MomentsAdjoint<'_>,
    with_params: bool,
) -> Result<InputAdjoint> {
    let (n, d, e) = (cache.nu.nrows(), model.input_dim(), model.output_dim());
    if adj.mean.len() != e
        || adj.cov.nrows() != e
        || adj.cov.ncols() != e
        || adj.v.nrows() != d
        || adj.v.ncols() != e
    {
        return Err(GpError::Shape {
            what: "moment-matching adjoints".into(),
            expected: format!("M̄ ({e}), S̄ ({e}×{e}), V̄ ({d}×{e})"),
            got: format!(
                "M̄ ({}), S̄ ({}×{}), V̄ ({}×{})",
                adj.mean.len(),
                adj.cov.nrows(),
                adj.cov.ncols(),
                adj.v.nrows(),
                adj.v.ncols()
            ),
        });
    }
    if with_params && matches!(model.variance, Variance::Model(_)) {
        return Err(GpError::Numerical {
            what: "moment-matching backward".into(),
            detail: "parameter adjoints are only defined for the deterministic (mean-only) GP"
                .into(),
        });
    }
    let s_bar_out = adj.cov;
    // S_ab = … − M_a M_b: fold that into the mean adjoint first.
    let mut m_bar_eff = adj.mean.to_vec();
    for a in 0..e {
        for b in 0..e {
            m_bar_eff[a] -= (s_bar_out[(a, b)] + s_bar_out[(b, a)]) * cache.mean[b];
        }
    }

    let pair_grads: Vec<PairGrad> = cache
        .pairs
        .par_iter()
        .map(|pc| {
            let (a, b) = (pc.a, pc.b);
            let g = if a == b {
                s_bar_out[(a, a)]
            } else {
                s_bar_out[(a, b)] + s_bar_out[(b, a)]
            };
            let w_diag = match (a == b, model.variance) {
                (true, Variance::Model(w)) => Some(&w[a]),
                _ => None,
            };
            let blk = PairBlock::new(&cache.nu, &cache.outputs, pc);
            // Φ = t L ∘ (G β_a β_bᵀ − δ_ab S̄_aa W_a)
            let beta_a: Vec<f64> = (0..n).map(|i| model.beta[(i, a)]).collect();
            let beta_b: Vec<f64> = (0..n).map(|j| model.beta[(j, b)]).collect();
            let ops = blk.operands(&beta_a, &beta_b, w_diag);
            let scale_w = if w_diag.is_some() { pc.t * g } else { 0.0 };
            let kb = block_backward(
                &ops,
                pc.t * g,
                scale_w,
                with_params.then_some(blk.a_cols.as_slice()),
            );
            let r = kb.phi_row;
            let c = kb.phi_col;
            let phi_b = Mat::from_fn(n, d, |i, k| kb.phi_b[k * n + i]);
            let l_beta_b = kb.l_beta_b;
            let lt_beta_a = kb.lt_beta_a;
            let phi_sum: f64 = r.iter().sum();
            // T̄ = 𝒜ᵀdiag(r)𝒜 + ℬᵀdiag(c)ℬ + 2𝒜ᵀΦℬ
            let mut t_bar = weighted_gram(blk.scaled_a.as_ref(), &r);
            let gb_ = weighted_gram(blk.scaled_b.as_ref(), &c);
            let cross = mul_tn(blk.scaled_a.as_ref(), phi_b.as_ref());
            for k in 0..d {
                for l in 0..d {
                    t_bar[(k, l)] += gb_[(k, l)] + 2.0 * cross[(k, l)];
                }
            }
            // s̄ += ½ R⁻ᵀ T̄ (I − 2TΛ') − ½ ΣΦ R⁻ᵀΛ'
            let i_minus = Mat::from_fn(
                d,
                d,
                |k, l| if k == l { 1.0 } else { 0.0 } - 2.0 * pc.t_mat[(k, l)] * pc.lam[l],
            );
            let rt_tbar = mul_tn(pc.r_inv.as_ref(), t_bar.as_ref());
            let mut s_bar = mul(rt_tbar.as_ref(), i_minus.as_ref());
            for k in 0..d {
                for l in 0..d {
                    s_bar[(k, l)] =
                        0.5 * s_bar[(k, l)] - 0.5 * phi_sum * pc.r_inv[(l, k)] * pc.lam[l];
                }
            }
            // Σ_i ā_i = Σ_j b̄_j = 2T(𝒜ᵀr + ℬᵀc)
            let ar = weighted_col_sum(blk.scaled_a.as_ref(), &r);
            let bc = weighted_col_sum(blk.scaled_b.as_ref(), &c);
            let sum_ab: Vec<f64> = (0..d).map(|k| ar[k] + bc[k]).collect();
            let gvec: Vec<f64> = mat_vec(pc.t_mat.as_ref(), &sum_ab)
                .iter()
                .map(|v| 2.0 * v)
                .collect();
            let nu_r = weighted_col_sum(cache.nu.as_ref(), &r);
            let nu_c = weighted_col_sum(cache.nu.as_ref(), &c);
            let la = &cache.outputs[a].inv_ls2;
            let lb = &cache.outputs[b].inv_ls2;
            let nu_sum: Vec<f64> = (0..d)
                .map(|k| la[k] * (gvec[k] - nu_r[k]) + lb[k] * (gvec[k] - nu_c[k]))
                .collect();

            let params = with_params.then(|| {
                let phit = kb.phit_a.as_ref().expect("requested with the parameters");
                let phit_a = Mat::from_fn(n, d, |j, k| phit[j * d + k]);
                // Ā = 2(diag(r)𝒜 + Φℬ)T, ℬ̄ = 2(diag(c)ℬ + Φᵀ𝒜)T
                let abar_pre = Mat::from_fn(n, d, |i, k| {
                    2.0 * (r[i] * blk.scaled_a[(i, k)] + phi_b[(i, k)])
                });
                let bbar_pre = Mat::from_fn(n, d, |j, k| {
                    2.0 * (c[j] * blk.scaled_b[(j, k)] + phit_a[(j, k)])
                });
                let abar = mul(abar_pre.as_ref(), pc.t_mat.as_ref());
                let bbar = mul(bbar_pre.as_ref(), pc.t_mat.as_ref());
                let nu_adj = Mat::from_fn(n, d, |i, k| {
                    let x = cache.nu[(i, k)];
                    la[k] * (abar[(i, k)] - r[i] * x) + lb[k] * (bbar[(i, k)] - c[i] * x)
                });
                // Λ̄'_d = −2 (T T̄ᵀ T)_dd − ΣΦ T_dd
                let tt = mul(pc.t_mat.as_ref(), t_bar.transpose());
                let ttt = mul(tt.as_ref(), pc.t_mat.as_ref());
                let lam_bar: Vec<f64> = (0..d)
                    .map(|k| -2.0 * ttt[(k, k)] - phi_sum * pc.t_mat[(k, k)])
                    .collect();
                let mut inv_a = lam_bar.clone();
                let mut inv_b = lam_bar;
                for k in 0..d {
                    for i in 0..n {
                        let x = cache.nu[(i, k)];
                        inv_a[k] += abar[(i, k)] * x - 0.5 * r[i] * x * x;
                        inv_b[k] += bbar[(i, k)] * x - 0.5 * c[i] * x * x;
                    }
                }
                let tg = pc.t * g;
                PairParamGrad {
                    nu: nu_adj,
                    beta_a: l_beta_b.iter().map(|v| tg * v).collect(),
                    beta_b: lt_beta_a.iter().map(|v| tg * v).collect(),
                    inv_ls2_a: inv_a,
                    inv_ls2_b: inv_b,
                    log_sf_each: 2.0 * phi_sum,
                }
            });
            PairGrad {
                s_bar,
                nu_sum,
                params,
            }
        })
        .collect();

    let mut s_bar = Mat::<f64>::zeros(d, d);
    let mut nu_sum = vec![0.0; d];
    let mut params = with_params.then(|| ParamAdjoint {
        centres: Mat::zeros(n, d),
        beta: Mat::zeros(n, e),
        log_ls: Mat::zeros(d, e),
        log_sf: vec![0.0; e],
    });
    // Adjoints of the diagonal Λ⁻¹ of each output, converted to log ℓ at the end.
    let mut inv_ls2_bar = vec![vec![0.0; d]; e];
    for (pc, pg) in cache.pairs.iter().zip(pair_grads) {
        for k in 0..d {
            nu_sum[k] += pg.nu_sum[k];
            for l in 0..d {
                s_bar[(k, l)] += pg.s_bar[(k, l)];
            }
        }
        if let (Some(p), Some(pp)) = (params.as_mut(), pg.params) {
            for i in 0..n {
                for k in 0..d {
                    p.centres[(i, k)] += pp.nu[(i, k)];
                }
                p.beta[(i, pc.a)] += pp.beta_a[i];
                p.beta[(i, pc.b)] += pp.beta_b[i];
            }
            for k in 0..d {
                inv_ls2_bar[pc.a][k] += pp.inv_ls2_a[k];
                inv_ls2_bar[pc.b][k] += pp.inv_ls2_b[k];
            }
            p.log_sf[pc.a] += pp.log_sf_each;
            p.log_sf[pc.b] += pp.log_sf_each;
        }
    }

    // Mean part.
    for a in 0..e {
        let oc = &cache.outputs[a];
        let vbar: Vec<f64> = (0..d).map(|k| adj.v[(k, a)]).collect();
        let ubar = mat_vec(oc.a.as_ref(), &vbar);
        let nu_u = mat_vec(cache.nu.as_ref(), &ubar);
        let wbar: Vec<f64> = (0..n).map(|i| m_bar_eff[a] + nu_u[i]).collect();
        let w: Vec<f64> = (0..n).map(|i| model.beta[(i, a)] * oc.q[i]).collect();
        let gq: Vec<f64> = (0..n).map(|i| w[i] * wbar[i]).collect();
        let w_sum: f64 = w.iter().sum();
        let g_sum: f64 = gq.iter().sum();
        let nu_g = weighted_col_sum(cache.nu.as_ref(), &gq);
        let a_nu_g = mat_vec(oc.a.as_ref(), &nu_g);
        for k in 0..d {
            nu_sum[k] += w_sum * ubar[k] - a_nu_g[k];
        }
        // Ā = V̄ uᵀ − ½ Σ g_i ν_i ν_iᵀ ;  s̄ += −A Ā A − ½ (Σg) A
        let mut abar = weighted_gram(cache.nu.as_ref(), &gq);
        for k in 0..d {
            for l in 0..d {
                abar[(k, l)] = vbar[k] * oc.u[l] - 0.5 * abar[(k, l)];
            }
        }
        let aa = mul(oc.a.as_ref(), abar.as_ref());
        let aaa = mul(aa.as_ref(), oc.a.as_ref());
        for k in 0..d {
            for l in 0..d {
                s_bar[(k, l)] -= aaa[(k, l)] + 0.5 * g_sum * oc.a[(k, l)];
            }
        }
        if let Some(p) = params.as_mut() {
            let a_nu = mul(cache.nu.as_ref(), oc.a.as_ref());
            for i in 0..n {
                p.beta[(i, a)] += oc.q[i] * wbar[i];
                for k in 0..d {
                    p.centres[(i, k)] += w[i] * ubar[k] - gq[i] * a_nu[(i, k)];
                }
            }
            p.log_sf[a] += 2.0 * g_sum;
            let inv = &oc.inv_ls2;
            for k in 0..d {
                // Λ̄_kk from A = (s+Λ)⁻¹ and from c ∝ |Λ|^{1/2} |s+Λ|^{-1/2}; dΛ_kk/dlog ℓ_k = 2Λ_kk.
                let lam_kk = 1.0 / inv[k];
                let lam_bar = -aaa[(k, k)] - 0.5 * g_sum * oc.a[(k, k)] + 0.5 * g_sum * inv[k];
                // Λ⁻¹ enters the pair blocks; d(1/ℓ²)/dlog ℓ = −2/ℓ².
                p.log_ls[(k, a)] = 2.0 * lam_kk * lam_bar - 2.0 * inv[k] * inv_ls2_bar[a][k];
            }
        }
    }
    if let (Some(p), Variance::Model(_)) = (params.as_mut(), model.variance) {
        // Unreachable by the check above; kept so a future relaxation cannot silently drop
        // the σ_f² term of the model variance.
        for a in 0..e {
            p.log_sf[a] += 2.0 * model.hyp[a].sf2() * s_bar_out[(a, a)];
        }
    }
    crate::linalg::symmetrise(&mut s_bar);
    let m_bar: Vec<f64> = nu_sum.iter().map(|v| -v).collect();
    Ok(InputAdjoint {
        m: m_bar,
        s: s_bar,
        params,
    })
}
