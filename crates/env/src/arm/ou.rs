//! Initial stiffness profiles (§5-1-2, Fig. 5-1): an Ornstein–Uhlenbeck process per axis,
//! discretised exactly at the learning step Δt:
//! k₊ = μ + (k − μ)e^{−θΔt} + s·sqrt(1 − e^{−2θΔt})·ε,  ε ~ N(0, 1),
//! μ = (a_min + a_max)/2, s = (a_max − a_min)/6 (the stationary std), k₀ = μ, clipped to
//! [a_min, a_max]. All values are **ours**: the thesis shows only the figure.

use crate::EnvError;
use rand::rngs::ChaCha8Rng;
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};

/// Parameters of the OU stiffness profile.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct OuParams {
    /// Lower limit (N/m). Default 5 (the thesis's policy limit, Table 5-2).
    pub a_min: f64,
    /// Upper limit (N/m). Default 250 (Table 5-2).
    pub a_max: f64,
    /// Mean-reversion rate θ (1/s). **Ours**: 0.5.
    pub theta: f64,
    /// Step Δt (s). Default 0.1 (the learning step).
    pub dt: f64,
}

impl Default for OuParams {
    fn default() -> Self {
        OuParams {
            a_min: 5.0,
            a_max: 250.0,
            theta: 0.5,
            dt: 0.1,
        }
    }
}

impl OuParams {
    /// Mean μ.
    pub fn mean(&self) -> f64 {
        0.5 * (self.a_min + self.a_max)
    }
    /// Stationary standard deviation s.
    pub fn std(&self) -> f64 {
        (self.a_max - self.a_min) / 6.0
    }
    /// Lag-1 autocorrelation e^{−θΔt}.
    pub fn rho(&self) -> f64 {
        (-self.theta * self.dt).exp()
    }

    /// Checks the parameters.
    pub fn validate(&self) -> Result<(), EnvError> {
        crate::error::positive("ou.a_min", self.a_min)?;
        if !(self.a_max.is_finite() && self.a_max > self.a_min) {
            return Err(EnvError::config(
                "ou.a_max",
                self.a_max,
                format!("> a_min = {}", self.a_min),
            ));
        }
        crate::error::positive("ou.theta", self.theta)?;
        crate::error::positive("ou.dt", self.dt)
    }

    /// One profile of `n` values starting at μ, drawn from `rng`; `clip` limits to
    /// [a_min, a_max] (turn off only to check the process statistics).
    pub fn sample(&self, n: usize, rng: &mut ChaCha8Rng, clip: bool) -> Vec<f64> {
        let (mu, rho) = (self.mean(), self.rho());
        let step_std = self.std() * (1.0 - rho * rho).sqrt();
        let mut k = mu;
        let mut out = Vec::with_capacity(n);
        for i in 0..n {
            if i > 0 {
                let eps: f64 = StandardNormal.sample(rng);
                k = mu + (k - mu) * rho + step_std * eps;
                if clip {
                    k = k.clamp(self.a_min, self.a_max);
                }
            }
            out.push(k);
        }
        out
    }

    /// Stiffness profiles (k_x, k_y) of `n` steps from one seed: the x axis is drawn first,
    /// then the y axis, from one ChaCha8 stream.
    pub fn profiles(&self, n: usize, seed: u64) -> Vec<[f64; 2]> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let kx = self.sample(n, &mut rng, true);
        let ky = self.sample(n, &mut rng, true);
        kx.into_iter().zip(ky).map(|(a, b)| [a, b]).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Check (j), OU part: over 1e4 profiles the lag-1 autocorrelation is e^{−θΔt} ± 0.01, the
    /// std is s ± 3 % (unclipped), and clipped profiles stay within the limits.
    #[test]
    fn check_j_ou_statistics() {
        let p = OuParams::default();
        let (mu, s, rho) = (p.mean(), p.std(), p.rho());
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let n = 100;
        let profiles: Vec<Vec<f64>> = (0..10_000).map(|_| p.sample(n, &mut rng, false)).collect();
        // Std across profiles at the last step (variance s²(1 − ρ^{2·99}) ≈ s²).
        let last: Vec<f64> = profiles.iter().map(|v| v[n - 1] - mu).collect();
        let m = last.iter().sum::<f64>() / last.len() as f64;
        let sd =
            (last.iter().map(|d| (d - m).powi(2)).sum::<f64>() / (last.len() - 1) as f64).sqrt();
        let expected_sd = s * (1.0 - rho.powi(2 * (n as i32 - 1))).sqrt();
        assert!(
            (sd / expected_sd - 1.0).abs() < 0.03,
            "std {sd} vs {expected_sd}"
        );
        // Lag-1 autocorrelation, pooled over profiles and steps (AR(1) regression coefficient,
        // unbiased even though the process starts at μ).
        let (mut num, mut den) = (0.0, 0.0);
        for v in &profiles {
            for t in 0..n - 1 {
                num += (v[t] - mu) * (v[t + 1] - mu);
                den += (v[t] - mu) * (v[t] - mu);
            }
        }
        let r1 = num / den;
        eprintln!("(j) OU: std {sd:.3} vs {expected_sd:.3}, lag-1 {r1:.4} vs {rho:.4}");
        assert!((r1 - rho).abs() < 0.01, "lag-1 {r1} vs {rho}");
        // Clipped: within limits.
        let mut rng = ChaCha8Rng::seed_from_u64(12);
        for _ in 0..10_000 {
            for k in p.sample(n, &mut rng, true) {
                assert!(k >= p.a_min && k <= p.a_max);
            }
        }
        assert_eq!(p.profiles(100, 3), p.profiles(100, 3));
        assert_ne!(p.profiles(100, 3), p.profiles(100, 4));
    }
}
