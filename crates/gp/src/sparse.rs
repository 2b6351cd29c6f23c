//! The sparse GP: FITC / SPGP with M inducing inputs shared by all outputs (PILCO's `gp1`
//! model and `fitc.m` training), and [`DynamicsModel`], which picks the full or the sparse GP
//! by the number of training points as PILCO does.
//!
//! For each output (oracle README, gp1), with `K_mm = k(U,U) + 10⁻⁶ I` everywhere:
//!
//! * `Γ = diag(σ_f² − diag(K_nm K_mm⁻¹ K_mn)) + σ_n² I`,
//! * `B = K_mm + K_mn Γ⁻¹ K_nm`, `β = B⁻¹ K_mn Γ⁻¹ y` (M),
//! * the matrix that replaces `(K + σ_n² I)⁻¹` in the variance terms: `K_mm⁻¹ − B⁻¹` (M×M).
//!
//! [`SparseGpModel`] exposes these with the accessor names and shapes of
//! [`GpModel`] — [`inputs`](SparseGpModel::inputs) (the inducing inputs, M×D),
//! [`beta`](SparseGpModel::beta) (M×E), [`inv_k`](SparseGpModel::inv_k) (E matrices M×M) and
//! [`hyp`](SparseGpModel::hyp) — so moment matching consumes either model the same way.
//! Everything is computed in the well-conditioned form of [`fitc`] (no explicit `B`).
//!
//! Training of the inducing inputs by the FITC marginal likelihood: [`train_inducing`] and the
//! whole PILCO pipeline [`train_sparse`] (see this module's `train` for how it differs
//! from pilco-matlab's `train.m`).

pub mod fitc;
mod train;

pub use fitc::{fitc_nlml, FitcEval, FITC_RIDGE};
pub use train::{
    select_subset, train_inducing, train_sparse, InducingOptions, InducingReport,
    SparseTrainOptions, SparseTrainReport,
};

use crate::error::Result;
use crate::kernel::Hyper;
use crate::linalg::{symmetrise, JitterPolicy};
use crate::model::{check_query, validate_data, GpModel};
use crate::train::{train as train_full, TrainOptions, TrainReport};
use faer::{Mat, MatRef};
use rayon::prelude::*;

/// A sparse (FITC) multi-output GP, ready for prediction and moment matching.
#[derive(Clone, Debug)]
pub struct SparseGpModel {
    inducing: Mat<f64>,
    hyp: Vec<Hyper>,
    /// M×E.
    beta: Mat<f64>,
    /// Per output `K_mm⁻¹ − B⁻¹`, M×M.
    inv_k: Vec<Mat<f64>>,
    jitter: Vec<f64>,
    nlml: Vec<f64>,
    n_train: usize,
}

impl SparseGpModel {
    /// Build the FITC model of `targets` (N×E) on `inputs` (N×D) with one hyper-parameter set
    /// per output and the inducing inputs `inducing` (M×D, shared by all outputs).
    pub fn new(
        inputs: MatRef<'_, f64>,
        targets: MatRef<'_, f64>,
        hyp: Vec<Hyper>,
        inducing: Mat<f64>,
    ) -> Result<Self> {
        validate_data(inputs, targets, &hyp)?;
        fitc::validate_inducing(inducing.as_ref(), inputs.ncols(), "inducing inputs")?;
        let m = inducing.nrows();
        let per_output: Vec<Result<OutputParts>> = hyp
            .par_iter()
            .enumerate()
            .map(|(e, h)| {
                let y: Vec<f64> = (0..targets.nrows()).map(|i| targets[(i, e)]).collect();
                output_parts(inputs, &y, h, inducing.as_ref())
            })
            .collect();
        let mut beta = Mat::zeros(m, hyp.len());
        let mut inv_k = Vec::with_capacity(hyp.len());
        let mut jitter = Vec::with_capacity(hyp.len());
        let mut nlml = Vec::with_capacity(hyp.len());
        for (e, r) in per_output.into_iter().enumerate() {
            let p = r?;
            for i in 0..m {
                beta[(i, e)] = p.beta[i];
            }
            inv_k.push(p.inv_k);
            jitter.push(p.jitter);
            nlml.push(p.nlml);
        }
        Ok(Self {
            inducing,
            hyp,
            beta,
            inv_k,
            jitter,
            nlml,
            n_train: inputs.nrows(),
        })
    }

