//! The expected return over H = 100 steps on workload W1 (N = 300, D+U = 8, E = 6): value
//! alone against value + gradient, with RBF policies of 10, 50 (W1's own) and 100 basis
//! functions — the reverse sweep's cost must not grow with the number of policy parameters.

use criterion::{criterion_group, criterion_main, Criterion};
use faer::Mat;
use std::hint::black_box;
use vicpilco_bench::W1;
use vicpilco_learn::value::value;
use vicpilco_pilco::policy::RbfPolicy;

fn bench(c: &mut Criterion) {
    let path = vicpilco_bench::default_dir().join("w1.json");
    let w1 = match W1::load(&path) {
        Ok(w) => w,
        Err(e) => {
            eprintln!("skipping the W1 value benchmarks: {e}");
            return;
        }
    };
    let mut g = c.benchmark_group("value_w1_H100");
    g.sample_size(10);
    for n_basis in [10usize, 50, 100] {
        let mut pb = w1.problem().unwrap();
        if n_basis != w1.n_basis {
            // Centres and targets cycle through W1's own, shifted so they stay distinct.
            let src = pb.policy.centres().to_owned();
            let tgt = pb.policy.targets().to_owned();
            let n = src.nrows();
            let centres = Mat::from_fn(n_basis, src.ncols(), |i, k| {
                src[(i % n, k)] + 0.01 * (i / n) as f64
            });
            let targets = Mat::from_fn(n_basis, tgt.ncols(), |i, k| tgt[(i % n, k)]);
            let log_ls = Mat::from_fn(src.ncols(), tgt.ncols(), |k, a| {
                pb.policy.hyp()[a].log_ls[k]
            });
            pb.policy = RbfPolicy::new(centres, targets, log_ls.as_ref(), 100.0).unwrap();
        }
        let pred = pb.predictor().unwrap();
        let starts = std::slice::from_ref(&pb.start);
        g.bench_function(format!("value_nc{n_basis}"), |b| {
            b.iter(|| value(&pred, &pb.ret, black_box(starts), false).unwrap())
        });
        g.bench_function(format!("value_grad_nc{n_basis}"), |b| {
            b.iter(|| value(&pred, &pb.ret, black_box(starts), true).unwrap())
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
