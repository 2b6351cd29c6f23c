//! Sensors (§5-2): joint encoders, tachometers and a force/torque sensor at the TCP, each with
//! i.i.d. Gaussian noise drawn fresh every control tick from a seeded ChaCha8 stream.

use super::params::SensorParams;
use rand::rngs::ChaCha8Rng;
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};

/// One set of readings.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Reading {
    /// Encoder angles q̃ (rad).
    pub q: [f64; 3],
    /// Tachometer rates q̃̇ (rad/s).
    pub qd: [f64; 3],
    /// F/T force (x, y) the TCP exerts on the environment, base frame (N). The torque channel
    /// reads 0 (point contact).
    pub f: [f64; 2],
}

/// The noisy sensor suite.
#[derive(Debug)]
pub struct Sensors {
    std: SensorParams,
    noise: bool,
    rng: ChaCha8Rng,
}

impl Sensors {
    /// Sensors with noise levels `std`, switched on by `noise`, seeded by `seed`.
    pub fn new(std: SensorParams, noise: bool, seed: u64) -> Sensors {
        Sensors {
            std,
            noise,
            rng: ChaCha8Rng::seed_from_u64(seed),
        }
    }

    /// Reads the true joint state and contact force. Draw order per tick: q1..q3, q̇1..q̇3,
    /// f_x, f_y (fixed, so a seed gives the same stream on every machine).
    pub fn read(&mut self, q: &[f64; 3], qd: &[f64; 3], f: &[f64; 2]) -> Reading {
        if !self.noise {
            return Reading {
                q: *q,
                qd: *qd,
                f: *f,
            };
        }
        let mut n = || -> f64 { StandardNormal.sample(&mut self.rng) };
        let mut r = Reading::default();
        for (r, v) in r.q.iter_mut().zip(q) {
            *r = v + self.std.encoder_std * n();
        }
        for (r, v) in r.qd.iter_mut().zip(qd) {
            *r = v + self.std.tacho_std * n();
        }
        for (r, v) in r.f.iter_mut().zip(f) {
            *r = v + self.std.force_std * n();
        }
        r
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Check (i): 1e5 readings at rest. Each channel's std is within 2 % of its σ, its mean
    /// within 3σ/√n of the truth, and its lag-1 autocorrelation |ρ| < 0.01.
    #[test]
    fn check_i_noise_statistics() {
        let p = SensorParams::default();
        let mut s = Sensors::new(p.clone(), true, 2024);
        let (q, qd, f) = ([0.3, 1.2, -1.5], [0.0; 3], [12.5, 0.0]);
        let n = 100_000;
        let mut ch: Vec<Vec<f64>> = (0..8).map(|_| Vec::with_capacity(n)).collect();
        for _ in 0..n {
            let r = s.read(&q, &qd, &f);
            for i in 0..3 {
                ch[i].push(r.q[i] - q[i]);
                ch[3 + i].push(r.qd[i] - qd[i]);
            }
            for i in 0..2 {
                ch[6 + i].push(r.f[i] - f[i]);
            }
        }
        let sig = [
            p.encoder_std,
            p.encoder_std,
            p.encoder_std,
            p.tacho_std,
            p.tacho_std,
            p.tacho_std,
            p.force_std,
            p.force_std,
        ];
        for (c, sigma) in ch.iter().zip(sig) {
            let nf = n as f64;
            let mean = c.iter().sum::<f64>() / nf;
            let var = c.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (nf - 1.0);
            let sd = var.sqrt();
            let r1 = c
                .windows(2)
                .map(|w| (w[0] - mean) * (w[1] - mean))
                .sum::<f64>()
                / (var * (nf - 1.0));
            eprintln!(
                "(i) std/σ − 1 = {:+.4}, mean/(σ/√n) = {:+.2}, lag-1 ρ = {r1:+.4}",
                sd / sigma - 1.0,
                mean / (sigma / nf.sqrt())
            );
            assert!((sd / sigma - 1.0).abs() < 0.02, "std {sd} vs {sigma}");
            assert!(mean.abs() < 3.0 * sigma / nf.sqrt(), "mean {mean}");
            assert!(r1.abs() < 0.01, "lag-1 {r1}");
        }
        // Off: exact.
        let mut off = Sensors::new(p, false, 1);
        assert_eq!(off.read(&q, &qd, &f).f, f);
    }
}
