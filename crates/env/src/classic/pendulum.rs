//! Pendulum swing-up: a uniform rod turning about one end, driven by a bounded torque, starts
//! hanging down and must be swung up and balanced upright.
//!
//! State `z = (θ̇, θ)`: angular velocity (rad/s) and angle (rad), θ = 0 hanging down, θ = π
//! upright. Equation of motion (rod of mass m and length l, pivot friction b, torque u):
//!
//! ```text
//! θ̈ = (u − b θ̇ − m g l sin θ / 2) / (m l² / 3)
//! E = m l² θ̇² / 6 − m g l cos θ / 2,        dE/dt = θ̇ (u − b θ̇)
//! ```
//!
//! # Constants and their sources
//!
//! Sources are the pilco-matlab release's `scenarios/pendulum/` files: `dynamics_pendulum.m`
//! (dyn), `settings_pendulum.m` (set), `loss_pendulum.m` (loss), `pendulum_learn.m` (learn),
//! plus `base/rollout.m` and `gp/train.m`.
//!
//! | constant | value | source |
//! |---|---|---|
//! | rod length l | 1 m | dyn `l` |
//! | rod mass m | 1 kg | dyn `m` |
//! | gravity g | 9.82 m/s² | dyn `g` |
//! | friction b | 0.01 N m s/rad | dyn `b` |
//! | time step dt | 0.1 s | set `dt` |
//! | horizon H | 40 steps (T = 4 s, `ceil(T/dt)`) | set `T`, `H` |
//! | RK4 substeps | 100 (h = 1 ms) | **ours** (PILCO: `ode45`) |
//! | start mean | (0, 0) | set `mu0` |
//! | start covariance | 0.01 I (std 0.1 rad/s, 0.1 rad) | set `S0` |
//! | measurement noise std | (0.1 rad/s, 0.01 rad) | set `plant.noise` = diag(0.1², 0.01²) |
//! | action limit | 2.5 N m | set `policy.maxU` |
//! | angle indices | [1] (θ) | set `angi` = [2] |
//! | augmented vector | (θ̇, θ, sin θ, cos θ) | set, comment 1a |
//! | policy inputs | [0, 2, 3] = (θ̇, sin θ, cos θ) | set `poli` = [1 3 4] |
//! | GP inputs | [0, 2, 3] + action | set `dyni` = [1 3 4], `trainDynModel.m` |
//! | difference targets | [0, 1] (both) | set `difi` = [1 2] |
//! | RBF basis functions | 20 | set `nc` |
//! | RBF length-scales, sf, sn | (1, 0.7, 0.7), 1, 0.01 | set `policy.p.hyp` |
//! | initial pseudo-targets | 0.1 · randn | set `policy.p.targets` |
//! | cost length | 1 m | set `cost.p` |
//! | cost width | 0.5 | set `cost.width` |
//! | cost target | (0, π) | set `cost.target` |
//! | cost Q | ℓ² on the (sin θ, cos θ) block | loss |
//! | discount, exploration | 1, 0 | set `cost.gamma`, `cost.expl` |
//! | optimiser budget | 75 line searches, 30 evaluations each | set `opt.length`, `opt.MFEPLS` |
//! | policy optimiser | L-BFGS, 10 correction pairs, Wolfe constants of `minimize.m` (RHO 0.05, SIG 0.1) | **ours** (PILCO: BFGS with `minimize.m`'s line search) |
//! | policy updates N | 10 | set `N` |
//! | random roll-outs J | 1, uniform actions in ±maxU | set `J`, learn, `rollout.m` |
//! | start distributions K | 1 | set `K` |
//! | GP training | 300 line searches (full), 500 (sparse) | set `trainOpt` |
//! | sparse GP | 300 inducing inputs, used above 300 points | set `dynmodel.induce`, `train.m` |
//! | sparse GP hyper-parameters | fitted on all points, then the inducing inputs with them fixed | `train.m` |
//! | success test | last 10 states: tip ≤ 0.2 m from upright, \|θ̇\| ≤ 1 rad/s | **ours** |
//!
//! With target (0, π) augmented to (0, π, 0, −1), `(a − a*)ᵀ Q (a − a*)` =
//! `l² sin²θ + l² (cos θ + 1)²`, the squared distance of the tip `(l sin θ, −l cos θ)` from
//! `(0, l)`. The tip threshold 0.2 m is 0.4 cost widths (≈ 0.2 rad from upright).
//!
//! Note on sources: the newest snapshot of the `UCL-SML/pilco-matlab` repository carries an
//! experimental pendulum (gravity multiplied by 0, b = 1, dt = 0.2 s, T = 25 s, maxU = 6,
//! nc = 30, N = 20, MFEPLS = 20, 2000 inducing inputs) that is not a swing-up task; the
//! values above are those of the released scenario (identical in several independent copies
//! of the release).

use super::ode;
use super::{ClassicEnv, ClassicSystem, Dynamics, Scenario, SuccessTest};
use crate::error::{non_negative, positive};
use crate::EnvError;
use std::f64::consts::PI;

