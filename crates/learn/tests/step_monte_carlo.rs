//! One prediction step's forward moments against Monte Carlo: an independent check of the
//! thesis's extensions to PILCO's step, which the oracle's `value` cases (PILCO's own
//! relative targets only) and the finite-difference tests (gradient against value) cannot
//! catch if the value itself is wrong.
//!
//! With a linear, unsquashed policy and a known time input, the GP's input (state entries and
//! action) is exactly Gaussian, so moment matching gives the exact mean and covariance of the
//! next state: sampling `x_t`, applying the policy, drawing each GP output from its posterior
//! at that input and assembling `x_{t+1}` must reproduce them within the sampling error. The
//! step here mixes every kind of next-state entry the experiments use: relative and absolute
//! targets, linear prior terms (the lead's force prior) and a known prior-mean shift (the
//! reference's increment, thesis §4-1-2), with time among the policy's and the GP's inputs.
//! It runs through the full GP and through a FITC model (PILCO's `gp0` and `gp1`).

use faer::Mat;
use rand::{RngExt, SeedableRng};
use rand_distr::StandardNormal;
use vicpilco_gp::linalg::Chol;
use vicpilco_gp::moments::MmModel;
use vicpilco_gp::{GpModel, Hyper, SparseGpModel};
use vicpilco_learn::step::{LinearPrior, Predictor, StepSpec, Target};
use vicpilco_pilco::policy::{LinearPolicy, Policy};

type Rng = rand::rngs::ChaCha8Rng;

const SAMPLES: usize = 200_000;
/// Standard errors an exact moment may sit from its Monte Carlo estimate. Each of the 3 + 6
/// moments compared has its own standard error, estimated from the samples.
const TOLERANCE_SE: f64 = 5.0;

fn normal(rng: &mut Rng) -> f64 {
    rng.sample(StandardNormal)
}

#[test]
fn step_moments_match_monte_carlo_for_every_kind_of_target() {
    check_step_against_monte_carlo(Dynamics::Full);
}

/// The same through a FITC model on 12 inducing inputs (the VIL runs' model above 300 points).
#[test]
fn sparse_step_moments_match_monte_carlo() {
    check_step_against_monte_carlo(Dynamics::Sparse);
}

#[derive(Clone, Copy, PartialEq)]
enum Dynamics {
    Full,
    Sparse,
}

