//! Every number of the arm experiment, as documented configuration with defaults.
//!
//! Values from the thesis carry their section; values marked **ours** are not in the thesis
//! (issue 5 fixes them) and are listed in `crates/env/README.md`.

use super::plan::ReferenceSpec;
use crate::error::{finite, non_negative, positive, Num};
use crate::EnvError;
use serde::{Deserialize, Serialize};
use std::fmt;
use std::str::FromStr;

/// Inertial and kinematic parameters of the planar 3R arm (§5-2). Index i is link/joint i+1.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ArmParams {
    /// Link lengths l_i (m). Thesis: 0.40.
    pub length: [f64; 3],
    /// Link masses m_i (kg). Thesis: 1.
    pub mass: [f64; 3],
    /// Distance from joint i to the centre of mass of link i (m). **Ours**: l_i/2.
    pub com: [f64; 3],
    /// Link inertia about its centre of mass (kg·m²). **Ours**: m l²/12 (uniform rod).
    pub inertia: [f64; 3],
    /// Motor rotor inertia per joint, added to M's diagonal (kg·m²). Thesis: 1e-4 (printed in
    /// "Nm/rad"); gear ratio 1 is **ours**.
    pub motor_inertia: [f64; 3],
    /// Viscous joint friction (N·m·s/rad). Thesis: "small"; 0.01 is **ours**. Not modelled by
    /// the controllers.
    pub joint_friction: [f64; 3],
}

impl Default for ArmParams {
    fn default() -> Self {
        let l = 0.40;
        let m = 1.0;
        ArmParams {
            length: [l; 3],
            mass: [m; 3],
            com: [l / 2.0; 3],
            inertia: [m * l * l / 12.0; 3],
            motor_inertia: [1e-4; 3],
            joint_friction: [0.01; 3],
        }
    }
}

impl ArmParams {
    /// The same arm with masses, link inertias and motor inertias multiplied by `factor` (the
    /// plant/model mismatch of §5-2: "perturbed by 15%"). Lengths, centres of mass and
    /// friction are unchanged.
    pub fn scaled_inertia(&self, factor: f64) -> ArmParams {
        let s = |a: [f64; 3]| a.map(|v| v * factor);
        ArmParams {
            mass: s(self.mass),
            inertia: s(self.inertia),
            motor_inertia: s(self.motor_inertia),
            ..self.clone()
        }
    }

    /// Checks every entry; `prefix` is the field path used in error messages.
    pub fn validate(&self, prefix: &str) -> Result<(), EnvError> {
        for i in 0..3 {
            positive(&format!("{prefix}.length[{i}]"), self.length[i])?;
            positive(&format!("{prefix}.mass[{i}]"), self.mass[i])?;
            non_negative(&format!("{prefix}.inertia[{i}]"), self.inertia[i])?;
            non_negative(
                &format!("{prefix}.motor_inertia[{i}]"),
                self.motor_inertia[i],
            )?;
            non_negative(
                &format!("{prefix}.joint_friction[{i}]"),
                self.joint_friction[i],
            )?;
            let c = self.com[i];
            if !(c.is_finite() && c >= 0.0 && c <= self.length[i]) {
                return Err(EnvError::config(
                    format!("{prefix}.com[{i}]"),
                    c,
                    format!("in [0, length[{i}] = {}]", self.length[i]),
                ));
            }
            // Joint i alone turning moves link i's centre by com[i] per radian and turns the
            // link and its motor, so with all three zero that motion costs no kinetic energy
            // and the mass matrix is singular (every other link contributes ≥ 0).
            if self.inertia[i] + self.mass[i] * c * c + self.motor_inertia[i] == 0.0 {
                return Err(EnvError::config(
                    format!("{prefix}.inertia[{i}]"),
                    self.inertia[i],
                    format!(
                        "> 0 while com[{i}] and motor_inertia[{i}] are 0 (the link must resist \
                         its joint's rotation, or the mass matrix is singular)"
                    ),
                ));
            }
        }
        Ok(())
    }
}

