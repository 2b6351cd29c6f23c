//! Planar 3-DOF arm under Cartesian impedance control with peg-in-hole contact (thesis ch. 5,
//! issue 5).
//!
//! Layers, bottom up:
//! * [`params`]: every number, with defaults (thesis values and documented choices of ours).
//! * [`kinematics`], [`dynamics`]: closed-form f_k, J, J̇q̇, M(q), C(q, q̇) on `[f64; 3]` arrays,
//!   and a recursive Newton–Euler that checks them.
//! * [`contact`]: wall, hole channel, end wall and insertion spring as penalty forces.
//! * [`sim::Plant`]: the true (mismatched) arm plus contact, integrated by classic RK4 at a
//!   fixed step; [`sim::ArmSim`]: one control tick = sensors → impedance law → torque held
//!   over the RK4 substeps.
//! * [`impedance`]: SIC and GIC. [`plan`]: min-jerk reference. [`ou`]: OU stiffness profiles.
//! * [`ArmEnv`]: the [`crate::Environment`] (VIL / VILTA). [`run`]: one episode to files
//!   (`vicpilco sim`), with [`plot`].
//!
//! Determinism: one ChaCha8 stream per episode seeds the sensor noise; nothing else is random
//! and nothing is shared between episodes, so the same seed gives bit-identical traces on any
//! thread.

pub mod contact;
pub mod dynamics;
mod env;
pub mod impedance;
pub mod kinematics;
pub mod mat3;
pub mod ou;
pub mod params;
pub mod plan;
pub mod plot;
pub mod run;
pub mod sensors;
pub mod sim;
pub mod trace;

pub use env::{ArmEnv, LEAD_NAMES, PATH_SAMPLE_INTERVAL, START_MAX_PENETRATION, STATE_NAMES};
pub use ou::OuParams;
pub use params::{
    ActionMode, ArmConfig, ArmParams, ContactParams, ControllerKind, Geometry, ImpedanceParams,
    OnDivergence, ReferenceOrigin, SensorParams,
};
pub use plan::{RefPoint, ReferenceSpec, ViaPlan};
pub use sim::{ArmSim, Plant, TickStatus};
pub use trace::TickRecord;
