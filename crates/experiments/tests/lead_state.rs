//! `vilta.lead_state` (ours): the reference's lead over the TCP as two more state entries,
//! which the dynamics GP takes as inputs and predicts, and the policy takes as inputs.

mod common;

use vicpilco_experiments::{config, run, RunOptions};

const LEAD_TABLE: &str = "[vilta.lead_state]\nprediction_std = 0.001\npolicy_lengthscale = 0.05\n";

fn with_lead(extra: &str) -> String {
    format!("{}\n{extra}", config::shipped("vilta").unwrap().1)
}

#[test]
fn the_lead_adds_two_state_entries_gp_inputs_and_policy_inputs() {
    let base = config::parse(config::shipped("vilta").unwrap().1, "vilta.toml").unwrap();
    assert_eq!(
        (base.state_dim(), base.gp_input_dim(), base.n_params()),
        (6, 8, 416)
    );
    assert!(!base.ours_keys().contains(&"vilta.lead_state"));
    let written = serde_json::to_value(&base).unwrap();
    assert!(written["vilta"].get("lead_state").is_none(), "{written}");

    let cfg = config::parse(&with_lead(LEAD_TABLE), "lead.toml").unwrap();
    // n_ψ = N_c (n_π + m) + n_π m = 50 (6 + 4) + 6 · 4.
    assert_eq!(
        (
            cfg.state_dim(),
            cfg.n_policy_inputs(),
            cfg.gp_input_dim(),
            cfg.n_params()
        ),
        (8, 6, 10, 524)
    );
    assert!(cfg.ours_keys().contains(&"vilta.lead_state"));

    for (field, bad) in [("prediction_std", "0.0"), ("policy_lengthscale", "-1.0")] {
        let table = LEAD_TABLE.replace(&format!("{field} = "), &format!("{field} = {bad} #"));
        let err = config::parse(&with_lead(&table), "lead.toml")
            .unwrap_err()
            .to_string();
        assert!(
            err.contains(&format!("vilta.lead_state.{field}")) && err.contains("lead.toml"),
            "{err}"
        );
    }
}

/// One quick update learns on the 8-entry state: every recorded state carries the lead, equal
/// to the reference less the TCP, and the long-term prediction has 8 entries per step.
#[test]
fn a_quick_update_learns_and_predicts_the_lead() {
    let dir = common::scratch("lead-state", "quick");
    std::fs::create_dir_all(&dir).unwrap();
    let cfg = dir.join("vilta.toml");
    std::fs::write(&cfg, with_lead(LEAD_TABLE)).unwrap();
    let opts = RunOptions {
        seed: 1,
        out: dir.join("run"),
        episodes: Some(1),
        quick: true,
        config: Some(cfg),
        ..Default::default()
    };
    run("vilta", &opts, &mut ()).expect("a vilta update with the lead state");
    let rollouts = common::json_lines(&dir.join("run").join("rollouts.jsonl"));
    assert_eq!(rollouts.len(), 2, "the search and one update");
    for record in &rollouts {
        for info in record["rollout"]["infos"].as_array().unwrap() {
            let (r, s) = (&info["reference"], &info["true_state"]);
            assert_eq!(s.as_array().unwrap().len(), 8);
            for a in 0..2 {
                let lead = r[a].as_f64().unwrap() - s[a].as_f64().unwrap();
                assert!((s[6 + a].as_f64().unwrap() - lead).abs() < 1e-12, "{info}");
            }
        }
    }
    let summary: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.join("run").join("summary.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(summary["n_params"], 524, "{}", summary["n_params"]);
    assert_eq!(summary["policy"], "rbf (50 basis functions, 6 inputs)");
    let predictions = common::json_lines(&dir.join("run").join("predictions.jsonl"));
    let p = &predictions[0];
    assert_eq!(p["state_names"][6], "lead_x");
    let mean = p["starts"][0][10]["mean"]
        .as_array()
        .expect("step 10's mean");
    assert_eq!(mean.len(), 8);
    assert!(mean.iter().all(|v| v.as_f64().is_some_and(f64::is_finite)));
}