/// Penalty contact of every surface (§5-2-1).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ContactParams {
    /// Surface stiffness K_env (N/m). Thesis: 1e5.
    pub k_env: f64,
    /// Surface damping (N·s/m), applied only while the TCP moves into the surface. Thesis:
    /// "low"; 50 is **ours**.
    pub b_env: f64,
    /// Viscous tangential friction C_f (N·s/m) while touching a surface. Thesis: 0.5.
    pub friction: f64,
}

impl Default for ContactParams {
    fn default() -> Self {
        ContactParams {
            k_env: 1e5,
            b_env: 50.0,
            friction: 0.5,
        }
    }
}

/// Wall, hole and insertion spring (§5-2-1, §5-2-2). Everything is placed relative to
/// `hole_center`, so [`Geometry::shifted`] moves the whole scene (the VILTA experiment shifts
/// it by +0.05 m in x).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Geometry {
    /// Middle of the hole channel (x, y) (m). Thesis: (0.70, 0.20).
    pub hole_center: [f64; 2],
    /// Half-width of the channel = clearance each side of the point peg (m). Thesis: 0.005.
    pub hole_radius: f64,
    /// Channel depth (m). Thesis: 0.10. The wall face is at `hole_center.x − depth/2`
    /// (0.65, thesis), the end wall at `hole_center.x + depth/2` (0.75).
    pub hole_depth: f64,
    /// Insertion spring stiffness (N/m). Thesis: 300.
    pub k_insert: f64,
    /// Where the spring catches, measured from the hole centre in +x (m). Thesis: "just after
    /// the centre"; 0 is **ours**.
    pub spring_catch_offset: f64,
    /// Where the spring releases, measured back from the end wall (m). Thesis: "stops 2 cm
    /// before the end", read as a click-through: the force drops to 0 there.
    pub spring_release_before_end: f64,
    /// **Ours**: keep the spring force at its release value (9 N) up to the end wall instead
    /// of dropping to 0.
    pub hold: bool,
}

impl Default for Geometry {
    fn default() -> Self {
        Geometry {
            hole_center: [0.70, 0.20],
            hole_radius: 0.005,
            hole_depth: 0.10,
            k_insert: 300.0,
            spring_catch_offset: 0.0,
            spring_release_before_end: 0.02,
            hold: false,
        }
    }
}

impl Geometry {
    /// x of the wall face (m).
    pub fn wall_x(&self) -> f64 {
        self.hole_center[0] - 0.5 * self.hole_depth
    }
    /// x of the end wall of the channel (m).
    pub fn end_x(&self) -> f64 {
        self.hole_center[0] + 0.5 * self.hole_depth
    }
    /// x where the insertion spring starts to push back (m).
    pub fn spring_catch_x(&self) -> f64 {
        self.hole_center[0] + self.spring_catch_offset
    }
    /// x where the insertion spring releases (m).
    pub fn spring_release_x(&self) -> f64 {
        self.end_x() - self.spring_release_before_end
    }
    /// The same scene moved by (dx, dy).
    pub fn shifted(&self, dx: f64, dy: f64) -> Geometry {
        Geometry {
            hole_center: [self.hole_center[0] + dx, self.hole_center[1] + dy],
            ..self.clone()
        }
    }
    fn validate(&self) -> Result<(), EnvError> {
        finite("geometry.hole_center[0]", self.hole_center[0])?;
        finite("geometry.hole_center[1]", self.hole_center[1])?;
        positive("geometry.hole_radius", self.hole_radius)?;
        positive("geometry.hole_depth", self.hole_depth)?;
        non_negative("geometry.k_insert", self.k_insert)?;
        let (catch, release) = (self.spring_catch_x(), self.spring_release_x());
        if !(catch >= self.wall_x() && catch <= release && release <= self.end_x()) {
            return Err(EnvError::config(
                "geometry.spring_catch_offset",
                self.spring_catch_offset,
                format!(
                    "such that wall {} ≤ catch {catch} ≤ release {release} ≤ end {}",
                    self.wall_x(),
                    self.end_x()
                ),
            ));
        }
        Ok(())
    }
}

