//! The classic PILCO benchmarks: pendulum swing-up and cart-pole swing-up.
//!
//! Both follow PILCO's published scenarios (Deisenroth & Rasmussen, ICML 2011; the MATLAB
//! release `pilco-matlab`, files `scenarios/pendulum/*` and `scenarios/cartPole/*`). Every
//! number lives in a [`Scenario`], whose `Default` for each system is PILCO's value; the
//! per-system module docs ([`PendulumScenario`], [`CartPoleScenario`]) list each constant with
//! the PILCO file it comes from and mark the values that are ours.
//!
//! # Simulation
//!
//! * The true state is integrated by classic RK4 ([`ode`]) under a zero-order-held action,
//!   `substeps` RK4 steps per learning step (ours; PILCO uses adaptive `ode45`). The default
//!   keeps the RK4 step at most [`ode::MAX_SUBSTEP`] = 1 ms (100 substeps for dt = 0.1 s).
//! * Observation = true state + i.i.d. Gaussian noise with std `noise_std` (PILCO's
//!   `plant.noise`, a diagonal covariance). The noise of an episode comes from
//!   `ChaCha8Rng::seed_from_u64(seed)` with the `seed` given to `reset`; draws are taken in
//!   state order, one set per observation (the first at `reset`), so a seed fixes the trace
//!   bit for bit.
//! * `reset(start, seed)` sets the true state to `start` exactly; drawing `start` from the start
//!   distribution `N(start_mean, start_cov)` is the caller's job (as PILCO's
//!   `rollout(gaussian(mu0, S0), …)`); [`Scenario::sample_start`] does it.
//! * Actions: one scalar (torque or force). Wrong length, non-finite, or `|u| > max_action` is
//!   an [`EnvError`] naming the field; there is no clipping (the learner's sine squashing keeps
//!   actions within `±max_action`).
//! * Angles are not wrapped (PILCO does not wrap them either; the GP and the policy see
//!   `sin θ, cos θ`). The success test measures the distance to upright modulo 2π.
//! * `done` after `horizon` steps. `info.true_state` holds the noise-free state;
//!   `info.values` holds `energy` (J), `tip_distance` (m, the distance the cost penalises),
//!   `cost` (PILCO's immediate saturating cost of the true state) and `action`.
//!
//! # Augmented vector and index conventions
//!
//! PILCO appends `sin θ, cos θ` of each angle (in `angle_indices` order) after the state; we
//! keep that layout, so index lists are PILCO's 1-based `poli`, `dyni`, `difi`, `angi` minus
//! one. Pendulum: `[θ̇, θ, sin θ, cos θ]`. Cart-pole: `[x, v, θ̇, θ, sin θ, cos θ]`.
//!
//! # Cost
//!
//! PILCO's `loss_pendulum.m` / `loss_cp.m`: for each width `w` in `cost_widths`,
//! `c = 1 − exp(−½ (a − a*)ᵀ W (a − a*))` with `a` the augmented state, `a*` the augmented
//! target and `W = Q / w²`; the costs of several widths are averaged. `Q` is chosen so that
//! `(a − a*)ᵀ Q (a − a*)` is the squared distance between the pole tip and its upright target
//! position ([`Scenario::cost_q`]). As blocks of `vicpilco_pilco`: one `SaturatingCost` per
//! width on the augmented vector with weight [`Scenario::cost_weight`] and target
//! [`Scenario::augmented_target`].
//!
//! # Success tests (ours)
//!
//! [`Scenario::success`]: over the last `success.window` states of the true trajectory (the
//! last second for both systems), the pole tip stays within `success.max_tip_distance` of its
//! upright target and `|θ̇| ≤ success.max_angular_speed`. Both distance thresholds are 0.4 cost
//! widths, where the immediate cost is at most `1 − exp(−0.08)` ≈ 0.077 (pendulum: 0.2 m ≈
//! 0.2 rad with l = 1 m; cart-pole: 0.1 m). See [`SuccessTest`].

use crate::{EnvError, Environment, Step, StepInfo};
use rand::rngs::ChaCha8Rng;
use rand::{Rng, RngExt, SeedableRng};
use rand_distr::{Distribution, StandardNormal};
use std::collections::BTreeMap;

mod cartpole;
pub mod ode;
mod pendulum;

pub use cartpole::{CartPole, CartPolePhysics, CartPoleScenario};
pub use pendulum::{Pendulum, PendulumPhysics, PendulumScenario};

