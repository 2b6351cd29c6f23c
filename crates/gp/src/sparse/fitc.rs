//! The FITC (SPGP) approximation of one output: factorisation, negative log marginal likelihood
//! and its gradient w.r.t. the inducing inputs and the hyper-parameters (PILCO's `fitc.m`,
//! which has the inducing-input part only).
//!
//! Notation (oracle README, gp1): training inputs X (N×D), inducing inputs U (M×D),
//! `K_mm = k(U,U) + ρI` (ρ = [`FITC_RIDGE`]), `K_mn = k(U,X)`, `Q = K_nm K_mm⁻¹ K_mn`,
//! `Γ = diag(σ_f² − diag Q) + σ_n² I` (diagonal γ), and the FITC covariance `C = Q + Γ`.
//!
//! Stable form (Snelson's thesis §2.3; what `fitc.m`/`gp1d.m` do): with `K_mm = L Lᵀ`,
//! `V = L⁻¹ K_mn` and `A = I + V Γ⁻¹ Vᵀ = L_A L_Aᵀ` (eigenvalues ≥ 1, well conditioned
//! whatever the ridge does to K_mm), `B = K_mm + K_mn Γ⁻¹ K_nm = L A Lᵀ` and
//!
//! * `log|C| = log|A| + Σ log γ_n`,
//! * `α = C⁻¹ y = Γ⁻¹ (y − Vᵀ r)`, `r = A⁻¹ V Γ⁻¹ y`,
//! * `nlml = ½ yᵀα + ½ log|C| + (N/2) log 2π`,
//! * `β = B⁻¹ K_mn Γ⁻¹ y = L⁻ᵀ r`, `K_mm⁻¹ − B⁻¹ = L⁻ᵀ (I − A⁻¹) L⁻¹`.
//!
//! **Gradient.** `C̄ = ½(C⁻¹ − ααᵀ)` is the adjoint of C. Q enters C directly and through
//! `γ = σ_f² + σ_n² − diag Q`, so the adjoint of Q is `D = C̄ − Diag(C̄)`. From
//! `dQ = dK_nm P + Pᵀ dK_mn − Pᵀ dK_mm P` (`P = K_mm⁻¹ K_mn`):
//! `K̄_mn = 2 P D` and `K̄_mm = −P D Pᵀ = −½ K̄_mn Pᵀ`. With Woodbury (`C⁻¹ = Γ⁻¹ − Γ⁻¹K_nm B⁻¹
//! K_mn Γ⁻¹`) everything stays O(N M²):
//!
//! `K̄_mn = L⁻ᵀ T`, `T = V diag(δ − g) + A⁻¹V diag(g) − (Vα) αᵀ`, `K̄_mm = −½ L⁻ᵀ (T Vᵀ) L⁻¹`,
//!
//! with `g = 1/γ`, `s_n = v_nᵀ A⁻¹ v_n`, `δ_n = g_n² s_n + α_n²`, and
//! `C̄_nn = ½(g_n − g_n² s_n − α_n²)`. The SE kernel then gives, with `E = K̄_mn ∘ K_mn` and
//! `F = K̄_mm ∘ k(U,U)`:
//!
//! * `∂/∂u_md = −ℓ_d⁻² [Σ_n E_mn (u_md − x_nd) + 2 Σ_j F_mj (u_md − u_jd)]`,
//! * `∂/∂log ℓ_d = ℓ_d⁻² [Σ_mn E_mn (u_md − x_nd)² + Σ_ij F_ij (u_id − u_jd)²]`,
//! * `∂/∂log σ_f = 2 (Σ E + Σ F + σ_f² Σ_n C̄_nn)`, `∂/∂log σ_n = 2 σ_n² Σ_n C̄_nn`.
//!
//! `T Vᵀ = V diag(δ − g) Vᵀ + I − A⁻¹ − (Vα)(Vα)ᵀ` (because `A⁻¹ V Γ⁻¹ Vᵀ = I − A⁻¹`) is
//! symmetric, so only its lower triangle is multiplied out.
//!
//! Cost per evaluation: one M×N triangular solve and a half product for the factorisation,
//! two solves for `A⁻¹V`, a half product for `T Vᵀ` and one solve for `K̄_mn` (≈ 6·M²N
//! flops), plus O(M³ + MND).

use crate::error::{GpError, Result};
use crate::fastexp::exp_in_place;
use crate::kernel::{Hyper, Kernel, SquaredExponential};
use crate::linalg::{check_finite, symmetrise, Chol, JitterPolicy};
use crate::model::validate_data;
use faer::{Accum, Mat, MatRef, Par};

/// The fixed ridge PILCO adds to `K_mm` wherever it appears (`fitc.m`, `gp1d.m`).
pub const FITC_RIDGE: f64 = 1e-6;