/// Desired Cartesian impedance (§2-2, §5-2-3). Stiffness k_x, k_y comes from the action.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ImpedanceParams {
    /// Desired inertia M_d for (x, y, φ) (kg, kg, kg·m²). Thesis: "predetermined"; (1, 1, 0.05)
    /// is **ours**.
    pub mass: [f64; 3],
    /// Fixed rotational stiffness holding φ at 0 (N·m/rad). **Ours**: 20.
    pub k_phi: f64,
    /// Damping ratio ζ (§5-2-3): B_d = 2ζ·sqrt((K_d + K_e)·M_d) per axis. Thesis: 0.7.
    pub zeta: f64,
}

impl Default for ImpedanceParams {
    fn default() -> Self {
        ImpedanceParams {
            mass: [1.0, 1.0, 0.05],
            k_phi: 20.0,
            zeta: 0.7,
        }
    }
}

/// Sensor noise standard deviations, SI units (§5-2: the thesis's "variance 0.1 \[deg\]",
/// "0.1 \[N\]" carry unsquared units, so they are read as standard deviations).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SensorParams {
    /// Encoder noise per joint (rad). Thesis: 0.1°.
    pub encoder_std: f64,
    /// Tachometer noise per joint (rad/s). Thesis: 0.1°/s.
    pub tacho_std: f64,
    /// Force/torque sensor noise per force axis (N). Thesis: 0.1 N. The torque channel reads
    /// exactly 0 (point contact; **ours**).
    pub force_std: f64,
}

impl Default for SensorParams {
    fn default() -> Self {
        SensorParams {
            encoder_std: 0.1_f64.to_radians(),
            tacho_std: 0.1_f64.to_radians(),
            force_std: 0.1,
        }
    }
}

/// Which impedance law computes the joint torques.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ControllerKind {
    /// General Cartesian impedance control (eqs. 2-11, 2-17, 2-18): model-based, uses the F/T
    /// sensor.
    Gic,
    /// Simple Cartesian impedance control (eq. 2-8): transposed-Jacobian spring-damper.
    Sic,
    /// Zero torque (for tests of the plant).
    Off,
}

impl FromStr for ControllerKind {
    type Err = EnvError;
    fn from_str(s: &str) -> Result<Self, EnvError> {
        match s.to_ascii_lowercase().as_str() {
            "gic" => Ok(ControllerKind::Gic),
            "sic" => Ok(ControllerKind::Sic),
            "off" => Ok(ControllerKind::Off),
            _ => Err(EnvError::UnknownController(s.to_string())),
        }
    }
}

impl fmt::Display for ControllerKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            ControllerKind::Gic => "gic",
            ControllerKind::Sic => "sic",
            ControllerKind::Off => "off",
        })
    }
}

/// What the action of one learning step contains.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum ActionMode {
    /// VIL: a = (k_x, k_y); the reference comes from [`ArmConfig::reference`], indexed by time.
    Vil,
    /// VILTA: a = (k_x, k_y, Δx_ref, Δy_ref). Δ is metres per `delta_tick` seconds (eq. 4-24):
    /// ẋ_v = Δ/delta_tick, integrated every control tick, ẍ_v = 0, from `origin`.
    Vilta {
        /// Largest allowed |Δ| (m). Thesis Table 5-6: 0.0025.
        delta_max: f64,
        /// The tick Δ refers to (s). Thesis: 5 ms (the 200 Hz controller period).
        delta_tick: f64,
        /// Where the integration of the reference starts.
        #[serde(default, skip_serializing_if = "ReferenceOrigin::is_start")]
        origin: ReferenceOrigin,
        /// Largest distance (m) x_v may lead the controller's measured TCP position along each
        /// of x and y (ours; `None`: unbounded, as issue 5), as a real impedance controller
        /// saturates its tracking error. A command pushing the lead ℓ further out is slowed by
        /// max(0, 1 − |ℓ|/max_lead), so ℓ approaches the limit smoothly; a TCP pushed back
        /// drags x_v along. The spring force then stays within k · max_lead and the state the
        /// GP does not see, x_v − x, within ±max_lead.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        max_lead: Option<f64>,
        /// Whether the observation (and the true state) carries the reference's lead over the
        /// TCP, ℓ = (x_v − x, y_v − y), as entries 6 and 7 (ours; `false`: the six
        /// entries). The controller knows x_v, so ℓ is as observable as x; without it x_v is a
        /// state the learner never sees and the dynamics are not Markov in the observation.
        #[serde(default, skip_serializing_if = "std::ops::Not::not")]
        lead_state: bool,
    },
}

