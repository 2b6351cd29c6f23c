//! How much the dynamics model's verdict on one fixed policy moves from update to update.
//!
//! Why: in the VIL runs a policy predicted at 60 ± 5 and confirmed by its roll-out was, one
//! update later, predicted at 70–75 ± 20 by the model retrained on that confirming roll-out.
//! This replays a run's model training (warm-started chain, as the learning loop does) on its
//! recorded roll-outs 0..K for K in FROM..=TO and prints, for one policy of the run (the final
//! one, the one update U rolled out, from `policies.jsonl`, or constant gains `const:KX,KY`,
//! whose true return `gain_sweep` measures), the predicted return (mean ± std of the summed
//! immediate cost, and the objective J) and the Δẋ model's hyper-parameters, so training
//! settings can be compared by their stability, and a model's verdict checked against a
//! policy whose outcome is known.
//!
//! `cargo run --release -p vicpilco-experiments --example model_drift -- RUN_DIR FROM TO [final | U | const:KX,KY] [CONFIG]`
//! Settings come from CONFIG, by default the shipped config of the run's experiment name, so
//! a training setting can be tried on a run's recorded data. Where the run chose its model on
//! the newest roll-out (`gp.model_selection = "last-rollout"`) and the settings still ask for
//! it, each update keeps the previous hyper-parameters or refits as the run recorded.

use anyhow::{Context, Result};
use vicpilco_experiments::{arm, config, record::Checkpoint};
use vicpilco_gp::moments::MmModel;
use vicpilco_gp::train::initial_hyper;
use vicpilco_gp::DynamicsModel;
use vicpilco_learn::data::training_set;
use vicpilco_learn::step::StepSpec;
use vicpilco_pilco::policy::{LinearPolicy, Policy};

/// Index of Δẋ among the arm's GP targets.
const DXD: usize = 2;

