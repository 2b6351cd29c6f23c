//! Training the sparse GP (PILCO's `train.m` when `gpmodel.induce` exists, with `fitc.m`).
//!
//! 1. Hyper-parameters: the full GP trained ([`crate::train::train`], with the penalty when
//!    it is on) on all N training points, as pilco-matlab does, or — when
//!    [`SparseTrainOptions::hyper_points`] asks for it — on a subset of that many points chosen
//!    by [`select_subset`]. All N costs O(N³) per evaluation; the subset keeps it O(M³).
//! 2. Inducing inputs: start from the given ones (warm start) or from the same subset of the
//!    training inputs (pilco-matlab: a random subset), then minimise
//!    `Σ_e nlml_FITC,e(U)` over U (M×D, shared by all outputs) with the hyper-parameters fixed,
//!    by L-BFGS with the analytic gradient of [`fitc`](super::fitc). Outputs are evaluated in
//!    parallel and summed in output order.

use super::fitc::{factor, gradient, validate_inducing};
use super::SparseGpModel;
use crate::error::{GpError, Result};
use crate::kernel::Hyper;
use crate::model::validate_data;
use crate::train::{
    minimize, train, MinimizeOptions, Termination, TrainOptions, TrainReport, Wolfe,
};
use faer::{Mat, MatRef};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::time::{Duration, Instant};

/// Optimiser settings of [`train_inducing`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InducingOptions {
    /// L-BFGS iterations (default 100; pilco-matlab allows 1000 evaluations, 3000 the first
    /// time).
    pub max_iters: u64,
    /// Stop when `‖∇‖₂ ≤ grad_tol` (default 1e-6).
    pub grad_tol: f64,
    /// Stop when one iteration changes the summed nlml by less than
    /// `rel_tol · max(|f|, |f_prev|, 1)` (default 1e-6).
    pub rel_tol: f64,
    /// L-BFGS memory (default 10).
    pub memory: usize,
    /// [`train_sparse`] multiplies `max_iters` by this when the inducing inputs start from a
    /// subset of the data rather than from a previous fit (pilco-matlab's `train.m` triples its
    /// budget then: the first fit has furthest to go). Default 1.
    pub cold_start_factor: u64,
}

impl Default for InducingOptions {
    fn default() -> Self {
        Self {
            max_iters: 100,
            grad_tol: 1e-6,
            rel_tol: 1e-6,
            memory: 10,
            cold_start_factor: 1,
        }
    }
}

/// Options of [`train_sparse`].
#[derive(Clone, Debug)]
pub struct SparseTrainOptions {
    /// Number of inducing inputs M (default 300).
    pub num_inducing: usize,
    /// Seed of the subset selection ([`select_subset`]).
    pub seed: u64,
    /// Hyper-parameter training.
    pub hyper: TrainOptions,
    /// Train the hyper-parameters on a random subset of at most this many points
    /// ([`select_subset`]); `None`: on all N points, as pilco-matlab. Default `Some(300)`:
    /// affordable for the thousands of points of the arm experiments.
    pub hyper_points: Option<usize>,
    /// Inducing-input optimisation.
    pub inducing: InducingOptions,
}

impl Default for SparseTrainOptions {
    fn default() -> Self {
        Self {
            num_inducing: 300,
            seed: 0,
            hyper: TrainOptions::default(),
            hyper_points: Some(300),
            inducing: InducingOptions::default(),
        }
    }
}

/// How the inducing-input optimisation went.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct InducingReport {
    /// `Σ_e nlml_FITC,e` at the initial inducing inputs.
    pub initial_nlml: f64,
    /// `Σ_e nlml_FITC,e` at the returned inducing inputs (the sum of `output_nlml`).
    pub nlml: f64,
    /// Final FITC nlml of each output.
    pub output_nlml: Vec<f64>,
    /// L-BFGS iterations, over all restarts.
    pub iterations: u64,
    /// Evaluations of the summed objective (all outputs, value and gradient), including the
    /// final one at the returned inducing inputs.
    pub evaluations: usize,
    /// Why L-BFGS stopped; [`Termination::converged`] separates convergence from a spent
    /// budget or a failed line search.
    pub termination: Termination,
    /// Wall time of the whole [`train_inducing`] call.
    pub wall_time: Duration,
}

