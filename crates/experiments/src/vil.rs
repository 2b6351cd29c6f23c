//! The thesis's VIL experiment (§5-4, Tables 5-1 to 5-4): learn stiffness profiles (k_x, k_y)
//! along the given min-jerk plan for the peg-in-hole task on the simulated arm under GIC.
//!
//! Settings (ours where the thesis is silent, as issue 6 fixes them): Δt = 0.1 s, H = 100;
//! GP inputs (x, y, ẋ, ẏ, t, k_x, k_y); targets Δx, Δy, Δẋ, Δẏ relative, each minus the
//! reference's increment over the step (prior mean), f_x, f_y absolute; full GP up to 300
//! points, FITC with 300 inducing inputs above; RBF policy with 10 basis functions on
//! (x, y, ẋ, ẏ) → (k_x, k_y) ∈ [5, 250] N/m (partial non-negative saturation); saturating costs
//! on (x, y) (target (0.75, 0.20), width 0.05 m) and on (f_x, f_y) (target 0, width 20 N),
//! w2 = −0.25 on the std of their sum, w3 = 0.01 on the energy of (k_x, k_y) with
//! S = diag(250²); L-BFGS with Length 50, MFEPLS 25; one initial roll-out with OU stiffness.

use faer::Mat;
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use vicpilco_env::arm::{ArmConfig, ArmEnv, OuParams};
use vicpilco_gp::sparse::SparseTrainOptions;
use vicpilco_gp::{DynamicsOptions, TrainOptions};
use vicpilco_learn::outer::{derive_seed, LoopSetup, OptimiserOptions};
use vicpilco_learn::step::{StepSpec, Target};
use vicpilco_learn::value::ReturnSpec;
use vicpilco_pilco::cost::{CostSum, EnergyCost, SaturatingCost};
use vicpilco_pilco::policy::RbfPolicy;
use vicpilco_pilco::squash::{PartialSat, SatRange};

use crate::ExperimentError;

/// Every number of the VIL experiment, with the thesis's or the values as defaults.
#[derive(Clone, Debug, serde::Serialize)]
pub struct VilSettings {
    pub horizon: usize,
    pub dt: f64,
    /// Stiffness limits of the policy (N/m).
    pub k_min: f64,
    pub k_max: f64,
    pub n_basis: usize,
    /// Initial RBF length-scales for (x, y, ẋ, ẏ) (ours).
    pub policy_lengthscales: [f64; 4],
    /// Std of the initial pseudo-targets (ours, as PILCO: 0.1).
    pub policy_target_std: f64,
    pub position_target: [f64; 2],
    pub position_width: f64,
    pub force_width: f64,
    pub w_std: f64,
    pub w_energy: f64,
    pub opt_length: u64,
    pub opt_mfepls: u64,
    pub episodes: usize,
    pub sparse_threshold: usize,
    pub n_inducing: usize,
    pub gp_line_searches: u64,
    /// Start state (x, y, ẋ, ẏ, f_x, f_y) and its prediction std (ours).
    pub start: [f64; 6],
    pub start_std: [f64; 6],
}

impl Default for VilSettings {
    fn default() -> Self {
        Self {
            horizon: 100,
            dt: 0.1,
            k_min: 5.0,
            k_max: 250.0,
            n_basis: 10,
            policy_lengthscales: [0.1, 0.1, 0.1, 0.1],
            policy_target_std: 0.1,
            position_target: [0.75, 0.20],
            position_width: 0.05,
            force_width: 20.0,
            w_std: -0.25,
            w_energy: 0.01,
            opt_length: 50,
            opt_mfepls: 25,
            episodes: 25,
            sparse_threshold: 300,
            n_inducing: 300,
            gp_line_searches: 300,
            start: [0.5, 0.0, 0.0, 0.0, 0.0, 0.0],
            start_std: [0.002, 0.002, 0.005, 0.005, 0.1, 0.1],
        }
    }
}

fn diag(v: &[f64]) -> Mat<f64> {
    Mat::from_fn(v.len(), v.len(), |i, j| if i == j { v[i] } else { 0.0 })
}

