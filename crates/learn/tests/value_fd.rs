//! dJ/dψ from the reverse sweep against central finite differences of J, over the variants
//! the learning loop uses: linear and RBF policies, with and without squashing (symmetric and
//! non-negative), relative and absolute targets, an angle (trig augmentation), time as an
//! input, a prior-mean shift, linear prior terms, the std and energy terms, discounting and
//! K > 1 starts. Each variant must also give the same J and dJ/dψ, bit for bit, on one thread
//! and on several.

use faer::Mat;
use rand::{RngExt, SeedableRng};
use rand_distr::StandardNormal;
use vicpilco_gp::fd::{directional, rel_diff};
use vicpilco_gp::moments::MmModel;
use vicpilco_gp::{GpModel, Hyper};
use vicpilco_learn::step::{LinearPrior, Predictor, StepSpec, Target};
use vicpilco_learn::value::{value, ReturnSpec};
use vicpilco_pilco::cost::{CostSum, EnergyCost, SaturatingCost};
use vicpilco_pilco::policy::{LinearPolicy, Policy, RbfPolicy};
use vicpilco_pilco::squash::{PartialSat, SatRange};

type Rng = rand::rngs::ChaCha8Rng;

fn normal(rng: &mut Rng) -> f64 {
    rng.sample(StandardNormal)
}

fn random_gp(rng: &mut Rng, n: usize, d_in: usize, d_out: usize) -> GpModel {
    let x = Mat::from_fn(n, d_in, |_, _| normal(rng));
    let y = Mat::from_fn(n, d_out, |i, j| {
        0.3 * (x[(i, j % d_in)] + 0.5 * x[(i, d_in - 1)]).sin() + 0.01 * normal(rng)
    });
    let hyp = (0..d_out)
        .map(|_| Hyper {
            log_ls: (0..d_in)
                .map(|_| 0.3 + 0.5 * rng.random_range(0.0..1.0))
                .collect(),
            log_sf: -1.0,
            log_sn: -4.0,
        })
        .collect();
    GpModel::new(x, y, hyp).unwrap()
}

struct Variant {
    name: &'static str,
    rbf: bool,
    squash: Option<Vec<SatRange>>,
    angles: Vec<usize>,
    time_input: bool,
    targets: Vec<Target>,
    /// (target, state, coefficient) terms of the targets' prior means.
    linear_prior: Vec<(usize, usize, f64)>,
    prior_shift: bool,
    w_std: f64,
    energy: bool,
    gamma: f64,
    starts: usize,
    /// Angles augmented before the state cost (a cost on their sine and cosine is added).
    cost_angles: Vec<usize>,
}

/// A linear, unsquashed policy on three relative targets with no cost extras; each test
/// names only what it changes.
fn plain(name: &'static str) -> Variant {
    Variant {
        name,
        rbf: false,
        squash: None,
        angles: vec![],
        time_input: false,
        targets: vec![Target::Relative; 3],
        linear_prior: vec![],
        prior_shift: false,
        w_std: 0.0,
        energy: false,
        gamma: 1.0,
        starts: 1,
        cost_angles: vec![],
    }
}

