//! PILCO's pendulum and cart-pole swing-ups as learning problems, with every setting taken
//! from [`vicpilco_env::classic::Scenario`] (PILCO's published values).

use faer::Mat;
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use vicpilco_env::classic::{ClassicEnv, ClassicSystem, Dynamics, Scenario};
use vicpilco_gp::sparse::{InducingOptions, SparseTrainOptions};
use vicpilco_gp::train::Wolfe;
use vicpilco_gp::{DynamicsOptions, TrainOptions};
use vicpilco_learn::joint::Joint;
use vicpilco_learn::outer::{derive_seed, LoopSetup, OptimiserOptions};
use vicpilco_learn::start::StartDistribution;
use vicpilco_learn::step::{StepSpec, Target};
use vicpilco_learn::value::ReturnSpec;
use vicpilco_pilco::cost::{CostSum, SaturatingCost};
use vicpilco_pilco::policy::RbfPolicy;
use vicpilco_pilco::squash::{PartialSat, SatRange, TrigAug};

use crate::ExperimentError;

/// Seed purpose of the policy initialisation (see [`derive_seed`]).
const PURPOSE_POLICY_INIT: u64 = 11;

fn rows(m: &[Vec<f64>]) -> Mat<f64> {
    Mat::from_fn(m.len(), m.first().map_or(0, Vec::len), |i, j| m[i][j])
}

/// PILCO's RBF initialisation: centres drawn from the start distribution mapped to the policy
/// inputs (moment-matched through the trig augmentation), targets `σ_t · randn`.
fn initial_policy<P: ClassicSystem>(
    scn: &Scenario<P>,
    seed: u64,
) -> Result<RbfPolicy, ExperimentError> {
    let d0 = P::STATE_DIM;
    let s0 = rows(&scn.start_cov);
    let mut joint = Joint::new(scn.start_mean.clone(), s0.clone());
    if !scn.angle_indices.is_empty() {
        let trig = TrigAug::new(d0, &scn.angle_indices, &vec![1.0; scn.angle_indices.len()])?;
        let (mo, _) = trig.forward(&scn.start_mean, s0.as_ref());
        joint.append(&(0..d0).collect::<Vec<_>>(), &mo);
    }
    let (m, s) = joint.marginal(&scn.policy_inputs);
    let mut rng = rand::rngs::ChaCha8Rng::seed_from_u64(derive_seed(seed, 0, PURPOSE_POLICY_INIT));
    let chol = vicpilco_gp::linalg::Chol::with_jitter(
        s.as_ref(),
        "policy-input start covariance",
        Default::default(),
    )?;
    let l = chol.l();
    let dp = scn.policy_inputs.len();
    let mut centres = Mat::zeros(scn.n_basis, dp);
    for i in 0..scn.n_basis {
        let z: Vec<f64> = (0..dp).map(|_| StandardNormal.sample(&mut rng)).collect();
        for a in 0..dp {
            centres[(i, a)] = m[a] + (0..=a).map(|k| l[(a, k)] * z[k]).sum::<f64>();
        }
    }
    let targets = Mat::from_fn(scn.n_basis, 1, |_, _| {
        scn.policy_target_std * Distribution::<f64>::sample(&StandardNormal, &mut rng)
    });
    let log_ls = Mat::from_fn(dp, 1, |a, _| scn.policy_lengthscales[a].ln());
    Ok(RbfPolicy::new(
        centres,
        targets,
        log_ls.as_ref(),
        scn.policy_signal_std / scn.policy_noise_std,
    )?)
}