/// Where x, ẋ, t (when a GP input) and k_x sit among the GP inputs: the state entries listed
/// in `spec.dyn_inputs`, then the actions.
fn shown_inputs(spec: &StepSpec) -> Vec<(usize, &'static str)> {
    // Time follows the state (and any angles' sine and cosine) in the augmented vector.
    let time = spec.time_input.then(|| spec.augmented_dim() - 1);
    let mut shown: Vec<(usize, &'static str)> =
        [(Some(0), "l_x"), (Some(2), "l_xd"), (time, "l_t")]
            .into_iter()
            .filter_map(|(entry, name)| {
                let entry = entry?;
                let at = spec.dyn_inputs.iter().position(|&i| i == entry)?;
                Some((at, name))
            })
            .collect();
    shown.push((spec.dyn_inputs.len(), "l_kx"));
    shown
}

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let usage = "usage: model_drift RUN_DIR FROM TO [final | POLICY_UPDATE | const:KX,KY] [CONFIG]";
    let dir = std::path::PathBuf::from(args.get(1).context(usage)?);
    let from: usize = args.get(2).context(usage)?.parse()?;
    let to: usize = args.get(3).context(usage)?.parse()?;
    let ck: Checkpoint =
        serde_json::from_str(&std::fs::read_to_string(dir.join("checkpoint.json"))?)?;
    let cfg = match args.get(5) {
        Some(path) => config::load(std::path::Path::new(path))?,
        None => {
            let (label, text) = config::shipped(&ck.experiment).context("unknown experiment")?;
            config::parse(text, label)?
        }
    };
    if let Some(gains) = args.get(4).and_then(|a| a.strip_prefix("const:")) {
        let gains: Vec<f64> = gains
            .split(',')
            .map(str::parse)
            .collect::<Result<_, _>>()
            .context(usage)?;
        return replay(&cfg, &ck, constant_gains(&cfg, &gains)?, from, to);
    }
    let saved: serde_json::Value = match args.get(4).filter(|a| *a != "final") {
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
    anyhow::ensure!(
        cfg.policy.kind == config::PolicyKind::Rbf,
        "{}: model_drift replays RBF-policy runs only",
        ck.experiment
    );
    let mut policy = arm::rbf_policy(&cfg, 0)?;
    policy.set_params(&params)?;
    replay(&cfg, &ck, policy, from, to)
}

/// A policy whose saturated output is the constant `gains` (k_x, k_y): zero weights and the
/// offset that the saturation maps onto each gain.
fn constant_gains(cfg: &config::ArmExperiment, gains: &[f64]) -> Result<LinearPolicy> {
    let (lo, hi) = (cfg.policy.k_min, cfg.policy.k_max);
    anyhow::ensure!(
        gains.len() == cfg.n_actions() && gains.iter().all(|k| *k > lo && *k < hi),
        "const: needs {} gains strictly inside ({lo}, {hi})",
        cfg.n_actions()
    );
    // σ(u) = (9 sin u + sin 3u)/8 increases on [−π/2, π/2]; bisect σ(u) = target.
    let sigma = |u: f64| (9.0 * u.sin() + (3.0 * u).sin()) / 8.0;
    let offset = |k: f64| {
        let target = (k - (hi + lo) / 2.0) / ((hi - lo) / 2.0);
        let (mut a, mut b) = (-std::f64::consts::FRAC_PI_2, std::f64::consts::FRAC_PI_2);
        for _ in 0..100 {
            let mid = 0.5 * (a + b);
            if sigma(mid) < target {
                a = mid
            } else {
                b = mid
            }
        }
        0.5 * (a + b)
    };
    let b: Vec<f64> = gains.iter().map(|&k| offset(k)).collect();
    Ok(LinearPolicy::new(
        faer::Mat::zeros(gains.len(), 4).as_ref(),
        &b,
    )?)
}

fn replay<P: Policy + Clone + Sync>(
    cfg: &config::ArmExperiment,
    ck: &Checkpoint,
    policy: P,
    from: usize,
    to: usize,
) -> Result<()>
where
    P::Cache: Send,
{
    let (setup, _env) = arm::setup(cfg, policy.clone(), ck.seed)?;
    let data = &ck.state.data;
    anyhow::ensure!(
        data.len() >= to,
        "the run has {} roll-outs, and TO = {to} trains on {to}: give a smaller TO, or continue \
         the run (vicpilco run ... --resume --episodes N)",
        data.len()
    );

    let inputs = shown_inputs(&setup.spec);
    print!("{:>3}{:>7}{:>9}{:>8}{:>9}", "K", "N", "J", "mean", "std");
    for &(_, name) in &inputs {
        print!("{name:>10}");
    }
    println!("{:>10}{:>10}", "sf", "sn");
    let mut hyp = None;
    let mut inducing = None;
    let mut last = None;
    for k in 1..=to {
        let (x, y) = training_set(&setup.spec, &data[..k], setup.prior_shift.as_deref());
        let init = hyp
            .clone()
            .unwrap_or_else(|| initial_hyper(x.as_ref(), y.as_ref()));
        let n = x.nrows();
        // A run that chose its model on the newest roll-out recorded the choice per update;
        // the replay makes the same one (it cannot re-score: that needs each update's policy).
        let kept = setup.model_selection.compares()
            && ck
                .state
                .episodes
                .get(k - 1)
                .and_then(|e| e.model_selection)
                .is_some_and(|s| s.kept_previous);
        let opts = if kept {
            setup.dynamics.keeping_hyper_parameters()
        } else {
            setup.dynamics.clone()
        };
        let (model, _) = DynamicsModel::fit(
            x,
            y,
            &init,
            inducing.as_ref().map(|m: &faer::Mat<f64>| m.as_ref()),
            &opts,
        )?;
        hyp = Some(model.hyp().to_vec());
        if model.is_sparse() {
            inducing = Some(model.inputs().to_owned());
        }
        if k < from {
            continue;
        }
        let out = setup.predicted_value(&policy, MmModel::dynamics(&model), false)?;
        let (mean, std) = setup.ret.predicted_return(&out);
        let h = &model.hyp()[DXD];
        print!("{k:>3}{n:>7}{:>9.2}{mean:>8.2}{std:>9.2}", out.j);
        for &(i, _) in &inputs {
            print!("{:>10.3e}", h.log_ls[i].exp());
        }
        println!("{:>10.3e}{:>10.3e}", h.log_sf.exp(), h.log_sn.exp());
        if k == to {
            last = Some(out);
        }
    }
    // Where the prediction spreads: the last model's predicted state every second.
    if let Some(out) = last {
        println!("\nmodel {to}, first start: step, then mean ± std of x, y, xd, yd, f_x, f_y, then the actions' means");
        for (t, step) in out.trajectories[0].iter().enumerate().step_by(10) {
            print!("{t:>4}");
            for (i, m) in step.mean.iter().enumerate().take(6) {
                print!("  {m:>8.3} ± {:<7.3}", step.cov[(i, i)].max(0.0).sqrt());
            }
            for a in &step.action_mean {
                print!("{a:>8.1}");
            }
            println!();
        }
    }
    Ok(())
}
