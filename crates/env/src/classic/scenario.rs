//! A classic benchmark's settings ([`Scenario`]) and their validation, every error naming
//! the field.

use super::ClassicSystem;
use crate::error::{non_negative, positive};
use crate::EnvError;
use rand::{Rng, RngExt};
use rand_distr::{Distribution, StandardNormal};

/// When an episode counts as solved (ours, not PILCO's). See the module docs.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
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
/// [`PendulumScenario`](super::PendulumScenario) and [`CartPoleScenario`](super::CartPoleScenario)
/// for the numbers and their sources).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
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
        // The cost's Q is written for the system's own augmented layout; any other number of
        // angles would index past it (or leave the cost blind to the angle).
        let cost_dim = P::cost_q(self.cost_length).len();
        if na != cost_dim {
            return Err(EnvError::config(
                "scenario.angle_indices",
                format!("{:?}", self.angle_indices),
                format!(
                    "{} index long: the cost's Q covers {cost_dim} augmented entries, the {n} \
                     states and a sine and cosine per angle",
                    cost_dim.saturating_sub(n) / 2
                ),
            ));
        }
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