/// The learning problem and the simulator of a classic scenario.
pub fn setup<P, const N: usize>(
    scn: Scenario<P>,
    seed: u64,
) -> Result<(LoopSetup<RbfPolicy>, ClassicEnv<P, N>), ExperimentError>
where
    P: ClassicSystem + Dynamics<N> + Send + Sync + 'static,
{
    scn.validate()?;
    let d0 = P::STATE_DIM;
    let aug = scn.augmented_dim();
    let spec = StepSpec {
        state_dim: d0,
        angles: scn.angle_indices.clone(),
        time_input: false,
        policy_inputs: scn.policy_inputs.clone(),
        dyn_inputs: scn.dyn_inputs.clone(),
        targets: (0..d0)
            .map(|k| {
                if scn.difference_targets.contains(&k) {
                    Target::Relative
                } else {
                    Target::Absolute
                }
            })
            .collect(),
        linear_prior: vec![],
        dt: scn.dt,
    };
    let all: Vec<usize> = (0..aug).collect();
    let target = scn.augmented_target();
    let costs = scn
        .cost_widths
        .iter()
        .map(|&w| SaturatingCost::new(&all, rows(&scn.cost_weight(w)).as_ref(), &target))
        .collect::<Result<Vec<_>, _>>()?;
    let n_widths = scn.cost_widths.len() as f64;
    let ret = ReturnSpec {
        state_cost: Some(CostSum::new(aug, costs)?),
        cost_angles: scn.angle_indices.clone(),
        // PILCO averages the costs of its widths.
        w_mean: 1.0 / n_widths,
        w_std: scn.exploration / n_widths,
        energy: None,
        gamma: scn.discount,
        horizon: scn.horizon,
    };
    let squash = PartialSat::new(
        1,
        &[0],
        &[SatRange::Symmetric {
            a_max: scn.max_action,
        }],
    )?;
    let start = (scn.start_mean.clone(), rows(&scn.start_cov));
    let dynamics = DynamicsOptions {
        sparse_threshold: scn.sparse_inducing,
        train: TrainOptions {
            max_iters: scn.gp_train_full as u64,
            ..TrainOptions::default()
        },
        sparse: SparseTrainOptions {
            num_inducing: scn.sparse_inducing,
            seed,
            hyper: TrainOptions::default(),
            // pilco-matlab's train.m fits the hyper-parameters on every point (≤ 640 here).
            hyper_points: None,
            inducing: InducingOptions {
                max_iters: scn.gp_train_sparse as u64,
                // pilco-matlab's train.m triples the budget of the first sparse fit.
                cold_start_factor: 3,
                ..InducingOptions::default()
            },
        },
    };
    let policy = initial_policy(&scn, seed)?;
    let explore_scn = scn.clone();
    let success_scn = scn.clone();
    let setup = LoopSetup {
        spec,
        squash: Some(squash),
        ret,
        prediction_starts: vec![start.clone(); scn.start_distributions.max(1)],
        env_start: StartDistribution::Gaussian {
            mean: start.0,
            cov: start.1,
        },
        prior_shift: None,
        dynamics,
        model_selection: vicpilco_learn::selection::ModelSelection::Likelihood,
        optimiser: OptimiserOptions {
            length: scn.opt_length as u64,
            mfepls: scn.opt_mfepls as u64,
            memory: scn.opt_memory,
            wolfe: Wolfe::PILCO,
            // PILCO's scenarios are in units where the raw parameters are well scaled.
            scale_params: None,
            // Off, as when the stored swing-up tables were measured (PILCO's own is 100).
            max_slope_ratio: None,
        },
        initial_rollouts: scn.initial_rollouts,
        episodes: scn.policy_updates,
        rollouts_per_episode: 1,
        policy,
        explore: Box::new(move |seed, t, _obs| {
            // One independent uniform action per step, as PILCO's random policy.
            let mut rng = rand::rngs::ChaCha8Rng::seed_from_u64(derive_seed(seed, t as u64, 0));
            vec![explore_scn.random_action(&mut rng)]
        }),
        success: Box::new(move |r| success_scn.success(&r.true_states)),
        seed,
    };
    let env = ClassicEnv::new(scn)?;
    Ok((setup, env))
}