/// The VIL-GIC learning problem (RBF policy) and its arm environment.
pub fn setup(
    st: &VilSettings,
    seed: u64,
) -> Result<(LoopSetup<RbfPolicy>, ArmEnv), ExperimentError> {
    let cfg = ArmConfig::default();
    let reference = cfg.reference.clone();
    let spec = StepSpec {
        state_dim: 6,
        angles: vec![],
        time_input: true,
        policy_inputs: vec![0, 1, 2, 3],
        dyn_inputs: vec![0, 1, 2, 3, 6],
        targets: vec![
            Target::Relative,
            Target::Relative,
            Target::Relative,
            Target::Relative,
            Target::Absolute,
            Target::Absolute,
        ],
        dt: st.dt,
    };
    // Prior mean of the relative targets: the reference's increment over each step.
    let prior_shift: Vec<Vec<f64>> = (0..st.horizon)
        .map(|t| {
            let (a, b) = (
                reference.eval(t as f64 * st.dt),
                reference.eval((t + 1) as f64 * st.dt),
            );
            vec![
                b.x[0] - a.x[0],
                b.x[1] - a.x[1],
                b.xd[0] - a.xd[0],
                b.xd[1] - a.xd[1],
                0.0,
                0.0,
            ]
        })
        .collect();
    let pos_w = 1.0 / (st.position_width * st.position_width);
    let f_w = 1.0 / (st.force_width * st.force_width);
    let costs = vec![
        SaturatingCost::new(&[0, 1], diag(&[pos_w, pos_w]).as_ref(), &st.position_target)?,
        SaturatingCost::new(&[4, 5], diag(&[f_w, f_w]).as_ref(), &[0.0, 0.0])?,
    ];
    let ret = ReturnSpec {
        state_cost: Some(CostSum::new(6, costs)?),
        cost_angles: vec![],
        w_mean: 1.0,
        w_std: st.w_std,
        energy: Some((
            EnergyCost::new(&[st.k_max, st.k_max], &[true, true])?,
            st.w_energy,
        )),
        gamma: 1.0,
        horizon: st.horizon,
    };
    let bounded = SatRange::Bounded {
        a_min: st.k_min,
        a_max: st.k_max,
    };
    let squash = PartialSat::new(2, &[0, 1], &[bounded, bounded])?;
    // Centres along the reference (ours: spreads the basis functions over the task).
    let mut rng = rand::rngs::ChaCha8Rng::seed_from_u64(derive_seed(seed, 0, 11));
    let t_end = st.horizon as f64 * st.dt;
    let centres = Mat::from_fn(st.n_basis, 4, |i, k| {
        let r = reference.eval(t_end * (i as f64 + 0.5) / st.n_basis as f64);
        [r.x[0], r.x[1], r.xd[0], r.xd[1]][k]
    });
    let targets = Mat::from_fn(st.n_basis, 2, |_, _| {
        st.policy_target_std * Distribution::<f64>::sample(&StandardNormal, &mut rng)
    });
    let log_ls = Mat::from_fn(4, 2, |k, _| st.policy_lengthscales[k].ln());
    let policy = RbfPolicy::new(centres, targets, log_ls.as_ref(), 100.0)?;
    let start_cov = diag(&st.start_std.map(|s| s * s));
    let ou = OuParams {
        a_min: st.k_min,
        a_max: st.k_max,
        dt: st.dt,
        ..OuParams::default()
    };
    let horizon = st.horizon;
    let end_x = cfg.geometry.end_x() - cfg.insert_tolerance;
    let env = ArmEnv::new(cfg)?;
    let setup = LoopSetup {
        spec,
        squash: Some(squash),
        ret,
        prediction_starts: vec![(st.start.to_vec(), start_cov.clone())],
        env_start: (st.start.to_vec(), Mat::zeros(6, 6)),
        prior_shift: Some(prior_shift),
        dynamics: DynamicsOptions {
            sparse_threshold: st.sparse_threshold,
            train: TrainOptions {
                max_iters: st.gp_line_searches,
                ..TrainOptions::default()
            },
            sparse: SparseTrainOptions {
                num_inducing: st.n_inducing,
                seed,
                ..SparseTrainOptions::default()
            },
        },
        optimiser: OptimiserOptions {
            length: st.opt_length,
            mfepls: st.opt_mfepls,
            memory: 10,
        },
        initial_rollouts: 1,
        episodes: st.episodes,
        policy,
        explore: Box::new(move |seed, t, _obs| {
            let k = ou.profiles(horizon, seed)[t.min(horizon - 1)];
            k.to_vec()
        }),
        success: Box::new(move |r| {
            let in_hole = r
                .infos
                .last()
                .and_then(|i| i.flags.get("in_hole"))
                .copied()
                .unwrap_or(false);
            in_hole && r.true_states.last().is_some_and(|s| s[0] >= end_x)
        }),
        seed,
    };
    Ok((setup, env))
}
