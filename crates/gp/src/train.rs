//! Hyper-parameter training of the exact multi-output GP (PILCO's `train.m`, full-GP part).
//!
//! Each output e has its own log hyper-parameters θ_e = (log ℓ_1..log ℓ_D, log σ_f, log σ_n)
//! and is trained independently by minimising
//!
//! `nlml_e(θ_e) [+ hypCurb(θ_e)]`, `nlml = ½ yᵀ(K+σ_n²I)⁻¹y + ½ log|K+σ_n²I| + (N/2) log 2π`
//!
//! (see [`nlml`](crate::train::nlml()) and [`HypCurb`]) with L-BFGS from argmin
//! ([`minimize`]), warm-started from the given hyper-parameters. Outputs run in parallel
//! (rayon); results are collected in output order, so the outcome does not depend on the
//! thread count.
//!
//! With [`TrainOptions::cold_restart`] each output is also trained from PILCO's data-derived
//! first guess ([`initial_hyper`]) and keeps the lower penalised objective: a warm start carries
//! a poor local optimum from one data set to the next, which the first guess on the current
//! data escapes (measured on the arm's velocity model, EXPERIMENTS.md).
//!
//! pilco-matlab minimises `hypCurb` with Rasmussen's `minimize.m` (BFGS, 500 evaluations);
//! the optimum is the same, the path is not.

mod lbfgs;
mod nlml;

pub use lbfgs::{minimize, MinimizeOptions, MinimizeResult, Termination, Wolfe, MAX_RESTARTS};
pub use nlml::{input_std, nlml, nlml_curb, nlml_with_kernel, HypCurb, NlmlEval, NlmlWorkspace};

use crate::error::{GpError, Result};
use crate::kernel::{Hyper, SquaredExponential};
use crate::linalg::JitterPolicy;
use crate::model::validate_data;
use faer::MatRef;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::time::{Duration, Instant};

/// Options of [`train`].
#[derive(Clone, Debug)]
pub struct TrainOptions {
    /// L-BFGS iterations per output (default 100); 0 keeps the given hyper-parameters.
    pub max_iters: u64,
    /// Stop when `‖∇‖₂` of the objective is below this (default 1e-6).
    pub grad_tol: f64,
    /// Stop when one iteration changes the objective by less than
    /// `rel_tol · max(|f|, |f_prev|, 1)` (default 1e-6).
    pub rel_tol: f64,
    /// PILCO's `hypCurb` penalty; `None` trains the plain likelihood (default: on, as PILCO).
    pub penalty: Option<HypCurb>,
    /// L-BFGS memory (default 10 correction pairs).
    pub memory: usize,
    /// Jitter allowed when `K + σ_n² I` does not factorise.
    pub jitter: JitterPolicy,
    /// Also train every output from [`initial_hyper`] of the data and keep, per output, the
    /// start that reaches the lower objective (default off: PILCO warm-starts only).
    pub cold_restart: bool,
    /// Per input d, a length-scale below which the objective adds [`floor_penalty`] (not in
    /// PILCO; empty, the default, or 0 for an input: no floor). Why: a length-scale at the
    /// scale of an input's measurement noise fits that noise (EXPERIMENTS.md, the arm's
    /// velocity model), and the likelihood on a few hundred points can prefer it.
    pub lengthscale_floor: Vec<f64>,
    /// Per input d, a length-scale above which the objective adds [`ceiling_penalty`] (not in
    /// PILCO; empty, the default, or 0 for an input: no ceiling). Why: on data where an input
    /// matters only in a narrow band (the arm's hole is 1 cm wide in y), the likelihood can
    /// prefer a length-scale that smears the band away; PILCO's `hypCurb` only stops
    /// length-scales near 100 input standard deviations.
    pub lengthscale_ceiling: Vec<f64>,
}

impl Default for TrainOptions {
    fn default() -> Self {
        Self {
            max_iters: 100,
            grad_tol: 1e-6,
            rel_tol: 1e-6,
            penalty: Some(HypCurb::default()),
            memory: 10,
            jitter: JitterPolicy::default(),
            cold_restart: false,
            lengthscale_floor: Vec::new(),
            lengthscale_ceiling: Vec::new(),
        }
    }
}

impl TrainOptions {
    pub(crate) fn minimize_options(&self) -> MinimizeOptions {
        MinimizeOptions {
            max_iters: self.max_iters,
            grad_tol: self.grad_tol,
            rel_tol: self.rel_tol,
            memory: self.memory,
            max_line_search_evals: None,
            wolfe: Wolfe::LOOSE,
            // The training's iteration budget is not PILCO's line-search count: no cap.
            max_slope_ratio: None,
        }
    }
}

