//! The exact multi-output GP: E independent GPs on shared N×D training inputs, one
//! hyper-parameter set per output, with the Cholesky factors and `β = (K + σ_n² I)⁻¹ y` cached.

use crate::error::{GpError, Result};
use crate::kernel::{row, Hyper, Kernel, SquaredExponential};
use crate::linalg::{check_finite, Chol, JitterPolicy};
use faer::{Mat, MatRef};
use rayon::prelude::*;

/// Cholesky factor, β and inverse of one output's training covariance.
type OutputFactors = (Chol, Vec<f64>, Mat<f64>);

/// A fitted exact GP (E outputs).
#[derive(Clone, Debug)]
pub struct GpModel {
    inputs: Mat<f64>,
    targets: Mat<f64>,
    hyp: Vec<Hyper>,
    chol: Vec<Chol>,
    /// N×E, column e is `(K_e + σ_ne² I)⁻¹ y_e`.
    beta: Mat<f64>,
    /// `(K_e + σ_ne² I)⁻¹` per output, needed by the model-uncertainty term of moment
    /// matching.
    inv_k: Vec<Mat<f64>>,
}

/// Check inputs, targets and hyper-parameters agree in shape, hold at least one training
/// point and only finite numbers.
pub fn validate_data(
    inputs: MatRef<'_, f64>,
    targets: MatRef<'_, f64>,
    hyp: &[Hyper],
) -> Result<()> {
    check_finite(inputs, "GP training inputs")?;
    check_finite(targets, "GP training targets")?;
    // A GP on no data is only its prior, and moment matching's block kernels assume N ≥ 1.
    if inputs.nrows() == 0 {
        return Err(GpError::Shape {
            what: "GP training inputs".into(),
            expected: "at least 1 row (one per training point)".into(),
            got: "0 rows".into(),
        });
    }
    if inputs.nrows() != targets.nrows() {
        return Err(GpError::Shape {
            what: "GP training targets".into(),
            expected: format!("{} rows (one per input)", inputs.nrows()),
            got: format!("{} rows", targets.nrows()),
        });
    }
    if hyp.len() != targets.ncols() {
        return Err(GpError::Shape {
            what: "GP hyper-parameters".into(),
            expected: format!("{} sets (one per output)", targets.ncols()),
            got: format!("{}", hyp.len()),
        });
    }
    for (e, h) in hyp.iter().enumerate() {
        if h.dim() != inputs.ncols() {
            return Err(GpError::Shape {
                what: format!("length-scales of output {e}"),
                expected: format!("{} (one per input dimension)", inputs.ncols()),
                got: format!("{}", h.dim()),
            });
        }
        if !h.is_finite() {
            return Err(GpError::Numerical {
                what: format!("hyper-parameters of output {e}"),
                detail: format!("non-finite value in {:?}", h.to_pilco()),
            });
        }
    }
    Ok(())
}

impl GpModel {
    /// Factorise `K_e + σ_ne² I` for each output (with reported jitter if needed).
    pub fn new(inputs: Mat<f64>, targets: Mat<f64>, hyp: Vec<Hyper>) -> Result<Self> {
        validate_data(inputs.as_ref(), targets.as_ref(), &hyp)?;
        let kernel = SquaredExponential;
        let n = inputs.nrows();
        let per_output: Vec<Result<OutputFactors>> = hyp
            .par_iter()
            .enumerate()
            .map(|(e, h)| {
                let mut k = kernel.gram(h, inputs.as_ref());
                let sn2 = h.sn2();
                for i in 0..n {
                    k[(i, i)] += sn2;
                }
                let chol = Chol::with_jitter(
                    k.as_ref(),
                    &format!("K + sn2 I of output {e}"),
                    JitterPolicy::default(),
                )?;
                let y: Vec<f64> = (0..n).map(|i| targets[(i, e)]).collect();
                let beta = chol.solve_vec(&y);
                let inv = chol.inverse();
                Ok((chol, beta, inv))
            })
            .collect();
        let mut chol = Vec::with_capacity(hyp.len());
        let mut inv_k = Vec::with_capacity(hyp.len());
        let mut beta = Mat::zeros(n, hyp.len());
        for (e, r) in per_output.into_iter().enumerate() {
            let (c, b, inv) = r?;
            for i in 0..n {
                beta[(i, e)] = b[i];
            }
            chol.push(c);
            inv_k.push(inv);
        }
        Ok(Self {
            inputs,
            targets,
            hyp,
            chol,
            beta,
            inv_k,
        })
    }