/// What [`train_sparse`] did.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SparseTrainReport {
    /// Rows of the training data that gave the initial inducing inputs (without a warm start).
    pub subset: Vec<usize>,
    /// Number of training points the hyper-parameters were trained on.
    pub hyper_points: usize,
    /// Report of the hyper-parameter training (on those `hyper_points` points).
    pub hyper: TrainReport,
    /// `None` when N ≤ M (the inducing inputs are then the training inputs, not optimised).
    pub inducing: Option<InducingReport>,
    /// Wall time of the whole call: hyper-parameters, inducing inputs and model build.
    pub wall_time: Duration,
}

/// `m` distinct indices out of `0..n`, drawn by a partial Fisher–Yates shuffle driven by
/// SplitMix64 seeded with `seed`, returned sorted. Deterministic on every platform.
pub fn select_subset(n: usize, m: usize, seed: u64) -> Vec<usize> {
    let m = m.min(n);
    let mut state = seed;
    let mut next = || {
        state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    };
    let mut idx: Vec<usize> = (0..n).collect();
    for i in 0..m {
        // Multiply-shift maps the 64-bit draw to 0..n−i without modulo bias worth mentioning.
        let span = (n - i) as u128;
        let j = i + ((u128::from(next()) * span) >> 64) as usize;
        idx.swap(i, j);
    }
    let mut out = idx[..m].to_vec();
    out.sort_unstable();
    out
}

fn rows(x: MatRef<'_, f64>, idx: &[usize]) -> Mat<f64> {
    Mat::from_fn(idx.len(), x.ncols(), |i, c| x[(idx[i], c)])
}

/// Summed FITC nlml over outputs and its gradient w.r.t. U (row-major flat M·D).
fn summed(
    inputs: MatRef<'_, f64>,
    ys: &[Vec<f64>],
    hyp: &[Hyper],
    u: MatRef<'_, f64>,
) -> Option<(f64, Vec<f64>, Vec<f64>)> {
    let (m, d) = (u.nrows(), u.ncols());
    let per: Vec<Option<(f64, Mat<f64>)>> = hyp
        .par_iter()
        .zip(ys)
        .map(|(h, y)| {
            let f = factor(u, inputs, y, h, None).ok()?;
            let g = gradient(&f, u, inputs, h);
            Some((g.value, g.grad_inducing))
        })
        .collect();
    let mut value = 0.0;
    let mut grad = vec![0.0; m * d];
    let mut each = Vec::with_capacity(hyp.len());
    for p in per {
        let (v, g) = p?;
        value += v;
        each.push(v);
        for i in 0..m {
            for c in 0..d {
                grad[i * d + c] += g[(i, c)];
            }
        }
    }
    Some((value, grad, each))
}

