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
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use std::collections::BTreeMap;

mod cartpole;
pub mod ode;
mod pendulum;
mod scenario;

pub use cartpole::{CartPole, CartPolePhysics, CartPoleScenario};
pub use pendulum::{Pendulum, PendulumPhysics, PendulumScenario};
pub use scenario::{Scenario, SuccessTest};

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
                path: Vec::new(),
            },
            done: e.steps == s.horizon,
        })
    }
}

#[cfg(test)]
mod tests;