    /// Number of training points N.
    pub fn n(&self) -> usize {
        self.inputs.nrows()
    }
    /// Input dimension D (columns of the training inputs).
    pub fn input_dim(&self) -> usize {
        self.inputs.ncols()
    }
    /// Number of outputs E, one independent GP (and one [`Hyper`]) each.
    pub fn output_dim(&self) -> usize {
        self.hyp.len()
    }
    /// Training inputs X, N×D, one row per training point (the centres of moment matching).
    pub fn inputs(&self) -> MatRef<'_, f64> {
        self.inputs.as_ref()
    }
    /// Training targets, N×E: column e is `y_e`, the targets of output e.
    pub fn targets(&self) -> MatRef<'_, f64> {
        self.targets.as_ref()
    }
    /// Log hyper-parameters, one [`Hyper`] per output, in output order.
    pub fn hyp(&self) -> &[Hyper] {
        &self.hyp
    }
    /// `β_e = (K_e + σ_ne² I)⁻¹ y_e` as column e, N×E (PILCO's `beta`; jitter included): the
    /// predictive mean is `k_*ᵀ β_e`.
    pub fn beta(&self) -> MatRef<'_, f64> {
        self.beta.as_ref()
    }
    /// `(K_e + σ_ne² I)⁻¹` per output (E matrices, N×N; PILCO's `iK`, jitter included): the
    /// model-uncertainty term of moment matching (gp0).
    pub fn inv_k(&self) -> &[Mat<f64>] {
        &self.inv_k
    }
    /// Diagonal jitter each output's factorisation needed (0 when none).
    pub fn jitter(&self) -> Vec<f64> {
        self.chol.iter().map(|c| c.jitter).collect()
    }

    /// Predictive mean and latent variance (no noise) of every output at a deterministic input
    /// `x` of length D; another length is a [`GpError::Shape`].
    pub fn predict(&self, x: &[f64]) -> Result<(Vec<f64>, Vec<f64>)> {
        check_query(x, self.input_dim())?;
        let kernel = SquaredExponential;
        let n = self.n();
        let mut mean = Vec::with_capacity(self.hyp.len());
        let mut var = Vec::with_capacity(self.hyp.len());
        for (e, h) in self.hyp.iter().enumerate() {
            let kx: Vec<f64> = (0..n)
                .map(|i| kernel.eval(h, &row(self.inputs.as_ref(), i), x))
                .collect();
            mean.push((0..n).map(|i| kx[i] * self.beta[(i, e)]).sum());
            let v = self.chol[e].solve_vec(&kx);
            let kk: f64 = kx.iter().zip(&v).map(|(a, b)| a * b).sum();
            var.push((h.sf2() - kk).max(0.0));
        }
        Ok((mean, var))
    }
}

/// The length check of a deterministic prediction input: the kernel zips `x` with each
/// training row, so a wrong length would be silently truncated rather than fail.
pub(crate) fn check_query(x: &[f64], d: usize) -> Result<()> {
    if x.len() == d {
        return Ok(());
    }
    Err(GpError::Shape {
        what: "GP prediction input x".into(),
        expected: format!("length {d} (the input dimension D)"),
        got: format!("length {}", x.len()),
    })
}

/// Adjoints of a GP's data and hyper-parameters.
#[derive(Clone, Debug)]
pub struct GpDataAdjoint {
    /// N×D.
    pub inputs: Mat<f64>,
    /// N×E.
    pub targets: Mat<f64>,
    /// One `[log ℓ_1..log ℓ_D, log σ_f, log σ_n]` per output (PILCO column layout).
    pub hyp: Vec<Vec<f64>>,
}

impl GpModel {
    /// Chain adjoints through `β_e = (K_e + σ_ne² I)⁻¹ y_e`: given `β̄` (N×E) and the direct
    /// adjoints of the moment formulas (`centres`, `log_ls`, `log_sf` of
    /// [`crate::moments::ParamAdjoint`]), return the total adjoints of inputs, targets and
    /// hyper-parameters. With `ȳ = K̃⁻¹β̄` and `Ḡ = −½(ȳβᵀ + βȳᵀ)` (the gradient w.r.t. the
    /// symmetric K̃), `∂K_ij/∂x_i = −K_ij Λ⁻¹(x_i − x_j)`, `∂K_ij/∂log ℓ_d = K_ij (x_id − x_jd)²/ℓ_d²`.
    pub fn chain_param_adjoint(&self, direct: &crate::moments::ParamAdjoint) -> GpDataAdjoint {
        let (n, d, e) = (self.n(), self.input_dim(), self.output_dim());
        let kernel = SquaredExponential;
        let mut inputs = direct.centres.clone();
        let mut targets = Mat::zeros(n, e);
        let mut hyp = Vec::with_capacity(e);
        for a in 0..e {
            let h = &self.hyp[a];
            let bbar: Vec<f64> = (0..n).map(|i| direct.beta[(i, a)]).collect();
            let ybar = self.chol[a].solve_vec(&bbar);
            for i in 0..n {
                targets[(i, a)] = ybar[i];
            }
            let k = kernel.gram(h, self.inputs.as_ref());
            let il2 = h.inv_ls2();
            let mut g_ls = vec![0.0; d];
            let mut g_sf = 0.0;
            let mut g_sn = 0.0;
            for i in 0..n {
                let gii = -ybar[i] * self.beta[(i, a)];
                g_sf += 2.0 * gii * k[(i, i)];
                g_sn += 2.0 * h.sn2() * gii;
                for j in 0..i {
                    // Ḡ_ij + Ḡ_ji
                    let g2 = -(ybar[i] * self.beta[(j, a)] + self.beta[(i, a)] * ybar[j]);
                    let gk = g2 * k[(i, j)];
                    g_sf += 2.0 * gk;
                    for c in 0..d {
                        let dx = self.inputs[(i, c)] - self.inputs[(j, c)];
                        g_ls[c] += gk * il2[c] * dx * dx;
                        let dxi = -gk * il2[c] * dx;
                        inputs[(i, c)] += dxi;
                        inputs[(j, c)] -= dxi;
                    }
                }
            }
            let mut col: Vec<f64> = (0..d).map(|c| direct.log_ls[(c, a)] + g_ls[c]).collect();
            col.push(direct.log_sf[a] + g_sf);
            col.push(g_sn);
            hyp.push(col);
        }
        GpDataAdjoint {
            inputs,
            targets,
            hyp,
        }
    }
}