/// Optimise the inducing inputs (shared by all outputs) by the summed FITC negative log
/// marginal likelihood, hyper-parameters fixed, from `init` (M×D).
pub fn train_inducing(
    inputs: MatRef<'_, f64>,
    targets: MatRef<'_, f64>,
    hyp: &[Hyper],
    init: MatRef<'_, f64>,
    opts: &InducingOptions,
) -> Result<(Mat<f64>, InducingReport)> {
    let start = Instant::now();
    validate_data(inputs, targets, hyp)?;
    validate_inducing(init, inputs.ncols(), "initial inducing inputs")?;
    let (m, d) = (init.nrows(), inputs.ncols());
    let ys: Vec<Vec<f64>> = (0..targets.ncols())
        .map(|e| (0..targets.nrows()).map(|i| targets[(i, e)]).collect())
        .collect();
    let x0: Vec<f64> = (0..m)
        .flat_map(|i| (0..d).map(move |c| (i, c)))
        .map(|(i, c)| init[(i, c)])
        .collect();
    let as_mat = |p: &[f64]| MatRef::from_row_major_slice(p, m, d).to_owned();
    let mut initial = None;
    let mut f = |p: &[f64]| {
        let (v, g, _) = summed(inputs, &ys, hyp, as_mat(p).as_ref())?;
        initial.get_or_insert(v);
        Some((v, g))
    };
    let mopts = MinimizeOptions {
        max_iters: opts.max_iters,
        grad_tol: opts.grad_tol,
        rel_tol: opts.rel_tol,
        memory: opts.memory,
        max_line_search_evals: None,
        wolfe: Wolfe::LOOSE,
        max_slope_ratio: None,
    };
    let r = minimize(&mut f, x0, &mopts).ok_or_else(|| GpError::Numerical {
        what: "FITC nlml at the initial inducing inputs".into(),
        detail: "not finite, or K_mm + 1e-6 I not positive definite".into(),
    })?;
    let initial_nlml = initial.unwrap_or(f64::NAN);
    let u = as_mat(&r.x);
    let (value, _, each) =
        summed(inputs, &ys, hyp, u.as_ref()).ok_or_else(|| GpError::Numerical {
            what: "FITC nlml at the optimised inducing inputs".into(),
            detail: "evaluation failed".into(),
        })?;
    Ok((
        u,
        InducingReport {
            initial_nlml,
            nlml: value,
            output_nlml: each,
            iterations: r.iterations,
            evaluations: r.evaluations + 1,
            termination: r.termination,
            wall_time: start.elapsed(),
        },
    ))
}

/// PILCO's sparse training pipeline (module docs): hyper-parameters, then the
/// inducing inputs, then the [`SparseGpModel`]. When N ≤ M every training input is an inducing
/// input and nothing is optimised beyond the hyper-parameters.
pub fn train_sparse(
    inputs: MatRef<'_, f64>,
    targets: MatRef<'_, f64>,
    init_hyp: &[Hyper],
    init_inducing: Option<MatRef<'_, f64>>,
    opts: &SparseTrainOptions,
) -> Result<(SparseGpModel, SparseTrainReport)> {
    let start = Instant::now();
    validate_data(inputs, targets, init_hyp)?;
    let n = inputs.nrows();
    let subset = select_subset(n, opts.num_inducing.max(1), opts.seed);
    let xs = rows(inputs, &subset);
    let hyper_rows = match opts.hyper_points {
        Some(k) if k < n => Some(select_subset(n, k.max(1), opts.seed)),
        _ => None,
    };
    let (hyp, hyper) = match &hyper_rows {
        Some(r) => train(
            rows(inputs, r).as_ref(),
            rows(targets, r).as_ref(),
            init_hyp,
            &opts.hyper,
        )?,
        None => train(inputs, targets, init_hyp, &opts.hyper)?,
    };
    let (u, inducing) = if subset.len() >= n {
        (inputs.to_owned(), None)
    } else {
        let warm = match init_inducing {
            Some(u0) if u0.nrows() == subset.len() && u0.ncols() == inputs.ncols() => {
                Some(u0.to_owned())
            }
            Some(u0) => {
                tracing::warn!(
                    given = ?(u0.nrows(), u0.ncols()),
                    wanted = ?(subset.len(), inputs.ncols()),
                    "warm-start inducing inputs have the wrong shape; starting from the subset"
                );
                None
            }
            None => None,
        };
        let mut iopts = opts.inducing;
        if warm.is_none() {
            iopts.max_iters = iopts
                .max_iters
                .saturating_mul(iopts.cold_start_factor.max(1));
        }
        let init = warm.unwrap_or(xs);
        let (u, rep) = train_inducing(inputs, targets, &hyp, init.as_ref(), &iopts)?;
        (u, Some(rep))
    };
    let model = SparseGpModel::new(inputs, targets, hyp, u)?;
    Ok((
        model,
        SparseTrainReport {
            hyper_points: hyper_rows.as_ref().map_or(n, Vec::len),
            subset,
            hyper,
            inducing,
            wall_time: start.elapsed(),
        },
    ))
}
