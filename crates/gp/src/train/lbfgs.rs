//! L-BFGS (argmin 0.11, More–Thuente line search, `Vec<f64>` backend) behind one function,
//! [`minimize`], for objectives that return value and gradient together.
//!
//! * argmin asks for the cost and the gradient in separate calls at the same point, so the
//!   objective sits behind a one-entry memo keyed on the exact parameter bits: each distinct
//!   point is evaluated once ([`MinimizeResult::evaluations`] counts those).
//! * A failed evaluation (not positive definite even with jitter, non-finite numbers) is
//!   reported to argmin as `+inf`. The line search cannot interpolate through it and stops; the
//!   minimiser then restarts from the best point so far with a fresh history and a 10× shorter
//!   first step (at most [`MAX_RESTARTS`] times).
//! * argmin's first L-BFGS step is the raw negative gradient (no curvature information yet),
//!   which for a likelihood in log hyper-parameters can be a jump by hundreds of log units. The
//!   objective handed to argmin is therefore scaled by `1/max(1, ‖∇f(x₀)‖)`, so the first trial
//!   step has length ≤ 1. L-BFGS and the line search are invariant to this scale afterwards;
//!   the stopping rules below are applied to the unscaled objective.
//! * PILCO's maximum slope ratio (`minimize.m`'s MSR, [`MinimizeOptions::max_slope_ratio`]):
//!   from the second line search on, the first trial step `α₀ = min(1, MSR · b·s_prev / s)`, so
//!   the first-order decrease `α₀ s` that a line search first tries is at most MSR times the
//!   one the previous line search achieved (`b` its accepted step, `s = ∇fᵀd` the slopes).
//!   L-BFGS's natural step 1 is kept otherwise. PILCO applies the same rule to its first line
//!   search, where it reduces to a step of length min(‖∇f‖, 1/‖∇f‖); ours stays the scaled
//!   step above, of length min(‖∇f‖, 1).
//! * Stopping rules (the W1 bench rule): `‖∇f‖₂ ≤ grad_tol`, or the change of the objective in
//!   one iteration `|f_k − f_{k−1}| ≤ rel_tol · max(|f_k|, |f_{k−1}|, 1)`, or `max_iters`.

mod line_search;

use argmin::core::{
    CostFunction, Executor, Gradient, Problem, Solver, State, TerminationReason, TerminationStatus,
    KV,
};
use argmin::solver::quasinewton::LBFGS;
use line_search::{BoundedLineSearch, SlopeMemory, St};
use serde::{Deserialize, Serialize};
use std::cell::{Cell, RefCell};
use std::rc::Rc;

/// How many times a failed line search may restart the optimiser from the best point.
pub const MAX_RESTARTS: usize = 2;

/// Why an optimisation stopped.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Termination {
    /// `‖∇f‖₂` fell below the gradient tolerance.
    GradientNorm,
    /// The objective changed by less than the relative tolerance in one iteration.
    RelativeChange,
    /// The iteration budget was used up.
    MaxIterations,
    /// The line search could not make progress (after the allowed restarts); the best point
    /// found is returned. The text is argmin's message.
    LineSearchFailed(String),
}

impl Termination {
    /// True for the two convergence criteria.
    pub fn converged(&self) -> bool {
        matches!(self, Self::GradientNorm | Self::RelativeChange)
    }
}

/// The Wolfe conditions the line search accepts a step with: sufficient decrease
/// `f(x + αd) ≤ f(x) + c1 α ∇fᵀd` and curvature `|∇f(x + αd)ᵀd| ≤ c2 |∇fᵀd|`,
/// `0 < c1 < c2 < 1`. A small `c2` makes each line search more exact.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Wolfe {
    /// Sufficient-decrease (Armijo) constant c1 (`minimize.m`'s RHO).
    pub c1: f64,
    /// Curvature constant c2 (`minimize.m`'s SIG).
    pub c2: f64,
}

impl Wolfe {
    /// The usual quasi-Newton choice (argmin's default): almost any decrease is accepted, so
    /// most line searches take one evaluation.
    pub const LOOSE: Wolfe = Wolfe { c1: 1e-4, c2: 0.9 };
    /// The constants of Rasmussen's `minimize.m`, which PILCO optimises its policies with:
    /// RHO = 0.05, SIG = 0.1. With a budget counted in line searches (PILCO's "Length"), the
    /// more exact searches make more progress per line search.
    pub const PILCO: Wolfe = Wolfe { c1: 0.05, c2: 0.1 };
}

