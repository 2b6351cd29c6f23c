//! The interface between the learning loop and a system it learns on.

use crate::EnvError;
use std::collections::BTreeMap;

/// A system the PILCO learning loop interacts with, one learning step (`dt()` seconds) at a time.
///
/// The trait is object-safe (`Box<dyn Environment>` works) so a simulator and a real robot
/// driven from outside can be swapped at run time.
///
/// Contract:
/// * [`reset`](Environment::reset) must be called before the first [`step`](Environment::step)
///   and after an episode is over (`Step::done`); otherwise `step` returns an error.
/// * Randomness is injected, never drawn from a global source: the caller draws the start
///   state from its start distribution and passes a `seed` for this episode's sensor noise,
///   so episode `k` can be reproduced from `(master seed, k)` alone.
/// * Bad input (wrong length, non-finite or out-of-range values) is an [`EnvError`] naming
///   the offending field, never a panic and never silently clipped.
pub trait Environment {
    /// Length of the observed state `s` returned by `reset` and `step`.
    fn state_dim(&self) -> usize;
    /// Length of the action `a` passed to `step`.
    fn action_dim(&self) -> usize;
    /// Seconds of system time per learning step.
    fn dt(&self) -> f64;
    /// Number of learning steps in one episode (the horizon H); `step` number `H` sets `done`.
    fn horizon(&self) -> usize;
    /// Names of the state entries, in order (for files, plots and logs). `vicpilco report`
    /// knows the arm's and the swing-ups' names and units; any other name may end in its unit,
    /// as `"z [m]"`, which the plots show as the unit.
    fn state_names(&self) -> Vec<String>;
    /// Names of the action entries, in order (units as for [`Environment::state_names`]).
    fn action_names(&self) -> Vec<String>;
    /// Starts an episode at `start` (a state of length `state_dim`, drawn by the caller from its
    /// start distribution) with sensor noise seeded by `seed`. Returns the first (noisy)
    /// observation, which may differ from `start` (noise; entries a system cannot set, such as
    /// contact forces).
    fn reset(&mut self, start: &[f64], seed: u64) -> Result<Vec<f64>, EnvError>;
    /// Applies `action` for `dt()` seconds and returns the observation at the end of the step.
    fn step(&mut self, action: &[f64]) -> Result<Step, EnvError>;
}

/// What one learning step returns.
#[derive(Clone, Debug, PartialEq)]
pub struct Step {
    /// The measured state at the end of the step (length `state_dim`), what the learner sees.
    pub observation: Vec<f64>,
    /// Diagnostics the learner must not use as observations.
    pub info: StepInfo,
    /// True when the episode is over: the horizon is reached, or the system stopped it
    /// (`info.stopped_early` says why; for the arm also `info.flags`, e.g. `singular`,
    /// `diverged`). Call `reset` before stepping again.
    pub done: bool,
}

/// Diagnostics of one step. Simulators fill in the true state; a real robot, which has no
/// noise-free state, sets it equal to the observation (the learning loop refuses one that is
/// not `state_dim` long, the default empty one included).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct StepInfo {
    /// System time at the end of the step, seconds since reset.
    pub t: f64,
    /// The noise-free state at the end of the step, same layout as the observation.
    pub true_state: Vec<f64>,
    /// The commanded reference at the end of the step, same layout as the first
    /// `reference.len()` state entries (for the arm: `x_v, y_v, ẋ_v, ẏ_v`); the learner may use
    /// it as the GP prior mean. `None` when the system has no reference.
    pub reference: Option<Vec<f64>>,
    /// Boolean events at the end of the step (for the arm: `contact`, `in_hole`, `singular`, …).
    pub flags: BTreeMap<String, bool>,
    /// Other named scalars (for the arm: joint angles, largest force during the step, …).
    pub values: BTreeMap<String, f64>,
    /// Why the system ended the episode during this step, before the step's full `dt` (for
    /// the arm: a singular Jacobian, a runaway joint). `None` for a whole step. Such a step's
    /// transition spans less than `dt`, so a learner must not fit its dynamics to it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stopped_early: Option<String>,
    /// Where the system's end point went during the step: its true (x, y) at regular instants
    /// within the step, the last at the step's end. One sample per step would draw straight
    /// chords that cut through the corners a contact makes; plots join these instead. Empty
    /// when the system does not record it (the classic systems, runs recorded before it).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub path: Vec<[f64; 2]>,
}