fn check_step_against_monte_carlo(kind: Dynamics) {
    let mut rng = Rng::seed_from_u64(7);
    let (d0, actions, dt, t) = (3, 2, 0.1, 4);
    let spec = StepSpec {
        state_dim: d0,
        angles: vec![],
        time_input: true,
        // Time is augmented entry 3.
        policy_inputs: vec![0, 1, 3],
        dyn_inputs: vec![0, 2, 3],
        targets: vec![Target::Relative, Target::Absolute, Target::Relative],
        linear_prior: vec![
            LinearPrior {
                target: 1,
                state: 0,
                coefficient: 0.5,
            },
            LinearPrior {
                target: 2,
                state: 1,
                coefficient: -0.3,
            },
        ],
        dt,
    };
    let shift: Vec<Vec<f64>> = (0..10)
        .map(|k| vec![0.02 * k as f64, -0.01, 0.005 * k as f64])
        .collect();

    // A GP on (x0, x2, time, u0, u1) with smooth, clearly nonlinear outputs.
    let gp_dim = spec.dyn_inputs.len() + actions;
    let n = 30;
    let x_train = Mat::from_fn(n, gp_dim, |_, _| normal(&mut rng));
    let y_train = Mat::from_fn(n, d0, |i, e| {
        0.4 * (x_train[(i, e % gp_dim)] + 0.7 * x_train[(i, gp_dim - 1)]).sin()
            + 0.01 * normal(&mut rng)
    });
    let hyp: Vec<Hyper> = (0..d0)
        .map(|e| Hyper {
            log_ls: (0..gp_dim).map(|d| 0.1 * ((d + e) % 4) as f64).collect(),
            log_sf: -0.7,
            log_sn: -3.0,
        })
        .collect();
    let inducing = Mat::from_fn(12, gp_dim, |i, j| x_train[(i, j)]);
    let sparse =
        SparseGpModel::new(x_train.as_ref(), y_train.as_ref(), hyp.clone(), inducing).unwrap();
    let full = GpModel::new(x_train, y_train, hyp).unwrap();
    let dynamics = || match kind {
        Dynamics::Full => MmModel::with_uncertainty(&full),
        Dynamics::Sparse => MmModel::sparse(&sparse),
    };
    let predict = |input: &[f64]| match kind {
        Dynamics::Full => full.predict(input),
        Dynamics::Sparse => sparse.predict(input),
    };

    let w = Mat::from_fn(actions, spec.policy_inputs.len(), |_, _| {
        0.6 * normal(&mut rng)
    });
    let b = [0.3, -0.2];
    let policy = LinearPolicy::new(w.as_ref(), &b).unwrap();
    let predictor = Predictor::new(&spec, &policy, None, dynamics(), Some(&shift)).unwrap();

    let m = vec![0.2, -0.4, 0.1];
    let root = Mat::from_fn(d0, d0, |i, j| 0.3 * ((i + 2 * j) % 3) as f64 - 0.2);
    let s = Mat::from_fn(d0, d0, |i, j| {
        (0..d0).map(|k| root[(i, k)] * root[(j, k)]).sum::<f64>() + if i == j { 0.05 } else { 0.0 }
    });
    let out = predictor.step(t, &m, &s).unwrap();

    let chol = Chol::new(s.as_ref(), "the start covariance").unwrap();
    let l = chol.l();
    let time = t as f64 * dt;
    let mut next = Vec::with_capacity(SAMPLES);
    for _ in 0..SAMPLES {
        let z: Vec<f64> = (0..d0).map(|_| normal(&mut rng)).collect();
        let x: Vec<f64> = (0..d0)
            .map(|i| m[i] + (0..=i).map(|k| l[(i, k)] * z[k]).sum::<f64>())
            .collect();
        let augmented = [x[0], x[1], x[2], time];
        let pick = |idx: &[usize]| -> Vec<f64> { idx.iter().map(|&i| augmented[i]).collect() };
        let u = policy.action(&pick(&spec.policy_inputs));
        let mut gp_input = pick(&spec.dyn_inputs);
        gp_input.extend(&u);
        let (mean, var) = predict(&gp_input).unwrap();
        let x_next: Vec<f64> = (0..d0)
            .map(|k| {
                let y = mean[k] + var[k].sqrt() * normal(&mut rng);
                let previous = if spec.targets[k] == Target::Relative {
                    x[k]
                } else {
                    0.0
                };
                y + previous + spec.linear_prior_mean(k, &x) + shift[t][k]
            })
            .collect();
        next.push(x_next);
    }

    let stats = MonteCarlo::new(&next);
    let worst = stats.worst_gap(&out.next_mean, &out.next_cov);
    assert!(
        worst.0 < TOLERANCE_SE,
        "moment matching is {:.1} standard errors from Monte Carlo at {}",
        worst.0,
        worst.1
    );

    // The check has teeth: a step that dropped the linear prior terms, the prior-mean shift
    // or the relative targets' previous state would sit far outside it.
    let mut no_prior = spec.clone();
    no_prior.linear_prior.clear();
    let mut all_absolute = spec.clone();
    all_absolute.targets = vec![Target::Absolute; d0];
    for (what, mutant, shifted) in [
        ("no linear prior terms", &no_prior, true),
        ("no prior-mean shift", &spec, false),
        ("every target absolute", &all_absolute, true),
    ] {
        let p = Predictor::new(
            mutant,
            &policy,
            None,
            dynamics(),
            shifted.then_some(shift.as_slice()),
        )
        .unwrap();
        let wrong = p.step(t, &m, &s).unwrap();
        let gap = stats.worst_gap(&wrong.next_mean, &wrong.next_cov).0;
        assert!(
            gap > 4.0 * TOLERANCE_SE,
            "{what}: only {gap:.1} standard errors off"
        );
    }
}

/// Sample mean and covariance of the next states, with each moment's standard error.
struct MonteCarlo {
    mean: Vec<f64>,
    mean_se: Vec<f64>,
    /// Lower triangle: `(k, j, covariance, standard error)`.
    cov: Vec<(usize, usize, f64, f64)>,
}

impl MonteCarlo {
    fn new(next: &[Vec<f64>]) -> Self {
        let n = next.len() as f64;
        let d = next[0].len();
        let mean: Vec<f64> = (0..d)
            .map(|k| next.iter().map(|v| v[k]).sum::<f64>() / n)
            .collect();
        let mut cov = Vec::new();
        let mut mean_se = vec![0.0; d];
        for k in 0..d {
            for j in 0..=k {
                let products: Vec<f64> = next
                    .iter()
                    .map(|v| (v[k] - mean[k]) * (v[j] - mean[j]))
                    .collect();
                let c = products.iter().sum::<f64>() / (n - 1.0);
                let spread = products.iter().map(|p| (p - c).powi(2)).sum::<f64>() / n;
                cov.push((k, j, c, (spread / n).sqrt()));
                if j == k {
                    mean_se[k] = (c / n).sqrt();
                }
            }
        }
        Self { mean, mean_se, cov }
    }

    /// The largest distance, in standard errors, of a predicted moment from its sample value,
    /// and which moment it is.
    fn worst_gap(&self, mean: &[f64], cov: &Mat<f64>) -> (f64, String) {
        let means = self.mean.iter().enumerate().map(|(k, &mc)| {
            (
                (mean[k] - mc).abs() / self.mean_se[k],
                format!("mean {k}: {:.6} against {mc:.6}", mean[k]),
            )
        });
        let covs = self.cov.iter().map(|&(k, j, mc, se)| {
            (
                (cov[(k, j)] - mc).abs() / se,
                format!("cov ({k}, {j}): {:.6} against {mc:.6}", cov[(k, j)]),
            )
        });
        means
            .chain(covs)
            .max_by(|a, b| a.0.total_cmp(&b.0))
            .expect("at least one moment")
    }
}
