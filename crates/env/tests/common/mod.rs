//! Shared helpers of the arm scenario tests.
#![allow(dead_code)]

use vicpilco_env::arm::{ArmConfig, ArmEnv, TickRecord};
use vicpilco_env::{Environment, Step};

/// Runs `steps` learning steps from (x, y) at rest with constant stiffness `k`, recording the
/// per-tick trace. Returns the environment (for its trace) and the steps.
pub fn run(
    mut cfg: ArmConfig,
    start: [f64; 2],
    k: [f64; 2],
    seed: u64,
    steps: usize,
) -> (ArmEnv, Vec<Step>) {
    cfg.record_trace = true;
    cfg.horizon = steps;
    let mut env = ArmEnv::new(cfg).expect("valid config");
    env.reset(&[start[0], start[1], 0.0, 0.0, 0.0, 0.0], seed)
        .expect("reset");
    let mut out = Vec::with_capacity(steps);
    for _ in 0..steps {
        let s = env.step(&k).expect("step");
        let done = s.done;
        out.push(s);
        if done {
            break;
        }
    }
    (env, out)
}

/// Mean and (population) standard deviation.
pub fn mean_std(v: &[f64]) -> (f64, f64) {
    let n = v.len() as f64;
    let m = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / n;
    (m, var.sqrt())
}

/// Records with t in [t0, t1).
pub fn window(trace: &[TickRecord], t0: f64, t1: f64) -> Vec<TickRecord> {
    trace
        .iter()
        .filter(|r| r.t >= t0 - 1e-12 && r.t < t1 - 1e-12)
        .copied()
        .collect()
}