/// Stopping rules and memory of [`minimize`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MinimizeOptions {
    /// L-BFGS iteration budget, shared by all restarts.
    pub max_iters: u64,
    /// Stop when `‖∇f‖₂ ≤ grad_tol` (of the unscaled objective).
    pub grad_tol: f64,
    /// Stop when one iteration changes f by at most `rel_tol · max(|f_k|, |f_{k−1}|, 1)`.
    pub rel_tol: f64,
    /// Number of correction pairs L-BFGS keeps.
    pub memory: usize,
    /// At most this many evaluations in one line search (PILCO's MFEPLS); `None`: unbounded.
    /// A line search cut short hands its last trial point to L-BFGS; the best point seen is
    /// still what [`minimize`] returns.
    pub max_line_search_evals: Option<u64>,
    /// Acceptance rule of the line search; must satisfy `0 < c1 < c2 < 1`.
    pub wolfe: Wolfe,
    /// PILCO's maximum slope ratio (MSR, 100 in `minimize.m` and the thesis's Table 5-4): caps
    /// each line search's first trial step as the module documentation says; `None`: every
    /// line search first tries L-BFGS's step 1. Must be positive.
    pub max_slope_ratio: Option<f64>,
}

/// Outcome of [`minimize`].
#[derive(Clone, Debug)]
pub struct MinimizeResult {
    /// Best point found.
    pub x: Vec<f64>,
    /// Objective value there.
    pub value: f64,
    /// L-BFGS iterations over all restarts.
    pub iterations: u64,
    /// Distinct objective evaluations (value and gradient together).
    pub evaluations: usize,
    /// Why the last run (after any restarts) stopped.
    pub termination: Termination,
    /// Line searches whose first trial step the maximum slope ratio shortened below 1.
    pub slope_capped: usize,
}

/// One evaluated point: parameters, value, gradient.
type Point = (Vec<f64>, f64, Vec<f64>);

/// Memoised objective as argmin sees it: `scale · f`.
struct Memo<'f, F> {
    f: RefCell<&'f mut F>,
    scale: f64,
    last: RefCell<Option<Point>>,
    /// Owned by [`minimize`], not by the memo: when a line search fails, argmin's L-BFGS drops
    /// the problem, and a count kept inside it was lost with it.
    evals: &'f Cell<usize>,
}

impl<F: FnMut(&[f64]) -> Option<(f64, Vec<f64>)>> Memo<'_, F> {
    fn eval(&self, x: &[f64]) -> (f64, Vec<f64>) {
        if let Some((px, v, g)) = self.last.borrow().as_ref() {
            if px.len() == x.len() && px.iter().zip(x).all(|(a, b)| a.to_bits() == b.to_bits()) {
                return (*v, g.clone());
            }
        }
        self.evals.set(self.evals.get() + 1);
        let out = {
            let mut f = self.f.borrow_mut();
            (*f)(x)
        };
        let (v, g) = match out {
            Some((v, g)) if v.is_finite() && g.iter().all(|a| a.is_finite()) => {
                (self.scale * v, g.iter().map(|a| self.scale * a).collect())
            }
            _ => (f64::INFINITY, vec![f64::NAN; x.len()]),
        };
        *self.last.borrow_mut() = Some((x.to_vec(), v, g.clone()));
        (v, g)
    }
}

impl<F: FnMut(&[f64]) -> Option<(f64, Vec<f64>)>> CostFunction for Memo<'_, F> {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, x: &Vec<f64>) -> Result<f64, argmin::core::Error> {
        Ok(self.eval(x).0)
    }
}

impl<F: FnMut(&[f64]) -> Option<(f64, Vec<f64>)>> Gradient for Memo<'_, F> {
    type Param = Vec<f64>;
    type Gradient = Vec<f64>;
    fn gradient(&self, x: &Vec<f64>) -> Result<Vec<f64>, argmin::core::Error> {
        Ok(self.eval(x).1)
    }
}

/// argmin's L-BFGS with our stopping rules (argmin's own are absolute and set to 0).
struct Lbfgs {
    inner: LBFGS<BoundedLineSearch, Vec<f64>, Vec<f64>, f64>,
    scale: f64,
    grad_tol: f64,
    rel_tol: f64,
    reason: Option<Termination>,
}

