//! Moment matching at the thesis's VIL size (N=300, D=7, E=6) and on workload W1
//! (N=300, D=8, E=6): forward, backward (input adjoints), forward+backward.

use criterion::{criterion_group, criterion_main, Criterion};
use faer::Mat;
use rand::{RngExt, SeedableRng};
use rand_distr::StandardNormal;
use std::hint::black_box;
use vicpilco_bench::W1;
use vicpilco_gp::moments::{backward, forward, MmModel, MomentsAdjoint};
use vicpilco_gp::{GpModel, Hyper};

fn random_gp(n: usize, d: usize, e: usize, seed: u64) -> GpModel {
    let mut rng = rand::rngs::ChaCha8Rng::seed_from_u64(seed);
    let x = Mat::from_fn(n, d, |_, _| rng.sample::<f64, _>(StandardNormal));
    let y = Mat::from_fn(n, e, |i, j| {
        (x[(i, j % d)]).sin() + 0.01 * rng.sample::<f64, _>(StandardNormal)
    });
    let hyp = (0..e)
        .map(|_| Hyper {
            log_ls: (0..d).map(|_| rng.random_range(0.0..1.0)).collect(),
            log_sf: 0.0,
            log_sn: -4.0,
        })
        .collect();
    GpModel::new(x, y, hyp).unwrap()
}

fn input(d: usize) -> (Vec<f64>, Mat<f64>) {
    let m = (0..d).map(|k| 0.1 * k as f64).collect();
    let s = Mat::from_fn(d, d, |i, j| if i == j { 0.1 } else { 0.02 });
    (m, s)
}

fn bench_case(c: &mut Criterion, name: &str, gp: &GpModel) {
    let (d, e) = (gp.input_dim(), gp.output_dim());
    let (m, s) = input(d);
    let mm = MmModel::with_uncertainty(gp);
    let mbar = vec![1.0; e];
    let sbar = Mat::from_fn(e, e, |i, j| 1.0 / (1 + i + j) as f64);
    let vbar = Mat::from_fn(d, e, |i, j| 0.1 * (i + j) as f64);
    let adj = MomentsAdjoint {
        mean: &mbar,
        cov: sbar.as_ref(),
        v: vbar.as_ref(),
    };
    let mut g = c.benchmark_group(name);
    g.sample_size(30);
    g.bench_function("forward", |b| {
        b.iter(|| forward(&mm, black_box(&m), s.as_ref()).unwrap())
    });
    let (_, cache) = forward(&mm, &m, s.as_ref()).unwrap();
    g.bench_function("backward", |b| {
        b.iter(|| backward(&mm, black_box(&cache), adj, false).unwrap())
    });
    g.bench_function("forward+backward", |b| {
        b.iter(|| {
            let (_, cache) = forward(&mm, black_box(&m), s.as_ref()).unwrap();
            backward(&mm, &cache, adj, false).unwrap()
        })
    });
    g.finish();
}

fn moments(c: &mut Criterion) {
    bench_case(c, "mm_vil_N300_D7_E6", &random_gp(300, 7, 6, 1));
    let path = vicpilco_bench::default_dir().join("w1.json");
    match W1::load(&path) {
        Ok(w1) => bench_case(c, "mm_w1_N300_D8_E6", &w1.dynamics_gp().unwrap()),
        Err(e) => eprintln!("skipping W1 moment-matching bench: {e}"),
    }
}

criterion_group!(benches, moments);
criterion_main!(benches);
