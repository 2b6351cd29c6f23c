//! GP training benchmarks (`cargo bench -p vicpilco-gp --bench train`).
//!
//! * W1 (`../shared/bench/w1.json`, or the file named by `VICPILCO_W1`): one nlml value +
//!   gradient (N = 300, D = 8), and training all 6 outputs from `train_init_*` to convergence
//!   (L-BFGS, ≤ 100 iterations per output, gradient-norm and relative-change tolerance 1e-6,
//!   PILCO's hypCurb penalty on), with the final values printed once.
//! * Sparse: 2000 points of made-up smooth data (D = 8, E = 6, fixed seed), 300 inducing inputs:
//!   building the FITC model, and one evaluation of the summed FITC nlml with its gradient
//!   w.r.t. the inducing inputs (the unit cost of inducing-input training).

use criterion::{criterion_group, criterion_main, Criterion};
use faer::Mat;
use rand::rngs::ChaCha8Rng;
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use std::path::PathBuf;
use std::time::Duration;
use vicpilco_gp::linalg::JitterPolicy;
use vicpilco_gp::sparse::{fitc_nlml, select_subset};
use vicpilco_gp::train::{input_std, nlml_with_kernel, train, NlmlWorkspace, TrainOptions};
use vicpilco_gp::{Hyper, SparseGpModel, SquaredExponential};

struct W1 {
    x: Mat<f64>,
    y: Mat<f64>,
    init: Vec<Hyper>,
}

fn w1_path() -> PathBuf {
    std::env::var_os("VICPILCO_W1").map_or_else(
        || {
            PathBuf::from(concat!(
                env!("CARGO_MANIFEST_DIR"),
                "/../../../shared/bench/w1.json"
            ))
        },
        PathBuf::from,
    )
}

fn load_w1() -> Option<W1> {
    let path = w1_path();
    let text = match std::fs::read_to_string(&path) {
        Ok(t) => t,
        Err(e) => {
            eprintln!(
                "W1 workload {} not readable ({e}); skipping W1 benchmarks",
                path.display()
            );
            return None;
        }
    };
    let v: serde_json::Value = serde_json::from_str(&text).expect("w1.json is valid JSON");
    let rows = |k: &str| -> Vec<Vec<f64>> {
        serde_json::from_value(v[k].clone()).unwrap_or_else(|e| panic!("w1.json field {k}: {e}"))
    };
    let vec = |k: &str| -> Vec<f64> {
        serde_json::from_value(v[k].clone()).unwrap_or_else(|e| panic!("w1.json field {k}: {e}"))
    };
    let to_mat = |r: &[Vec<f64>]| Mat::from_fn(r.len(), r[0].len(), |i, j| r[i][j]);
    let (x, y) = (to_mat(&rows("X")), to_mat(&rows("Y")));
    let ll = rows("train_init_log_lengthscales");
    let (sf, sn) = (
        vec("train_init_log_signal_std"),
        vec("train_init_log_noise_std"),
    );
    let init = (0..y.ncols())
        .map(|e| Hyper {
            log_ls: (0..x.ncols()).map(|d| ll[d][e]).collect(),
            log_sf: sf[e],
            log_sn: sn[e],
        })
        .collect();
    Some(W1 { x, y, init })
}

fn bench_w1(c: &mut Criterion) {
    let Some(w) = load_w1() else { return };
    let opts = TrainOptions::default();
    // Report the fit once.
    let (_, rep) = train(w.x.as_ref(), w.y.as_ref(), &w.init, &opts).expect("W1 trains");
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
    let (_, rep) = train(w.x.as_ref(), w.y.as_ref(), &w.init, &plain).expect("W1 trains");
    eprintln!("W1 training without penalty: nlml {:?}", rep.objectives());

    let y0: Vec<f64> = (0..w.y.nrows()).map(|i| w.y[(i, 0)]).collect();
    let mut g = c.benchmark_group("w1");
    g.sample_size(20);
    // As in the training loop: buffers reused between evaluations.
    let mut ws = NlmlWorkspace::new(w.x.nrows());
    g.bench_function("nlml_value_and_gradient_n300_d8", |b| {
        b.iter(|| {
            nlml_with_kernel(
                &SquaredExponential,
                w.x.as_ref(),
                &y0,
                &w.init[0],
                JitterPolicy::default(),
                &mut ws,
            )
            .unwrap()
        })
    });
    g.sample_size(10).measurement_time(Duration::from_secs(8));
    g.bench_function("train_6_outputs_penalty", |b| {
        b.iter(|| train(w.x.as_ref(), w.y.as_ref(), &w.init, &opts).unwrap())
    });
    g.finish();
}

/// 2000 × 8 inputs, 6 smooth outputs with noise 0.01, and hyper-parameters from data spreads
/// (length-scales = input std, σ_f = target std, σ_n = σ_f/10, as pilco-matlab initialises).
fn sparse_problem() -> (Mat<f64>, Mat<f64>, Vec<Hyper>, Mat<f64>) {
    let (n, d, e, m) = (2000, 8, 6, 300);
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
    let c = input_std(x.as_ref());
    let hyp = (0..e)
        .map(|k| {
            let col = Mat::from_fn(n, 1, |i, _| y[(i, k)]);
            let sy = input_std(col.as_ref())[0];
            Hyper {
                log_ls: c.iter().map(|v| v.ln()).collect(),
                log_sf: sy.ln(),
                log_sn: (sy / 10.0).ln(),
            }
        })
        .collect();
    let sub = select_subset(n, m, 1);
    let u = Mat::from_fn(m, d, |i, c| x[(sub[i], c)]);
    (x, y, hyp, u)
}

fn bench_sparse(c: &mut Criterion) {
    let (x, y, hyp, u) = sparse_problem();
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

criterion_group!(benches, bench_w1, bench_sparse);
criterion_main!(benches);
