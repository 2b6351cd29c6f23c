//! Reference trajectories x_v(t) = (x, y, φ) with velocity and acceleration (§5-1-1).
//!
//! The VIL plan is quintic minimum-jerk segments, rest to rest, between via points:
//! x(τ) = a + (b − a)(10τ³ − 15τ⁴ + 6τ⁵), τ = (t − t_i)/(t_{i+1} − t_i), which minimises
//! ∫ x⃛ᵀx⃛ dt (the thesis prints a garbled integrand). Peak speed 1.875·|b − a|/T at τ = ½.

use crate::EnvError;
use serde::{Deserialize, Serialize};

/// Reference pose, velocity and acceleration at one instant.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RefPoint {
    /// x_v (m, m, rad).
    pub x: [f64; 3],
    /// ẋ_v.
    pub xd: [f64; 3],
    /// ẍ_v.
    pub xdd: [f64; 3],
}

/// Via points P_i reached at times t_i, rest to rest; held before the first and after the last.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ViaPlan {
    /// Via points (x, y, φ).
    pub points: Vec<[f64; 3]>,
    /// Strictly increasing times (s), one per point.
    pub times: Vec<f64>,
}

impl ViaPlan {
    /// The thesis's plan (§5-2-2, Fig. 5-3): P0 = (0.50, 0, 0) start; P1 = (0.70, 0, 0), 50 mm
    /// behind the face; P2 = (0.70, 0.20, 0), the hole centre; P3 = (0.80, 0.20, 0), 50 mm behind
    /// the end wall (the printed x_hole + l_hole/2 = 0.75 cannot beat the 9 N spring). Times
    /// 0, 3, 5, 8 s are **ours**; held to the end of the episode.
    pub fn thesis() -> ViaPlan {
        ViaPlan {
            points: vec![
                [0.50, 0.0, 0.0],
                [0.70, 0.0, 0.0],
                [0.70, 0.20, 0.0],
                [0.80, 0.20, 0.0],
            ],
            times: vec![0.0, 3.0, 5.0, 8.0],
        }
    }

    /// Reference at time t.
    pub fn eval(&self, t: f64) -> RefPoint {
        let n = self.points.len();
        if t <= self.times[0] {
            return hold(self.points[0]);
        }
        if t >= self.times[n - 1] {
            return hold(self.points[n - 1]);
        }
        // segment i with times[i] ≤ t < times[i+1]
        let i = self.times.partition_point(|&ti| ti <= t) - 1;
        let (a, b) = (self.points[i], self.points[i + 1]);
        let dur = self.times[i + 1] - self.times[i];
        let tau = (t - self.times[i]) / dur;
        let (s, sd, sdd) = min_jerk(tau);
        let mut r = RefPoint::default();
        for k in 0..3 {
            let d = b[k] - a[k];
            r.x[k] = a[k] + d * s;
            r.xd[k] = d * sd / dur;
            r.xdd[k] = d * sdd / (dur * dur);
        }
        r
    }

    fn validate(&self) -> Result<(), EnvError> {
        if self.points.is_empty() || self.points.len() != self.times.len() {
            return Err(EnvError::config(
                "reference.times",
                format!(
                    "{} times for {} points",
                    self.times.len(),
                    self.points.len()
                ),
                "one time per point, at least one point",
            ));
        }
        for (i, p) in self.points.iter().enumerate() {
            for (k, v) in p.iter().enumerate() {
                crate::error::finite(&format!("reference.points[{i}][{k}]"), *v)?;
            }
        }
        for i in 0..self.times.len() {
            crate::error::finite(&format!("reference.times[{i}]"), self.times[i])?;
            if i > 0 && self.times[i] <= self.times[i - 1] {
                return Err(EnvError::config(
                    format!("reference.times[{i}]"),
                    self.times[i],
                    format!("> reference.times[{}] = {}", i - 1, self.times[i - 1]),
                ));
            }
        }
        Ok(())
    }
}

/// Normalised quintic s(τ), ds/dτ, d²s/dτ² on τ ∈ [0, 1].
#[inline]
pub fn min_jerk(tau: f64) -> (f64, f64, f64) {
    let t2 = tau * tau;
    let t3 = t2 * tau;
    (
        t3 * (10.0 - 15.0 * tau + 6.0 * t2),
        30.0 * t2 * (1.0 - 2.0 * tau + t2),
        60.0 * tau * (1.0 - 3.0 * tau + 2.0 * t2),
    )
}