/// Checks dJ/dψ against finite differences and returns J and dJ/dψ at the variant's ψ₀.
fn check(v: Variant, seed: u64) -> (f64, Vec<f64>) {
    let mut rng = Rng::seed_from_u64(seed);
    let d0 = v.targets.len();
    let u = 2;
    let spec = StepSpec {
        state_dim: d0,
        angles: v.angles.clone(),
        time_input: v.time_input,
        policy_inputs: (0..d0 + 2 * v.angles.len() + v.time_input as usize)
            .filter(|&i| !v.angles.contains(&i))
            .collect(),
        dyn_inputs: (0..d0 + 2 * v.angles.len() + v.time_input as usize)
            .filter(|&i| !v.angles.contains(&i))
            .collect(),
        targets: v.targets.clone(),
        linear_prior: v
            .linear_prior
            .iter()
            .map(|&(target, state, coefficient)| LinearPrior {
                target,
                state,
                coefficient,
            })
            .collect(),
        dt: 0.1,
    };
    let p_in = spec.policy_inputs.len();
    let gp = random_gp(&mut rng, 25, spec.dyn_inputs.len() + u, d0);
    let horizon = 5;
    let shift: Vec<Vec<f64>> = (0..horizon)
        .map(|t| (0..d0).map(|k| 0.01 * (t + k) as f64).collect())
        .collect();
    let squash = v
        .squash
        .as_ref()
        .map(|r| PartialSat::new(u, &[0, 1], r).unwrap());
    let mut costs =
        vec![SaturatingCost::new(&[0], Mat::from_fn(1, 1, |_, _| 4.0).as_ref(), &[0.5]).unwrap()];
    if d0 > 2 {
        costs.push(
            SaturatingCost::new(
                &[1, 2],
                Mat::from_fn(2, 2, |i, j| if i == j { 2.0 } else { 0.3 }).as_ref(),
                &[0.1, -0.2],
            )
            .unwrap(),
        );
    }
    if !v.cost_angles.is_empty() {
        costs.push(
            SaturatingCost::new(
                &[d0, d0 + 1],
                Mat::from_fn(2, 2, |i, j| if i == j { 1.5 } else { 0.2 }).as_ref(),
                &[0.0, -1.0],
            )
            .unwrap(),
        );
    }
    let n_cost_dims = d0 + 2 * v.cost_angles.len();
    let ret = ReturnSpec {
        state_cost: Some(CostSum::new(n_cost_dims, costs).unwrap()),
        cost_angles: v.cost_angles.clone(),
        w_mean: 1.0,
        w_std: v.w_std,
        energy: v
            .energy
            .then(|| (EnergyCost::new(&[2.0, 3.0], &[true, true]).unwrap(), 0.05)),
        gamma: v.gamma,
        horizon,
    };
    let starts: Vec<(Vec<f64>, Mat<f64>)> = (0..v.starts)
        .map(|k| {
            let m: Vec<f64> = (0..d0).map(|i| 0.1 * (i + k) as f64).collect();
            let s = Mat::from_fn(d0, d0, |i, j| if i == j { 0.02 } else { 0.003 });
            (m, s)
        })
        .collect();
    let shift_opt = v.prior_shift.then_some(shift.as_slice());
    let problem = Problem {
        spec: &spec,
        squash: squash.as_ref(),
        gp: &gp,
        shift: shift_opt,
        ret: &ret,
        starts: &starts,
    };
    let run = |params: &[f64], with_grad: bool| -> (f64, Option<Vec<f64>>) {
        if v.rbf {
            let mut pol = rbf_template(p_in, u);
            pol.set_params(params).unwrap();
            problem.evaluate(&pol, with_grad)
        } else {
            let mut pol = LinearPolicy::zeros(p_in, u);
            pol.set_params(params).unwrap();
            problem.evaluate(&pol, with_grad)
        }
    };
    let p0: Vec<f64> = if v.rbf {
        let mut p = rbf_template(p_in, u).params();
        let n_hyp = (p_in + 2) * u;
        for x in p[n_hyp..].iter_mut() {
            *x += 0.3 * normal(&mut rng);
        }
        p
    } else {
        (0..u + u * p_in).map(|_| 0.3 * normal(&mut rng)).collect()
    };
    let (j0, grad) = run(&p0, true);
    assert!(j0.is_finite());
    let grad = grad.unwrap();
    // Runs are reproduced on machines with other core counts (and resumed with another
    // RAYON_NUM_THREADS), so J and dJ/dψ must not depend on how the work is split.
    for threads in [1, 3] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let (j, g) = pool.install(|| run(&p0, true));
        assert_eq!(
            (j, g.as_deref()),
            (j0, Some(grad.as_slice())),
            "{} on {threads} threads",
            v.name
        );
    }
    for trial in 0..3 {
        let dir: Vec<f64> = p0.iter().map(|_| normal(&mut rng)).collect();
        let numeric = directional(&mut |p: &[f64]| run(p, false).0, &p0, &dir, 1e-5);
        let analytic: f64 = grad.iter().zip(&dir).map(|(g, d)| g * d).sum();
        let err = rel_diff(analytic, numeric, 1e-8);
        assert!(
            err < 1e-6,
            "{} trial {trial}: analytic {analytic:.12e} numeric {numeric:.12e} rel {err:.2e}",
            v.name
        );
    }
    (j0, grad)
}

/// Everything but the policy: J (and dJ/dψ) of any policy type.
struct Problem<'a> {
    spec: &'a StepSpec,
    squash: Option<&'a PartialSat>,
    gp: &'a GpModel,
    shift: Option<&'a [Vec<f64>]>,
    ret: &'a ReturnSpec,
    starts: &'a [(Vec<f64>, Mat<f64>)],
}

impl Problem<'_> {
    fn evaluate<P: Policy + Sync>(&self, pol: &P, with_grad: bool) -> (f64, Option<Vec<f64>>)
    where
        P::Cache: Send,
    {
        let pred = Predictor::new(
            self.spec,
            pol,
            self.squash,
            MmModel::with_uncertainty(self.gp),
            self.shift,
        )
        .unwrap();
        let out = value(&pred, self.ret, self.starts, with_grad).unwrap();
        (out.j, out.grad)
    }
}