    /// Number of inducing inputs M (the "training set" moment matching runs over).
    pub fn n(&self) -> usize {
        self.inducing.nrows()
    }
    /// Number of training points the model was built from.
    pub fn n_train(&self) -> usize {
        self.n_train
    }
    /// Input dimension D (columns of the inducing and of the training inputs).
    pub fn input_dim(&self) -> usize {
        self.inducing.ncols()
    }
    /// Number of outputs E, each with its own [`Hyper`] on the shared inducing inputs.
    pub fn output_dim(&self) -> usize {
        self.hyp.len()
    }
    /// The inducing inputs U, M×D (the centres moment matching uses).
    pub fn inputs(&self) -> MatRef<'_, f64> {
        self.inducing.as_ref()
    }
    /// Log hyper-parameters, one [`Hyper`] per output, in output order.
    pub fn hyp(&self) -> &[Hyper] {
        &self.hyp
    }
    /// `β_e = B_e⁻¹ K_mn Γ_e⁻¹ y_e` as column e, M×E.
    pub fn beta(&self) -> MatRef<'_, f64> {
        self.beta.as_ref()
    }
    /// `K_mm⁻¹ − B_e⁻¹` per output (M×M): what replaces `(K + σ_n² I)⁻¹` in moment matching.
    pub fn inv_k(&self) -> &[Mat<f64>] {
        &self.inv_k
    }
    /// Diagonal jitter `K_mm + 10⁻⁶ I` needed on top of the ridge, per output (0 when none).
    pub fn jitter(&self) -> Vec<f64> {
        self.jitter.clone()
    }
    /// FITC negative log marginal likelihood of each output at the model's parameters.
    pub fn nlml(&self) -> &[f64] {
        &self.nlml
    }

    /// Predictive mean and latent variance (no noise) of every output at a deterministic
    /// input `x` of length D: `k_*ᵀ β` and `σ_f² − k_*ᵀ (K_mm⁻¹ − B⁻¹) k_*`. Another length is
    /// a [`GpError::Shape`](crate::GpError::Shape).
    pub fn predict(&self, x: &[f64]) -> Result<(Vec<f64>, Vec<f64>)> {
        check_query(x, self.input_dim())?;
        let xm = MatRef::from_row_major_slice(x, 1, x.len());
        let mut mean = Vec::with_capacity(self.hyp.len());
        let mut var = Vec::with_capacity(self.hyp.len());
        for (e, h) in self.hyp.iter().enumerate() {
            let k = fitc::se_cross(h, self.inducing.as_ref(), xm);
            let k = k.col_as_slice(0);
            mean.push(
                k.iter()
                    .enumerate()
                    .map(|(i, v)| v * self.beta[(i, e)])
                    .sum(),
            );
            let ik = fitc::mat_vec(self.inv_k[e].as_ref(), k);
            let q: f64 = k.iter().zip(&ik).map(|(a, b)| a * b).sum();
            var.push((h.sf2() - q).max(0.0));
        }
        Ok((mean, var))
    }
}

struct OutputParts {
    beta: Vec<f64>,
    inv_k: Mat<f64>,
    jitter: f64,
    nlml: f64,
}

fn output_parts(
    inputs: MatRef<'_, f64>,
    y: &[f64],
    h: &Hyper,
    u: MatRef<'_, f64>,
) -> Result<OutputParts> {
    let f = fitc::factor(u, inputs, y, h, Some(JitterPolicy::default()))?;
    let m = u.nrows();
    // β = L⁻ᵀ r.
    let mut beta = Mat::from_fn(m, 1, |i, _| f.r[i]);
    f.l.solve_lt_in_place(beta.as_mut());
    // K_mm⁻¹ − B⁻¹ = L⁻ᵀ (I − A⁻¹) L⁻¹.
    let mut s = f.la.inverse();
    for j in 0..m {
        s.col_as_slice_mut(j).iter_mut().for_each(|v| *v = -*v);
        s[(j, j)] += 1.0;
    }
    f.l.solve_lt_in_place(s.as_mut());
    let mut inv_k = s.transpose().to_owned();
    f.l.solve_lt_in_place(inv_k.as_mut());
    symmetrise(&mut inv_k);
    Ok(OutputParts {
        beta: beta.col_as_slice(0).to_vec(),
        inv_k,
        jitter: f.l.jitter,
        nlml: f.value,
    })
}

/// The dynamics model PILCO trains: the exact GP for small data sets and the sparse FITC GP
/// above a threshold. Both expose `inputs()`, `beta()`, `inv_k()`, `hyp()` with the same
/// meaning for moment matching.
#[derive(Clone, Debug)]
pub enum DynamicsModel {
    /// Exact GP on all N training points, what [`fit`](Self::fit) builds for
    /// N ≤ [`DynamicsOptions::sparse_threshold`] (moment matching as PILCO's gp0).
    Full(GpModel),
    /// FITC GP on M inducing inputs, built above the threshold (moment matching as gp1).
    Sparse(SparseGpModel),
}

