//! `vilta.lead_state` (ours): the reference's lead over the TCP as two more state entries,
//! which the dynamics GP takes as inputs and predicts, and the policy takes as inputs.

mod common;

use vicpilco_experiments::{arm, config, run, RunOptions};
use vicpilco_learn::data::{training_set, Rollout};

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

    let with_force_prior = |k0: &str| format!("{LEAD_TABLE}force_prior_stiffness = {k0}\n");
    for (field, table) in [
        (
            "prediction_std",
            LEAD_TABLE.replace("prediction_std = ", "prediction_std = 0.0 #"),
        ),
        (
            "policy_lengthscale",
            LEAD_TABLE.replace("policy_lengthscale = ", "policy_lengthscale = -1.0 #"),
        ),
        ("force_prior_stiffness", with_force_prior("-50.0")),
        ("force_prior_stiffness", with_force_prior("inf")),
    ] {
        let err = config::parse(&with_lead(&table), "lead.toml")
            .unwrap_err()
            .to_string();
        assert!(
            err.contains(&format!("vilta.lead_state.{field}")) && err.contains("lead.toml"),
            "{err}"
        );
    }
}

/// The lead inputs' initial length-scale belongs to an RBF policy: required with one, refused
/// with a linear policy, which has none.
#[test]
fn the_lead_length_scale_follows_the_policy_kind() {
    let without_ls = "[vilta.lead_state]\nprediction_std = 0.001\n";
    let linear = |lead: &str| {
        with_lead(lead)
            .replace("kind = \"rbf\"", "kind = \"linear\"")
            .replace("n_basis = ", "# n_basis = ")
            .replace("lengthscales = [", "# lengthscales = [")
            .replace("snr = ", "# snr = ")
    };
    let err = |text: &str| config::parse(text, "lead.toml").unwrap_err().to_string();
    let missing = err(&with_lead(without_ls));
    assert!(
        missing.contains("vilta.lead_state.policy_lengthscale")
            && missing.contains("required for an RBF policy"),
        "{missing}"
    );
    let refused = err(&linear(LEAD_TABLE));
    assert!(
        refused.contains("vilta.lead_state.policy_lengthscale")
            && refused.contains("does not apply to a linear policy"),
        "{refused}"
    );
    let cfg = config::parse(&linear(without_ls), "lead.toml").unwrap();
    // A linear policy on (x, y, ẋ, ẏ, ℓ_x, ℓ_y) with 4 outputs: m (n_π + 1) = 4 · 7.
    assert_eq!((cfg.n_policy_inputs(), cfg.n_params()), (6, 28));
    let written = serde_json::to_value(&cfg).unwrap();
    assert!(
        written["vilta"]["lead_state"]
            .get("policy_lengthscale")
            .is_none(),
        "{written}"
    );
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

    // vilta.lead_state.force_prior_stiffness: the same roll-outs give force targets less
    // k₀ times the step's starting lead, and nothing else changes.
    let k0 = 50.0;
    let plain = config::parse(&with_lead(LEAD_TABLE), "lead.toml").unwrap();
    let with_prior = config::parse(
        &with_lead(&format!("{LEAD_TABLE}force_prior_stiffness = {k0}\n")),
        "lead.toml",
    )
    .unwrap();
    assert!(with_prior.ours_keys().contains(&"vilta.lead_state"));
    let spec_of = |cfg| {
        let policy = arm::rbf_policy(cfg, 1).unwrap();
        arm::setup(cfg, policy, 1).unwrap().0.spec
    };
    let (spec_plain, spec_prior) = (spec_of(&plain), spec_of(&with_prior));
    assert!(spec_plain.linear_prior.is_empty());
    let terms: Vec<(usize, usize, f64)> = spec_prior
        .linear_prior
        .iter()
        .map(|t| (t.target, t.state, t.coefficient))
        .collect();
    assert_eq!(terms, [(4, 6, k0), (5, 7, k0)]);
    let recorded: Vec<Rollout> = rollouts
        .iter()
        .map(|r| serde_json::from_value(r["rollout"].clone()).unwrap())
        .collect();
    let (inputs, targets_plain) = training_set(&spec_plain, &recorded, None);
    let (inputs_prior, targets_prior) = training_set(&spec_prior, &recorded, None);
    assert_eq!(inputs, inputs_prior);
    let starts: Vec<&Vec<f64>> = recorded
        .iter()
        .flat_map(|r| &r.observations[..r.len()])
        .collect();
    assert_eq!(starts.len(), targets_plain.nrows());
    let mut largest = 0.0_f64;
    for (i, x) in starts.iter().enumerate() {
        for e in 0..8 {
            let shift = match e {
                4 | 5 => k0 * x[e + 2],
                _ => 0.0,
            };
            let got = targets_plain[(i, e)] - targets_prior[(i, e)];
            assert!(
                (got - shift).abs() < 1e-9,
                "row {i} target {e}: {got} vs {shift}"
            );
            largest = largest.max(shift.abs());
        }
    }
    assert!(
        largest > 1.0,
        "the search's lead shifts the force targets ({largest} N)"
    );
}
