//! Time the dynamics-model fit a checkpointed run would do next, and say where the time goes.
//!
//! Why: the arm runs' training time per update ranges from seconds to over ten minutes
//! (VILTA), and the loop records only the total. This redoes the next update's fit exactly as
//! the loop does it (same data, same warm start, same options) and prints the hyper-parameter
//! training per output (iterations, evaluations, jitter, which start was kept) and the
//! inducing-input optimisation.
//!
//! `cargo run --release -p vicpilco-experiments --example train_time -- RUN_DIR [CONFIG]
//! [--gradual-underflow]` reads `RUN_DIR/checkpoint.json`; the settings come from CONFIG when
//! given (the run's `--config` file), else from the shipped config of the run's experiment.
//! Like a run it flushes subnormals to zero; `--gradual-underflow` times the IEEE default
//! instead (`vicpilco_experiments::subnormals`). It also times one value + gradient of the
//! run's current policy under the new model, the unit of the policy optimisation.

use anyhow::{Context, Result};
use std::time::Instant;
use vicpilco_experiments::{arm, config, record::Checkpoint, subnormals};
use vicpilco_gp::moments::MmModel;
use vicpilco_gp::sparse::DynamicsReport;
use vicpilco_gp::DynamicsModel;
use vicpilco_learn::data::training_set;
use vicpilco_pilco::policy::Policy;

fn main() -> Result<()> {
    let mut args: Vec<String> = std::env::args().collect();
    let gradual = args.iter().any(|a| a == "--gradual-underflow");
    args.retain(|a| a != "--gradual-underflow");
    if gradual {
        fit_and_time(&args)
    } else {
        subnormals::run_flushed(|| fit_and_time(&args))
    }
}

fn fit_and_time(args: &[String]) -> Result<()> {
    let dir = std::path::PathBuf::from(
        args.get(1)
            .context("usage: train_time RUN_DIR [CONFIG] [--gradual-underflow]")?,
    );
    let text = std::fs::read_to_string(dir.join("checkpoint.json"))?;
    let ck: Checkpoint = serde_json::from_str(&text)?;
    let cfg = match args.get(2) {
        Some(path) => config::load(std::path::Path::new(path))?,
        None => {
            let (label, cfg_text) =
                config::shipped(&ck.experiment).context("unknown experiment")?;
            config::parse(cfg_text, label)?
        }
    };
    let mut policy = arm::rbf_policy(&cfg, ck.seed)?;
    policy.set_params(&ck.state.policy_params)?;
    let (setup, _env) = arm::setup(&cfg, policy.clone(), ck.seed)?;
    let state = &ck.state;
    let (inputs, targets) = training_set(&setup.spec, &state.data, setup.prior_shift.as_deref());
    let init = state
        .hyp
        .clone()
        .context("the checkpoint has no fitted hyper-parameters yet (update 0)")?;
    let inducing = state
        .inducing
        .as_ref()
        .map(|rows| faer::Mat::from_fn(rows.len(), rows[0].len(), |i, j| rows[i][j]));
    println!(
        "{}: update {} → fit on {} points, D = {}, E = {}",
        dir.display(),
        state.completed + 1,
        inputs.nrows(),
        inputs.ncols(),
        targets.ncols()
    );
    // The unit of the inducing-input optimisation: one FITC nlml + gradient per output, at the
    // warm start, with the hyper-parameters the last fit left.
    if let Some(u) = &inducing {
        for (e, (name, h)) in arm::GP_TARGET_NAMES.iter().zip(&init).enumerate() {
            let y: Vec<f64> = (0..targets.nrows()).map(|i| targets[(i, e)]).collect();
            let t0 = Instant::now();
            let eval = vicpilco_gp::sparse::fitc_nlml(inputs.as_ref(), &y, h, u.as_ref())?;
            println!(
                "one FITC nlml + gradient, {name}: {:.3} s (nlml {:.1})",
                t0.elapsed().as_secs_f64(),
                eval.value
            );
        }
    }
    let t0 = Instant::now();
    let (model, report) = DynamicsModel::fit(
        inputs,
        targets,
        &init,
        inducing.as_ref().map(|m| m.as_ref()),
        &setup.dynamics,
    )?;
    println!("total {:.1} s", t0.elapsed().as_secs_f64());
    let hyper = report.hyper();
    println!(
        "hyper-parameters: {:.1} s (outputs trained in parallel)",
        hyper.wall_time.as_secs_f64()
    );
    println!(
        "{:>5}{:>8}{:>8}{:>10}{:>10}{:>12}{:>12}  termination",
        "", "iters", "evals", "seconds", "kept", "max jitter", "nlml"
    );
    for (name, o) in arm::GP_TARGET_NAMES.iter().zip(&hyper.outputs) {
        println!(
            "{name:>5}{:>8}{:>8}{:>10.1}{:>10}{:>12.1e}{:>12.1}  {:?}",
            o.iterations,
            o.evaluations,
            o.wall_time.as_secs_f64(),
            if o.from_cold_restart { "cold" } else { "warm" },
            o.max_jitter,
            o.nlml,
            o.termination
        );
    }
    if let DynamicsReport::Sparse(s) = &report {
        println!("hyper-parameters trained on {} points", s.hyper_points);
        match &s.inducing {
            Some(i) => println!(
                "inducing inputs: {:.1} s, {} iterations, {} evaluations, nlml {:.1} → {:.1}, {:?}",
                i.wall_time.as_secs_f64(),
                i.iterations,
                i.evaluations,
                i.initial_nlml,
                i.nlml,
                i.termination
            ),
            None => println!("inducing inputs: the training inputs (N ≤ M)"),
        }
    }
    // The unit of the policy optimisation: one value + gradient of the current policy.
    let t0 = Instant::now();
    let out = setup.predicted_value(&policy, MmModel::dynamics(&model), true)?;
    println!(
        "one value + gradient of the current policy under the new model: {:.2} s (J = {:.3})",
        t0.elapsed().as_secs_f64(),
        out.j
    );
    Ok(())
}