/// `k(A, B)` for the SE kernel, |A|×|B|, computed on length-scale-scaled coordinates.
pub(crate) fn se_cross(h: &Hyper, a: MatRef<'_, f64>, b: MatRef<'_, f64>) -> Mat<f64> {
    let d = a.ncols();
    let il: Vec<f64> = h.log_ls.iter().map(|l| (-l).exp()).collect();
    let scaled = |x: MatRef<'_, f64>| -> Vec<f64> {
        (0..x.nrows())
            .flat_map(|i| (0..d).map(move |c| (i, c)))
            .map(|(i, c)| x[(i, c)] * il[c])
            .collect()
    };
    let (sa, sb) = (scaled(a), scaled(b));
    let log_sf2 = 2.0 * h.log_sf;
    let mut k = Mat::zeros(a.nrows(), b.nrows());
    for j in 0..b.nrows() {
        let bj = &sb[j * d..(j + 1) * d];
        let col = k.col_as_slice_mut(j);
        for (v, ai) in col.iter_mut().zip(sa.chunks_exact(d)) {
            let q: f64 = ai.iter().zip(bj).map(|(p, r)| (p - r) * (p - r)).sum();
            *v = log_sf2 - 0.5 * q;
        }
        // σ_f² exp(−q/2) = exp(2 log σ_f − q/2), vectorised over the column.
        exp_in_place(col);
    }
    k
}

/// Everything one output's FITC model keeps after factorising.
pub(crate) struct FitcFactor {
    /// `k(U, X)`, M×N.
    pub kmn: Mat<f64>,
    /// `k(U, U)` without the ridge, M×M.
    pub kmm: Mat<f64>,
    /// Cholesky factor of `K_mm + ρI` (+ jitter, if it needed some).
    pub l: Chol,
    /// `L⁻¹ K_mn`, M×N.
    pub v: Mat<f64>,
    /// Diagonal of Γ.
    pub gamma: Vec<f64>,
    /// Cholesky factor of `A = I + V Γ⁻¹ Vᵀ`.
    pub la: Chol,
    /// `A⁻¹ V Γ⁻¹ y` (so β = L⁻ᵀ r).
    pub r: Vec<f64>,
    /// `C⁻¹ y`.
    pub alpha: Vec<f64>,
    /// Negative log marginal likelihood.
    pub value: f64,
}

/// Check inducing inputs `what` are finite and M×`d` with M ≥ 1 (the training data are
/// [`validate_data`]'s).
pub(crate) fn validate_inducing(inducing: MatRef<'_, f64>, d: usize, what: &str) -> Result<()> {
    check_finite(inducing, what)?;
    if inducing.ncols() != d || inducing.nrows() == 0 {
        return Err(GpError::Shape {
            what: what.into(),
            expected: format!("M×{d} with M ≥ 1"),
            got: format!("{}×{}", inducing.nrows(), inducing.ncols()),
        });
    }
    Ok(())
}

/// Factorise one output. `kmm_jitter`: `None` refuses a `K_mm + ρI` that is not numerically
/// positive definite (the training objective, as `fitc.m`); `Some` adds reported jitter (model
/// building).
pub(crate) fn factor(
    u: MatRef<'_, f64>,
    x: MatRef<'_, f64>,
    y: &[f64],
    h: &Hyper,
    kmm_jitter: Option<JitterPolicy>,
) -> Result<FitcFactor> {
    let (m, n) = (u.nrows(), x.nrows());
    let kernel = SquaredExponential;
    let kmm = kernel.gram(h, u);
    let mut kmm_r = kmm.clone();
    for i in 0..m {
        kmm_r[(i, i)] += FITC_RIDGE;
    }
    let what = "K_mm + 1e-6 I (FITC)";
    let l = match kmm_jitter {
        None => Chol::new(kmm_r.as_ref(), what)?,
        Some(p) => Chol::with_jitter(kmm_r.as_ref(), what, p)?,
    };
    let kmn = se_cross(h, u, x);
    let mut v = kmn.clone();
    l.solve_l_in_place(v.as_mut());

    let base = h.sf2() + h.sn2();
    let mut gamma = Vec::with_capacity(n);
    for j in 0..n {
        let q: f64 = v.col_as_slice(j).iter().map(|a| a * a).sum();
        let g = base - q;
        if !(g > 0.0 && g.is_finite()) {
            return Err(GpError::Numerical {
                what: "FITC diagonal Γ".into(),
                detail: format!("Γ_{j} = {g} is not positive"),
            });
        }
        gamma.push(g);
    }
    // A = I + Ṽ Ṽᵀ with Ṽ = V Γ^{-1/2}.
    let mut vt = v.clone();
    for j in 0..n {
        let s = 1.0 / gamma[j].sqrt();
        vt.col_as_slice_mut(j).iter_mut().for_each(|a| *a *= s);
    }
    let mut a = Mat::<f64>::identity(m, m);
    lower_product_add(&mut a, vt.as_ref(), vt.as_ref());
    drop(vt);
    let la = Chol::new(a.as_ref(), "I + V Γ⁻¹ Vᵀ (FITC)")?;

    let yg: Vec<f64> = y.iter().zip(&gamma).map(|(a, g)| a / g).collect();
    let w = mat_vec(v.as_ref(), &yg);
    let r = la.solve_vec(&w);
    let vtr = mat_t_vec(v.as_ref(), &r);
    let alpha: Vec<f64> = (0..n).map(|j| (y[j] - vtr[j]) / gamma[j]).collect();
    let fit: f64 = y.iter().zip(&alpha).map(|(a, b)| a * b).sum();
    let log_gamma: f64 = gamma.iter().map(|g| g.ln()).sum();
    let value = 0.5 * fit
        + 0.5 * (la.log_det() + log_gamma)
        + 0.5 * n as f64 * (2.0 * std::f64::consts::PI).ln();
    if !value.is_finite() {
        return Err(GpError::Numerical {
            what: "FITC nlml".into(),
            detail: "non-finite value".into(),
        });
    }
    Ok(FitcFactor {
        kmn,
        kmm,
        l,
        v,
        gamma,
        la,
        r,
        alpha,
        value,
    })
}