impl<O> Solver<O, St> for Lbfgs
where
    LBFGS<BoundedLineSearch, Vec<f64>, Vec<f64>, f64>: Solver<O, St>,
{
    fn name(&self) -> &str {
        "L-BFGS (vicpilco stopping rules)"
    }

    fn init(
        &mut self,
        problem: &mut Problem<O>,
        state: St,
    ) -> Result<(St, Option<KV>), argmin::core::Error> {
        self.inner.init(problem, state)
    }

    fn next_iter(
        &mut self,
        problem: &mut Problem<O>,
        state: St,
    ) -> Result<(St, Option<KV>), argmin::core::Error> {
        self.inner.next_iter(problem, state)
    }

    fn terminate(&mut self, state: &St) -> TerminationStatus {
        let gnorm = state
            .get_gradient()
            .map(|g| g.iter().map(|v| v * v).sum::<f64>().sqrt() / self.scale)
            .unwrap_or(f64::INFINITY);
        let reason = if gnorm <= self.grad_tol {
            Some(Termination::GradientNorm)
        } else {
            let (f, fp) = (state.get_cost(), state.get_prev_cost());
            let tol = self.rel_tol * f.abs().max(fp.abs()).max(self.scale);
            (fp.is_finite() && (f - fp).abs() <= tol).then_some(Termination::RelativeChange)
        };
        match reason {
            Some(r) => {
                self.reason = Some(r);
                TerminationStatus::Terminated(TerminationReason::SolverConverged)
            }
            None => TerminationStatus::NotTerminated,
        }
    }
}