/// What a classic system provides to its [`Scenario`] and environment, independent of the
/// state length's type-level value.
pub trait ClassicSystem: Clone + std::fmt::Debug {
    /// Number of state entries.
    const STATE_DIM: usize;
    /// Names of the state entries, in order.
    const STATE_NAMES: &'static [&'static str];
    /// Name of the single action entry (`torque`, `force`).
    const ACTION_NAME: &'static str;
    /// Unit of the action (`N m`, `N`).
    const ACTION_UNIT: &'static str;
    /// Index of the pole's angular velocity θ̇ in the state.
    const ANGULAR_VELOCITY: usize;
    /// The cost's `Q` on the augmented vector (`STATE_DIM + 2` square) for pole length
    /// `cost_length`: `(a − a*)ᵀ Q (a − a*)` is the squared tip-to-target distance.
    fn cost_q(cost_length: f64) -> Vec<Vec<f64>>;
    /// Total mechanical energy of state `z` (J), PILCO's energy expression.
    fn energy(&self, z: &[f64]) -> f64;
    /// Checks the physical constants.
    fn validate(&self) -> Result<(), EnvError>;
}

/// The equations of motion `ż = f(z, u)` on a fixed-size state.
pub trait Dynamics<const N: usize> {
    /// Time derivative of state `z` under action `u`.
    fn derivative(&self, z: &[f64; N], u: f64) -> [f64; N];
}

/// When an episode counts as solved (ours, not PILCO's). See the module docs.
#[derive(Clone, Debug, PartialEq)]
pub struct SuccessTest {
    /// Number of final states checked (10 = the last second at dt = 0.1 s).
    pub window: usize,
    /// Largest distance of the pole tip from its upright target position (m), the distance
    /// the cost penalises.
    pub max_tip_distance: f64,
    /// Largest |θ̇| (rad/s), so the pole is balanced rather than passing through the top
    /// (`f64::INFINITY`: no limit).
    pub max_angular_speed: f64,
}