fn rbf_template(d: usize, e: usize) -> RbfPolicy {
    let nc = 4;
    let centres = Mat::from_fn(nc, d, |i, k| 0.2 * ((i * 3 + k * 5) % 7) as f64 - 0.6);
    let targets = Mat::from_fn(nc, e, |i, a| 0.1 * ((i + 2 * a) % 5) as f64 - 0.2);
    let log_ls = Mat::from_fn(d, e, |k, a| 0.1 * (k + a) as f64);
    RbfPolicy::new(centres, targets, log_ls.as_ref(), 100.0).unwrap()
}

#[test]
fn linear_policy_plain() {
    check(plain("linear, no squash, relative"), 1);
}

#[test]
fn linear_policy_saturated_mixed_targets_energy() {
    check(
        Variant {
            squash: Some(vec![
                SatRange::Symmetric { a_max: 2.0 },
                SatRange::Symmetric { a_max: 3.0 },
            ]),
            targets: vec![Target::Relative, Target::Absolute, Target::Relative],
            w_std: -0.25,
            energy: true,
            gamma: 0.9,
            ..plain("linear, symmetric squash, mixed targets, energy, std")
        },
        2,
    );
}

#[test]
fn rbf_policy_nonnegative_squash_angle() {
    check(
        Variant {
            rbf: true,
            squash: Some(vec![
                SatRange::Bounded {
                    a_min: 0.5,
                    a_max: 3.0,
                },
                SatRange::Symmetric { a_max: 1.5 },
            ]),
            angles: vec![2],
            cost_angles: vec![2],
            ..plain("rbf, partial non-negative squash, angle in dynamics and cost")
        },
        3,
    );
}

#[test]
fn rbf_policy_time_prior_mean_energy_two_starts() {
    check(
        Variant {
            rbf: true,
            squash: Some(vec![
                SatRange::Bounded {
                    a_min: 0.5,
                    a_max: 3.0,
                },
                SatRange::Bounded {
                    a_min: 0.2,
                    a_max: 2.0,
                },
            ]),
            time_input: true,
            targets: vec![Target::Relative, Target::Relative, Target::Absolute],
            prior_shift: true,
            w_std: -0.25,
            energy: true,
            starts: 2,
            ..plain("rbf, time input, prior mean, energy, std, K = 2")
        },
        4,
    );
}

#[test]
fn rbf_policy_unsquashed_absolute() {
    check(
        Variant {
            rbf: true,
            targets: vec![Target::Absolute; 2],
            ..plain("rbf, no squash, absolute targets")
        },
        5,
    );
}

#[test]
fn rbf_policy_linear_prior_terms() {
    check(
        Variant {
            rbf: true,
            squash: Some(vec![
                SatRange::Bounded {
                    a_min: 0.5,
                    a_max: 3.0,
                },
                SatRange::Symmetric { a_max: 1.5 },
            ]),
            targets: vec![Target::Relative, Target::Absolute, Target::Absolute],
            linear_prior: vec![(1, 0, 0.7), (2, 1, -1.3), (2, 2, 0.4), (0, 2, 0.25)],
            w_std: -0.25,
            energy: true,
            ..plain("rbf, linear prior terms on relative and absolute targets")
        },
        6,
    );
}

/// An absolute target whose prior is its own previous value is a relative target: the same J
/// and dJ/dψ, through the prior-term code paths instead of the relative ones.
#[test]
fn a_unit_prior_on_its_own_state_is_a_relative_target() {
    let variant = |targets: Vec<Target>, linear_prior: Vec<(usize, usize, f64)>| Variant {
        squash: Some(vec![
            SatRange::Symmetric { a_max: 2.0 },
            SatRange::Symmetric { a_max: 3.0 },
        ]),
        targets,
        linear_prior,
        prior_shift: true,
        w_std: -0.25,
        ..plain("linear, relative or unit linear prior")
    };
    let (j_rel, g_rel) = check(variant(vec![Target::Relative; 3], vec![]), 7);
    let (j_lin, g_lin) = check(
        variant(
            vec![Target::Relative, Target::Absolute, Target::Absolute],
            vec![(1, 1, 1.0), (2, 2, 1.0)],
        ),
        7,
    );
    assert!(rel_diff(j_lin, j_rel, 1e-12) < 1e-12, "{j_lin} {j_rel}");
    for (a, b) in g_lin.iter().zip(&g_rel) {
        assert!(rel_diff(*a, *b, 1e-12) < 1e-10, "{g_lin:?}\n{g_rel:?}");
    }
}

