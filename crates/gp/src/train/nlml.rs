//! The training objective of one output: the negative log marginal likelihood (PILCO's `gpr`
//! with `covSum{covSEard, covNoise}`) and the optional hyper-parameter penalty (`hypCurb`).
//!
//! With `K̃ = K + σ_n² I` and `α = K̃⁻¹ y`:
//!
//! `nlml = ½ yᵀα + ½ log|K̃| + (N/2) log 2π`,
//!
//! `∂nlml/∂θ = ½ tr((K̃⁻¹ − ααᵀ) ∂K̃/∂θ)` for θ = (log ℓ_1..log ℓ_D, log σ_f, log σ_n), where
//! `∂K̃/∂log σ_n = 2σ_n² I` and the kernel terms come from [`Kernel::gram_grad_contract`].
//!
//! One evaluation costs one Cholesky factorisation, one explicit inverse (the gradient needs
//! every entry of `K̃⁻¹`) and one O(N²D) contraction.
//!
//! The penalty (PILCO's `hypCurb`, switched on by default in training) is
//!
//! `Σ_d ((log ℓ_d − log c_d)/log ls)^p + ((log σ_f − log σ_n)/log snr)^p`
//!
//! with `c_d` the sample standard deviation (N−1 normalisation) of input column d. It keeps the
//! length-scales within a factor `ls` of the data spread and the signal-to-noise ratio below
//! `snr`, and is negligible inside that box (p = 30).

use crate::error::{GpError, Result};
use crate::kernel::{Hyper, Kernel, SquaredExponential};
use crate::linalg::{JitterPolicy, SpdWorkspace};
use crate::model::validate_data;
use faer::{Mat, MatRef};

/// Value and gradient of a training objective at one hyper-parameter set.
#[derive(Clone, Debug, PartialEq)]
pub struct NlmlEval {
    /// The objective value.
    pub value: f64,
    /// Gradient w.r.t. the log hyper-parameters in PILCO order
    /// `[log ℓ_1..log ℓ_D, log σ_f, log σ_n]`.
    pub grad: Vec<f64>,
    /// Diagonal jitter the Cholesky factorisation of `K + σ_n² I` needed (0 when none).
    pub jitter: f64,
}

/// PILCO's `hypCurb` penalty on extreme hyper-parameters (defaults: p = 30, ls = 100,
/// snr = 1000, as in pilco-matlab's `train.m`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HypCurb {
    /// Penalty power p (even, so the penalty is symmetric).
    pub power: i32,
    /// Allowed length-scale spread `ls`: log ℓ_d may move about `log ls` from log c_d.
    pub ls: f64,
    /// Allowed signal-to-noise ratio `snr`: log σ_f − log σ_n may reach about `log snr`.
    pub snr: f64,
}

impl Default for HypCurb {
    fn default() -> Self {
        Self {
            power: 30,
            ls: 100.0,
            snr: 1000.0,
        }
    }
}

impl HypCurb {
    /// Penalty value and gradient (PILCO order) for `hyp`, with `input_std` = c_d, one per
    /// length-scale ([`GpError::Shape`] otherwise).
    pub fn penalty(&self, hyp: &Hyper, input_std: &[f64]) -> Result<(f64, Vec<f64>)> {
        let d = hyp.dim();
        if input_std.len() != d {
            return Err(GpError::Shape {
                what: "hypCurb input_std (c_d)".into(),
                expected: format!("length {d} (one per length-scale)"),
                got: format!("length {}", input_std.len()),
            });
        }
        let p = self.power;
        let pf = f64::from(p);
        let mut value = 0.0;
        let mut grad = vec![0.0; d + 2];
        let lls = self.ls.ln();
        for c in 0..d {
            let z = (hyp.log_ls[c] - input_std[c].ln()) / lls;
            value += z.powi(p);
            grad[c] = pf * z.powi(p - 1) / lls;
        }
        let lsnr = self.snr.ln();
        let z = (hyp.log_sf - hyp.log_sn) / lsnr;
        value += z.powi(p);
        let g = pf * z.powi(p - 1) / lsnr;
        grad[d] = g;
        grad[d + 1] = -g;
        Ok((value, grad))
    }
}

/// Sample standard deviation (N−1 normalisation, MATLAB's `std`) of column `c`; 0 for fewer than
/// two rows. Callers choose their own floor for a zero spread, because a zero cannot go into a log.
pub(crate) fn column_std(m: MatRef<'_, f64>, c: usize) -> f64 {
    let n = m.nrows();
    if n < 2 {
        return 0.0;
    }
    let mean = (0..n).map(|i| m[(i, c)]).sum::<f64>() / n as f64;
    let ss: f64 = (0..n).map(|i| (m[(i, c)] - mean).powi(2)).sum();
    (ss / (n - 1) as f64).sqrt()
}

/// `column_std` of every input column: the `c_d` of [`HypCurb`]. A column with zero spread (or
/// a single row) gets 1, so the penalty stays finite.
pub fn input_std(inputs: MatRef<'_, f64>) -> Vec<f64> {
    (0..inputs.ncols())
        .map(|c| {
            let s = column_std(inputs, c);
            if s > 0.0 && s.is_finite() {
                s
            } else {
                1.0
            }
        })
        .collect()
}

