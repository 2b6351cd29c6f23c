//! Environments for vicpilco.
//!
//! * [`Environment`]: the small, object-safe interface the PILCO learning loop is generic over.
//!   A simulator and a real robot driven from outside both fit it: the caller draws the start
//!   state and the per-episode noise seed, the environment runs one learning step of `dt()`
//!   seconds per [`Environment::step`] and returns the (noisy) observation plus diagnostics.
//! * [`arm`]: the planar 3-DOF arm of the thesis (§5-2) under simple (SIC) or general (GIC)
//!   Cartesian impedance control (or none, `off`, for tests of the plant), pushing a point peg
//!   against a stiff wall, into a 5 mm hole and against an insertion spring. See
//!   `crates/env/README.md` for every parameter.
//! * [`classic`]: PILCO's pendulum and cart-pole swing-up benchmarks with the constants of
//!   its published scenarios, integrated by RK4 under zero-order hold.
//! * [`font`]: the font embedded for every plot (the simulator's and the report's).
//!
//! The crate uses plain fixed-size arrays for the arm (no linear-algebra crate) and allocates
//! nothing inside the integrator loop.
//!
//! ## Example
//!
//! One 10 s VIL episode of the arm with constant gains of 250 N/m along the thesis's plan
//! (noise and the 15 % model mismatch on): the peg goes through the hole and ends pressed
//! against its end wall at x = 0.75 m, where the impedance spring, whose reference ends at
//! x = 0.80 m, pushes with k_x · 0.05 m ≈ 12.5 N:
//!
//! ```
//! use vicpilco_env::arm::{ArmConfig, ArmEnv};
//! use vicpilco_env::Environment;
//!
//! let mut env = ArmEnv::new(ArmConfig::default())?;
//! let start = [0.5, 0.0, 0.0, 0.0, 0.0, 0.0]; // x, y, ẋ, ẏ, f_x, f_y
//! env.reset(&start, 1)?;
//! let (k_x, k_y) = (250.0, 250.0);
//! let mut steps = 0;
//! let last = loop {
//!     let step = env.step(&[k_x, k_y])?;
//!     steps += 1;
//!     if step.done {
//!         break step;
//!     }
//! };
//! assert_eq!(steps, env.horizon());
//! assert!(last.info.flags["in_hole"] && env.inserted());
//! let (x, f_x) = (last.info.true_state[0], last.info.true_state[4]);
//! assert!((x - 0.75).abs() < 1e-3);
//! assert!((f_x - k_x * (0.80 - x)).abs() < 0.5);
//! # Ok::<(), vicpilco_env::EnvError>(())
//! ```
#![warn(missing_docs)]

pub mod arm;
pub mod classic;
mod environment;
mod error;
pub mod font;

pub use environment::{Environment, Step, StepInfo};
pub use error::EnvError;
