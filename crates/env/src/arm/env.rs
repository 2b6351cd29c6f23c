//! The arm as an [`Environment`]: VIL (a = (k_x, k_y)) or VILTA (a = (k_x, k_y, Δx_ref,
//! Δy_ref)), observation s = (x, y, ẋ, ẏ, f_x, f_y) from the noisy readings, plus for VILTA
//! with `lead_state` the reference's lead (x_v − x, y_v − y).

use super::kinematics::ik;
use super::params::{ActionMode, ArmConfig, OnDivergence, ReferenceOrigin};
use super::plan::RefPoint;
use super::sensors::Reading;
use super::sim::{ArmSim, TickStatus};
use super::trace::TickRecord;
use super::{impedance, mat3::V3};
use crate::{EnvError, Environment, Step, StepInfo};
use std::collections::BTreeMap;

/// Names of the observed state entries.
pub const STATE_NAMES: [&str; 6] = ["x", "y", "xd", "yd", "fx", "fy"];
/// Names of the VILTA reference-lead entries that follow [`STATE_NAMES`] with `lead_state`.
pub const LEAD_NAMES: [&str; 2] = ["lead_x", "lead_y"];

/// Deepest start inside a surface that `reset` accepts (m); deeper starts are an error.
pub const START_MAX_PENETRATION: f64 = 1e-3;

/// Interval (s) at which [`StepInfo::path`] samples the TCP within a step. At the VILTA
/// reference's top speed (0.5 m/s) the chord between samples is at most 5 mm, the hole's
/// half-width, so a drawn path does not cut through the wall's corners; ten samples per 0.1 s
/// step add ≈ 40 kB to a roll-out's record.
pub const PATH_SAMPLE_INTERVAL: f64 = 0.01;

/// The planar arm peg-in-hole environment.
#[derive(Debug)]
pub struct ArmEnv {
    cfg: ArmConfig,
    sim: Option<ArmSim>,
    steps: usize,
    done: bool,
    /// VILTA: the integrated reference (x_v, y_v, φ_v), its commanded velocity, and the
    /// velocity it moves at this tick (the commanded one unless `max_lead` slows it).
    vilta_x: V3,
    vilta_xd: V3,
    vilta_xd_now: V3,
}

impl ArmEnv {
    /// A new environment; validates `cfg`. Call [`Environment::reset`] before stepping.
    pub fn new(cfg: ArmConfig) -> Result<ArmEnv, EnvError> {
        cfg.validate()?;
        Ok(ArmEnv {
            cfg,
            sim: None,
            steps: 0,
            done: false,
            vilta_x: [0.0; 3],
            vilta_xd: [0.0; 3],
            vilta_xd_now: [0.0; 3],
        })
    }

    /// The configuration.
    pub fn config(&self) -> &ArmConfig {
        &self.cfg
    }

    /// The running simulator (after `reset`).
    pub fn sim(&self) -> Option<&ArmSim> {
        self.sim.as_ref()
    }

    /// The per-tick trace of the current episode (empty unless `record_trace`).
    pub fn trace(&self) -> &[TickRecord] {
        self.sim.as_ref().map(|s| s.trace()).unwrap_or(&[])
    }

    /// Moves the per-tick trace out.
    pub fn take_trace(&mut self) -> Vec<TickRecord> {
        self.sim
            .as_mut()
            .map(|s| s.take_trace())
            .unwrap_or_default()
    }

    /// Whether the TCP is inserted now: in the hole and within `insert_tolerance` of the end
    /// wall (true state).
    pub fn inserted(&self) -> bool {
        self.sim.as_ref().is_some_and(|s| {
            let x = s.plant().tcp(s.state()).x[0];
            s.in_hole() && x >= self.cfg.geometry.end_x() - self.cfg.insert_tolerance
        })
    }

    fn stiffness_names(&self) -> [&'static str; 4] {
        ["k_x", "k_y", "dx_ref", "dy_ref"]
    }