#[test]
fn a_linear_prior_term_beyond_the_state_or_not_finite_is_refused() {
    let mut rng = Rng::seed_from_u64(8);
    let gp = random_gp(&mut rng, 10, 4, 2);
    let policy = LinearPolicy::zeros(2, 2);
    for (term, says) in [
        ((2, 0, 1.0), "target 2 to state 0"),
        ((0, 3, 1.0), "target 0 to state 3"),
        ((1, 0, f64::NAN), "coefficient NaN"),
    ] {
        let spec = StepSpec {
            state_dim: 2,
            angles: vec![],
            time_input: false,
            policy_inputs: vec![0, 1],
            dyn_inputs: vec![0, 1],
            targets: vec![Target::Absolute; 2],
            linear_prior: vec![LinearPrior {
                target: term.0,
                state: term.1,
                coefficient: term.2,
            }],
            dt: 0.1,
        };
        let err = Predictor::new(&spec, &policy, None, MmModel::with_uncertainty(&gp), None)
            .err()
            .expect("refused")
            .to_string();
        assert!(err.contains("linear_prior") && err.contains(says), "{err}");
    }
}

/// `value` and `Predictor::step` check what they are given against the predictor's state and
/// actions (the loop's `check_against` shares these checks), where a start or return of the
/// wrong size used to panic inside the prediction.
#[test]
fn value_and_step_refuse_starts_and_costs_that_do_not_fit_naming_them() {
    let mut rng = Rng::seed_from_u64(9);
    let gp = random_gp(&mut rng, 10, 3, 2);
    let spec = StepSpec {
        state_dim: 2,
        angles: vec![],
        time_input: false,
        policy_inputs: vec![0, 1],
        dyn_inputs: vec![0, 1],
        targets: vec![Target::Relative; 2],
        linear_prior: vec![],
        dt: 0.1,
    };
    let policy = LinearPolicy::zeros(2, 1);
    let pred = Predictor::new(&spec, &policy, None, MmModel::with_uncertainty(&gp), None).unwrap();
    let cost = |d: usize| CostSum::loss_sat(Mat::<f64>::identity(d, d).as_ref(), &vec![0.0; d]);
    let ret = ReturnSpec {
        state_cost: Some(cost(2).unwrap()),
        cost_angles: vec![],
        w_mean: 1.0,
        w_std: 0.0,
        energy: None,
        gamma: 1.0,
        horizon: 3,
    };
    let s1 = Mat::from_fn(1, 1, |_, _| 0.1);
    let s2 = Mat::from_fn(2, 2, |i, j| if i == j { 0.1 } else { 0.0 });
    let good = vec![(vec![0.0, 0.0], s2.clone())];
    let spec_err = |r: Result<vicpilco_learn::value::ValueOut, vicpilco_learn::LearnError>| match r
    {
        Err(vicpilco_learn::LearnError::Spec(msg)) => msg,
        Err(e) => panic!("not a set-up error: {e}"),
        Ok(_) => panic!("accepted"),
    };
    let with = |f: fn(&mut ReturnSpec)| {
        let mut r = ret.clone();
        f(&mut r);
        r
    };
    for (bad_ret, says) in [
        (
            with(|r| {
                r.state_cost =
                    Some(CostSum::loss_sat(Mat::<f64>::identity(3, 3).as_ref(), &[0.0; 3]).unwrap())
            }),
            "ret.state_cost: 3 inputs, but the state with its cost angles has 2",
        ),
        (
            with(|r| r.cost_angles = vec![2]),
            "ret.cost_angles: index 2 ≥ state dimension 2",
        ),
        (
            with(|r| r.energy = Some((EnergyCost::new(&[1.0, 1.0], &[true, true]).unwrap(), 0.1))),
            "ret.energy: 2 inputs for 1 actions",
        ),
    ] {
        assert_eq!(spec_err(value(&pred, &bad_ret, &good, true)), says);
    }
    for (starts, says) in [
        (
            vec![(vec![0.0], s1.clone())],
            "starts: start 0: a mean of 1 and a 1×1 covariance for 2 states",
        ),
        (
            vec![good[0].clone(), (vec![0.0, 0.0], s1.clone())],
            "starts: start 1: a mean of 2 and a 1×1 covariance for 2 states",
        ),
        (
            vec![(vec![0.0, f64::NAN], s2.clone())],
            "starts: start 0: mean entry 1 is NaN",
        ),
        (vec![], "starts: none given (at least one)"),
    ] {
        assert_eq!(spec_err(value(&pred, &ret, &starts, true)), says);
    }
    assert!(value(&pred, &ret, &good, true).is_ok());

    let msg = match pred.step(0, &[0.0], &s1) {
        Err(e) => e.to_string(),
        Ok(_) => panic!("a step from a 1-entry state was accepted"),
    };
    assert_eq!(
        msg,
        "prediction set-up: step input: a mean of 1 and a 1×1 covariance for 2 states"
    );
    assert!(pred.step(0, &[0.0, 0.0], &s2).is_ok());
}