/// Physical constants of the pendulum (a uniform rod about one end).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct PendulumPhysics {
    /// Rod length l (m).
    pub length: f64,
    /// Rod mass m (kg).
    pub mass: f64,
    /// Gravitational acceleration g (m/s²).
    pub gravity: f64,
    /// Viscous friction at the pivot b (N m s/rad).
    pub friction: f64,
}

impl Default for PendulumPhysics {
    /// PILCO's `dynamics_pendulum.m`: l = 1 m, m = 1 kg, g = 9.82 m/s², b = 0.01 N m s/rad.
    fn default() -> Self {
        PendulumPhysics {
            length: 1.0,
            mass: 1.0,
            gravity: 9.82,
            friction: 0.01,
        }
    }
}

impl Dynamics<2> for PendulumPhysics {
    fn derivative(&self, z: &[f64; 2], u: f64) -> [f64; 2] {
        let (l, m, g, b) = (self.length, self.mass, self.gravity, self.friction);
        let (dtheta, theta) = (z[0], z[1]);
        let ddtheta = (u - b * dtheta - 0.5 * m * g * l * theta.sin()) / (m * l * l / 3.0);
        [ddtheta, dtheta]
    }
}

impl ClassicSystem for PendulumPhysics {
    const STATE_DIM: usize = 2;
    const STATE_NAMES: &'static [&'static str] = &["dtheta", "theta"];
    const ACTION_NAME: &'static str = "torque";
    const ACTION_UNIT: &'static str = "N m";
    const ANGULAR_VELOCITY: usize = 0;

    /// 4 × 4, zero except `Q[2][2] = Q[3][3] = l²` (the sin/cos block).
    fn cost_q(cost_length: f64) -> Vec<Vec<f64>> {
        let mut q = vec![vec![0.0; 4]; 4];
        q[2][2] = cost_length * cost_length;
        q[3][3] = cost_length * cost_length;
        q
    }

    fn energy(&self, z: &[f64]) -> f64 {
        let (l, m, g) = (self.length, self.mass, self.gravity);
        m * l * l * z[0] * z[0] / 6.0 - 0.5 * m * g * l * z[1].cos()
    }

    fn validate(&self) -> Result<(), EnvError> {
        positive("pendulum.length", self.length)?;
        positive("pendulum.mass", self.mass)?;
        non_negative("pendulum.gravity", self.gravity)?;
        non_negative("pendulum.friction", self.friction)
    }
}

/// The pendulum swing-up scenario; `Default` is PILCO's (see the module docs' table).
pub type PendulumScenario = Scenario<PendulumPhysics>;

impl Default for Scenario<PendulumPhysics> {
    fn default() -> Self {
        let dt = 0.1;
        let t_total = 4.0;
        Scenario {
            physics: PendulumPhysics::default(),
            dt,
            horizon: (t_total / dt - 1e-9_f64).ceil() as usize,
            substeps: ode::substeps_for(dt, ode::MAX_SUBSTEP),
            start_mean: vec![0.0, 0.0],
            start_cov: vec![vec![0.01, 0.0], vec![0.0, 0.01]],
            noise_std: vec![0.1, 0.01],
            max_action: 2.5,
            angle_indices: vec![1],
            policy_inputs: vec![0, 2, 3],
            dyn_inputs: vec![0, 2, 3],
            difference_targets: vec![0, 1],
            n_basis: 20,
            policy_lengthscales: vec![1.0, 0.7, 0.7],
            policy_signal_std: 1.0,
            policy_noise_std: 0.01,
            policy_target_std: 0.1,
            cost_length: 1.0,
            cost_widths: vec![0.5],
            cost_target: vec![0.0, PI],
            discount: 1.0,
            exploration: 0.0,
            opt_length: 75,
            opt_mfepls: 30,
            opt_memory: 10,
            policy_updates: 10,
            initial_rollouts: 1,
            start_distributions: 1,
            gp_train_full: 300,
            gp_train_sparse: 500,
            sparse_inducing: 300,
            success: SuccessTest {
                window: 10,
                max_tip_distance: 0.2,
                max_angular_speed: 1.0,
            },
        }
    }
}

