//! Profiler driver (valgrind --tool=callgrind, perf) and load-robust timer: forward and
//! backward moment matching on W1 (N = 300, D = 8, E = 6), `reps` times (first argument).
//! Prints wall time and process CPU time per call (utime + stime from /proc/self/stat), the
//! latter being meaningful on a loaded machine when run with RAYON_NUM_THREADS=1.
use faer::Mat;
use vicpilco_bench::W1;
use vicpilco_gp::moments::{backward, forward, MmModel, MomentsAdjoint};

fn cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    // Fields after the parenthesised command name; utime and stime are fields 14 and 15.
    let rest = stat.rsplit_once(')').map_or("", |(_, r)| r);
    let f: Vec<f64> = rest
        .split_whitespace()
        .filter_map(|v| v.parse().ok())
        .collect();
    // rest starts at field 3 (state is not numeric and was filtered out): utime = f[10].
    (f.get(10).copied().unwrap_or(0.0) + f.get(11).copied().unwrap_or(0.0)) / 100.0
}

fn main() {
    let w1 = W1::load(&vicpilco_bench::default_dir().join("w1.json")).unwrap();
    let gp = w1.dynamics_gp().unwrap();
    let mm = MmModel::with_uncertainty(&gp);
    let m = vec![0.1; 8];
    let s = Mat::from_fn(8, 8, |i, j| if i == j { 0.1 } else { 0.01 });
    let reps: usize = std::env::args().nth(1).map_or(1, |v| v.parse().unwrap());
    let e = 6;
    let sbar = Mat::from_fn(e, e, |i, j| (i + j) as f64);
    let vbar = Mat::from_fn(8, e, |i, j| (i * j) as f64);
    let ones = vec![1.0; e];
    let adj = MomentsAdjoint {
        mean: &ones,
        cov: sbar.as_ref(),
        v: vbar.as_ref(),
    };
    let (_, cache) = forward(&mm, &m, s.as_ref()).unwrap();
    let (t, c) = (std::time::Instant::now(), cpu_seconds());
    for _ in 0..reps {
        std::hint::black_box(forward(&mm, &m, s.as_ref()).unwrap());
    }
    let (fw, fc) = (
        t.elapsed().as_secs_f64() / reps as f64,
        (cpu_seconds() - c) / reps as f64,
    );
    let (t, c) = (std::time::Instant::now(), cpu_seconds());
    for _ in 0..reps {
        std::hint::black_box(backward(&mm, &cache, adj, false).unwrap());
    }
    let (bw, bc) = (
        t.elapsed().as_secs_f64() / reps as f64,
        (cpu_seconds() - c) / reps as f64,
    );
    println!(
        "forward:  {:.3} ms wall, {:.3} ms CPU per call",
        fw * 1e3,
        fc * 1e3
    );
    println!(
        "backward: {:.3} ms wall, {:.3} ms CPU per call (ratio {:.2} CPU)",
        bw * 1e3,
        bc * 1e3,
        bc / fc
    );
}