/// What the environment does when a control tick diverges (a non-finite state, or a joint
/// faster than `max_joint_speed`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum OnDivergence {
    /// End the episode at the last state before the runaway tick, with flag `diverged` and
    /// the step's [`crate::StepInfo::stopped_early`] naming what ran away.
    #[default]
    EndEpisode,
    /// Return [`EnvError::Diverged`] from `step` (for checking integrator settings).
    Error,
}

/// Where VILTA's reference position x_v comes from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ReferenceOrigin {
    /// Integrated over the whole episode from the start pose (issue 5). x_v is then a state
    /// the observations do not show: after contact it keeps moving into the surface and the
    /// contact force grows with it.
    #[default]
    Start,
    /// Restarted at the measured TCP position (the observation the policy acted on) at each
    /// learning step, then integrated over the step (ours). x_v − x stays within
    /// v_max · Δt, so the impedance's spring force stays within k · v_max · Δt; its damping
    /// adds B_d · ẋ_v as with either origin.
    Measured,
}

impl ReferenceOrigin {
    /// The default (serialised configs omit it, so their identity stays the same).
    pub fn is_start(&self) -> bool {
        *self == ReferenceOrigin::Start
    }
}

impl ActionMode {
    /// VILTA with the thesis's limits (Table 5-6), integrated from the start pose.
    pub fn vilta() -> ActionMode {
        ActionMode::Vilta {
            delta_max: 0.0025,
            delta_tick: 0.005,
            origin: ReferenceOrigin::Start,
            max_lead: None,
            lead_state: false,
        }
    }
}

/// Full configuration of the arm environment. `Default` is the thesis's VIL set-up with the
/// issue's choices (GIC, 1 kHz, noise and mismatch on).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ArmConfig {
    /// The nominal arm: the model the controller uses. The plant is this scaled by `mismatch`.
    pub arm: ArmParams,
    /// Plant/model inertia ratio (§5-2: 15 % → 1.15). 1.0 switches the mismatch off.
    pub mismatch: f64,
    /// Surface contact parameters.
    pub contact: ContactParams,
    /// Scene geometry.
    pub geometry: Geometry,
    /// Desired impedance.
    pub impedance: ImpedanceParams,
    /// Sensor noise levels.
    pub sensors: SensorParams,
    /// Whether sensor noise is applied.
    pub noise: bool,
    /// The impedance law.
    pub controller: ControllerKind,
    /// Control rate (Hz). **Ours**: 1000 (the thesis's 200 Hz limit-cycles at a 1e5 N/m wall;
    /// see the README). Torque is zero-order held between ticks.
    pub control_hz: f64,
    /// Largest RK4 step (s); the step used is control period / ceil(control period / h).
    pub h: f64,
    /// Seconds per learning step Δt (thesis: 0.1). Must be a whole number of control ticks.
    pub step_dt: f64,
    /// Learning steps per episode H (thesis: T = 10 s → 100).
    pub horizon: usize,
    /// Action layout.
    pub mode: ActionMode,
    /// Reference trajectory in VIL mode (thesis: min-jerk via points P0..P3).
    pub reference: ReferenceSpec,
    /// |det J| below this at a control tick ends the episode with flag `singular` (issue: 1e-4).
    pub singular_det: f64,
    /// Any joint speed above this (rad/s) is reported as divergence. **Ours**: 100.
    pub max_joint_speed: f64,
    /// What the arm's [`Environment::step`](crate::Environment::step) does when the simulation
    /// diverges. **Ours**: end the episode, as a real arm stops at its limits, so a learned
    /// policy that drives the arm into a runaway still leaves its roll-out's data behind.
    #[serde(default)]
    pub on_divergence: OnDivergence,
    /// Insertion counts when the TCP ends within this distance of the end wall while in the
    /// hole (m). **Ours**: 0.005 (x ≥ 0.745).
    pub insert_tolerance: f64,
    /// Record one [`super::TickRecord`] per control tick (for `vicpilco sim` and tests).
    pub record_trace: bool,
}