/// How the training of one output went.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct OutputReport {
    /// Final value of the minimised objective (nlml plus the penalty when it is on).
    pub objective: f64,
    /// Final negative log marginal likelihood without the penalty.
    pub nlml: f64,
    /// Objective at the start point.
    pub initial_objective: f64,
    /// L-BFGS iterations.
    pub iterations: u64,
    /// Objective evaluations (value and gradient together), including the final one.
    pub evaluations: usize,
    /// Why L-BFGS stopped; [`Termination::converged`] separates convergence from a spent
    /// budget or a failed line search.
    pub termination: Termination,
    /// Wall time of this output's training from the kept start (with a cold restart, the
    /// other start's time is not included).
    pub wall_time: Duration,
    /// Jitter the Cholesky factorisation needed at the final hyper-parameters (0 when none).
    pub jitter: f64,
    /// Whether the kept result came from the cold restart rather than the given start.
    #[serde(default)]
    pub from_cold_restart: bool,
    /// Largest jitter needed at any point the optimiser evaluated.
    pub max_jitter: f64,
}

/// What [`train`] returns besides the hyper-parameters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TrainReport {
    /// One entry per output, in output order.
    pub outputs: Vec<OutputReport>,
    /// Wall time of the whole call.
    pub wall_time: Duration,
}

impl TrainReport {
    /// Final objective values, one per output.
    pub fn objectives(&self) -> Vec<f64> {
        self.outputs.iter().map(|o| o.objective).collect()
    }
    /// How many outputs kept the cold restart's fit.
    pub fn cold_restarts(&self) -> usize {
        self.outputs.iter().filter(|o| o.from_cold_restart).count()
    }
}

/// Train the hyper-parameters of every output of an exact GP on `inputs` (N×D) and `targets`
/// (N×E), starting from `init` (one [`Hyper`] per output).
///
/// Errors: NaN/inf in the data ([`GpError::NonFinite`] naming row and column), shape
/// mismatches, and a start point where the objective cannot be evaluated. Trial points where it
/// cannot be evaluated are rejected by the optimiser, not fatal.
pub fn train(
    inputs: MatRef<'_, f64>,
    targets: MatRef<'_, f64>,
    init: &[Hyper],
    opts: &TrainOptions,
) -> Result<(Vec<Hyper>, TrainReport)> {
    let start = Instant::now();
    validate_data(inputs, targets, init)?;
    let c = input_std(inputs);
    let cold = opts.cold_restart.then(|| initial_hyper(inputs, targets));
    let results: Vec<Result<(Hyper, OutputReport)>> = init
        .par_iter()
        .enumerate()
        .map(|(e, h)| {
            let y: Vec<f64> = (0..targets.nrows()).map(|i| targets[(i, e)]).collect();
            let name = |err| match err {
                GpError::Optimiser(msg) => GpError::Optimiser(format!("output {e}: {msg}")),
                other => other,
            };
            let warm = train_output(inputs, &y, h, &c, opts).map_err(name)?;
            let Some(cold) = cold.as_ref().map(|g| &g[e]).filter(|g| *g != h) else {
                return Ok(warm);
            };
            match train_output(inputs, &y, cold, &c, opts) {
                // Ties keep the warm start, so a restart never moves a converged fit.
                Ok((hc, mut rc)) if rc.objective < warm.1.objective => {
                    rc.from_cold_restart = true;
                    Ok((hc, rc))
                }
                Ok(_) => Ok(warm),
                // The restart is a second opinion: its failure leaves the warm fit standing.
                Err(err) => {
                    tracing::warn!(output = e, %err, "cold restart of the GP fit failed; keeping the warm start");
                    Ok(warm)
                }
            }
        })
        .collect();
    let mut hyp = Vec::with_capacity(init.len());
    let mut outputs = Vec::with_capacity(init.len());
    for (e, r) in results.into_iter().enumerate() {
        let (h, rep) = r?;
        if rep.max_jitter > 0.0 {
            tracing::warn!(
                output = e,
                final_jitter = rep.jitter,
                max_jitter = rep.max_jitter,
                "GP training needed Cholesky jitter"
            );
        }
        tracing::debug!(output = e, nlml = rep.nlml, iterations = rep.iterations, termination = ?rep.termination, "trained GP output");
        hyp.push(h);
        outputs.push(rep);
    }
    Ok((
        hyp,
        TrainReport {
            outputs,
            wall_time: start.elapsed(),
        },
    ))
}

/// Objective of one output: nlml (+ penalty).
fn objective(
    inputs: MatRef<'_, f64>,
    y: &[f64],
    h: &Hyper,
    c: &[f64],
    opts: &TrainOptions,
    ws: &mut NlmlWorkspace,
) -> Result<(NlmlEval, f64)> {
    let mut e = nlml_with_kernel(&SquaredExponential, inputs, y, h, opts.jitter, ws)?;
    let plain = e.value;
    if let Some(curb) = &opts.penalty {
        let (p, g) = curb.penalty(h, c)?;
        e.value += p;
        e.grad.iter_mut().zip(&g).for_each(|(a, b)| *a += b);
    }
    for (bounds, penalty) in [
        (
            &opts.lengthscale_floor,
            floor_penalty as fn(&Hyper, &[f64]) -> _,
        ),
        (&opts.lengthscale_ceiling, ceiling_penalty),
    ] {
        if !bounds.is_empty() {
            let (p, g) = penalty(h, bounds);
            e.value += p;
            e.grad.iter_mut().zip(&g).for_each(|(a, b)| *a += b);
        }
    }
    Ok((e, plain))
}

