//! Fit the arm's dynamics GP to the first roll-outs of a run and score it on the next one.
//!
//! Why: the GP's hyper-parameters decide whether the model sees the wall, the spring and the
//! effect of stiffness at all; this prints them in natural units and the held-out one-step
//! log predictive density per target, so training settings can be compared on recorded data.
//!
//! `cargo run --release -p vicpilco-experiments --example dynamics_fit -- RUN_DIR [K] [CURB_LS]`
//! trains on roll-outs 0..K (default 3, i.e. ≤ 300 points: the full GP) and scores roll-out K.
//! Above 300 points it does what the sparse fit does to the hyper-parameters: trains them on
//! the run's random 300-point subset, once from PILCO's cold start and once warm-started from
//! the checkpoint's last fit, and scores the exact GP on that subset.
//! Settings come from the shipped config of the run's experiment name (not a `--config` file).

use anyhow::{Context, Result};
use faer::Mat;
use vicpilco_experiments::{arm, config, record::Checkpoint};
use vicpilco_gp::sparse::select_subset;
use vicpilco_gp::train::{initial_hyper, train, HypCurb, TrainOptions};
use vicpilco_gp::{GpModel, Hyper};
use vicpilco_learn::data::training_set;

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let dir = std::path::PathBuf::from(
        args.get(1)
            .context("usage: dynamics_fit RUN_DIR [K] [CURB_LS]")?,
    );
    let k: usize = args.get(2).map_or(Ok(3), |s| s.parse())?;
    let curb_ls: f64 = args.get(3).map_or(Ok(100.0), |s| s.parse())?;
    let text = std::fs::read_to_string(dir.join("checkpoint.json"))?;
    let ck: Checkpoint = serde_json::from_str(&text)?;
    let (label, cfg_text) = config::shipped(&ck.experiment).context("unknown experiment")?;
    let cfg = config::parse(cfg_text, label)?;
    let policy = arm::rbf_policy(&cfg, 0)?;
    let (setup, env) = arm::setup(&cfg, policy, 0)?;
    let data = &ck.state.data;
    anyhow::ensure!(
        data.len() > k,
        "the run has {} roll-outs (its initial one and {} updates), and K = {k} needs {}: give \
         a smaller K, or continue the run (vicpilco run ... --resume --episodes N)",
        data.len(),
        data.len().saturating_sub(1),
        k + 1
    );
    let input_names = arm::gp_input_names(&setup.spec, &env);
    let (x, y) = training_set(&setup.spec, &data[..k], setup.prior_shift.as_deref());
    let (xt, yt) = training_set(&setup.spec, &data[k..=k], setup.prior_shift.as_deref());
    let opts = TrainOptions {
        max_iters: cfg.gp.line_searches,
        penalty: Some(HypCurb {
            ls: curb_ls,
            ..HypCurb::default()
        }),
        ..TrainOptions::default()
    };
    let (x, y) = if x.nrows() > cfg.gp.sparse_threshold {
        let rows = select_subset(x.nrows(), cfg.gp.hyper_points, ck.seed);
        let pick = |m: &Mat<f64>| Mat::from_fn(rows.len(), m.ncols(), |i, j| m[(rows[i], j)]);
        (pick(&x), pick(&y))
    } else {
        (x, y)
    };
    let mut starts = vec![("cold", initial_hyper(x.as_ref(), y.as_ref()))];
    if let Some(h) = &ck.state.hyp {
        starts.push(("warm", h.clone()));
    }
    for (name, init) in starts {
        let (hyp, report) = train(x.as_ref(), y.as_ref(), &init, &opts)?;
        println!(
            "{} training points, curb ls {curb_ls}, {name} start",
            x.nrows()
        );
        print_fit(&input_names, &x, &y, &xt, &yt, hyp, &report.objectives())?;
    }
    Ok(())
}

fn print_fit(
    input_names: &[String],
    x: &Mat<f64>,
    y: &Mat<f64>,
    xt: &Mat<f64>,
    yt: &Mat<f64>,
    hyp: Vec<Hyper>,
    objectives: &[f64],
) -> Result<()> {
    print!("{:>5}", "");
    for n in input_names {
        print!("{n:>10}");
    }
    println!(
        "{:>10}{:>10}{:>10}{:>10}{:>10}",
        "sf", "sn", "train obj", "nlpd", "rmse/sd"
    );
    let model = GpModel::new(x.clone(), y.clone(), hyp.clone())?;
    let scores = held_out(&model, xt, yt)?;
    for (e, h) in hyp.iter().enumerate() {
        print!("{:>5}", arm::GP_TARGET_NAMES[e]);
        for l in &h.log_ls {
            print!("{:>10.3e}", l.exp());
        }
        let (nlpd, rel) = scores[e];
        println!(
            "{:>10.3e}{:>10.3e}{:>10.1}{:>10.3}{:>10.3}",
            h.log_sf.exp(),
            h.log_sn.exp(),
            objectives[e],
            nlpd,
            rel
        );
    }
    Ok(())
}

/// Mean negative log predictive density and RMSE over the target's std, per output.
fn held_out(model: &GpModel, x: &Mat<f64>, y: &Mat<f64>) -> Result<Vec<(f64, f64)>> {
    let e = y.ncols();
    let mut nlpd = vec![0.0; e];
    let mut se = vec![0.0; e];
    let mut ss = vec![0.0; e];
    let n = x.nrows();
    for i in 0..n {
        let xi: Vec<f64> = (0..x.ncols()).map(|j| x[(i, j)]).collect();
        let (m, v) = model.predict(&xi)?;
        for o in 0..e {
            let var = v[o] + (2.0 * model.hyp()[o].log_sn).exp();
            let r = y[(i, o)] - m[o];
            nlpd[o] += 0.5 * (r * r / var + var.ln() + std::f64::consts::TAU.ln());
            se[o] += r * r;
            ss[o] += y[(i, o)] * y[(i, o)];
        }
    }
    Ok((0..e)
        .map(|o| (nlpd[o] / n as f64, (se[o] / ss[o].max(1e-300)).sqrt()))
        .collect())
}