/// A classic benchmark: physics, simulation and PILCO's learning settings. Plain data; every
/// field is public. `Scenario::<PendulumPhysics>::default()` and
/// `Scenario::<CartPolePhysics>::default()` are PILCO's published values (see the aliases
/// [`PendulumScenario`] and [`CartPoleScenario`] for the numbers and their sources).
#[derive(Clone, Debug, PartialEq)]
pub struct Scenario<P> {
    /// Physical constants.
    pub physics: P,
    // --- simulation ---------------------------------------------------------------------
    /// Seconds per learning step (PILCO `dt`); the action is held constant over it.
    pub dt: f64,
    /// Learning steps per episode, `H = ceil(T / dt)` (PILCO `H`).
    pub horizon: usize,
    /// RK4 substeps per learning step (ours; default gives h ≤ 1 ms).
    pub substeps: usize,
    /// Mean of the start-state distribution (PILCO `mu0`).
    pub start_mean: Vec<f64>,
    /// Covariance of the start-state distribution, row-major (PILCO `S0`).
    pub start_cov: Vec<Vec<f64>>,
    /// Std of the i.i.d. Gaussian measurement noise per state entry (square roots of the
    /// diagonal of PILCO `plant.noise`).
    pub noise_std: Vec<f64>,
    /// Action limit: actions must satisfy `|u| ≤ max_action` (PILCO `policy.maxU`).
    pub max_action: f64,
    // --- representation -----------------------------------------------------------------
    /// State indices treated as angles (PILCO `angi`, 0-based).
    pub angle_indices: Vec<usize>,
    /// Policy inputs, indices into the augmented vector (PILCO `poli`, 0-based).
    pub policy_inputs: Vec<usize>,
    /// GP dynamics-model inputs besides the action, indices into the augmented vector
    /// (PILCO `dyni`, 0-based); the action is appended as the last GP input.
    pub dyn_inputs: Vec<usize>,
    /// State entries whose GP targets are differences `z_{t+1} − z_t` rather than values
    /// (PILCO `difi`, 0-based).
    pub difference_targets: Vec<usize>,
    // --- policy -------------------------------------------------------------------------
    /// Number of RBF basis functions of the policy (PILCO `nc`).
    pub n_basis: usize,
    /// Initial RBF length-scales, one per policy input (PILCO `exp(policy.p.hyp(1:D))`).
    /// PILCO initialises the centres as `n_basis` samples of the start distribution mapped
    /// to policy-input space (`gaussian(mm(poli), ss(poli,poli), nc)`, where `mm, ss` are the
    /// moment-matched mean and covariance of the augmented start state).
    pub policy_lengthscales: Vec<f64>,
    /// Initial RBF signal std (PILCO `exp(hyp(D+1))` = 1; fixed during learning).
    pub policy_signal_std: f64,
    /// Initial RBF noise std (PILCO `exp(hyp(D+2))` = 0.01, i.e. SNR 100; fixed).
    pub policy_noise_std: f64,
    /// Std of the initial pseudo-targets: PILCO draws them as `0.1 · randn(nc, 1)`.
    pub policy_target_std: f64,
    // --- cost ---------------------------------------------------------------------------
    /// Pole length used by the cost's tip geometry (PILCO `cost.p`).
    pub cost_length: f64,
    /// Widths of the saturating cost; one saturating cost per width, averaged (PILCO
    /// `cost.width`).
    pub cost_widths: Vec<f64>,
    /// Target state (PILCO `cost.target`); augmented by its sin/cos for the cost.
    pub cost_target: Vec<f64>,
    /// Discount factor of the expected return (PILCO `cost.gamma`).
    pub discount: f64,
    /// Exploration weight on the cost's std (PILCO `cost.expl`; 0 = none).
    pub exploration: f64,
    // --- learning loop ------------------------------------------------------------------
    /// Policy optimiser budget: maximum number of line searches (PILCO `opt.length`).
    pub opt_length: usize,
    /// Maximum number of function evaluations per line search (PILCO `opt.MFEPLS`).
    pub opt_mfepls: usize,
    /// Correction pairs of the L-BFGS policy optimiser. **Ours**: PILCO optimises with full
    /// BFGS; 10 is the usual L-BFGS memory.
    pub opt_memory: usize,
    /// Number of policy updates, i.e. learning episodes after the random ones (PILCO `N`).
    pub policy_updates: usize,
    /// Number of initial roll-outs with the random policy (PILCO `J`): each action drawn
    /// independently, uniformly in `±max_action`, every step (PILCO `rollout` with a policy
    /// that has no `fcn`: `maxU · (2 rand − 1)`); see [`Scenario::random_action`].
    pub initial_rollouts: usize,
    /// Number of start distributions optimised for (PILCO `K`).
    pub start_distributions: usize,
    /// GP hyper-parameter training budget, line searches of the full GP (PILCO
    /// `trainOpt(1)`); PILCO warm-starts from the previous episode's hyper-parameters.
    pub gp_train_full: usize,
    /// Line searches for the sparse GP's pseudo-inputs (PILCO `trainOpt(2)`; tripled the
    /// first time the sparse GP is trained).
    pub gp_train_sparse: usize,
    /// Number of inducing inputs of the sparse (FITC) GP; PILCO uses the sparse GP once the
    /// training set has more points than this, initialising the pseudo-inputs as a random
    /// subset of the training inputs (PILCO `size(dynmodel.induce, 1)`, `train.m`).
    pub sparse_inducing: usize,
    // --- evaluation ---------------------------------------------------------------------
    /// The success test (ours).
    pub success: SuccessTest,
}

impl<P: ClassicSystem> Scenario<P> {
    /// Length of the augmented vector: state plus `sin, cos` per angle.
    pub fn augmented_dim(&self) -> usize {
        P::STATE_DIM + 2 * self.angle_indices.len()
    }

    /// The augmented vector `[z; sin z_a, cos z_a for a in angle_indices]`.
    pub fn augment(&self, z: &[f64]) -> Vec<f64> {
        let mut a = z.to_vec();
        for &i in &self.angle_indices {
            a.push(z[i].sin());
            a.push(z[i].cos());
        }
        a
    }

    /// The cost target in augmented form (PILCO augments `cost.target` with its sin/cos).
    pub fn augmented_target(&self) -> Vec<f64> {
        self.augment(&self.cost_target)
    }

    /// The cost's `Q` (see [`ClassicSystem::cost_q`]) for `cost_length`.
    pub fn cost_q(&self) -> Vec<Vec<f64>> {
        P::cost_q(self.cost_length)
    }

