//! The recorded return of constant stiffness on the arm, over a grid of (k_x, k_y).
//!
//! Why: the VIL runs alternate between roll-outs that insert and roll-outs that stop on the
//! insertion spring, with returns a few units apart. This shows, without any learning, how far
//! the task's cost separates the two outcomes: per constant gain pair, whether the peg
//! inserts, where it stops, the largest contact force and the return (all of it and its last
//! 5 s, where insertion happens), each from the same start and noise seed as the runs'
//! constant-gain check.
//!
//! `cargo run --release -p vicpilco-experiments --example gain_sweep -- [EXPERIMENT] [SEED]`
//! (defaults: vil-gic-rbf10, seed 1). The gains are clipped to the config's [k_min, k_max].

use anyhow::{Context, Result};
use vicpilco_env::arm::ArmEnv;
use vicpilco_experiments::{arm, config};
use vicpilco_learn::outer::{derive_seed, rollout, LoopSetup};
use vicpilco_pilco::policy::RbfPolicy;

const KX: [f64; 13] = [
    25.0, 50.0, 75.0, 100.0, 120.0, 130.0, 135.0, 140.0, 145.0, 150.0, 175.0, 200.0, 250.0,
];
const KY: [f64; 3] = [25.0, 127.5, 250.0];
/// Indices of f_x, f_y in the arm's state (x, y, ẋ, ẏ, f_x, f_y).
const FORCE: [usize; 2] = [4, 5];

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let name = args.get(1).map_or("vil-gic-rbf10", String::as_str);
    let seed: u64 = args.get(2).map_or(Ok(1), |s| s.parse())?;
    let (label, text) = config::shipped(name).context("unknown experiment")?;
    let cfg = config::parse(text, label)?;
    anyhow::ensure!(
        !arm::is_linear(&cfg),
        "{name}: pick an RBF config (the gains, not the policy, are swept; the simulator is the same)"
    );
    let (setup, mut env) = arm::setup(&cfg, arm::rbf_policy(&cfg, 0)?, seed)?;
    let (k_min, k_max) = (cfg.policy.k_min, cfg.policy.k_max);
    println!("{name}, seed {seed}: constant (k_x, k_y) clipped to [{k_min}, {k_max}] N/m");
    println!(
        "{:>7}{:>7}{:>10}{:>10}{:>9}{:>10}{:>12}",
        "k_x", "k_y", "inserts", "final x", "max |f|", "return", "last 5 s"
    );
    for ky in KY {
        for kx in KX {
            let gains = [kx.clamp(k_min, k_max), ky.clamp(k_min, k_max)];
            let (ok, final_x, max_f, ret, tail) = constant(&setup, &mut env, seed, gains)?;
            println!(
                "{:>7.1}{:>7.1}{:>10}{:>10.3}{:>9.1}{:>10.2}{:>12.2}",
                gains[0], gains[1], ok, final_x, max_f, ret, tail
            );
        }
    }
    Ok(())
}

/// Inserted, final x, max contact force, return, and return over the last 5 s.
fn constant(
    setup: &LoopSetup<RbfPolicy>,
    env: &mut ArmEnv,
    seed: u64,
    gains: [f64; 2],
) -> Result<(bool, f64, f64, f64, f64)> {
    let start = setup
        .env_start
        .sample(derive_seed(seed, 0, arm::PURPOSE_EVALUATION))?;
    let r = rollout(
        env,
        &start,
        derive_seed(seed, 1, arm::PURPOSE_EVALUATION),
        |_, _| Ok(gains.to_vec()),
    )?;
    let costs = setup.recorded_costs(&r);
    let half = costs.len() / 2;
    let max_f = r
        .true_states
        .iter()
        .map(|s| s[FORCE[0]].hypot(s[FORCE[1]]))
        .fold(0.0, f64::max);
    let final_x = r.true_states.last().map_or(f64::NAN, |s| s[0]);
    Ok((
        arm::inserted(&r),
        final_x,
        max_f,
        setup.recorded_return(&r),
        costs[half..].iter().sum(),
    ))
}
