//! Squashing and augmentation blocks built on exact moments of sinusoids of Gaussians:
//! [`SineSat`] (PILCO's `gSat`), [`PartialSat`] (the thesis's partial non-negative
//! saturation for impedance gains) and [`TrigAug`] (PILCO's `gTrig`).

mod sat;
mod sines;
mod trig;

pub use sat::{PartialSat, SatRange, SineSat};
pub use sines::SinesCache;
pub use trig::TrigAug;
