use super::{LoopSetup, OptimiserOptions};
use crate::selection::ModelSelection;
use crate::start::StartDistribution;
use crate::step::{StepSpec, Target};
use crate::value::ReturnSpec;
use faer::Mat;
use vicpilco_gp::fd::{directional, rel_diff};
use vicpilco_gp::moments::MmModel;
use vicpilco_gp::train::Wolfe;
use vicpilco_gp::{DynamicsOptions, GpModel, Hyper};
use vicpilco_pilco::cost::{CostSum, SaturatingCost};
use vicpilco_pilco::policy::{LinearPolicy, Policy};
use vicpilco_pilco::squash::{PartialSat, SatRange};

/// A one-dimensional system `x' = x + 0.1 u` learned from a 5 × 5 grid of (x, u), a linear
/// policy squashed onto [−1, 1], and a saturating cost around x = 1 over 10 steps.
fn problem() -> (LoopSetup<LinearPolicy>, GpModel) {
    let grid = |k: usize| k as f64 / 2.0 - 1.0;
    let inputs = Mat::from_fn(25, 2, |i, j| if j == 0 { grid(i / 5) } else { grid(i % 5) });
    let targets = Mat::from_fn(25, 1, |i, _| 0.1 * inputs[(i, 1)]);
    let hyp = vec![Hyper {
        log_ls: vec![1.0, 0.5],
        log_sf: -1.5,
        log_sn: -5.0,
    }];
    let gp = GpModel::new(inputs, targets, hyp).unwrap();
    let width = Mat::from_fn(1, 1, |_, _| 1.0);
    let cost = SaturatingCost::new(&[0], width.as_ref(), &[1.0]).unwrap();
    let start_cov = Mat::from_fn(1, 1, |_, _| 0.01);
    let setup = LoopSetup {
        spec: StepSpec {
            state_dim: 1,
            angles: vec![],
            time_input: false,
            policy_inputs: vec![0],
            dyn_inputs: vec![0],
            targets: vec![Target::Relative],
            linear_prior: vec![],
            dt: 0.1,
        },
        squash: Some(PartialSat::new(1, &[0], &[SatRange::Symmetric { a_max: 1.0 }]).unwrap()),
        ret: ReturnSpec {
            state_cost: Some(CostSum::new(1, vec![cost]).unwrap()),
            cost_angles: vec![],
            w_mean: 1.0,
            w_std: 0.0,
            energy: None,
            gamma: 1.0,
            horizon: 10,
        },
        prediction_starts: vec![(vec![0.0], start_cov.clone())],
        env_start: StartDistribution::Gaussian {
            mean: vec![0.0],
            cov: start_cov,
        },
        prior_shift: None,
        dynamics: DynamicsOptions::default(),
        model_selection: ModelSelection::Likelihood,
        optimiser: OptimiserOptions {
            length: 2,
            mfepls: 5,
            memory: 5,
            wolfe: Wolfe::PILCO,
            scale_params: None,
            max_slope_ratio: None,
        },
        initial_rollouts: 1,
        episodes: 1,
        rollouts_per_episode: 1,
        policy: LinearPolicy::zeros(1, 1),
        explore: Box::new(|_, _, _| vec![0.0]),
        success: Box::new(|_| false),
        seed: 1,
    };
    (setup, gp)
}

/// The optimiser searches over q = ψ / scale; the gradient it is handed must be dJ/dq =
/// scale ⊙ dJ/dψ, checked here against central differences of J as a function of q. Scales
/// far from 1 and from each other make a missing or inverted factor show.
#[test]
fn the_optimisers_gradient_over_scaled_parameters_matches_central_differences() {
    let (setup, gp) = problem();
    let mm = MmModel::with_uncertainty(&gp);
    let scales = [0.3, 2.5];
    let q = [0.4 / 0.3, 0.6 / 2.5]; // ψ = [b, w] = [0.4, 0.6]
    let mut candidate = setup.policy.clone();
    let (j, grad) = setup.scaled_value(&mut candidate, mm, &scales, &q).unwrap();
    assert_eq!(grad.len(), q.len());
    assert_eq!(candidate.params(), vec![0.4, 0.6]);
    let mut j_of_q = |q: &[f64]| {
        let mut p = setup.policy.clone();
        setup.scaled_value(&mut p, mm, &scales, q).unwrap().0
    };
    assert_eq!(j_of_q(&q), j);
    for dir in [[1.0, 0.0], [0.0, 1.0], [0.6, -0.8]] {
        let fd = directional(&mut j_of_q, &q, &dir, 1e-4);
        let analytic: f64 = grad.iter().zip(&dir).map(|(g, d)| g * d).sum();
        assert!(
            rel_diff(analytic, fd, 1e-6) < 1e-6,
            "along {dir:?}: analytic {analytic}, finite difference {fd}"
        );
    }
}