/// Minimise `f` (returning value and gradient, or `None` where it cannot be evaluated) by
/// L-BFGS from `x0`. Returns `None` when `f` fails at `x0`, `opts.wolfe` violates
/// `0 < c1 < c2 < 1` or `opts.max_slope_ratio` is not positive and finite.
pub fn minimize<F>(f: &mut F, x0: Vec<f64>, opts: &MinimizeOptions) -> Option<MinimizeResult>
where
    F: FnMut(&[f64]) -> Option<(f64, Vec<f64>)>,
{
    let finite = |r: Option<(f64, Vec<f64>)>| {
        r.filter(|(v, g)| v.is_finite() && g.iter().all(|a| a.is_finite()))
    };
    if opts
        .max_slope_ratio
        .is_some_and(|r| !(r.is_finite() && r > 0.0))
    {
        return None;
    }
    let (mut best_f, mut grad) = finite(f(&x0))?;
    let mut best_x = x0;
    let mut evaluations = 1;
    let mut slope_capped = 0;
    let mut iterations = 0u64;
    let mut step_shrink = 1.0;
    let memo_evals = Cell::new(0usize);
    let mut gnorm = grad.iter().map(|v| v * v).sum::<f64>().sqrt();
    for restart in 0..=MAX_RESTARTS {
        // At the start, and at the best point a failed line search restarts from.
        if gnorm <= opts.grad_tol {
            return Some(MinimizeResult {
                x: best_x,
                value: best_f,
                iterations,
                evaluations,
                termination: Termination::GradientNorm,
                slope_capped,
            });
        }
        let scale = step_shrink / gnorm.max(1.0);
        // Seed the memo with the start point, which is already evaluated.
        let seed = (
            best_x.clone(),
            scale * best_f,
            grad.iter().map(|g| scale * g).collect(),
        );
        let memo = Memo {
            f: RefCell::new(&mut *f),
            scale,
            last: RefCell::new(Some(seed)),
            evals: &memo_evals,
        };
        // A restart begins with a fresh history, as PILCO's does after a failed search.
        let memory = Rc::new(SlopeMemory::default());
        let linesearch = BoundedLineSearch::new(
            opts.wolfe,
            opts.max_line_search_evals,
            opts.max_slope_ratio,
            Rc::clone(&memory),
        )?;
        let inner = LBFGS::new(linesearch, opts.memory.max(1))
            .with_tolerance_grad(0.0)
            .and_then(|s| s.with_tolerance_cost(0.0))
            .expect("non-negative tolerances");
        let solver = Lbfgs {
            inner,
            scale,
            grad_tol: opts.grad_tol,
            rel_tol: opts.rel_tol,
            reason: None,
        };
        let remaining = opts.max_iters.saturating_sub(iterations);
        let start = best_x.clone();
        let run = Executor::new(memo, solver)
            .configure(|s| s.param(start).max_iters(remaining))
            .ctrlc(false)
            .run();
        let (mut state, solver) = match run {
            Ok(r) => (r.state, r.solver),
            // argmin errors outside the line search (should not happen): keep the best point.
            Err(e) => {
                return Some(MinimizeResult {
                    x: best_x,
                    value: best_f,
                    iterations,
                    evaluations: evaluations + memo_evals.get(),
                    termination: Termination::LineSearchFailed(e.to_string()),
                    slope_capped: slope_capped + memory.capped(),
                })
            }
        };
        iterations += state.get_iter();
        evaluations += memo_evals.take();
        slope_capped += memory.capped();
        let run_best = state.get_best_cost() / scale;
        if let Some(x) = state.take_best_param() {
            if run_best < best_f {
                best_f = run_best;
                best_x = x;
            }
        }
        let termination = match (solver.reason, state.get_termination_reason()) {
            (Some(r), _) => r,
            (None, Some(TerminationReason::MaxItersReached)) => Termination::MaxIterations,
            (None, Some(other)) => Termination::LineSearchFailed(other.text().to_string()),
            (None, None) => Termination::MaxIterations,
        };
        let retry = matches!(termination, Termination::LineSearchFailed(_))
            && restart < MAX_RESTARTS
            && iterations < opts.max_iters;
        if !retry {
            return Some(MinimizeResult {
                x: best_x,
                value: best_f,
                iterations,
                evaluations,
                termination,
                slope_capped,
            });
        }
        // Restart from the best point with a fresh history and a shorter first step.
        let (v, g) = finite(f(&best_x))?;
        evaluations += 1;
        best_f = v;
        grad = g;
        gnorm = grad.iter().map(|v| v * v).sum::<f64>().sqrt();
        step_shrink *= 0.1;
    }
    unreachable!("the restart loop returns on its last pass")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rosenbrock(x: &[f64]) -> Option<(f64, Vec<f64>)> {
        let (a, b) = (x[0], x[1]);
        let v = (1.0 - a).powi(2) + 100.0 * (b - a * a).powi(2);
        let g = vec![
            -2.0 * (1.0 - a) - 400.0 * a * (b - a * a),
            200.0 * (b - a * a),
        ];
        Some((v, g))
    }

    #[test]
    fn minimises_rosenbrock() {
        let opts = MinimizeOptions {
            max_iters: 200,
            grad_tol: 1e-8,
            rel_tol: 0.0,
            memory: 10,
            max_line_search_evals: None,
            wolfe: Wolfe::LOOSE,
            max_slope_ratio: None,
        };
        let r = minimize(&mut rosenbrock, vec![-1.2, 1.0], &opts).unwrap();
        assert!(
            (r.x[0] - 1.0).abs() < 1e-6 && (r.x[1] - 1.0).abs() < 1e-6,
            "{r:?}"
        );
        assert!(r.termination.converged(), "{r:?}");
    }

    #[test]
    fn exact_line_searches_need_fewer_iterations() {
        let run = |wolfe| {
            let opts = MinimizeOptions {
                max_iters: 500,
                grad_tol: 1e-8,
                rel_tol: 0.0,
                memory: 10,
                max_line_search_evals: None,
                wolfe,
                max_slope_ratio: None,
            };
            minimize(&mut rosenbrock, vec![-1.2, 1.0], &opts).unwrap()
        };
        let (loose, pilco) = (run(Wolfe::LOOSE), run(Wolfe::PILCO));
        for r in [&loose, &pilco] {
            assert!(
                (r.x[0] - 1.0).abs() < 1e-6 && (r.x[1] - 1.0).abs() < 1e-6,
                "{r:?}"
            );
        }
        assert!(
            pilco.iterations < loose.iterations,
            "{pilco:?} vs {loose:?}"
        );
        let bad = MinimizeOptions {
            wolfe: Wolfe { c1: 0.5, c2: 0.1 },
            ..MinimizeOptions {
                max_iters: 1,
                grad_tol: 0.0,
                rel_tol: 0.0,
                memory: 1,
                max_line_search_evals: None,
                wolfe: Wolfe::LOOSE,
                max_slope_ratio: None,
            }
        };
        assert!(minimize(&mut rosenbrock, vec![0.0, 0.0], &bad).is_none());
    }

    #[test]
    fn failed_region_is_avoided_not_fatal() {
        // A quadratic with its minimum at 3, undefined beyond 4: the first steps overshoot.
        let calls = Cell::new(0usize);
        let mut f = |x: &[f64]| {
            calls.set(calls.get() + 1);
            (x[0] <= 4.0).then(|| (1000.0 * (x[0] - 3.0).powi(2), vec![2000.0 * (x[0] - 3.0)]))
        };
        let opts = MinimizeOptions {
            max_iters: 100,
            grad_tol: 1e-8,
            rel_tol: 0.0,
            memory: 5,
            max_line_search_evals: None,
            wolfe: Wolfe::LOOSE,
            max_slope_ratio: None,
        };
        let r = minimize(&mut f, vec![-10.0], &opts).unwrap();
        assert!((r.x[0] - 3.0).abs() < 1e-6, "{r:?}");
        assert_eq!(r.evaluations, calls.get(), "{r:?}");
    }

    #[test]
    fn evaluations_count_every_call_of_the_objective() {
        let calls = Cell::new(0usize);
        // Budget-bound runs with bounded line searches (the policy optimiser's setting) and
        // runs through failed line searches and restarts.
        let mut counted = |x: &[f64]| {
            calls.set(calls.get() + 1);
            rosenbrock(x)
        };
        for (max_iters, evals) in [(5, Some(2)), (30, Some(25)), (200, None)] {
            calls.set(0);
            let opts = MinimizeOptions {
                max_iters,
                grad_tol: 1e-10,
                rel_tol: 0.0,
                memory: 10,
                max_line_search_evals: evals,
                wolfe: Wolfe::PILCO,
                max_slope_ratio: None,
            };
            let r = minimize(&mut counted, vec![-1.2, 1.0], &opts).unwrap();
            assert_eq!(r.evaluations, calls.get(), "{r:?}");
            assert!(r.evaluations > r.iterations as usize, "{r:?}");
        }
        // The overshooting quadratic's count is checked in `failed_region_is_avoided_not_fatal`.
        // Rosenbrock undefined right of a wall the path runs into: line searches fail inside
        // argmin, which then drops the problem (and once, its evaluation count, with it).
        for wall in [-1.0, 0.0, 0.9] {
            let calls = Cell::new(0usize);
            let mut f = |x: &[f64]| {
                calls.set(calls.get() + 1);
                (x[0] <= wall).then(|| rosenbrock(x)).flatten()
            };
            let opts = MinimizeOptions {
                max_iters: 50,
                grad_tol: 1e-12,
                rel_tol: 0.0,
                memory: 10,
                max_line_search_evals: Some(25),
                wolfe: Wolfe::PILCO,
                max_slope_ratio: None,
            };
            let r = minimize(&mut f, vec![-1.2, 1.0], &opts).unwrap();
            assert!(
                matches!(r.termination, Termination::LineSearchFailed(_)),
                "{r:?}"
            );
            assert_eq!(r.evaluations, calls.get(), "wall {wall}: {r:?}");
        }
    }

    #[test]
    fn failure_at_the_start_is_none() {
        let mut f = |_: &[f64]| None;
        let opts = MinimizeOptions {
            max_iters: 10,
            grad_tol: 1e-6,
            rel_tol: 1e-6,
            memory: 5,
            max_line_search_evals: None,
            wolfe: Wolfe::LOOSE,
            max_slope_ratio: None,
        };
        assert!(minimize(&mut f, vec![0.0], &opts).is_none());
    }

    #[test]
    fn the_slope_ratio_shortens_first_steps_only_when_it_binds() {
        let opts = |max_slope_ratio| MinimizeOptions {
            max_iters: 60,
            grad_tol: 1e-10,
            rel_tol: 0.0,
            memory: 10,
            max_line_search_evals: Some(25),
            wolfe: Wolfe::PILCO,
            max_slope_ratio,
        };
        let free = minimize(&mut rosenbrock, vec![-1.2, 1.0], &opts(None)).unwrap();
        assert_eq!(free.slope_capped, 0);
        // A ratio no step comes near: the same run, point for point.
        let loose = minimize(&mut rosenbrock, vec![-1.2, 1.0], &opts(Some(1e12))).unwrap();
        assert_eq!(loose.slope_capped, 0);
        assert_eq!(
            (loose.x.clone(), loose.evaluations),
            (free.x.clone(), free.evaluations)
        );
        // A ratio below 1 caps every search after the first that made progress, and the
        // minimiser still gets there.
        let tight = minimize(&mut rosenbrock, vec![-1.2, 1.0], &opts(Some(0.5))).unwrap();
        assert!(tight.slope_capped > 0, "{tight:?}");
        assert!(
            tight.value < 1e-3 * rosenbrock(&[-1.2, 1.0]).unwrap().0,
            "{tight:?}"
        );
        assert!(minimize(&mut rosenbrock, vec![0.0, 0.0], &opts(Some(0.0))).is_none());
        assert!(minimize(&mut rosenbrock, vec![0.0, 0.0], &opts(Some(f64::NAN))).is_none());
    }
}