    /// Checks an action; never clips.
    fn check_action(&self, a: &[f64]) -> Result<(), EnvError> {
        if a.len() != self.action_dim() {
            return Err(EnvError::Dimension {
                what: "action",
                got: a.len(),
                expected: self.action_dim(),
            });
        }
        let names = self.stiffness_names();
        for i in 0..2 {
            if !(a[i].is_finite() && a[i] > 0.0) {
                return Err(EnvError::InvalidAction {
                    kind: "stiffness",
                    field: names[i].into(),
                    value: a[i],
                    requirement: "> 0 and finite".into(),
                });
            }
        }
        if let ActionMode::Vilta { delta_max, .. } = self.cfg.mode {
            for i in 2..4 {
                if !(a[i].is_finite() && a[i].abs() <= delta_max) {
                    return Err(EnvError::InvalidAction {
                        kind: "reference increment",
                        field: names[i].into(),
                        value: a[i],
                        requirement: format!("within ±{delta_max} m per tick"),
                    });
                }
            }
        }
        Ok(())
    }

    fn observation(&self, r: &Reading) -> Vec<f64> {
        let sim = self.sim.as_ref().expect("called after reset");
        let est = impedance::task_state(sim.model(), &r.q, &r.qd);
        let mut obs = vec![est.x[0], est.x[1], est.xd[0], est.xd[1], r.f[0], r.f[1]];
        self.push_lead(&mut obs, [est.x[0], est.x[1]]);
        obs
    }

    fn lead_state(&self) -> bool {
        matches!(
            self.cfg.mode,
            ActionMode::Vilta {
                lead_state: true,
                ..
            }
        )
    }

    /// Appends the reference's lead over `position` when the state carries it.
    fn push_lead(&self, state: &mut Vec<f64>, position: [f64; 2]) {
        if self.lead_state() {
            state.extend([self.vilta_x[0] - position[0], self.vilta_x[1] - position[1]]);
        }
    }

    fn reference_at(&self, t: f64) -> RefPoint {
        match self.cfg.mode {
            ActionMode::Vil => self.cfg.reference.eval(t),
            ActionMode::Vilta { .. } => RefPoint {
                x: self.vilta_x,
                xd: self.vilta_xd_now,
                xdd: [0.0; 3],
            },
        }
    }

    /// The TCP position as the controller estimates it from its latest reading.
    fn measured_position(&self) -> [f64; 2] {
        let sim = self.sim.as_ref().expect("called after reset");
        let r = sim.reading();
        let est = impedance::task_state(sim.model(), &r.q, &r.qd);
        [est.x[0], est.x[1]]
    }

    /// VILTA with `max_lead` d: the commanded velocity, slowed on each axis where it pushes
    /// the lead ℓ = x_v − x further out, by the factor max(0, 1 − |ℓ|/d). The lead then
    /// approaches d smoothly: switching the reference velocity between v and 0 at a hard
    /// limit would switch the damping force B_d · v (≈ 220 N at v_max) on and off every tick
    /// and rattle the peg against a wall.
    fn slowed_reference_velocity(&self, max_lead: f64) -> V3 {
        let x = self.measured_position();
        let mut xd = self.vilta_xd;
        for i in 0..2 {
            let lead = self.vilta_x[i] - x[i];
            if xd[i] * lead > 0.0 {
                xd[i] *= (1.0 - lead.abs() / max_lead).max(0.0);
            }
        }
        xd
    }

    /// VILTA with `max_lead`: a TCP pushed back from its reference (a bounce, a surface) drags
    /// x_v along, so the lead never exceeds `max_lead`.
    fn drag_reference(&mut self, max_lead: f64) {
        let x = self.measured_position();
        for i in 0..2 {
            let lead = self.vilta_x[i] - x[i];
            if lead.abs() > max_lead {
                self.vilta_x[i] = x[i] + max_lead.copysign(lead);
            }
        }
    }
}