/// `C ← C + A Bᵀ` where the product is known to be symmetric: only the lower triangle is
/// computed (half the flops), then mirrored. `C` must be symmetric on entry.
fn lower_product_add(c: &mut Mat<f64>, a: MatRef<'_, f64>, b: MatRef<'_, f64>) {
    use faer::linalg::matmul::triangular::{matmul as tri_matmul, BlockStructure};
    tri_matmul(
        c.as_mut(),
        BlockStructure::TriangularLower,
        Accum::Add,
        a,
        BlockStructure::Rectangular,
        b.transpose(),
        BlockStructure::Rectangular,
        1.0,
        Par::Seq,
    );
    for j in 0..c.ncols() {
        for i in 0..j {
            c[(i, j)] = c[(j, i)];
        }
    }
}

/// `A b` for an M×N matrix stored column-major.
pub(crate) fn mat_vec(a: MatRef<'_, f64>, b: &[f64]) -> Vec<f64> {
    let mut out = vec![0.0; a.nrows()];
    for (j, bj) in b.iter().enumerate() {
        for (o, v) in out.iter_mut().zip(a.col(j).iter()) {
            *o += v * bj;
        }
    }
    out
}

/// `Aᵀ b`.
pub(crate) fn mat_t_vec(a: MatRef<'_, f64>, b: &[f64]) -> Vec<f64> {
    (0..a.ncols())
        .map(|j| a.col(j).iter().zip(b).map(|(p, q)| p * q).sum())
        .collect()
}

/// FITC negative log marginal likelihood of one output with its gradients.
#[derive(Clone, Debug)]
pub struct FitcEval {
    /// The FITC nlml `½ yᵀC⁻¹y + ½ log|C| + (N/2) log 2π` (with `K_mm + ρI`, ρ = [`FITC_RIDGE`]).
    pub value: f64,
    /// ∂nlml/∂U, M×D.
    pub grad_inducing: Mat<f64>,
    /// ∂nlml/∂(log hyper-parameters), PILCO order `[log ℓ.., log σ_f, log σ_n]`.
    pub grad_hyp: Vec<f64>,
}

/// FITC negative log marginal likelihood of one output (targets `y`) and its gradient w.r.t.
/// the inducing inputs `u` (M×D) and the log hyper-parameters. The data are checked as
/// [`train_inducing`](super::train_inducing) checks them, so a NaN is reported where it is,
/// not as the non-positive Γ or the non-finite value it leads to.
pub fn fitc_nlml(
    inputs: MatRef<'_, f64>,
    y: &[f64],
    hyp: &Hyper,
    inducing: MatRef<'_, f64>,
) -> Result<FitcEval> {
    validate_data(
        inputs,
        MatRef::from_column_major_slice(y, y.len(), 1),
        std::slice::from_ref(hyp),
    )?;
    validate_inducing(inducing, inputs.ncols(), "inducing inputs")?;
    let f = factor(inducing, inputs, y, hyp, None)?;
    Ok(gradient(&f, inducing, inputs, hyp))
}

