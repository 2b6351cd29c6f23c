//! GP training benchmarks (`cargo bench -p vicpilco-bench --bench train`).
//!
//! * W1 (`w1.json` in `VICPILCO_BENCH_DIR`, default `../shared/bench`): one nlml value +
//!   gradient (N = 300, D = 8), and training all 6 outputs from `train_init_*` to convergence
//!   (L-BFGS, ≤ 100 iterations per output, gradient-norm and relative-change tolerance 1e-6,
//!   PILCO's hypCurb penalty on), with the final values printed once.
//! * Sparse: 2000 points of made-up smooth data (D = 8, E = 6, fixed seed), 300 inducing inputs:
//!   building the FITC model, and one evaluation of the summed FITC nlml with its gradient
//!   w.r.t. the inducing inputs (the unit cost of inducing-input training).
//! * The thesis's VIL size: training 6 outputs on N = 300 points with D = 7 inputs (made-up
//!   smooth data, PILCO's data-spread initialisation).

use criterion::{criterion_group, criterion_main, Criterion};
use faer::Mat;
use rand::rngs::ChaCha8Rng;
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use std::time::Duration;
use vicpilco_bench::{rows_to_mat, W1};
use vicpilco_gp::linalg::JitterPolicy;
use vicpilco_gp::sparse::{fitc_nlml, select_subset};
use vicpilco_gp::train::{initial_hyper, nlml_with_kernel, train, NlmlWorkspace, TrainOptions};
use vicpilco_gp::{Hyper, SparseGpModel, SquaredExponential};

/// W1's training inputs, targets and start point, or `None` (with a notice) when absent.
fn load_w1() -> Option<(Mat<f64>, Mat<f64>, Vec<Hyper>)> {
    let path = vicpilco_bench::default_dir().join("w1.json");
    match W1::load(&path) {
        Ok(w) => Some((rows_to_mat(&w.X), rows_to_mat(&w.Y), w.train_init())),
        Err(e) => {
            eprintln!("{e}; skipping W1 benchmarks");
            None
        }
    }
}

fn bench_w1(c: &mut Criterion) {
    let Some((x, y, init)) = load_w1() else {
        return;
    };
    let opts = TrainOptions::default();
    // Report the fit once.
    let (_, rep) = train(x.as_ref(), y.as_ref(), &init, &opts).expect("W1 trains");
    eprintln!("W1 training (hypCurb penalty on: p = 30, ls = 100, snr = 1000):");
    for (e, o) in rep.outputs.iter().enumerate() {
        eprintln!(
            "  output {e}: objective {:.4} (nlml {:.4}), {} iterations, {} evaluations, {:?}",
            o.objective, o.nlml, o.iterations, o.evaluations, o.termination
        );
    }
    let plain = TrainOptions {
        penalty: None,
        ..Default::default()
    };
    let (_, rep) = train(x.as_ref(), y.as_ref(), &init, &plain).expect("W1 trains");
    eprintln!("W1 training without penalty: nlml {:?}", rep.objectives());

    let y0: Vec<f64> = (0..y.nrows()).map(|i| y[(i, 0)]).collect();
    let mut g = c.benchmark_group("w1");
    g.sample_size(20);
    // As in the training loop: buffers reused between evaluations.
    let mut ws = NlmlWorkspace::new(x.nrows());
    g.bench_function("nlml_value_and_gradient_n300_d8", |b| {
        b.iter(|| {
            nlml_with_kernel(
                &SquaredExponential,
                x.as_ref(),
                &y0,
                &init[0],
                JitterPolicy::default(),
                &mut ws,
            )
            .unwrap()
        })
    });
    g.sample_size(10).measurement_time(Duration::from_secs(8));
    g.bench_function("train_6_outputs_penalty", |b| {
        b.iter(|| train(x.as_ref(), y.as_ref(), &init, &opts).unwrap())
    });
    g.finish();
}

/// n × d inputs, e smooth outputs with noise 0.01, and hyper-parameters from data spreads
/// (length-scales = input std, σ_f = target std, σ_n = σ_f/10, as pilco-matlab initialises).
fn smooth_problem(
    n: usize,
    d: usize,
    e: usize,
    m: usize,
) -> (Mat<f64>, Mat<f64>, Vec<Hyper>, Mat<f64>) {
    let mut rng = ChaCha8Rng::seed_from_u64(20261127);
    let x: Mat<f64> = Mat::from_fn(n, d, |_, _| StandardNormal.sample(&mut rng));
    let y = Mat::from_fn(n, e, |i, k| {
        let s: f64 = (0..d)
            .map(|c| x[(i, c)] * (1.0 + 0.1 * ((c + k) % 3) as f64))
            .sum();
        (0.5 * s).sin()
            + 0.3 * (x[(i, k)]).cos()
            + 0.01 * Distribution::<f64>::sample(&StandardNormal, &mut rng)
    });
    // PILCO's first guess: the workload the bench times starts where training starts.
    let hyp = initial_hyper(x.as_ref(), y.as_ref());
    let sub = select_subset(n, m, 1);
    let u = Mat::from_fn(m, d, |i, c| x[(sub[i], c)]);
    (x, y, hyp, u)
}

fn bench_sparse(c: &mut Criterion) {
    let (x, y, hyp, u) = smooth_problem(2000, 8, 6, 300);
    let mut g = c.benchmark_group("sparse_n2000_m300_d8_e6");
    g.sample_size(10).measurement_time(Duration::from_secs(8));
    g.bench_function("build_model", |b| {
        b.iter(|| SparseGpModel::new(x.as_ref(), y.as_ref(), hyp.clone(), u.clone()).unwrap())
    });
    let ys: Vec<Vec<f64>> = (0..6)
        .map(|k| (0..x.nrows()).map(|i| y[(i, k)]).collect())
        .collect();
    g.bench_function("fitc_nlml_grad_one_output", |b| {
        b.iter(|| fitc_nlml(x.as_ref(), &ys[0], &hyp[0], u.as_ref()).unwrap())
    });
    g.finish();
}

fn bench_vil_size(c: &mut Criterion) {
    let (x, y, hyp, _) = smooth_problem(300, 7, 6, 1);
    let opts = TrainOptions::default();
    let mut g = c.benchmark_group("vil_n300_d7_e6");
    g.sample_size(10).measurement_time(Duration::from_secs(8));
    g.bench_function("train_6_outputs_penalty", |b| {
        b.iter(|| train(x.as_ref(), y.as_ref(), &hyp, &opts).unwrap())
    });
    g.finish();
}

criterion_group!(benches, bench_w1, bench_sparse, bench_vil_size);
criterion_main!(benches);