/// Options of [`DynamicsModel::fit`].
#[derive(Clone, Debug)]
pub struct DynamicsOptions {
    /// Use the full GP when N ≤ this (default 300).
    pub sparse_threshold: usize,
    /// Hyper-parameter training (also used for the subset in the sparse case).
    pub train: TrainOptions,
    /// Inducing-input count, seed and optimiser settings of the sparse case (default M = 300).
    pub sparse: SparseTrainOptions,
}

impl Default for DynamicsOptions {
    fn default() -> Self {
        Self {
            sparse_threshold: 300,
            train: TrainOptions::default(),
            sparse: SparseTrainOptions::default(),
        }
    }
}

impl DynamicsOptions {
    /// The same options with the given hyper-parameters kept as they are: no training
    /// iterations and no cold restart (a sparse model still fits its inducing inputs). The
    /// learning loop's "previous hyper-parameters" candidate and its replays build it this way.
    pub fn keeping_hyper_parameters(&self) -> Self {
        let mut kept = self.clone();
        kept.train.max_iters = 0;
        kept.train.cold_restart = false;
        kept
    }
}

/// What [`DynamicsModel::fit`] did.
#[derive(Clone, Debug)]
pub enum DynamicsReport {
    /// Hyper-parameter training of the exact GP on all N points.
    Full(TrainReport),
    /// Hyper-parameter, then inducing-input training of the sparse GP ([`train_sparse`]).
    Sparse(SparseTrainReport),
}

impl DynamicsReport {
    /// The hyper-parameter training's report (on the subset in the sparse case).
    pub fn hyper(&self) -> &TrainReport {
        match self {
            Self::Full(r) => r,
            Self::Sparse(r) => &r.hyper,
        }
    }
}

impl DynamicsModel {
    /// Train and build the dynamics model of `targets` on `inputs`: the full GP when
    /// `N ≤ sparse_threshold`, else [`train_sparse`] (hyper-parameters warm-started from
    /// `init_hyp`, inducing inputs from `init_inducing` when given and of the right size).
    pub fn fit(
        inputs: Mat<f64>,
        targets: Mat<f64>,
        init_hyp: &[Hyper],
        init_inducing: Option<MatRef<'_, f64>>,
        opts: &DynamicsOptions,
    ) -> Result<(Self, DynamicsReport)> {
        if inputs.nrows() <= opts.sparse_threshold {
            let (hyp, rep) = train_full(inputs.as_ref(), targets.as_ref(), init_hyp, &opts.train)?;
            let model = GpModel::new(inputs, targets, hyp)?;
            return Ok((Self::Full(model), DynamicsReport::Full(rep)));
        }
        let mut sopts = opts.sparse.clone();
        sopts.hyper = opts.train.clone();
        let (model, rep) = train_sparse(
            inputs.as_ref(),
            targets.as_ref(),
            init_hyp,
            init_inducing,
            &sopts,
        )?;
        Ok((Self::Sparse(model), DynamicsReport::Sparse(rep)))
    }

    /// Whether this is the FITC model, whose [`inputs`](Self::inputs) are inducing inputs.
    pub fn is_sparse(&self) -> bool {
        matches!(self, Self::Sparse(_))
    }
    /// Training inputs (full) or inducing inputs (sparse).
    pub fn inputs(&self) -> MatRef<'_, f64> {
        match self {
            Self::Full(m) => m.inputs(),
            Self::Sparse(m) => m.inputs(),
        }
    }
    /// Weights of the predictive mean: N×E ([`GpModel::beta`]) or M×E
    /// ([`SparseGpModel::beta`]).
    pub fn beta(&self) -> MatRef<'_, f64> {
        match self {
            Self::Full(m) => m.beta(),
            Self::Sparse(m) => m.beta(),
        }
    }
    /// Per output, the matrix of the variance terms of moment matching: `(K + σ_n² I)⁻¹`
    /// (N×N, full) or `K_mm⁻¹ − B⁻¹` (M×M, sparse).
    pub fn inv_k(&self) -> &[Mat<f64>] {
        match self {
            Self::Full(m) => m.inv_k(),
            Self::Sparse(m) => m.inv_k(),
        }
    }
    /// Log hyper-parameters, one [`Hyper`] per output, in output order.
    pub fn hyp(&self) -> &[Hyper] {
        match self {
            Self::Full(m) => m.hyp(),
            Self::Sparse(m) => m.hyp(),
        }
    }
    /// Predictive mean and latent variance (no noise), E each, at a deterministic input `x`
    /// (length D): [`GpModel::predict`] or [`SparseGpModel::predict`], with their
    /// [`GpError::Shape`](crate::GpError::Shape) for another length.
    pub fn predict(&self, x: &[f64]) -> Result<(Vec<f64>, Vec<f64>)> {
        match self {
            Self::Full(m) => m.predict(x),
            Self::Sparse(m) => m.predict(x),
        }
    }
}

#[cfg(test)]
mod tests;