impl Environment for ArmEnv {
    fn state_dim(&self) -> usize {
        STATE_NAMES.len()
            + if self.lead_state() {
                LEAD_NAMES.len()
            } else {
                0
            }
    }
    fn action_dim(&self) -> usize {
        match self.cfg.mode {
            ActionMode::Vil => 2,
            ActionMode::Vilta { .. } => 4,
        }
    }
    fn dt(&self) -> f64 {
        self.cfg.step_dt
    }
    fn horizon(&self) -> usize {
        self.cfg.horizon
    }
    fn state_names(&self) -> Vec<String> {
        STATE_NAMES
            .iter()
            .chain(LEAD_NAMES.iter().filter(|_| self.lead_state()))
            .map(|s| s.to_string())
            .collect()
    }
    fn action_names(&self) -> Vec<String> {
        self.stiffness_names()[..self.action_dim()]
            .iter()
            .map(|s| s.to_string())
            .collect()
    }

    /// Places the TCP at (`start[0]`, `start[1]`) with φ = 0 by inverse kinematics (elbow q2 > 0),
    /// at rest. The other start entries (velocities, forces) must be finite and are ignored:
    /// the arm always starts at rest and contact forces follow from the pose. With
    /// `lead_state`, the reference starts `(start[6], start[7])` ahead of the start pose.
    fn reset(&mut self, start: &[f64], seed: u64) -> Result<Vec<f64>, EnvError> {
        if start.len() != self.state_dim() {
            return Err(EnvError::Dimension {
                what: "start state",
                got: start.len(),
                expected: self.state_dim(),
            });
        }
        for (v, name) in start.iter().zip(self.state_names()) {
            if !v.is_finite() {
                return Err(EnvError::NonFiniteStart {
                    field: name,
                    value: *v,
                });
            }
        }
        let l = self.cfg.arm.length;
        let min_sin_q2 = self.cfg.singular_det / (l[0] * l[1]);
        let pose = [start[0], start[1], 0.0];
        let q0 = ik(&l, &pose, min_sin_q2).map_err(|reason| EnvError::OutOfReach {
            x: start[0],
            y: start[1],
            reason,
        })?;
        let sim = ArmSim::new(&self.cfg, q0, seed)?;
        let c = sim.contact();
        if c.w[0].abs().max(c.w[1].abs()) > self.cfg.contact.k_env * START_MAX_PENETRATION {
            return Err(EnvError::OutOfReach {
                x: start[0],
                y: start[1],
                reason: format!(
                    "it lies inside a surface (contact force {:.1} N; at most {} m of penetration is allowed)",
                    c.w[0].hypot(c.w[1]),
                    START_MAX_PENETRATION
                ),
            });
        }
        let r = *sim.reading();
        self.sim = Some(sim);
        self.steps = 0;
        self.done = false;
        self.vilta_x = pose;
        if self.lead_state() {
            self.vilta_x[0] += start[6];
            self.vilta_x[1] += start[7];
        }
        self.vilta_xd = [0.0; 3];
        self.vilta_xd_now = [0.0; 3];
        Ok(self.observation(&r))
    }

