//! How much the dynamics model's verdict on one fixed policy moves from update to update.
//!
//! Why: in the VIL runs a policy predicted at 60 ± 5 and confirmed by its roll-out was, one
//! update later, predicted at 70–75 ± 20 by the model retrained on that confirming roll-out.
//! This replays a run's model training (warm-started chain, as the learning loop does) on its
//! recorded roll-outs 0..K for K in FROM..=TO and prints, for one policy of the run (the final
//! one, or the one update U rolled out, from `policies.jsonl`), the predicted return (mean ±
//! std of the summed immediate cost, and the objective J) and the Δẋ model's
//! hyper-parameters, so training settings can be compared by their stability.
//!
//! `cargo run --release -p vicpilco-experiments --example model_drift -- RUN_DIR FROM TO [U]`
//! Settings come from the shipped config of the run's experiment name.

use anyhow::{Context, Result};
use vicpilco_experiments::{arm, config, record::Checkpoint};
use vicpilco_gp::moments::MmModel;
use vicpilco_gp::train::initial_hyper;
use vicpilco_gp::DynamicsModel;
use vicpilco_learn::data::training_set;
use vicpilco_learn::step::Predictor;
use vicpilco_learn::value::value;
use vicpilco_pilco::policy::Policy;

/// Index of Δẋ among the arm's GP targets, and of x, ẋ, t, k_x among its inputs.
const DXD: usize = 2;
const INPUTS: [(usize, &str); 4] = [(0, "l_x"), (2, "l_xd"), (4, "l_t"), (5, "l_kx")];

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let usage = "usage: model_drift RUN_DIR FROM TO [POLICY_UPDATE]";
    let dir = std::path::PathBuf::from(args.get(1).context(usage)?);
    let from: usize = args.get(2).context(usage)?.parse()?;
    let to: usize = args.get(3).context(usage)?.parse()?;
    let ck: Checkpoint =
        serde_json::from_str(&std::fs::read_to_string(dir.join("checkpoint.json"))?)?;
    let saved: serde_json::Value = match args.get(4) {
        None => serde_json::from_str(&std::fs::read_to_string(dir.join("policy.json"))?)?,
        Some(u) => {
            let u: u64 = u.parse().context(usage)?;
            let path = dir.join("policies.jsonl");
            let text = std::fs::read_to_string(&path)
                .with_context(|| format!("{} (runs before policies.jsonl)", path.display()))?;
            let mut lines = text.lines().map(serde_json::from_str::<serde_json::Value>);
            lines
                .find(|v| v.as_ref().map_or(true, |v| v["episode"] == u))
                .with_context(|| format!("{}: no policy of update {u}", path.display()))??
        }
    };
    let params: Vec<f64> = serde_json::from_value(saved["params"].clone())?;
    let (label, cfg_text) = config::shipped(&ck.experiment).context("unknown experiment")?;
    let cfg = config::parse(cfg_text, label)?;
    anyhow::ensure!(
        cfg.policy.kind == config::PolicyKind::Rbf,
        "{}: model_drift replays RBF-policy runs only",
        ck.experiment
    );
    let mut policy = arm::rbf_policy(&cfg, 0)?;
    policy.set_params(&params)?;
    let (setup, _env) = arm::setup(&cfg, policy.clone(), ck.seed)?;
    let data = &ck.state.data;
    anyhow::ensure!(data.len() >= to, "the run has {} roll-outs", data.len());

    print!("{:>3}{:>7}{:>9}{:>8}{:>9}", "K", "N", "J", "mean", "std");
    for (_, name) in INPUTS {
        print!("{name:>10}");
    }
    println!("{:>10}{:>10}", "sf", "sn");
    let mut hyp = None;
    let mut inducing = None;
    for k in 1..=to {
        let (x, y) = training_set(&setup.spec, &data[..k], setup.prior_shift.as_deref());
        let init = hyp
            .clone()
            .unwrap_or_else(|| initial_hyper(x.as_ref(), y.as_ref()));
        let n = x.nrows();
        let (model, _) = DynamicsModel::fit(
            x,
            y,
            &init,
            inducing.as_ref().map(|m: &faer::Mat<f64>| m.as_ref()),
            &setup.dynamics,
        )?;
        hyp = Some(model.hyp().to_vec());
        if model.is_sparse() {
            inducing = Some(model.inputs().to_owned());
        }
        if k < from {
            continue;
        }
        let pred = Predictor::new(
            &setup.spec,
            &policy,
            setup.squash.as_ref(),
            MmModel::dynamics(&model),
            setup.prior_shift.as_deref(),
        )?;
        let out = value(&pred, &setup.ret, &setup.prediction_starts, false)?;
        let (mean, std) = setup.ret.predicted_return(&out);
        let h = &model.hyp()[DXD];
        print!("{k:>3}{n:>7}{:>9.2}{mean:>8.2}{std:>9.2}", out.j);
        for (i, _) in INPUTS {
            print!("{:>10.3e}", h.log_ls[i].exp());
        }
        println!("{:>10.3e}{:>10.3e}", h.log_sf.exp(), h.log_sn.exp());
    }
    Ok(())
}