pub(crate) fn gradient(
    f: &FitcFactor,
    u: MatRef<'_, f64>,
    x: MatRef<'_, f64>,
    h: &Hyper,
) -> FitcEval {
    let (m, n, d) = (u.nrows(), x.nrows(), x.ncols());
    // R = A⁻¹ V.
    let r = f.la.solve(f.v.as_ref());
    let t_vec = mat_vec(f.v.as_ref(), &f.alpha); // V α
    let mut diag_sum = 0.0; // Σ_n C̄_nn
                            // W = V diag(δ − g), later turned into T = W + R diag(g) − (Vα) αᵀ in place.
    let mut w = f.v.clone();
    let mut g = vec![0.0; n];
    for j in 0..n {
        g[j] = 1.0 / f.gamma[j];
        let s: f64 =
            f.v.col_as_slice(j)
                .iter()
                .zip(r.col_as_slice(j))
                .map(|(p, q)| p * q)
                .sum();
        let a = f.alpha[j];
        let delta = g[j] * g[j] * s + a * a;
        diag_sum += 0.5 * (g[j] - g[j] * g[j] * s - a * a);
        let scale = delta - g[j];
        w.col_as_slice_mut(j).iter_mut().for_each(|v| *v *= scale);
    }
    // S = T Vᵀ = V diag(δ − g) Vᵀ + (I − A⁻¹) − (Vα)(Vα)ᵀ, since A⁻¹ V Γ⁻¹ Vᵀ = I − A⁻¹.
    let mut s = f.la.inverse();
    for j in 0..m {
        for (i, v) in s.col_as_slice_mut(j).iter_mut().enumerate() {
            *v = -*v - t_vec[i] * t_vec[j];
        }
        s[(j, j)] += 1.0;
    }
    lower_product_add(&mut s, w.as_ref(), f.v.as_ref());
    // K̄_mm = −½ L⁻ᵀ S L⁻¹.
    f.l.solve_lt_in_place(s.as_mut());
    let mut kbar_mm = s.transpose().to_owned();
    f.l.solve_lt_in_place(kbar_mm.as_mut());
    symmetrise(&mut kbar_mm);
    for j in 0..m {
        kbar_mm
            .col_as_slice_mut(j)
            .iter_mut()
            .for_each(|v| *v *= -0.5);
    }
    // K̄_mn = L⁻ᵀ T.
    for j in 0..n {
        let a = f.alpha[j];
        let rj = r.col_as_slice(j);
        for ((v, rr), tv) in w.col_as_slice_mut(j).iter_mut().zip(rj).zip(&t_vec) {
            *v += rr * g[j] - tv * a;
        }
    }
    f.l.solve_lt_in_place(w.as_mut());
    let kbar_mn = w;

    let il2 = h.inv_ls2();
    let ur: Vec<f64> = (0..m)
        .flat_map(|i| (0..d).map(move |c| (i, c)))
        .map(|(i, c)| u[(i, c)])
        .collect();
    let mut gu = vec![0.0; m * d];
    let mut gl = vec![0.0; d];
    let mut sum_e = 0.0;
    let mut xj = vec![0.0; d];
    for j in 0..n {
        for (c, v) in xj.iter_mut().enumerate() {
            *v = x[(j, c)];
        }
        let kb = kbar_mn.col_as_slice(j);
        let kk = f.kmn.col_as_slice(j);
        for i in 0..m {
            let e = kb[i] * kk[i];
            sum_e += e;
            let ui = &ur[i * d..(i + 1) * d];
            let gi = &mut gu[i * d..(i + 1) * d];
            for c in 0..d {
                let diff = ui[c] - xj[c];
                gi[c] += e * diff;
                gl[c] += e * diff * diff;
            }
        }
    }
    let mut sum_f = 0.0;
    for j in 0..m {
        let kb = kbar_mm.col_as_slice(j);
        let kk = f.kmm.col_as_slice(j);
        let uj = &ur[j * d..(j + 1) * d];
        for i in 0..m {
            let e = kb[i] * kk[i];
            sum_f += e;
            if i == j {
                continue;
            }
            let ui = &ur[i * d..(i + 1) * d];
            let gi = &mut gu[i * d..(i + 1) * d];
            for c in 0..d {
                let diff = ui[c] - uj[c];
                gi[c] += 2.0 * e * diff;
                gl[c] += e * diff * diff;
            }
        }
    }
    let grad_inducing = Mat::from_fn(m, d, |i, c| -il2[c] * gu[i * d + c]);
    let mut grad_hyp: Vec<f64> = gl.iter().zip(&il2).map(|(g, l)| g * l).collect();
    grad_hyp.push(2.0 * (sum_e + sum_f + h.sf2() * diag_sum));
    grad_hyp.push(2.0 * h.sn2() * diag_sum);
    FitcEval {
        value: f.value,
        grad_inducing,
        grad_hyp,
    }
}
