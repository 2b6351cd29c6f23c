//! The line search under [`super::minimize`]'s L-BFGS: argmin's More–Thuente, stopped after a
//! fixed number of trial points, with PILCO's maximum-slope-ratio cap on its first trial step.

use super::Wolfe;
use argmin::core::{IterState, Problem, Solver, State, TerminationReason, TerminationStatus, KV};
use argmin::solver::linesearch::{LineSearch, MoreThuenteLineSearch};
use std::cell::{Cell, RefCell};
use std::rc::Rc;

type Ls = MoreThuenteLineSearch<Vec<f64>, Vec<f64>, f64>;
pub(super) type St = IterState<Vec<f64>, Vec<f64>, (), (), (), f64>;

/// Where the previous line search of one L-BFGS run started, in which direction, and its
/// slope there: the next line search recovers the accepted step `b` from its own start.
struct PreviousSearch {
    start: Vec<f64>,
    direction: Vec<f64>,
    slope: f64,
}

/// What the line searches of one L-BFGS run share (argmin clones the line search for each).
#[derive(Default)]
pub(super) struct SlopeMemory {
    previous: RefCell<Option<PreviousSearch>>,
    capped: Cell<usize>,
}

impl SlopeMemory {
    /// How many line searches had their first trial step shortened by the slope-ratio cap.
    pub(super) fn capped(&self) -> usize {
        self.capped.get()
    }
}

/// More–Thuente, stopped after a fixed number of trial points (PILCO's MFEPLS), with its first
/// trial step capped by PILCO's maximum slope ratio.
///
/// It also guards against a gap in argmin 0.11: when More–Thuente gives up (rounding
/// prevents progress) it returns a state without a parameter vector, and argmin's L-BFGS then
/// unwraps `None` and panics. Here such a state gets the line search's starting point back, so
/// L-BFGS sees "no progress" instead.
#[derive(Clone)]
pub(super) struct BoundedLineSearch {
    inner: Ls,
    max_evals: Option<u64>,
    start: Option<(Vec<f64>, f64)>,
    max_slope_ratio: Option<f64>,
    direction: Option<Vec<f64>>,
    memory: Rc<SlopeMemory>,
}

impl BoundedLineSearch {
    /// The line search of one L-BFGS run; `memory` is what argmin's per-iteration clones of it
    /// share. `None` for Wolfe constants argmin refuses.
    pub(super) fn new(
        wolfe: Wolfe,
        max_evals: Option<u64>,
        max_slope_ratio: Option<f64>,
        memory: Rc<SlopeMemory>,
    ) -> Option<Self> {
        Some(Self {
            inner: MoreThuenteLineSearch::new()
                .with_c(wolfe.c1, wolfe.c2)
                .ok()?,
            max_evals,
            start: None,
            max_slope_ratio,
            direction: None,
            memory,
        })
    }

    /// PILCO's first trial step `min(1, MSR · b·s_prev / s)` for a search from `x0` with slope
    /// `slope` along `direction`, and remember this search for the next one. `None` on the
    /// first search of a run, without a ratio, or where the previous step cannot be recovered
    /// (a search that went nowhere leaves PILCO's `b·s` as it was; ours falls back to 1).
    fn first_step(&self, x0: &[f64], direction: &[f64], slope: f64) -> Option<f64> {
        let max_ratio = self.max_slope_ratio?;
        let previous = self.memory.previous.replace(Some(PreviousSearch {
            start: x0.to_vec(),
            direction: direction.to_vec(),
            slope,
        }))?;
        let ratio = slope_ratio(&previous, x0, slope)?;
        // How far each search is from the cap: `RUST_LOG=debug` shows whether a run's MSR binds.
        tracing::debug!(
            ratio,
            max_ratio,
            "line search's slope over the previous achieved decrease"
        );
        Some((max_ratio / ratio).min(1.0))
    }
}

