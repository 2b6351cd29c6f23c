//! Range and cross-field checks of a parsed config; each error names the file and the first
//! bad key.

use super::{ArmExperiment, ConfigError, PolicyKind, PriorMean, Task};
use vicpilco_env::arm::ControllerKind;
use vicpilco_env::EnvError;

/// Most prediction steps a config may ask for (`horizon`): 1000 s at the thesis's 0.1 s step.
/// The policy gradient keeps every step's moment-matching cache for its reverse sweep, so
/// memory grows with the horizon; a mistyped horizon is refused here rather than found by the
/// allocator (or, for a very long one, never).
pub const MAX_HORIZON: usize = 10_000;
/// Most RBF basis functions (`policy.n_basis`): the policy's moment matching forms N_c × N_c
/// matrices (32 MB at 2000), where the thesis uses at most 75.
pub const MAX_N_BASIS: usize = 2_000;
/// Most L-BFGS correction pairs (`optimiser.memory`); each holds two vectors of all policy
/// parameters, and beyond a few dozen pairs L-BFGS gains nothing.
pub const MAX_LBFGS_MEMORY: usize = 1_000;

struct Check<'a> {
    file: &'a str,
}

impl Check<'_> {
    fn fail(&self, key: &str, message: String) -> ConfigError {
        ConfigError::Invalid {
            file: self.file.to_string(),
            key: key.to_string(),
            message,
        }
    }
    fn positive(&self, key: &str, v: f64) -> Result<(), ConfigError> {
        if v.is_finite() && v > 0.0 {
            Ok(())
        } else {
            Err(self.fail(key, format!("must be a finite number > 0, got {v}")))
        }
    }
    fn finite(&self, key: &str, v: f64) -> Result<(), ConfigError> {
        if v.is_finite() {
            Ok(())
        } else {
            Err(self.fail(key, format!("must be finite, got {v}")))
        }
    }
    fn at_least(&self, key: &str, v: usize, min: usize) -> Result<(), ConfigError> {
        if v >= min {
            Ok(())
        } else {
            Err(self.fail(key, format!("must be ≥ {min}, got {v}")))
        }
    }
    fn at_most(&self, key: &str, v: usize, max: usize) -> Result<(), ConfigError> {
        if v <= max {
            Ok(())
        } else {
            Err(self.fail(key, format!("must be ≤ {max}, got {v}")))
        }
    }
    fn require<T>(&self, key: &str, v: &Option<T>, why: &str) -> Result<(), ConfigError> {
        match v {
            Some(_) => Ok(()),
            None => Err(self.fail(key, format!("is required {why}"))),
        }
    }
    fn forbid<T>(&self, key: &str, v: &Option<T>, why: &str) -> Result<(), ConfigError> {
        match v {
            Some(_) => Err(self.fail(key, format!("does not apply {why}"))),
            None => Ok(()),
        }
    }
}

/// A setting as the TOML spells it (a quoted string for these enums).
fn spelt(v: &impl serde::Serialize) -> String {
    serde_json::to_string(v).unwrap_or_else(|e| e.to_string())
}

impl ArmExperiment {
    /// A `--config` file run under the name of a shipped experiment (`shipped`, that
    /// experiment's own settings) must be a variant of it: the same task, impedance law,
    /// policy family and kind of start, since the name decides which thesis claims the run is
    /// judged by and which runs `acceptance` pools with it. Everything else may differ (what
    /// the probes do). The error names the first key that makes it another experiment.
    pub fn check_variant_of(
        &self,
        name: &str,
        shipped: &ArmExperiment,
        file: &str,
    ) -> Result<(), ConfigError> {
        let c = Check { file };
        let other = |key: &str, this: String, theirs: String| {
            Err(c.fail(
                key,
                format!(
                    "is {this}, but `{name}` has {theirs}: this file is not a variant of \
                     `{name}`; run it under a name of its own"
                ),
            ))
        };
        if self.task != shipped.task {
            return other("task", spelt(&self.task), spelt(&shipped.task));
        }
        if self.controller != shipped.controller {
            return other(
                "controller",
                spelt(&self.controller),
                spelt(&shipped.controller),
            );
        }
        if self.policy.kind != shipped.policy.kind {
            return other(
                "policy.kind",
                spelt(&self.policy.kind),
                spelt(&shipped.policy.kind),
            );
        }
        let variable = |cfg: &ArmExperiment| match cfg.start.y_range {
            Some(_) => "set (a variable start)",
            None => "unset (a fixed start)",
        };
        if self.start.y_range.is_some() != shipped.start.y_range.is_some() {
            return other(
                "start.y_range",
                variable(self).into(),
                variable(shipped).into(),
            );
        }
        Ok(())
    }