/// Power of [`floor_penalty`] and [`ceiling_penalty`]: high, like `hypCurb`'s, so the penalty
/// is a wall.
pub const FLOOR_PENALTY_POWER: i32 = 30;

/// One-sided penalty keeping length-scale d above about half of `floor[d]`, with its gradient
/// (PILCO order): `Σ_d z_d^p` with `z_d = max(0, log floor_d − log ℓ_d) / log 2` and
/// p = [`FLOOR_PENALTY_POWER`]. It is 0 at and above the floor, below 1e-4 above 0.6 floor_d,
/// 1 at floor_d / 2 and 1e6 at floor_d / 3. Inputs with floor 0 (or beyond `floor`'s
/// length) are free.
pub fn floor_penalty(hyp: &Hyper, floor: &[f64]) -> (f64, Vec<f64>) {
    octave_wall(hyp, floor, -1.0)
}

/// The mirror of [`floor_penalty`]: keeps length-scale d below about twice `ceiling[d]`, with
/// `z_d = max(0, log ℓ_d − log ceiling_d) / log 2`. It is 0 at and below the ceiling, below
/// 1e-4 under 1.6 ceiling_d, 1 at 2 ceiling_d and 1e6 at 3 ceiling_d. Inputs with ceiling 0
/// (or beyond `ceiling`'s length) are free.
pub fn ceiling_penalty(hyp: &Hyper, ceiling: &[f64]) -> (f64, Vec<f64>) {
    octave_wall(hyp, ceiling, 1.0)
}

/// `Σ_d z_d^p`, `z_d = max(0, side · (log ℓ_d − log bound_d)) / log 2`, and its gradient in
/// PILCO order; `side` is −1 for a floor and +1 for a ceiling.
fn octave_wall(hyp: &Hyper, bound: &[f64], side: f64) -> (f64, Vec<f64>) {
    let d = hyp.dim();
    let mut grad = vec![0.0; d + 2];
    let mut value = 0.0;
    let (p, octave) = (FLOOR_PENALTY_POWER, std::f64::consts::LN_2);
    for (c, &b) in bound.iter().enumerate().take(d) {
        if b > 0.0 {
            let z = side * (hyp.log_ls[c] - b.ln()) / octave;
            if z > 0.0 {
                value += z.powi(p);
                grad[c] = side * f64::from(p) * z.powi(p - 1) / octave;
            }
        }
    }
    (value, grad)
}

fn train_output(
    inputs: MatRef<'_, f64>,
    y: &[f64],
    init: &Hyper,
    c: &[f64],
    opts: &TrainOptions,
) -> Result<(Hyper, OutputReport)> {
    let start = Instant::now();
    let mut ws = NlmlWorkspace::new(inputs.nrows());
    let mut max_jitter = 0.0f64;
    let mut initial_objective = None;
    let mut f = |x: &[f64]| -> Option<(f64, Vec<f64>)> {
        let h = Hyper::from_pilco(x).ok()?;
        let (e, _) = objective(inputs, y, &h, c, opts, &mut ws).ok()?;
        max_jitter = max_jitter.max(e.jitter);
        initial_objective.get_or_insert(e.value);
        Some((e.value, e.grad))
    };
    let Some(r) = minimize(&mut f, init.to_pilco(), &opts.minimize_options()) else {
        // The start point cannot be evaluated: report the real reason.
        objective(inputs, y, init, c, opts, &mut ws)?;
        return Err(GpError::Optimiser(
            "objective is not finite at the start point".into(),
        ));
    };
    let best = Hyper::from_pilco(&r.x)?;
    let (fin, plain) = objective(inputs, y, &best, c, opts, &mut ws)?;
    Ok((
        best,
        OutputReport {
            objective: fin.value,
            nlml: plain,
            initial_objective: initial_objective.unwrap_or(f64::NAN),
            iterations: r.iterations,
            evaluations: r.evaluations + 1,
            termination: r.termination,
            wall_time: start.elapsed(),
            jitter: fin.jitter,
            max_jitter,
            from_cold_restart: false,
        },
    ))
}

/// PILCO's first guess of the hyper-parameters from the data: length-scales = input standard
/// deviations, signal std = target std, noise std = target std / 10.
pub fn initial_hyper(inputs: MatRef<'_, f64>, targets: MatRef<'_, f64>) -> Vec<Hyper> {
    // A constant column (e.g. a saturated action) would give log 0; the floor keeps PILCO's
    // guess finite while leaving that length-scale tiny, unlike `input_std`'s floor of 1.
    let std = |m: MatRef<'_, f64>, c: usize| nlml::column_std(m, c).max(1e-6);
    let log_ls: Vec<f64> = (0..inputs.ncols()).map(|c| std(inputs, c).ln()).collect();
    (0..targets.ncols())
        .map(|e| {
            let sy = std(targets, e);
            Hyper {
                log_ls: log_ls.clone(),
                log_sf: sy.ln(),
                log_sn: (sy / 10.0).ln(),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests;