/// The pendulum swing-up as an [`Environment`](crate::Environment): state `(θ̇, θ)`, action
/// `torque` (N m). `Pendulum::default()` runs PILCO's scenario; `Pendulum::new(scenario)` any
/// other.
pub type Pendulum = ClassicEnv<PendulumPhysics, 2>;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Environment;

    /// Frictionless, unforced: the energy after 10 s (100 learning steps of 100 RK4 substeps)
    /// equals the initial energy to 1e-9 of the energy scale m g l / 2 = 4.91 J, from a large
    /// swing (θ0 = 2.5 rad, θ̇0 = 1 rad/s).
    #[test]
    fn energy_conserved_without_friction() {
        let p = PendulumPhysics {
            friction: 0.0,
            ..Default::default()
        };
        let z0 = [1.0, 2.5];
        let e0 = p.energy(&z0);
        let mut z = z0;
        let mut worst: f64 = 0.0;
        for _ in 0..100 {
            z = ode::integrate(&|z: &[f64; 2]| p.derivative(z, 0.0), z, 0.1, 100);
            worst = worst.max((p.energy(&z) - e0).abs());
        }
        let scale = 0.5 * p.mass * p.gravity * p.length;
        assert!(worst < 1e-9 * scale, "energy drift {worst:e} J");
    }

    /// With friction and torque: E(t) − E(0) equals the work ∫ θ̇ (u − b θ̇) dt, integrated
    /// alongside the state, to 1e-9 J over 4 s of a bang-bang torque (checks the u and b
    /// terms of the ODE against PILCO's energy expression).
    #[test]
    fn energy_balance_with_friction_and_torque() {
        let p = PendulumPhysics {
            friction: 0.5,
            ..Default::default()
        };
        let mut z = [0.0, 0.3, 0.0]; // (θ̇, θ, work)
        let e0 = p.energy(&z[..2]);
        for k in 0..40 {
            let u = if (k / 5) % 2 == 0 { 2.5 } else { -2.5 };
            let f = |z: &[f64; 3]| {
                let d = p.derivative(&[z[0], z[1]], u);
                [d[0], d[1], z[0] * (u - p.friction * z[0])]
            };
            z = ode::integrate(&f, z, 0.1, 100);
        }
        let gap = p.energy(&z[..2]) - e0 - z[2];
        assert!(
            gap.abs() < 1e-9,
            "energy balance gap {gap:e} J, work {}",
            z[2]
        );
        assert!(z[2].abs() > 0.1, "the test must exercise the work term");
    }

    /// At rest hanging down with zero torque the pendulum stays exactly at rest.
    #[test]
    fn rest_at_bottom_stays() {
        let mut env = Pendulum::default();
        env.reset(&[0.0, 0.0], 1).unwrap();
        for _ in 0..40 {
            let s = env.step(&[0.0]).unwrap();
            assert_eq!(s.info.true_state, vec![0.0, 0.0]);
        }
    }

    /// The derivative at one state against the formula evaluated by hand.
    #[test]
    fn derivative_by_hand() {
        let p = PendulumPhysics::default();
        // θ̈ = (1 − 0.01·2 − 9.82·sin(1)/2) · 3
        let d = p.derivative(&[2.0, 1.0], 1.0);
        let expect = (1.0 - 0.02 - 4.91 * 1.0f64.sin()) * 3.0;
        assert!((d[0] - expect).abs() < 1e-14 && d[1] == 2.0, "{d:?}");
    }

    /// Small oscillations have the period of a physical pendulum, 2π sqrt(2l / (3g)).
    #[test]
    fn small_oscillation_period() {
        let p = PendulumPhysics {
            friction: 0.0,
            ..Default::default()
        };
        let period = 2.0 * PI * (2.0 * p.length / (3.0 * p.gravity)).sqrt();
        let z = ode::integrate(
            &|z: &[f64; 2]| p.derivative(z, 0.0),
            [0.0, 1e-4],
            period,
            2000,
        );
        assert!(
            (z[1] - 1e-4).abs() < 1e-4 * 1e-6,
            "θ after one period {}",
            z[1]
        );
    }

    #[test]
    fn default_scenario_is_consistent() {
        let s = PendulumScenario::default();
        s.validate().unwrap();
        assert_eq!(s.horizon, 40);
        assert_eq!(s.substeps, 100);
        assert_eq!(s.augmented_dim(), 4);
        let t = s.augmented_target();
        assert!(
            (t[2] - 0.0).abs() < 1e-15 && (t[3] + 1.0).abs() < 1e-15,
            "{t:?}"
        );
        // upright: no cost; hanging: tip 2 l away; W = Q / 0.25
        assert!(s.tip_distance(&[0.0, PI]) < 1e-12);
        assert!(s.tip_distance(&[0.0, -PI]) < 1e-12);
        assert!((s.tip_distance(&[0.0, 0.0]) - 2.0).abs() < 1e-12);
        assert!((s.immediate_cost(&[0.0, 0.0]) - (1.0 - (-8.0f64).exp())).abs() < 1e-12);
        assert_eq!(s.cost_weight(0.5)[2][2], 4.0);
        // the 0.2 m threshold is about 0.2 rad
        let d = s.tip_distance(&[0.0, PI - 0.2]);
        assert!((d - 2.0 * (0.1f64).sin()).abs() < 1e-12);
    }

    #[test]
    fn success_test() {
        let s = PendulumScenario::default();
        let mut traj = vec![vec![0.0, 0.0]; 30];
        traj.extend(vec![vec![0.3, PI - 0.15]; 10]);
        assert!(s.success(&traj));
        // upright on the other side (θ = −π) counts too
        let other: Vec<[f64; 2]> = vec![[0.0, -PI + 0.1]; 10];
        assert!(s.success(&other));
        // too short
        assert!(!s.success(&traj[31..]));
        // one state too far from upright
        let mut bad = traj.clone();
        bad[35][1] = PI - 0.25;
        assert!(!s.success(&bad));
        // passing the top too fast
        let mut fast = traj.clone();
        fast[39][0] = 1.5;
        assert!(!s.success(&fast));
        // hanging down
        assert!(!s.success(&vec![vec![0.0, 0.0]; 40]));
    }
}
