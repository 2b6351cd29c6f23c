//! Small dense helpers (D×D and N×D blocks) shared by the forward and backward passes.

use super::forward::{MmModel, Variance};
use crate::error::{GpError, Result};
use crate::linalg::Chol;
use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, MatRef, Par};

/// Inverse and log-determinant of a small symmetric positive-definite matrix.
pub(crate) fn spd_inverse_logdet(a: MatRef<'_, f64>, what: &str) -> Result<(Mat<f64>, f64)> {
    let c = Chol::new(a, what)?;
    let mut inv = c.inverse();
    crate::linalg::symmetrise(&mut inv);
    Ok((inv, c.log_det()))
}

/// `C = A B` (fresh matrix).
pub(crate) fn mul(a: MatRef<'_, f64>, b: MatRef<'_, f64>) -> Mat<f64> {
    let mut c = Mat::zeros(a.nrows(), b.ncols());
    matmul(c.as_mut(), Accum::Replace, a, b, 1.0, Par::Seq);
    c
}

/// `C = Aᵀ B` (fresh matrix).
pub(crate) fn mul_tn(a: MatRef<'_, f64>, b: MatRef<'_, f64>) -> Mat<f64> {
    mul(a.transpose(), b)
}

/// `A diag(d)`: scale the columns.
pub(crate) fn scale_cols(a: MatRef<'_, f64>, d: &[f64]) -> Mat<f64> {
    let mut out = a.to_owned();
    for (j, dj) in d.iter().enumerate() {
        for v in out.col_mut(j).iter_mut() {
            *v *= dj;
        }
    }
    out
}

/// Row-wise quadratic forms `x_iᵀ T x_i` for the rows of X (T symmetric).
pub(crate) fn row_quad(x: MatRef<'_, f64>, t: MatRef<'_, f64>) -> Vec<f64> {
    let xt = mul(x, t);
    let mut out = vec![0.0; x.nrows()];
    for k in 0..x.ncols() {
        for ((o, a), b) in out.iter_mut().zip(xt.col(k).iter()).zip(x.col(k).iter()) {
            *o += a * b;
        }
    }
    out
}

/// `Xᵀ diag(w) X` (D×D).
pub(crate) fn weighted_gram(x: MatRef<'_, f64>, w: &[f64]) -> Mat<f64> {
    let (n, d) = (x.nrows(), x.ncols());
    let mut out = Mat::zeros(d, d);
    for k in 0..d {
        for l in 0..=k {
            let mut acc = 0.0;
            for i in 0..n {
                acc += w[i] * x[(i, k)] * x[(i, l)];
            }
            out[(k, l)] = acc;
            out[(l, k)] = acc;
        }
    }
    out
}

/// `Xᵀ w` (D).
pub(crate) fn weighted_col_sum(x: MatRef<'_, f64>, w: &[f64]) -> Vec<f64> {
    (0..x.ncols())
        .map(|k| (0..x.nrows()).map(|i| w[i] * x[(i, k)]).sum())
        .collect()
}

/// `A v` for a small matrix.
pub(crate) fn mat_vec(a: MatRef<'_, f64>, v: &[f64]) -> Vec<f64> {
    (0..a.nrows())
        .map(|i| (0..a.ncols()).map(|j| a[(i, j)] * v[j]).sum())
        .collect()
}

/// How far below 0 a moment-matching input variance may come before it is refused as a
/// caller's error rather than propagation's cancellation, as a fraction of the input's scale
/// ([`negative_variance_scale`]). The own-system example's 6 updates (seeds 1–3) reach 7.0e-5
/// of the data's variance and 3.3e-5 of ℓ²; the arm runs' quick updates reach none.
pub(crate) const NEGATIVE_VARIANCE_FRACTION: f64 = 1e-3;

/// The scale a negative variance on input `k` is measured against: the smaller of the
/// smallest squared length-scale on it (the moments depend on `s` through `Λ⁻¹s + I`) and the
/// variance of the model's centres along it (the input's own scale, which matters downstream:
/// ARD lets an input the outputs ignore take a length-scale far beyond its data). A column of
/// equal centres has no spread to measure by, and gets ℓ² alone.
fn negative_variance_scale(model: &MmModel<'_>, k: usize) -> f64 {
    let l2 = model
        .hyp
        .iter()
        .map(|h| (2.0 * h.log_ls[k]).exp())
        .fold(f64::INFINITY, f64::min);
    let c = model.centres.col(k);
    let n = c.nrows() as f64;
    let mean = c.iter().sum::<f64>() / n;
    let spread = c.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n;
    if spread > 0.0 && spread.is_finite() {
        l2.min(spread)
    } else {
        l2
    }
}