    /// Ranges and cross-field rules; the error names the first bad key.
    pub fn validate(&self, file: &str) -> Result<(), ConfigError> {
        let c = Check { file };
        if !matches!(self.controller, ControllerKind::Gic | ControllerKind::Sic) {
            return Err(c.fail("controller", "must be \"gic\" or \"sic\"".into()));
        }
        c.at_least("episodes", self.episodes, 1)?;
        c.at_least("horizon", self.horizon, 1)?;
        c.at_most("horizon", self.horizon, MAX_HORIZON)?;
        c.positive("dt", self.dt)?;
        let p = &self.policy;
        c.positive("policy.k_min", p.k_min)?;
        c.positive("policy.k_max", p.k_max)?;
        if p.k_min >= p.k_max {
            return Err(c.fail(
                "policy.k_min",
                format!("must be below policy.k_max = {}, got {}", p.k_max, p.k_min),
            ));
        }
        c.positive("policy.init_std", p.init_std)?;
        match p.kind {
            PolicyKind::Rbf => {
                c.require("policy.n_basis", &p.n_basis, "for an RBF policy")?;
                c.at_least("policy.n_basis", p.n_basis.unwrap_or(0), 1)?;
                c.at_most("policy.n_basis", p.n_basis.unwrap_or(0), MAX_N_BASIS)?;
                c.require("policy.lengthscales", &p.lengthscales, "for an RBF policy")?;
                for (i, &l) in p.lengthscales.iter().flatten().enumerate() {
                    c.positive(&format!("policy.lengthscales[{i}]"), l)?;
                }
                c.require("policy.snr", &p.snr, "for an RBF policy")?;
                c.positive("policy.snr", p.snr.unwrap_or(0.0))?;
            }
            PolicyKind::Linear => {
                c.forbid("policy.n_basis", &p.n_basis, "to a linear policy")?;
                c.forbid("policy.lengthscales", &p.lengthscales, "to a linear policy")?;
                c.forbid("policy.snr", &p.snr, "to a linear policy")?;
            }
        }
        let cost = &self.cost;
        if cost.position_dims.is_empty() || cost.position_dims.len() > 2 {
            return Err(c.fail(
                "cost.position_dims",
                format!(
                    "must name 1 or 2 of \"x\", \"y\", got {:?}",
                    cost.position_dims
                ),
            ));
        }
        for (i, d) in cost.position_dims.iter().enumerate() {
            if d != "x" && d != "y" || cost.position_dims[..i].contains(d) {
                return Err(c.fail(
                    "cost.position_dims",
                    format!("entries must be distinct \"x\" or \"y\", got {d:?}"),
                ));
            }
        }
        if cost.position_target.len() != cost.position_dims.len() {
            return Err(c.fail(
                "cost.position_target",
                format!(
                    "needs one value per entry of cost.position_dims ({}), got {}",
                    cost.position_dims.len(),
                    cost.position_target.len()
                ),
            ));
        }
        for (i, &v) in cost.position_target.iter().enumerate() {
            c.finite(&format!("cost.position_target[{i}]"), v)?;
        }
        c.positive("cost.position_width", cost.position_width)?;
        c.positive("cost.force_width", cost.force_width)?;
        if let Some(far) = cost.force_width_far {
            c.positive("cost.force_width_far", far)?;
            if far <= cost.force_width {
                return Err(c.fail(
                    "cost.force_width_far",
                    format!(
                        "must exceed cost.force_width ({}), got {far}",
                        cost.force_width
                    ),
                ));
            }
        }
        c.finite("cost.w_std", cost.w_std)?;
        if !(cost.w_energy.is_finite() && cost.w_energy >= 0.0) {
            return Err(c.fail(
                "cost.w_energy",
                format!("must be finite and ≥ 0, got {}", cost.w_energy),
            ));
        }
        let o = &self.optimiser;
        c.at_least("optimiser.length", o.length as usize, 1)?;
        c.at_least("optimiser.mfepls", o.mfepls as usize, 1)?;
        c.at_least("optimiser.memory", o.memory, 1)?;
        c.at_most("optimiser.memory", o.memory, MAX_LBFGS_MEMORY)?;
        if let Some(msr) = o.msr {
            c.positive("optimiser.msr", msr)?;
        }
        if !o.scale_params || p.kind != PolicyKind::Rbf {
            c.forbid(
                "optimiser.centre_scale",
                &o.centre_scale,
                "without an RBF policy and optimiser.scale_params = true",
            )?;
        }
        let g = &self.gp;
        c.at_least("gp.sparse_threshold", g.sparse_threshold, 1)?;
        c.at_least("gp.n_inducing", g.n_inducing, 1)?;
        c.at_least("gp.hyper_points", g.hyper_points, 1)?;
        c.at_least("gp.line_searches", g.line_searches as usize, 1)?;
        let d = self.gp_input_dim();
        for (key, bounds) in [
            ("gp.lengthscale_floor", &g.lengthscale_floor),
            ("gp.lengthscale_ceiling", &g.lengthscale_ceiling),
        ] {
            let Some(bounds) = bounds else { continue };
            if bounds.len() != d {
                return Err(c.fail(
                    key,
                    format!("needs one value per GP input ({d}), got {}", bounds.len()),
                ));
            }
            for (i, &b) in bounds.iter().enumerate() {
                if !(b.is_finite() && b >= 0.0) {
                    return Err(c.fail(
                        &format!("{key}[{i}]"),
                        format!("must be finite and ≥ 0, got {b}"),
                    ));
                }
            }
        }
        if let (Some(floor), Some(ceiling)) = (&g.lengthscale_floor, &g.lengthscale_ceiling) {
            for (i, (&f, &u)) in floor.iter().zip(ceiling).enumerate() {
                if f > 0.0 && u > 0.0 && f >= u {
                    return Err(c.fail(
                        &format!("gp.lengthscale_ceiling[{i}]"),
                        format!("must be above gp.lengthscale_floor[{i}] = {f}, got {u}"),
                    ));
                }
            }
        }
        let s = &self.start;
        for i in 0..6 {
            c.finite(&format!("start.state[{i}]"), s.state[i])?;
            c.positive(&format!("start.prediction_std[{i}]"), s.prediction_std[i])?;
        }
        if let Some([lo, hi]) = s.y_range {
            if !(lo.is_finite() && hi.is_finite() && lo <= hi) {
                return Err(c.fail(
                    "start.y_range",
                    format!("must be finite with lower ≤ upper, got [{lo}, {hi}]"),
                ));
            }
        }
        if let Some(ys) = &s.prediction_y {
            if ys.is_empty() {
                return Err(c.fail("start.prediction_y", "must not be empty".into()));
            }
            for (i, &y) in ys.iter().enumerate() {
                c.finite(&format!("start.prediction_y[{i}]"), y)?;
            }
        }
        c.positive("initial.ou_theta", self.initial.ou_theta)?;
        match self.task {
            Task::Vil => {
                c.forbid("vilta", &self.vilta, "to a VIL run")?;
                c.forbid("policy.delta_max", &p.delta_max, "to a VIL run")?;
                c.forbid("initial.scan", &self.initial.scan, "to a VIL run")?;
                if p.init_from_scan {
                    return Err(c.fail(
                        "policy.init_from_scan",
                        "sets the reference increments of a VILTA run, not a VIL one".into(),
                    ));
                }
                c.forbid(
                    "initial.scan_jitter",
                    &self.initial.scan_jitter,
                    "to a VIL run",
                )?;
            }
            Task::Vilta => {
                c.require("vilta", &self.vilta, "for a VILTA run")?;
                if self.gp.prior_mean == PriorMean::Reference {
                    return Err(c.fail(
                        "gp.prior_mean",
                        "must be \"zero\" for a VILTA run (it has no given reference)".into(),
                    ));
                }
                c.require("policy.delta_max", &p.delta_max, "for a VILTA run")?;
                c.positive("policy.delta_max", p.delta_max.unwrap_or(0.0))?;
                c.require("initial.scan", &self.initial.scan, "for a VILTA run")?;
                let scan = self.initial.scan.as_deref().unwrap_or(&[]);
                c.at_least("initial.scan", scan.len(), 2)?;
                for (i, w) in scan.windows(2).enumerate() {
                    if w[1][0].partial_cmp(&w[0][0]) != Some(std::cmp::Ordering::Greater) {
                        return Err(c.fail(
                            "initial.scan",
                            format!("times must increase: entry {} at t = {}", i + 1, w[1][0]),
                        ));
                    }
                }
                if p.init_from_scan && p.kind != PolicyKind::Rbf {
                    return Err(c.fail(
                        "policy.init_from_scan",
                        "needs an RBF policy, whose centres lie on the scan".into(),
                    ));
                }
                if let Some(j) = &self.initial.scan_jitter {
                    c.positive("initial.scan_jitter.std", j.std)?;
                    c.positive("initial.scan_jitter.theta", j.theta)?;
                }
                if let Some(v) = &self.vilta {
                    c.finite("vilta.geometry_shift_x", v.geometry_shift_x)?;
                    c.positive("vilta.delta_tick", v.delta_tick)?;
                    c.at_least("vilta.rollouts_per_iteration", v.rollouts_per_iteration, 1)?;
                    if let Some(d) = v.max_lead {
                        c.positive("vilta.max_lead", d)?;
                    }
                    if let Some(l) = &v.lead_state {
                        c.positive("vilta.lead_state.prediction_std", l.prediction_std)?;
                        let key = "vilta.lead_state.policy_lengthscale";
                        match p.kind {
                            PolicyKind::Rbf => {
                                c.require(key, &l.policy_lengthscale, "for an RBF policy")?;
                                c.positive(key, l.policy_lengthscale.unwrap_or(0.0))?;
                            }
                            PolicyKind::Linear => {
                                c.forbid(key, &l.policy_lengthscale, "to a linear policy")?;
                            }
                        }
                        if let Some(k) = l.force_prior_stiffness {
                            c.positive("vilta.lead_state.force_prior_stiffness", k)?;
                        }
                    }
                    if !v.max_lead_in_search && v.max_lead.is_none() {
                        return Err(c.fail(
                            "vilta.max_lead_in_search",
                            "exempts the search roll-out from vilta.max_lead, which is not set"
                                .into(),
                        ));
                    }
                    if !v.final_policy.is_last() && v.evaluation_starts == 0 {
                        return Err(c.fail(
                            "vilta.final_policy",
                            "chooses the policy the fresh starts evaluate, and \
                             vilta.evaluation_starts is 0"
                                .into(),
                        ));
                    }
                }
            }
        }
        self.check_simulator(&c)
    }

    /// The simulator's own rules on what this config sets (the step a whole number of control
    /// periods, …), named by this file's keys.
    fn check_simulator(&self, c: &Check<'_>) -> Result<(), ConfigError> {
        match crate::arm::arm_config(self).validate() {
            Ok(()) => Ok(()),
            Err(EnvError::InvalidConfig {
                field,
                value,
                requirement,
            }) => {
                let key = match field.as_str() {
                    "step_dt" => "dt".to_string(),
                    "horizon" => "horizon".to_string(),
                    "mode.delta_max" => "policy.delta_max".to_string(),
                    "mode.delta_tick" => "vilta.delta_tick".to_string(),
                    "mode.max_lead" => "vilta.max_lead".to_string(),
                    other => format!("(simulator) {other}"),
                };
                Err(c.fail(&key, format!("must be {requirement}, got {value}")))
            }
            Err(e) => Err(c.fail("(simulator)", e.to_string())),
        }
    }
}