    /// Weight matrix `W = Q / width²` of the saturating cost with that width (row-major).
    pub fn cost_weight(&self, width: f64) -> Vec<Vec<f64>> {
        let s = 1.0 / (width * width);
        self.cost_q()
            .into_iter()
            .map(|r| r.into_iter().map(|q| q * s).collect())
            .collect()
    }

    /// Distance of the pole tip from its target position (m): `sqrt((a − a*)ᵀ Q (a − a*))`.
    pub fn tip_distance(&self, z: &[f64]) -> f64 {
        let d: Vec<f64> = self
            .augment(z)
            .iter()
            .zip(self.augmented_target())
            .map(|(a, t)| a - t)
            .collect();
        let q = self.cost_q();
        let mut s = 0.0;
        for i in 0..d.len() {
            for j in 0..d.len() {
                s += d[i] * q[i][j] * d[j];
            }
        }
        s.max(0.0).sqrt()
    }

    /// PILCO's immediate cost of a known state: the mean over widths `w` of
    /// `1 − exp(−d² / (2 w²))` with `d` the [`tip_distance`](Self::tip_distance).
    pub fn immediate_cost(&self, z: &[f64]) -> f64 {
        let d2 = self.tip_distance(z).powi(2);
        let n = self.cost_widths.len().max(1) as f64;
        self.cost_widths
            .iter()
            .map(|w| 1.0 - (-0.5 * d2 / (w * w)).exp())
            .sum::<f64>()
            / n
    }

    /// The success test on a trajectory of true states (each of length `STATE_DIM`, e.g. the
    /// `info.true_state` of every step): true iff the trajectory has at least
    /// `success.window` states and each of the last `success.window` has its pole tip within
    /// `success.max_tip_distance` of the target and `|θ̇| ≤ success.max_angular_speed`.
    /// Both conditions are invariant to adding multiples of 2π to θ (the pole may come up on
    /// either side).
    pub fn success<S: AsRef<[f64]>>(&self, trajectory: &[S]) -> bool {
        let w = self.success.window;
        if w == 0 || trajectory.len() < w {
            return false;
        }
        trajectory[trajectory.len() - w..].iter().all(|z| {
            let z = z.as_ref();
            z.len() == P::STATE_DIM
                && self.tip_distance(z) <= self.success.max_tip_distance
                && z[P::ANGULAR_VELOCITY].abs() <= self.success.max_angular_speed
        })
    }

    /// One action of PILCO's random initial policy: uniform in `[−max_action, max_action)`,
    /// drawn independently every step.
    pub fn random_action<R: Rng + ?Sized>(&self, rng: &mut R) -> f64 {
        rng.random_range(-self.max_action..self.max_action)
    }

    /// One start state drawn from `N(start_mean, start_cov)` (PILCO's `gaussian(mu0, S0)`):
    /// `start_mean + L n` with `L` the Cholesky factor of `start_cov` and `n` standard normal
    /// draws in state order. Errors if `start_cov` is not symmetric positive definite.
    pub fn sample_start<R: Rng + ?Sized>(&self, rng: &mut R) -> Result<Vec<f64>, EnvError> {
        let n = self.start_mean.len();
        let c = &self.start_cov;
        if c.len() != n || c.iter().any(|r| r.len() != n) {
            return Err(EnvError::config(
                "scenario.start_cov",
                format!("{} rows", c.len()),
                format!("{n} × {n}"),
            ));
        }
        let mut l = vec![vec![0.0; n]; n];
        for i in 0..n {
            for j in 0..=i {
                if (c[i][j] - c[j][i]).abs() > 1e-12 * (c[i][j].abs() + c[j][i].abs()) {
                    return Err(EnvError::config(
                        "scenario.start_cov",
                        "asymmetric",
                        "symmetric",
                    ));
                }
                let s = c[i][j] - (0..j).map(|k| l[i][k] * l[j][k]).sum::<f64>();
                if i == j {
                    if !(s > 0.0 && s.is_finite()) {
                        return Err(EnvError::config(
                            format!("scenario.start_cov[{i}][{i}] (pivot)"),
                            s,
                            "> 0 (positive definite)",
                        ));
                    }
                    l[i][i] = s.sqrt();
                } else {
                    l[i][j] = s / l[j][j];
                }
            }
        }
        let e: Vec<f64> = (0..n).map(|_| StandardNormal.sample(rng)).collect();
        Ok((0..n)
            .map(|i| self.start_mean[i] + (0..=i).map(|k| l[i][k] * e[k]).sum::<f64>())
            .collect())
    }