fn hold(p: [f64; 3]) -> RefPoint {
    RefPoint {
        x: p,
        ..RefPoint::default()
    }
}

/// The VIL reference: the thesis plan, or simpler shapes used by the checks.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum ReferenceSpec {
    /// Minimum-jerk via points.
    MinJerk(ViaPlan),
    /// A constant pose (a step when it differs from the start pose).
    Fixed([f64; 3]),
    /// Linear ramp from `from` to `to` between `t0` and `t1`, held outside.
    Ramp {
        /// Pose before t0.
        from: [f64; 3],
        /// Pose after t1.
        to: [f64; 3],
        /// Ramp start (s).
        t0: f64,
        /// Ramp end (s).
        t1: f64,
    },
}

impl ReferenceSpec {
    /// The thesis plan [`ViaPlan::thesis`].
    pub fn thesis() -> ReferenceSpec {
        ReferenceSpec::MinJerk(ViaPlan::thesis())
    }

    /// Reference at time t.
    pub fn eval(&self, t: f64) -> RefPoint {
        match self {
            ReferenceSpec::MinJerk(p) => p.eval(t),
            ReferenceSpec::Fixed(x) => hold(*x),
            ReferenceSpec::Ramp { from, to, t0, t1 } => {
                if t <= *t0 {
                    hold(*from)
                } else if t >= *t1 {
                    hold(*to)
                } else {
                    let f = (t - t0) / (t1 - t0);
                    RefPoint {
                        x: std::array::from_fn(|k| from[k] + (to[k] - from[k]) * f),
                        xd: std::array::from_fn(|k| (to[k] - from[k]) / (t1 - t0)),
                        xdd: [0.0; 3],
                    }
                }
            }
        }
    }

    pub(crate) fn validate(&self) -> Result<(), EnvError> {
        match self {
            ReferenceSpec::MinJerk(p) => p.validate(),
            ReferenceSpec::Fixed(x) => {
                for (k, v) in x.iter().enumerate() {
                    crate::error::finite(&format!("reference.fixed[{k}]"), *v)?;
                }
                Ok(())
            }
            ReferenceSpec::Ramp { from, to, t0, t1 } => {
                for k in 0..3 {
                    crate::error::finite(&format!("reference.from[{k}]"), from[k])?;
                    crate::error::finite(&format!("reference.to[{k}]"), to[k])?;
                }
                crate::error::finite("reference.t0", *t0)?;
                if !(t1.is_finite() && t1 > t0) {
                    return Err(EnvError::config("reference.t1", t1, format!("> t0 = {t0}")));
                }
                Ok(())
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Check (j), plan part: via points hit with zero velocity and acceleration; the peak speed
    /// of each segment is 1.875·|b − a|/T.
    #[test]
    fn check_j_via_points_and_peak_speed() {
        let p = ViaPlan::thesis();
        for (i, &t) in p.times.iter().enumerate() {
            for eps in [0.0, 1e-13] {
                for tt in [t - eps, t + eps] {
                    let r = p.eval(tt);
                    for k in 0..3 {
                        assert!((r.x[k] - p.points[i][k]).abs() <= 1e-12, "P{i} at t = {tt}");
                        assert!(r.xd[k].abs() <= 1e-12 && r.xdd[k].abs() <= 1e-10);
                    }
                }
            }
        }
        for i in 0..3 {
            let (a, b) = (p.points[i], p.points[i + 1]);
            let dur = p.times[i + 1] - p.times[i];
            let dist = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
            let mut peak: f64 = 0.0;
            for s in 0..=10_000 {
                let r = p.eval(p.times[i] + dur * s as f64 / 10_000.0);
                peak = peak.max((r.xd[0].powi(2) + r.xd[1].powi(2)).sqrt());
            }
            assert!(
                (peak - 1.875 * dist / dur).abs() < 1e-9,
                "segment {i}: {peak}"
            );
        }
        // velocity is the derivative of position
        let (t, e) = (4.2, 1e-6);
        let (rp, rm, r) = (p.eval(t + e), p.eval(t - e), p.eval(t));
        assert!(((rp.x[1] - rm.x[1]) / (2.0 * e) - r.xd[1]).abs() < 1e-8);
        assert!(((rp.xd[1] - rm.xd[1]) / (2.0 * e) - r.xdd[1]).abs() < 1e-7);
    }
}
