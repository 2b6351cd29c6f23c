//! # vicpilco-learn: long-term prediction, the expected return and its policy gradient
//!
//! * [`joint`]: the joint Gaussian of a step, grown block by block, and its adjoint;
//! * [`step`]: one prediction step (state → policy → squashing → GP → next state), forward and
//!   backward;
//! * [`value`]: the expected return over a horizon and `dJ/dψ` by one reverse sweep;
//! * [`data`]: roll-outs and the GP training set built from them;
//! * [`outer`]: the learning loop over an [`vicpilco_env::Environment`], with checkpoints;
//! * [`record`]: what the loop reports after each update ([`record::LoopObserver`],
//!   [`record::LoopState`], [`record::EpisodeRecord`]);
//! * [`selection`]: which dynamics model an update optimises on (PILCO's refit or ours);
//! * [`replay`]: where another selection rule would have parted from a recorded run;
//! * [`start`]: start distributions of the real episodes.
//!
//! The whole learning loop on a system of your own: implement [`vicpilco_env::Environment`],
//! fill in an [`outer::LoopSetup`] and call its `run`, or hand both to
//! `vicpilco_experiments::own::run_own` for a run directory with checkpoints and a report
//! (`cargo run --release -p vicpilco-experiments --example own_system`).
//!
//! ## Example
//!
//! A one-dimensional system that moves by `Δx = 0.1 u` per step, learned by a GP from 49
//! transitions; a linear policy `u = w x + b`, squashed onto `[−1, 1]`, starts at
//! `x ~ N(0, 0.01²)` and is charged a saturating cost of width 1 around `x = 1` for 20 steps.
//! [`value::value`] predicts the expected return J and `dJ/dψ` in one reverse sweep; the
//! gradient matches a central difference of J, and it says that a larger offset `b` (moving
//! towards the target) lowers J:
//!
//! ```
//! use faer::Mat;
//! use vicpilco_gp::fd::{directional, rel_diff};
//! use vicpilco_gp::moments::MmModel;
//! use vicpilco_gp::train::initial_hyper;
//! use vicpilco_gp::{train, GpModel, TrainOptions};
//! use vicpilco_learn::step::{Predictor, StepSpec, Target};
//! use vicpilco_learn::value::{value, ReturnSpec};
//! use vicpilco_pilco::cost::{CostSum, SaturatingCost};
//! use vicpilco_pilco::policy::{LinearPolicy, Policy};
//! use vicpilco_pilco::squash::{PartialSat, SatRange};
//!
//! // Training set: inputs (x, u) on a 7 × 7 grid, target the increment Δx = 0.1 u.
//! let grid = |k: usize| k as f64 / 3.0 - 1.0; // −1 to 1
//! let inputs = Mat::from_fn(49, 2, |i, j| if j == 0 { 0.5 * grid(i / 7) } else { grid(i % 7) });
//! let targets = Mat::from_fn(49, 1, |i, _| 0.1 * inputs[(i, 1)]);
//! let start = initial_hyper(inputs.as_ref(), targets.as_ref());
//! let (hyp, _) = train(inputs.as_ref(), targets.as_ref(), &start, &TrainOptions::default())?;
//! let gp = GpModel::new(inputs, targets, hyp)?;
//!
//! let spec = StepSpec {
//!     state_dim: 1,
//!     angles: vec![],
//!     time_input: false,
//!     policy_inputs: vec![0],
//!     dyn_inputs: vec![0],
//!     targets: vec![Target::Relative],
//!     linear_prior: vec![],
//!     dt: 0.1,
//! };
//! let squash = PartialSat::new(1, &[0], &[SatRange::Symmetric { a_max: 1.0 }])?;
//! let width = Mat::from_fn(1, 1, |_, _| 1.0); // W = width⁻², width 1
//! let near_one = SaturatingCost::new(&[0], width.as_ref(), &[1.0])?;
//! let ret = ReturnSpec {
//!     state_cost: Some(CostSum::new(1, vec![near_one])?),
//!     cost_angles: vec![],
//!     w_mean: 1.0,
//!     w_std: 0.0,
//!     energy: None,
//!     gamma: 1.0,
//!     horizon: 20,
//! };
//! let starts = vec![(vec![0.0], Mat::from_fn(1, 1, |_, _| 1e-4))];
//!
//! let evaluate = |params: &[f64], with_grad: bool| {
//!     let mut policy = LinearPolicy::zeros(1, 1);
//!     policy.set_params(params).unwrap();
//!     let dynamics = MmModel::with_uncertainty(&gp);
//!     let predictor = Predictor::new(&spec, &policy, Some(&squash), dynamics, None).unwrap();
//!     value(&predictor, &ret, &starts, with_grad).unwrap()
//! };
//! let params = [0.2, -0.3]; // [b, w]: PILCO's order
//! let out = evaluate(&params, true);
//! let grad = out.grad.expect("asked for");
//! // J carries the round-off of solves with a nearly noise-free GP's kernel matrix, which a
//! // small step amplifies: here the two agree to 1e-9..1e-7 for h = 1e-2..1e-3 and drift
//! // to 1e-6..1e-4 for h = 1e-4..1e-6.
//! let h = 1e-3;
//! for dir in [[1.0, 0.0], [0.0, 1.0], [0.6, -0.8]] {
//!     let numeric = directional(&mut |p: &[f64]| evaluate(p, false).j, &params, &dir, h);
//!     let analytic = grad[0] * dir[0] + grad[1] * dir[1];
//!     assert!(rel_diff(analytic, numeric, 1e-8) < 1e-6, "{analytic} against {numeric}");
//! }
//! assert!(out.j > 0.0 && out.j < 20.0 && grad[0] < 0.0);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#![warn(missing_docs)]

pub mod data;
pub mod joint;
pub mod outer;
pub mod record;
pub mod replay;
pub mod selection;
pub mod start;
pub mod step;
pub mod value;

use thiserror::Error;

/// Why a prediction, a model fit, a replay or the learning loop failed.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum LearnError {
    /// Parts that do not fit together: out-of-range indices, mismatched dimensions, inverted
    /// bounds, no start distribution, an incomplete checkpoint or replay record. The text
    /// names the field or record at fault.
    #[error("prediction set-up: {0}")]
    Spec(String),
    /// A prediction came out NaN or infinite: an immediate cost (the text names the 1-based
    /// step) or the return at the policy an optimisation starts from.
    #[error("non-finite prediction: {0}")]
    NonFinite(String),
    /// Training a GP, factorising a covariance or moment matching through a GP failed.
    #[error(transparent)]
    Gp(#[from] vicpilco_gp::GpError),
    /// A policy, squashing or cost block rejected its definition, input or parameters.
    #[error(transparent)]
    Pilco(#[from] vicpilco_pilco::PilcoError),
    /// The system refused a reset or a step, or returned an observation or true state that is
    /// non-finite or not `state_dim` long; the text is its error, prefixed `step t:` (0-based)
    /// for a step.
    #[error("system: {0}")]
    Env(String),
}