    /// Checks every field that the simulator or the index conventions rely on.
    pub fn validate(&self) -> Result<(), EnvError> {
        let n = P::STATE_DIM;
        let na = self.augmented_dim();
        self.physics.validate()?;
        positive("scenario.dt", self.dt)?;
        if self.horizon == 0 {
            return Err(EnvError::config("scenario.horizon", 0, "≥ 1"));
        }
        if self.substeps == 0 {
            return Err(EnvError::config("scenario.substeps", 0, "≥ 1"));
        }
        length("scenario.start_mean", self.start_mean.len(), n)?;
        length("scenario.start_cov", self.start_cov.len(), n)?;
        for (i, r) in self.start_cov.iter().enumerate() {
            length(&format!("scenario.start_cov[{i}]"), r.len(), n)?;
        }
        length("scenario.noise_std", self.noise_std.len(), n)?;
        for (i, &s) in self.noise_std.iter().enumerate() {
            non_negative(&format!("scenario.noise_std[{i}]"), s)?;
        }
        positive("scenario.max_action", self.max_action)?;
        indices("scenario.angle_indices", &self.angle_indices, n)?;
        indices("scenario.policy_inputs", &self.policy_inputs, na)?;
        indices("scenario.dyn_inputs", &self.dyn_inputs, na)?;
        indices("scenario.difference_targets", &self.difference_targets, n)?;
        length(
            "scenario.policy_lengthscales",
            self.policy_lengthscales.len(),
            self.policy_inputs.len(),
        )?;
        positive("scenario.cost_length", self.cost_length)?;
        if self.cost_widths.is_empty() {
            return Err(EnvError::config("scenario.cost_widths", "[]", "non-empty"));
        }
        for (i, &w) in self.cost_widths.iter().enumerate() {
            positive(&format!("scenario.cost_widths[{i}]"), w)?;
        }
        length("scenario.cost_target", self.cost_target.len(), n)?;
        if self.success.window == 0 {
            return Err(EnvError::config("scenario.success.window", 0, "≥ 1"));
        }
        Ok(())
    }
}

pub(super) fn positive(field: &str, v: f64) -> Result<(), EnvError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(EnvError::config(field, v, "finite and > 0"))
    }
}

pub(super) fn non_negative(field: &str, v: f64) -> Result<(), EnvError> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err(EnvError::config(field, v, "finite and ≥ 0"))
    }
}

fn length(field: &str, got: usize, expected: usize) -> Result<(), EnvError> {
    if got == expected {
        Ok(())
    } else {
        Err(EnvError::config(
            field,
            format!("{got} entries"),
            format!("{expected} entries"),
        ))
    }
}

fn indices(field: &str, idx: &[usize], bound: usize) -> Result<(), EnvError> {
    match idx.iter().find(|&&i| i >= bound) {
        None => Ok(()),
        Some(i) => Err(EnvError::config(field, i, format!("< {bound}"))),
    }
}

/// One running episode.
#[derive(Debug)]
struct Episode<const N: usize> {
    z: [f64; N],
    steps: usize,
    rng: ChaCha8Rng,
}

/// A classic system as an [`Environment`]: RK4 under zero-order hold, noisy observations.
/// Use the aliases [`Pendulum`] and [`CartPole`].
#[derive(Debug)]
pub struct ClassicEnv<P, const N: usize> {
    scenario: Scenario<P>,
    episode: Option<Episode<N>>,
}

impl<P: ClassicSystem + Dynamics<N>, const N: usize> ClassicEnv<P, N> {
    /// An environment for `scenario` after [`Scenario::validate`].
    pub fn new(scenario: Scenario<P>) -> Result<Self, EnvError> {
        const { assert!(N == P::STATE_DIM, "N must equal the system's STATE_DIM") };
        scenario.validate()?;
        Ok(ClassicEnv {
            scenario,
            episode: None,
        })
    }

    /// The scenario this environment runs.
    pub fn scenario(&self) -> &Scenario<P> {
        &self.scenario
    }

    /// The current true state (`None` before the first `reset`).
    pub fn true_state(&self) -> Option<[f64; N]> {
        self.episode.as_ref().map(|e| e.z)
    }