impl Default for ArmConfig {
    fn default() -> Self {
        ArmConfig {
            arm: ArmParams::default(),
            mismatch: 1.15,
            contact: ContactParams::default(),
            geometry: Geometry::default(),
            impedance: ImpedanceParams::default(),
            sensors: SensorParams::default(),
            noise: true,
            controller: ControllerKind::Gic,
            control_hz: 1000.0,
            h: 1e-4,
            step_dt: 0.1,
            horizon: 100,
            mode: ActionMode::Vil,
            reference: ReferenceSpec::thesis(),
            singular_det: 1e-4,
            max_joint_speed: 100.0,
            on_divergence: OnDivergence::EndEpisode,
            insert_tolerance: 0.005,
            record_trace: false,
        }
    }
}

impl ArmConfig {
    /// The default with noise and mismatch off (the setting of most checks).
    pub fn ideal() -> Self {
        ArmConfig {
            noise: false,
            mismatch: 1.0,
            ..ArmConfig::default()
        }
    }

    /// Control ticks per learning step.
    pub fn ticks_per_step(&self) -> usize {
        (self.step_dt * self.control_hz).round() as usize
    }

    /// Control ticks between two samples of [`StepInfo::path`](crate::StepInfo::path): every
    /// [`PATH_SAMPLE_INTERVAL`](super::PATH_SAMPLE_INTERVAL), at least one tick and at most
    /// a step.
    pub fn ticks_per_path_sample(&self) -> usize {
        ((super::PATH_SAMPLE_INTERVAL * self.control_hz).round() as usize)
            .clamp(1, self.ticks_per_step().max(1))
    }

    /// RK4 substeps per control tick.
    pub fn substeps(&self) -> usize {
        let period = 1.0 / self.control_hz;
        ((period / self.h) * (1.0 - 1e-12)).ceil().max(1.0) as usize
    }

    /// Checks every field; the error names the first bad one.
    pub fn validate(&self) -> Result<(), EnvError> {
        self.arm.validate("arm")?;
        positive("mismatch", self.mismatch)?;
        positive("contact.k_env", self.contact.k_env)?;
        non_negative("contact.b_env", self.contact.b_env)?;
        non_negative("contact.friction", self.contact.friction)?;
        self.geometry.validate()?;
        for i in 0..3 {
            positive(&format!("impedance.mass[{i}]"), self.impedance.mass[i])?;
        }
        positive("impedance.k_phi", self.impedance.k_phi)?;
        positive("impedance.zeta", self.impedance.zeta)?;
        non_negative("sensors.encoder_std", self.sensors.encoder_std)?;
        non_negative("sensors.tacho_std", self.sensors.tacho_std)?;
        non_negative("sensors.force_std", self.sensors.force_std)?;
        positive("control_hz", self.control_hz)?;
        positive("h", self.h)?;
        if self.h > 1.0 / self.control_hz {
            return Err(EnvError::config(
                "h",
                Num(self.h),
                format!("≤ 1/control_hz = {}", Num(1.0 / self.control_hz)),
            ));
        }
        positive("step_dt", self.step_dt)?;
        let ticks = self.step_dt * self.control_hz;
        if ticks.round() < 1.0 || (ticks - ticks.round()).abs() > 1e-9 * ticks {
            return Err(EnvError::config(
                "step_dt",
                Num(self.step_dt),
                format!(
                    "a whole number of control periods (1/{} s)",
                    Num(self.control_hz)
                ),
            ));
        }
        if self.horizon == 0 {
            return Err(EnvError::config("horizon", 0, "≥ 1"));
        }
        if let ActionMode::Vilta {
            delta_max,
            delta_tick,
            max_lead,
            ..
        } = self.mode
        {
            positive("mode.delta_max", delta_max)?;
            positive("mode.delta_tick", delta_tick)?;
            if let Some(d) = max_lead {
                positive("mode.max_lead", d)?;
            }
        }
        self.reference.validate()?;
        positive("singular_det", self.singular_det)?;
        positive("max_joint_speed", self.max_joint_speed)?;
        non_negative("insert_tolerance", self.insert_tolerance)?;
        Ok(())
    }
}
