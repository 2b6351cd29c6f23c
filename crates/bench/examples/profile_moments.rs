//! Profiler driver (valgrind --tool=callgrind, perf): forward+backward moment matching on W1,
//! `reps` times (first argument), printing the mean wall time per call.
use faer::Mat;
use vicpilco_bench::W1;
use vicpilco_gp::moments::{backward, forward, MmModel, MomentsAdjoint};
fn main() {
    let w1 = W1::load(&vicpilco_bench::default_dir().join("w1.json")).unwrap();
    let gp = w1.dynamics_gp().unwrap();
    let mm = MmModel::with_uncertainty(&gp);
    let m = vec![0.1; 8];
    let s = Mat::from_fn(8, 8, |i, j| if i == j { 0.1 } else { 0.01 });
    let reps: usize = std::env::args().nth(1).map_or(1, |v| v.parse().unwrap());
    let t = std::time::Instant::now();
    let mut tf = std::time::Duration::ZERO;
    for _ in 0..reps {
        let t0 = std::time::Instant::now();
        let (mo, cache) = forward(&mm, &m, s.as_ref()).unwrap();
        tf += t0.elapsed();
        let e = 6;
        let sbar = Mat::from_fn(e, e, |i, j| (i + j) as f64);
        let vbar = Mat::from_fn(8, e, |i, j| (i * j) as f64);
        let ones = vec![1.0; e];
        backward(
            &mm,
            &cache,
            MomentsAdjoint {
                mean: &ones,
                cov: sbar.as_ref(),
                v: vbar.as_ref(),
            },
            false,
        )
        .unwrap();
        std::hint::black_box(mo);
    }
    eprintln!(
        "{:?} per fwd+bwd, {:?} per fwd",
        t.elapsed() / reps as u32,
        tf / reps as u32
    );
}
