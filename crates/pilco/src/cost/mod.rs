//! Costs with their mean, variance and input-output term under a Gaussian state or action,
//! and reverse-mode derivatives: the saturating cost (PILCO's `lossSat`) and sums of them,
//! and the thesis's normalised quadratic energy cost.

mod energy;
mod gauss_exp;
mod saturating;

pub use energy::{EnergyCache, EnergyCost};
pub use saturating::{CostSum, CostSumCache, SaturatingCost, VAR_CLAMP};