    /// The action as a scalar after the checks of the module docs.
    fn check_action(&self, action: &[f64]) -> Result<f64, EnvError> {
        if action.len() != 1 {
            return Err(EnvError::Dimension {
                what: "action",
                got: action.len(),
                expected: 1,
            });
        }
        let u = action[0];
        if !u.is_finite() {
            return Err(EnvError::InvalidAction {
                kind: "action",
                field: P::ACTION_NAME.to_string(),
                value: u,
                requirement: "finite".to_string(),
            });
        }
        let m = self.scenario.max_action;
        if u.abs() > m {
            return Err(EnvError::InvalidAction {
                kind: "action",
                field: P::ACTION_NAME.to_string(),
                value: u,
                requirement: format!("within ±{m} {} (max_action)", P::ACTION_UNIT),
            });
        }
        Ok(u)
    }
}

impl<P, const N: usize> Default for ClassicEnv<P, N>
where
    P: ClassicSystem + Dynamics<N>,
    Scenario<P>: Default,
{
    /// The environment of PILCO's published scenario.
    fn default() -> Self {
        Self::new(Scenario::default()).expect("the default scenario is valid")
    }
}

/// `z` plus one fresh noise draw per entry, in state order.
fn observe(z: &[f64], std: &[f64], rng: &mut ChaCha8Rng) -> Vec<f64> {
    z.iter()
        .zip(std)
        .map(|(&v, &s)| {
            let n: f64 = StandardNormal.sample(rng);
            v + s * n
        })
        .collect()
}

impl<P: ClassicSystem + Dynamics<N>, const N: usize> Environment for ClassicEnv<P, N> {
    fn state_dim(&self) -> usize {
        N
    }

    fn action_dim(&self) -> usize {
        1
    }

    fn dt(&self) -> f64 {
        self.scenario.dt
    }

    fn horizon(&self) -> usize {
        self.scenario.horizon
    }

    fn state_names(&self) -> Vec<String> {
        P::STATE_NAMES.iter().map(|s| s.to_string()).collect()
    }

    fn action_names(&self) -> Vec<String> {
        vec![P::ACTION_NAME.to_string()]
    }

    fn reset(&mut self, start: &[f64], seed: u64) -> Result<Vec<f64>, EnvError> {
        if start.len() != N {
            return Err(EnvError::Dimension {
                what: "start state",
                got: start.len(),
                expected: N,
            });
        }
        if let Some(i) = start.iter().position(|v| !v.is_finite()) {
            return Err(EnvError::NonFiniteStart {
                field: P::STATE_NAMES[i].to_string(),
                value: start[i],
            });
        }
        let z: [f64; N] = std::array::from_fn(|i| start[i]);
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let obs = observe(&z, &self.scenario.noise_std, &mut rng);
        self.episode = Some(Episode { z, steps: 0, rng });
        Ok(obs)
    }

    fn step(&mut self, action: &[f64]) -> Result<Step, EnvError> {
        let (steps, z0) = match &self.episode {
            None => return Err(EnvError::NotReset),
            Some(e) => (e.steps, e.z),
        };
        let s = &self.scenario;
        if steps >= s.horizon {
            return Err(EnvError::EpisodeOver {
                t: steps as f64 * s.dt,
            });
        }
        let u = self.check_action(action)?;
        let physics = &s.physics;
        let z = ode::integrate(
            &|z: &[f64; N]| physics.derivative(z, u),
            z0,
            s.dt,
            s.substeps,
        );
        let t = (steps + 1) as f64 * s.dt;
        if let Some(i) = z.iter().position(|v| !v.is_finite()) {
            self.episode = None;
            return Err(EnvError::Diverged {
                t,
                detail: format!("{} = {}", P::STATE_NAMES[i], z[i]),
            });
        }
        let e = self.episode.as_mut().expect("checked above");
        e.z = z;
        e.steps = steps + 1;
        let observation = observe(&z, &s.noise_std, &mut e.rng);
        let values = BTreeMap::from([
            ("action".to_string(), u),
            ("cost".to_string(), s.immediate_cost(&z)),
            ("energy".to_string(), physics.energy(&z)),
            ("tip_distance".to_string(), s.tip_distance(&z)),
        ]);
        Ok(Step {
            observation,
            info: StepInfo {
                t,
                true_state: z.to_vec(),
                reference: None,
                flags: BTreeMap::new(),
                values,
                stopped_early: None,
            },
            done: e.steps == s.horizon,
        })
    }
}

#[cfg(test)]
mod tests;
