//! Start distributions of the system's real episodes (the prediction's start distributions are
//! Gaussians given separately, see [`crate::outer::LoopSetup::prediction_starts`]).

use crate::LearnError;
use faer::Mat;
use rand::{RngExt, SeedableRng};
use rand_distr::{Distribution, StandardNormal};
use vicpilco_gp::linalg::Chol;

/// Where each real episode starts.
#[derive(Clone, Debug)]
pub enum StartDistribution {
    /// `N(mean, cov)`; a zero covariance gives the mean every time.
    Gaussian {
        /// Mean start state.
        mean: Vec<f64>,
        /// Its covariance (D×D, D = `mean.len()`); may be singular (factorised with jitter).
        cov: Mat<f64>,
    },
    /// Independent uniform entries on `[lo_i, hi_i]` (`lo_i = hi_i` fixes entry i), as the
    /// thesis's y0 ~ U(0.1, 0.3) of the variable-start VILTA run.
    Uniform {
        /// Lower bound of each state entry.
        lo: Vec<f64>,
        /// Upper bound of each entry: as long as `lo` and ≥ it entry by entry, or
        /// [`StartDistribution::sample`] fails.
        hi: Vec<f64>,
    },
}

impl StartDistribution {
    /// A fixed start.
    pub fn fixed(x: &[f64]) -> StartDistribution {
        StartDistribution::Uniform {
            lo: x.to_vec(),
            hi: x.to_vec(),
        }
    }

    /// Length of the states it draws.
    pub fn dim(&self) -> usize {
        match self {
            StartDistribution::Gaussian { mean, .. } => mean.len(),
            StartDistribution::Uniform { lo, .. } => lo.len(),
        }
    }

    /// One draw, reproducible from `seed`.
    pub fn sample(&self, seed: u64) -> Result<Vec<f64>, LearnError> {
        match self {
            StartDistribution::Gaussian { mean, cov } => sample_gaussian(mean, cov, seed),
            StartDistribution::Uniform { lo, hi } => {
                if lo.len() != hi.len() {
                    return Err(LearnError::Spec(format!(
                        "uniform start: {} lower and {} upper bounds",
                        lo.len(),
                        hi.len()
                    )));
                }
                if let Some(i) =
                    (0..lo.len()).find(|&i| lo[i].partial_cmp(&hi[i]).is_none_or(|o| o.is_gt()))
                {
                    return Err(LearnError::Spec(format!(
                        "uniform start entry {i}: lower bound {} above upper bound {}",
                        lo[i], hi[i]
                    )));
                }
                let mut rng = rand::rngs::ChaCha8Rng::seed_from_u64(seed);
                Ok(lo
                    .iter()
                    .zip(hi)
                    .map(|(&a, &b)| {
                        let u: f64 = rng.random();
                        a + (b - a) * u
                    })
                    .collect())
            }
        }
    }
}

/// A draw from `N(m, s)`. An all-zero `s` returns `m`; another singular `s` is factorised with
/// growing diagonal jitter ([`Chol::with_jitter`]), so its zero-variance dimensions get noise of
/// about the square root of the jitter used.
pub fn sample_gaussian(m: &[f64], s: &Mat<f64>, seed: u64) -> Result<Vec<f64>, LearnError> {
    let d = m.len();
    // A deterministic start (zero covariance) has no Cholesky factor to draw with.
    if (0..d).all(|i| (0..d).all(|j| s[(i, j)] == 0.0)) {
        return Ok(m.to_vec());
    }
    let mut rng = rand::rngs::ChaCha8Rng::seed_from_u64(seed);
    let z: Vec<f64> = (0..d).map(|_| StandardNormal.sample(&mut rng)).collect();
    let chol = Chol::with_jitter(s.as_ref(), "start-state covariance", Default::default())?;
    let l = chol.l();
    Ok((0..d)
        .map(|i| m[i] + (0..=i).map(|k| l[(i, k)] * z[k]).sum::<f64>())
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_draws_stay_in_their_box_and_repeat_with_the_seed() {
        let d = StartDistribution::Uniform {
            lo: vec![0.5, 0.1],
            hi: vec![0.5, 0.3],
        };
        let mut ys = Vec::new();
        for seed in 0..200 {
            let x = d.sample(seed).unwrap();
            assert_eq!(x[0], 0.5);
            assert!((0.1..=0.3).contains(&x[1]));
            assert_eq!(x, d.sample(seed).unwrap());
            ys.push(x[1]);
        }
        let mean = ys.iter().sum::<f64>() / ys.len() as f64;
        assert!(
            (mean - 0.2).abs() < 0.01,
            "mean of U(0.1, 0.3) draws {mean}"
        );
    }

    #[test]
    fn inverted_bounds_are_an_error_naming_the_entry() {
        let d = StartDistribution::Uniform {
            lo: vec![0.0, 0.3],
            hi: vec![0.0, 0.1],
        };
        let e = d.sample(1).unwrap_err().to_string();
        assert!(e.contains("entry 1"), "{e}");
    }

    #[test]
    fn gaussian_with_zero_covariance_is_its_mean() {
        let d = StartDistribution::Gaussian {
            mean: vec![1.0, 2.0],
            cov: Mat::zeros(2, 2),
        };
        assert_eq!(d.sample(7).unwrap(), vec![1.0, 2.0]);
    }
}
