//! Environments for vicpilco.
//!
//! * [`Environment`]: the small, object-safe interface the PILCO learning loop is generic over.
//!   A simulator and a real robot driven from outside both fit it: the caller draws the start
//!   state and the per-episode noise seed, the environment runs one learning step of `dt()`
//!   seconds per [`Environment::step`] and returns the (noisy) observation plus diagnostics.
//! * [`arm`]: the planar 3-DOF arm of the thesis (§5-2) under simple (SIC) or general (GIC)
//!   Cartesian impedance control, pushing a point peg against a stiff wall, into a 5 mm hole
//!   and against an insertion spring. See `crates/env/README.md` for every parameter.
//! * [`classic`]: PILCO's pendulum and cart-pole swing-up benchmarks with the constants of
//!   its published scenarios, integrated by RK4 under zero-order hold.
//!
//! The crate uses plain fixed-size arrays for the arm (no linear-algebra crate) and allocates
//! nothing inside the integrator loop.
#![warn(missing_docs)]

pub mod arm;
pub mod classic;
mod environment;
mod error;
pub mod font;

pub use environment::{Environment, Step, StepInfo};
pub use error::EnvError;