/// Negative log marginal likelihood of one output with the squared-exponential kernel, and its
/// gradient w.r.t. the log hyper-parameters (PILCO's `gpr`). The data are checked as
/// [`crate::train()`] checks them ([`validate_data`]), so a NaN is reported where it is, not as
/// the factorisation it breaks.
pub fn nlml(inputs: MatRef<'_, f64>, y: &[f64], hyp: &Hyper) -> Result<NlmlEval> {
    validate_data(
        inputs,
        MatRef::from_column_major_slice(y, y.len(), 1),
        std::slice::from_ref(hyp),
    )?;
    let mut ws = NlmlWorkspace::new(inputs.nrows());
    nlml_with_kernel(
        &SquaredExponential,
        inputs,
        y,
        hyp,
        JitterPolicy::default(),
        &mut ws,
    )
}

/// [`nlml`] plus the [`HypCurb`] penalty (PILCO's `hypCurb`), with `c_d` computed from `inputs`.
pub fn nlml_curb(
    inputs: MatRef<'_, f64>,
    y: &[f64],
    hyp: &Hyper,
    curb: &HypCurb,
) -> Result<NlmlEval> {
    let mut e = nlml(inputs, y, hyp)?;
    let (p, g) = curb.penalty(hyp, &input_std(inputs))?;
    e.value += p;
    e.grad.iter_mut().zip(&g).for_each(|(a, b)| *a += b);
    Ok(e)
}

/// Buffers [`nlml_with_kernel`] reuses between evaluations at one N (the training loop keeps
/// one per output), so an evaluation allocates no N×N matrix.
pub struct NlmlWorkspace {
    spd: SpdWorkspace,
    k: Mat<f64>,
    g: Mat<f64>,
}

impl NlmlWorkspace {
    /// Buffers for `n` training points (an n×n Cholesky workspace and two n×n matrices);
    /// [`nlml_with_kernel`] refuses a workspace sized for another N.
    pub fn new(n: usize) -> Self {
        Self {
            spd: SpdWorkspace::new(n),
            k: Mat::zeros(n, n),
            g: Mat::zeros(n, n),
        }
    }
}

/// [`nlml`] for any [`Kernel`], with the jitter policy used when `K + σ_n² I` does not
/// factorise, and a workspace (sized for N, see [`NlmlWorkspace`]). The data are not checked
/// for NaN here, once per optimiser evaluation: callers validate them once ([`validate_data`],
/// as [`crate::train()`] does).
pub fn nlml_with_kernel<K: Kernel + ?Sized>(
    kernel: &K,
    inputs: MatRef<'_, f64>,
    y: &[f64],
    hyp: &Hyper,
    jitter: JitterPolicy,
    ws: &mut NlmlWorkspace,
) -> Result<NlmlEval> {
    let (n, d) = (inputs.nrows(), inputs.ncols());
    if y.len() != n || hyp.dim() != d || ws.spd.dim() != n {
        return Err(GpError::Shape {
            what: "nlml arguments".into(),
            expected: format!("{n} targets, {d} length-scales and a workspace for {n}"),
            got: format!(
                "{} targets, {} length-scales and a workspace for {}",
                y.len(),
                hyp.dim(),
                ws.spd.dim()
            ),
        });
    }
    if !hyp.is_finite() {
        return Err(GpError::Numerical {
            what: "nlml".into(),
            detail: format!("non-finite hyper-parameters {:?}", hyp.to_pilco()),
        });
    }
    let sn2 = hyp.sn2();
    kernel.gram_into(hyp, inputs, ws.k.as_mut());
    let k = &mut ws.k;
    for i in 0..n {
        k[(i, i)] += sn2;
    }
    let jit = ws.spd.factor(k.as_ref(), "K + sn2 I (nlml)", jitter)?;
    // Back to the noise-free K that gram_grad_contract expects.
    for i in 0..n {
        k[(i, i)] -= sn2;
    }
    let alpha = ws.spd.solve_vec(y);
    let fit: f64 = y.iter().zip(&alpha).map(|(a, b)| a * b).sum();
    let value =
        0.5 * fit + 0.5 * ws.spd.log_det() + 0.5 * n as f64 * (2.0 * std::f64::consts::PI).ln();

    // G = ½ (K̃⁻¹ − ααᵀ), built in place in the inverse.
    ws.spd.inverse_into(ws.g.as_mut());
    let g = &mut ws.g;
    let mut trace = 0.0;
    for j in 0..n {
        let aj = alpha[j];
        let col = g.col_as_slice_mut(j);
        for (i, v) in col.iter_mut().enumerate() {
            *v = 0.5 * (*v - alpha[i] * aj);
        }
        trace += col[j];
    }
    let mut grad = kernel.gram_grad_contract(hyp, inputs, k.as_ref(), g.as_ref());
    grad.push(2.0 * sn2 * trace);

    if !value.is_finite() || grad.iter().any(|v| !v.is_finite()) {
        return Err(GpError::Numerical {
            what: "nlml".into(),
            detail: format!("non-finite value or gradient at {:?}", hyp.to_pilco()),
        });
    }
    Ok(NlmlEval {
        value,
        grad,
        jitter: jit,
    })
}