/// The entry check of [`super::forward`], once per call: the model's parts agree in shape
/// (its fields are public, so a hand-built one may not) and the input fits it.
pub(crate) fn check_moment_input(model: &MmModel<'_>, m: &[f64], s: MatRef<'_, f64>) -> Result<()> {
    let (n, d, e) = (model.centres.nrows(), model.input_dim(), model.output_dim());
    let shape = |what: String, expected: String, got: String| {
        Err(GpError::Shape {
            what,
            expected,
            got,
        })
    };
    if (model.beta.nrows(), model.beta.ncols()) != (n, e) {
        return shape(
            "moment-matching model β".into(),
            format!("{n}×{e} (one row per centre, one column per output)"),
            format!("{}×{}", model.beta.nrows(), model.beta.ncols()),
        );
    }
    if let Some((a, h)) = model.hyp.iter().enumerate().find(|(_, h)| h.dim() != d) {
        return shape(
            format!("moment-matching model hyp[{a}].log_ls"),
            format!("length {d} (one per centre column)"),
            format!("length {}", h.dim()),
        );
    }
    if let Variance::Model(w) = model.variance {
        if w.len() != e {
            return shape(
                "moment-matching model W".into(),
                format!("{e} matrices (one per output)"),
                format!("{}", w.len()),
            );
        }
        if let Some((a, wa)) = w
            .iter()
            .enumerate()
            .find(|(_, wa)| (wa.nrows(), wa.ncols()) != (n, n))
        {
            return shape(
                format!("moment-matching model W[{a}]"),
                format!("{n}×{n} (one row and column per centre)"),
                format!("{}×{}", wa.nrows(), wa.ncols()),
            );
        }
    }
    if m.len() != d || s.nrows() != d || s.ncols() != d {
        return Err(GpError::Shape {
            what: "moment-matching input".into(),
            expected: format!("mean of length {d} and {d}×{d} covariance"),
            got: format!(
                "mean of length {} and {}×{} covariance",
                m.len(),
                s.nrows(),
                s.ncols()
            ),
        });
    }
    if let Some(i) = m.iter().position(|v| !v.is_finite()) {
        return Err(GpError::NonFinite {
            what: "moment-matching input mean".into(),
            row: i,
            col: 0,
            value: m[i],
        });
    }
    crate::linalg::check_finite(s, "moment-matching input covariance")?;
    // Only the diagonal, O(D) per call: a full PSD test would cost a factorisation on the hot
    // path, and the Cholesky of `s + Λ` that follows catches gross indefiniteness. Variances
    // propagated over a horizon come out below 0 when the state is nearly deterministic: the
    // GP's predictive variance is a difference of terms far larger than itself (PILCO has the
    // same and goes on). One that is a small fraction of the input's scale changes the moments
    // by about that fraction; a caller's negative variance of the input's scale is refused.
    let largest = (0..d).fold(0.0f64, |acc, k| acc.max(s[(k, k)].abs()));
    let rounding = |k: usize| 1e-9 * (1.0 + m[k] * m[k] + largest);
    // The scale, O(N) per input, only where a variance is below rounding.
    let beyond = |k: usize| {
        s[(k, k)] < -rounding(k)
            && s[(k, k)]
                < -(rounding(k) + NEGATIVE_VARIANCE_FRACTION * negative_variance_scale(model, k))
    };
    if let Some(k) = (0..d).find(|&k| beyond(k)) {
        return Err(GpError::Numerical {
            what: "moment-matching input covariance".into(),
            detail: format!(
                "negative variance s[{k}, {k}] = {} at index {k}, beyond \
                 {NEGATIVE_VARIANCE_FRACTION} of that input's scale {} (the smaller of its \
                 smallest squared length-scale and its centres' variance)",
                s[(k, k)],
                negative_variance_scale(model, k)
            ),
        });
    }
    Ok(())
}