/// `s / (b·s_prev)`: the new search's slope over the first-order decrease the previous search
/// achieved, `b` being its step from `previous.start` along `previous.direction` to `x0`. The
/// first trial step is `min(1, MSR / ratio)` (PILCO writes it `bs / min(bs, s / MSR)` with
/// `bs = b·s_prev`). `None` where no positive step was made.
fn slope_ratio(previous: &PreviousSearch, x0: &[f64], slope: f64) -> Option<f64> {
    let d2: f64 = previous.direction.iter().map(|v| v * v).sum();
    let moved: f64 = x0
        .iter()
        .zip(&previous.start)
        .zip(&previous.direction)
        .map(|((x, p), d)| (x - p) * d)
        .sum();
    let step = moved / d2;
    let ratio = slope / (step * previous.slope);
    (step > 0.0 && ratio.is_finite() && ratio > 0.0).then_some(ratio)
}

impl LineSearch<Vec<f64>, f64> for BoundedLineSearch {
    fn search_direction(&mut self, direction: Vec<f64>) {
        // Kept only for the slope-ratio rule, which needs it in `init`.
        if self.max_slope_ratio.is_some() {
            self.direction = Some(direction.clone());
        }
        self.inner.search_direction(direction)
    }
    fn initial_step_length(&mut self, step_length: f64) -> Result<(), argmin::core::Error> {
        self.inner.initial_step_length(step_length)
    }
}

impl<O> Solver<O, St> for BoundedLineSearch
where
    Ls: Solver<O, St>,
{
    fn name(&self) -> &str {
        "More-Thuente line search (bounded evaluations)"
    }
    fn init(
        &mut self,
        problem: &mut Problem<O>,
        state: St,
    ) -> Result<(St, Option<KV>), argmin::core::Error> {
        self.start = state.get_param().map(|p| (p.clone(), state.get_cost()));
        if let (Some((x0, _)), Some(d), Some(g)) =
            (&self.start, &self.direction, state.get_gradient())
        {
            let slope: f64 = g.iter().zip(d).map(|(g, d)| g * d).sum();
            if let Some(alpha) = self.first_step(x0, d, slope) {
                if alpha < 1.0 {
                    self.memory.capped.set(self.memory.capped.get() + 1);
                }
                self.inner.initial_step_length(alpha)?;
            }
        }
        self.inner.init(problem, state)
    }
    fn next_iter(
        &mut self,
        problem: &mut Problem<O>,
        state: St,
    ) -> Result<(St, Option<KV>), argmin::core::Error> {
        let (st, kv) = self.inner.next_iter(problem, state)?;
        match (st.get_param(), &self.start) {
            (None, Some((p, c))) => Ok((st.param(p.clone()).cost(*c), kv)),
            _ => Ok((st, kv)),
        }
    }
    fn terminate(&mut self, state: &St) -> TerminationStatus {
        match self.max_evals {
            Some(m) if state.get_iter() >= m => {
                TerminationStatus::Terminated(TerminationReason::MaxItersReached)
            }
            _ => TerminationStatus::NotTerminated,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_capped_first_step_is_pilcos_rule() {
        // PILCO: a = bs / min(bs, s / MSR), with bs = b · s_prev (both slopes negative).
        let pilco = |msr: f64, b: f64, s_prev: f64, s: f64| {
            let bs = b * s_prev;
            bs / bs.min(s / msr)
        };
        let previous = PreviousSearch {
            start: vec![1.0, -2.0],
            direction: vec![0.5, 0.25],
            slope: -0.3,
        };
        for (msr, b, s) in [(100.0, 0.2, -1.0), (100.0, 0.2, -1e4), (10.0, 1e-3, -50.0)] {
            let x0: Vec<f64> = previous
                .start
                .iter()
                .zip(&previous.direction)
                .map(|(p, d)| p + b * d)
                .collect();
            let ours = (msr / slope_ratio(&previous, &x0, s).unwrap()).min(1.0);
            let theirs = pilco(msr, b, previous.slope, s);
            assert!(
                (ours - theirs).abs() <= 1e-12 * theirs,
                "{ours} vs {theirs}"
            );
        }
        // A search that went nowhere (or backwards) gives no cap.
        assert_eq!(slope_ratio(&previous, &previous.start, -1.0), None);
    }
}