    fn step(&mut self, action: &[f64]) -> Result<Step, EnvError> {
        let Some(sim) = self.sim.as_ref() else {
            return Err(EnvError::NotReset);
        };
        if self.done {
            return Err(EnvError::EpisodeOver { t: sim.t() });
        }
        self.check_action(action)?;
        let k = [action[0], action[1]];
        if let ActionMode::Vilta {
            delta_tick, origin, ..
        } = self.cfg.mode
        {
            self.vilta_xd = [action[2] / delta_tick, action[3] / delta_tick, 0.0];
            if origin == ReferenceOrigin::Measured {
                // From the position the policy observed.
                let obs = self.observation(sim.reading());
                self.vilta_x[..2].copy_from_slice(&obs[..2]);
            }
        }
        let ticks = self.cfg.ticks_per_step();
        let mut singular = false;
        let mut diverged = false;
        let mut stopped_early = None;
        let mut max_f: f64 = 0.0;
        let ticks_per_sample = self.cfg.ticks_per_path_sample();
        let mut path = Vec::with_capacity(ticks / ticks_per_sample + 1);
        for tick in 0..ticks {
            let sim = self.sim.as_ref().expect("checked above");
            let t = sim.t();
            let dt = sim.tick_dt();
            if let ActionMode::Vilta { max_lead, .. } = self.cfg.mode {
                self.vilta_xd_now = match max_lead {
                    Some(d) => self.slowed_reference_velocity(d),
                    None => self.vilta_xd,
                };
            }
            let refp = self.reference_at(t);
            let sim = self.sim.as_mut().expect("checked above");
            match sim.tick(k, &refp) {
                Ok(TickStatus::Ok) => {}
                Ok(TickStatus::Singular) => {
                    singular = true;
                    stopped_early = Some(format!(
                        "singular Jacobian at t = {t:.4} s: |det J| below singular_det = {}",
                        self.cfg.singular_det
                    ));
                    break;
                }
                Err(e @ EnvError::Diverged { .. })
                    if self.cfg.on_divergence == OnDivergence::EndEpisode =>
                {
                    diverged = true;
                    stopped_early = Some(e.to_string());
                    break;
                }
                Err(e) => {
                    // The ticks already run stay applied, so the arm is mid-step: only a
                    // reset may continue.
                    self.done = true;
                    return Err(e);
                }
            }
            let w = sim.contact().w;
            max_f = max_f.max(w[0].hypot(w[1]));
            if (tick + 1) % ticks_per_sample == 0 && tick + 1 < ticks {
                let tcp = sim.plant().tcp(sim.state());
                path.push([tcp.x[0], tcp.x[1]]);
            }
            if let ActionMode::Vilta { max_lead, .. } = self.cfg.mode {
                for i in 0..2 {
                    self.vilta_x[i] += self.vilta_xd_now[i] * dt;
                }
                if let Some(d) = max_lead {
                    self.drag_reference(d);
                }
            }
        }
        self.steps += 1;
        self.done = stopped_early.is_some() || self.steps >= self.cfg.horizon;
        let sim = self.sim.as_ref().expect("checked above");
        let r = *sim.reading();
        let t = sim.t();
        let tcp = sim.plant().tcp(sim.state());
        let c = sim.contact();
        let refp = self.reference_at(t);
        let s = sim.state();
        let mut flags = BTreeMap::new();
        flags.insert("contact".to_string(), c.any());
        flags.insert("face".to_string(), c.face);
        flags.insert("end_wall".to_string(), c.end);
        flags.insert("side_wall".to_string(), c.side);
        flags.insert("spring".to_string(), c.spring);
        flags.insert("in_hole".to_string(), sim.in_hole());
        flags.insert("singular".to_string(), singular);
        flags.insert("diverged".to_string(), diverged);
        flags.insert("inserted".to_string(), self.inserted());
        let mut values = BTreeMap::new();
        for i in 0..3 {
            values.insert(format!("q{}", i + 1), s[i]);
            values.insert(format!("qd{}", i + 1), s[3 + i]);
        }
        values.insert("phi".to_string(), tcp.x[2]);
        values.insert("max_abs_f".to_string(), max_f);
        path.push([tcp.x[0], tcp.x[1]]);
        let mut true_state = vec![tcp.x[0], tcp.x[1], tcp.xd[0], tcp.xd[1], c.w[0], c.w[1]];
        self.push_lead(&mut true_state, [tcp.x[0], tcp.x[1]]);
        Ok(Step {
            observation: self.observation(&r),
            info: StepInfo {
                t,
                true_state,
                reference: Some(vec![refp.x[0], refp.x[1], refp.xd[0], refp.xd[1]]),
                flags,
                values,
                stopped_early,
                path,
            },
            done: self.done,
        })
    }
}
