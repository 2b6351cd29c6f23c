//! The recorded return of constant stiffness on the arm, over a grid of (k_x, k_y).
//!
//! Why: the VIL runs alternate between roll-outs that insert and roll-outs that stop on the
//! insertion spring, with returns a few units apart. This shows, without any learning, how far
//! the task's cost separates the two outcomes: per constant gain pair, whether the peg
//! inserts, where it stops, the largest contact force and the return (all of it and its last
//! 5 s, where insertion happens), each from the same start and noise seed as the runs'
//! constant-gain check.
//!
//! With `switch`, the gains are not constant but switched on the measured x: k_x = PUSH while
//! x_on < x < x_off (the insertion spring lies at 0.70–0.73 m, the end wall at 0.75 m) and
//! LOW elsewhere, k_y constant. This asks whether the cost itself puts the best policy on the
//! knife-edge of the spring (it does for constant gains) or whether a policy with a wide
//! margin costs about as little.
//!
//! `cargo run --release -p vicpilco-experiments --example gain_sweep -- [EXPERIMENT] [SEED] [switch]`
//! (defaults: vil-gic-rbf10, seed 1, constant gains). The gains are clipped to the config's
//! [k_min, k_max].

use anyhow::{Context, Result};
use vicpilco_env::arm::ArmEnv;
use vicpilco_experiments::{arm, config};
use vicpilco_learn::outer::{derive_seed, rollout, LoopSetup};
use vicpilco_pilco::policy::RbfPolicy;

const KX: [f64; 13] = [
    25.0, 50.0, 75.0, 100.0, 120.0, 130.0, 135.0, 140.0, 145.0, 150.0, 175.0, 200.0, 250.0,
];
const KY: [f64; 3] = [25.0, 127.5, 250.0];
/// `switch` mode: k_x inside the x window (through the spring).
const PUSH: [f64; 4] = [140.0, 160.0, 200.0, 250.0];
/// `switch` mode: k_x outside the window.
const LOW: [f64; 3] = [5.0, 30.0, 80.0];
/// `switch` mode: constant k_y.
const KY_SWITCHED: [f64; 2] = [5.0, 30.0];
/// `switch` mode: (x_on, x_off) windows (m); the last stays stiff against the end wall.
const WINDOWS: [(f64, f64); 3] = [(0.60, 0.74), (0.69, 0.74), (0.69, 0.76)];

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
    if args.get(3).map(String::as_str) == Some("switch") {
        println!("{name}, seed {seed}: k_x switched on x, k_y constant, clipped to [{k_min}, {k_max}] N/m");
        println!(
            "{:>6}{:>6}{:>6}{:>7}{:>7}{:>9}{:>9}{:>9}{:>10}{:>10}",
            "push",
            "low",
            "k_y",
            "x_on",
            "x_off",
            "inserts",
            "final x",
            "max |f|",
            "return",
            "last 5 s"
        );
        for push in PUSH {
            for low in LOW {
                for ky in KY_SWITCHED {
                    for (x_on, x_off) in WINDOWS {
                        let clip = |k: f64| k.clamp(k_min, k_max);
                        let gains = |obs: &[f64]| {
                            let kx = if obs[0] > x_on && obs[0] < x_off {
                                push
                            } else {
                                low
                            };
                            [clip(kx), clip(ky)]
                        };
                        let (ok, final_x, max_f, ret, tail) = score(&setup, &mut env, seed, gains)?;
                        println!(
                            "{push:>6.0}{low:>6.0}{ky:>6.0}{x_on:>7.2}{x_off:>7.2}{ok:>9}{final_x:>9.3}{max_f:>9.1}{ret:>10.2}{tail:>10.2}"
                        );
                    }
                }
            }
        }
        return Ok(());
    }
    println!("{name}, seed {seed}: constant (k_x, k_y) clipped to [{k_min}, {k_max}] N/m");
    println!(
        "{:>7}{:>7}{:>10}{:>10}{:>9}{:>10}{:>12}",
        "k_x", "k_y", "inserts", "final x", "max |f|", "return", "last 5 s"
    );
    for ky in KY {
        for kx in KX {
            let gains = [kx.clamp(k_min, k_max), ky.clamp(k_min, k_max)];
            let (ok, final_x, max_f, ret, tail) = score(&setup, &mut env, seed, |_| gains)?;
            println!(
                "{:>7.1}{:>7.1}{:>10}{:>10.3}{:>9.1}{:>10.2}{:>12.2}",
                gains[0], gains[1], ok, final_x, max_f, ret, tail
            );
        }
    }
    Ok(())
}

/// Inserted, final x, max contact force, return, and return over the last 5 s of one roll-out
/// whose gains are `gains(observation)`.
fn score(
    setup: &LoopSetup<RbfPolicy>,
    env: &mut ArmEnv,
    seed: u64,
    gains: impl Fn(&[f64]) -> [f64; 2],
) -> Result<(bool, f64, f64, f64, f64)> {
    let start = setup
        .env_start
        .sample(derive_seed(seed, 0, arm::PURPOSE_EVALUATION))?;
    let r = rollout(
        env,
        &start,
        derive_seed(seed, 1, arm::PURPOSE_EVALUATION),
        |_, obs| Ok(gains(obs).to_vec()),
    )?;
    let costs = setup.recorded_costs(&r);
    let half = costs.len() / 2;
    let max_f = r
        .true_states
        .iter()
        .map(|s| s[arm::FORCE_INDICES[0]].hypot(s[arm::FORCE_INDICES[1]]))
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
