//! The settings the issue leaves open or that probes change (most of them "ours"): each parses,
//! reaches the run, is refused out of range, and is listed as ours when set.

use super::*;

#[test]
fn the_maximum_slope_ratio_parses_reaches_the_optimiser_and_must_be_positive() {
    // Table 5-4's MSR = 100 exists as `optimiser.msr`; the shipped files leave it off, as
    // every stored run was made (README, the table of keys in no shipped file).
    for (name, _) in CONFIGS {
        assert_eq!(shipped(name).optimiser.msr, None, "{name}");
    }
    let text = config::shipped("vil-gic").unwrap().1;
    let with = |msr: &str| text.replace("memory = 10 ", &format!("msr = {msr}\nmemory = 10 "));
    let cfg = config::parse(&with("100"), "test.toml").unwrap();
    assert_eq!(cfg.optimiser.msr, Some(100.0));
    let (setup, _) = arm::setup(&cfg, arm::rbf_policy(&cfg, 1).unwrap(), 1).unwrap();
    assert_eq!(setup.optimiser.max_slope_ratio, Some(100.0));
    for bad in ["0", "-1.0", "nan"] {
        let e = error_of(&with(bad));
        assert!(e.contains("optimiser.msr"), "{bad}: {e}");
    }
}

#[test]
fn the_centre_scale_rule_parses_and_needs_scaled_parameters() {
    use vicpilco_experiments::config::CentreScale;
    let text = config::shipped("vil-gic").unwrap().1;
    assert_eq!(shipped("vil-gic").optimiser.centre_scale, None);
    let smallest = text.replace(
        "scale_params = true",
        "scale_params = true\ncentre_scale = \"smallest\"",
    );
    let cfg = config::parse(&smallest, "test.toml").unwrap();
    assert_eq!(cfg.optimiser.centre_scale, Some(CentreScale::Smallest));
    assert!(cfg.ours_keys().contains(&"optimiser.centre_scale"));
    let e = error_of(&smallest.replace("\"smallest\"", "\"largest\""));
    assert!(e.contains("test.toml") && e.contains("largest"), "{e}");
    let e = error_of(&smallest.replace("scale_params = true", "scale_params = false"));
    assert!(e.contains("optimiser.centre_scale"), "{e}");
}

#[test]
fn a_lengthscale_floor_needs_one_non_negative_value_per_gp_input() {
    let text = config::shipped("vil-gic").unwrap().1;
    assert_eq!(shipped("vil-gic").gp.lengthscale_floor, None);
    let with = |floor: &str| {
        text.replace(
            "cold_restart = true",
            &format!("cold_restart = true\nlengthscale_floor = {floor}"),
        )
    };
    // VIL: x, y, ẋ, ẏ, t, k_x, k_y.
    let cfg = config::parse(&with("[0, 0, 0.01, 0.01, 0, 0, 0]"), "test.toml").unwrap();
    assert_eq!(cfg.gp_input_dim(), 7);
    assert!(cfg.ours_keys().contains(&"gp.lengthscale_floor"));
    let e = error_of(&with("[0, 0, 0.01, 0.01]"));
    assert!(e.contains("gp.lengthscale_floor") && e.contains('7'), "{e}");
    let e = error_of(&with("[0, 0, -0.01, 0.01, 0, 0, 0]"));
    assert!(e.contains("gp.lengthscale_floor[2]"), "{e}");
    // VILTA has no time input but four actions.
    assert_eq!(shipped("vilta").gp_input_dim(), 8);
}

#[test]
fn a_lengthscale_ceiling_is_checked_like_the_floor_and_must_lie_above_it() {
    let text = config::shipped("vilta").unwrap().1;
    assert_eq!(shipped("vilta").gp.lengthscale_ceiling, None);
    let with = |extra: &str| {
        text.replace(
            "cold_restart = true",
            &format!("cold_restart = true\n{extra}"),
        )
    };
    // VILTA: x, y, ẋ, ẏ, k_x, k_y, Δx_ref, Δy_ref; a 3 cm ceiling on y.
    let ceiling = "lengthscale_ceiling = [0, 0.03, 0, 0, 0, 0, 0, 0]";
    let cfg = config::parse(&with(ceiling), "test.toml").unwrap();
    assert_eq!(
        cfg.gp.lengthscale_ceiling.as_deref(),
        Some(&[0.0, 0.03, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0][..])
    );
    assert!(cfg.ours_keys().contains(&"gp.lengthscale_ceiling"));
    let e = error_of(&with("lengthscale_ceiling = [0, 0.03]"));
    assert!(
        e.contains("gp.lengthscale_ceiling") && e.contains('8'),
        "{e}"
    );
    let e = error_of(&with("lengthscale_ceiling = [0, inf, 0, 0, 0, 0, 0, 0]"));
    assert!(e.contains("gp.lengthscale_ceiling[1]"), "{e}");
    let floor = "lengthscale_floor = [0, 0.05, 0, 0, 0, 0, 0, 0]";
    let e = error_of(&with(&format!("{ceiling}\n{floor}")));
    assert!(
        e.contains("gp.lengthscale_ceiling[1]") && e.contains("gp.lengthscale_floor[1]"),
        "{e}"
    );
    let floor = "lengthscale_floor = [0, 0.01, 0, 0, 0, 0, 0, 0]";
    config::parse(&with(&format!("{ceiling}\n{floor}")), "test.toml").unwrap();
}

#[test]
fn force_inputs_add_the_contact_forces_to_the_gp_inputs() {
    let text = config::shipped("vilta").unwrap().1;
    let base = shipped("vilta");
    assert!(!base.gp.force_inputs);
    assert!(!base.ours_keys().contains(&"gp.force_inputs"));
    let cfg = config::parse(
        &text.replace(
            "cold_restart = true",
            "cold_restart = true\nforce_inputs = true",
        ),
        "test.toml",
    )
    .unwrap();
    assert!(cfg.ours_keys().contains(&"gp.force_inputs"));
    // x, y, ẋ, ẏ, f_x, f_y and the four actions.
    assert_eq!(cfg.gp_input_dim(), 10);
    let policy = arm::rbf_policy(&cfg, 1).unwrap();
    let (setup, _) = arm::setup(&cfg, policy, 1).unwrap();
    assert_eq!(setup.spec.dyn_inputs, vec![0, 1, 2, 3, 4, 5]);
    let (base_setup, _) = arm::setup(&base, arm::rbf_policy(&base, 1).unwrap(), 1).unwrap();
    assert_eq!(base_setup.spec.dyn_inputs, vec![0, 1, 2, 3]);
}

#[test]
fn vilta_reference_origin_is_the_start_unless_set_and_then_an_ours_key() {
    use vicpilco_env::arm::{ActionMode, ReferenceOrigin};
    let origin = |cfg: &config::ArmExperiment| match arm::arm_config(cfg).mode {
        ActionMode::Vilta { origin, .. } => origin,
        ActionMode::Vil => panic!("a VILTA config"),
    };
    for name in ["vilta", "vilta-var"] {
        let base = shipped(name);
        assert_eq!(origin(&base), ReferenceOrigin::Start);
        assert!(!base.ours_keys().contains(&"vilta.reference"));
        // The default is not written, so runs made before the option keep their identity.
        let written = serde_json::to_value(&base).unwrap();
        assert!(written["vilta"].get("reference").is_none(), "{written}");
    }
    let text = config::shipped("vilta").unwrap().1;
    let set = |value: &str| {
        config::parse(
            &text.replace("reference = \"start\"", &format!("reference = {value}")),
            "test.toml",
        )
    };
    let cfg = set("\"measured\"").unwrap();
    assert_eq!(origin(&cfg), ReferenceOrigin::Measured);
    assert!(cfg.ours_keys().contains(&"vilta.reference"));
    let err = set("\"elsewhere\"").unwrap_err().to_string();
    assert!(
        err.contains("reference") && err.contains("test.toml"),
        "{err}"
    );
}

#[test]
fn vilta_max_lead_is_unbounded_unless_set_positive_and_then_an_ours_key() {
    use vicpilco_env::arm::ActionMode;
    let lead = |cfg: &config::ArmExperiment| match arm::arm_config(cfg).mode {
        ActionMode::Vilta { max_lead, .. } => max_lead,
        ActionMode::Vil => panic!("a VILTA config"),
    };
    for name in ["vilta", "vilta-var"] {
        let base = shipped(name);
        assert_eq!(lead(&base), None);
        assert!(!base.ours_keys().contains(&"vilta.max_lead"));
        // Not written when absent, so stored runs keep their identity.
        let written = serde_json::to_value(&base).unwrap();
        assert!(written["vilta"].get("max_lead").is_none(), "{written}");
    }
    let set = |value: &str| vilta_with_vilta_line(&format!("max_lead = {value}"));
    let cfg = config::parse(&set("0.05"), "test.toml").unwrap();
    assert_eq!(lead(&cfg), Some(0.05));
    assert!(cfg.ours_keys().contains(&"vilta.max_lead"));
    for bad in ["0.0", "-0.05", "nan"] {
        let err = error_of(&set(bad));
        assert!(
            err.contains("vilta.max_lead") && err.contains("test.toml"),
            "{bad}: {err}"
        );
    }
}

#[test]
fn sensor_noise_is_on_unless_switched_off_and_then_an_ours_key() {
    for name in ["vil-gic-rbf10", "vil-sic", "vilta"] {
        let base = shipped(name);
        assert!(base.sensor_noise && arm::arm_config(&base).noise, "{name}");
        assert!(!base.ours_keys().contains(&"sensor_noise"));
        // Not written while on, so runs made before the key keep their identity.
        let written = serde_json::to_value(&base).unwrap();
        assert!(written.get("sensor_noise").is_none(), "{written}");
    }
    let text = config::shipped("vil-gic-rbf10").unwrap().1;
    let set = |value: &str| config::parse(&format!("sensor_noise = {value}\n{text}"), "test.toml");
    let off = set("false").unwrap();
    assert!(!arm::arm_config(&off).noise);
    assert!(off.ours_keys().contains(&"sensor_noise"));
    let err = set("\"no\"").unwrap_err().to_string();
    assert!(
        err.contains("sensor_noise") && err.contains("test.toml"),
        "{err}"
    );
}

#[test]
fn every_arm_run_selects_its_model_on_the_last_roll_out_and_says_it_is_ours() {
    for (name, _) in CONFIGS {
        let c = shipped(name);
        // vil-sic scores the candidates on the roll-out's states (on it the return rule keeps
        // an early, wide model for good: EXPERIMENTS.md, "The selection's lock-in"), each entry
        // by Huber's density (the hole's force impulse must not decide: eighth session).
        let rule = if *name == "vil-sic" {
            ModelSelection::LastRolloutStatesHuber
        } else {
            ModelSelection::LastRollout
        };
        assert_eq!(c.gp.model_selection, rule, "{name}");
        assert!(c.ours_keys().contains(&"gp.model_selection"), "{name}");
        let chosen = match c.policy.kind {
            PolicyKind::Rbf => {
                arm::setup(&c, arm::rbf_policy(&c, 1).unwrap(), 1)
                    .unwrap()
                    .0
                    .model_selection
            }
            PolicyKind::Linear => {
                arm::setup(&c, arm::linear_policy(&c, 1).unwrap(), 1)
                    .unwrap()
                    .0
                    .model_selection
            }
        };
        assert_eq!(chosen, rule, "{name}");
    }
    let text = config::shipped("vil-gic-rbf10").unwrap().1;
    let set = |value: &str| {
        config::parse(
            &text.replace(
                "model_selection = \"last-rollout\"",
                &format!("model_selection = {value}"),
            ),
            "test.toml",
        )
    };
    let pilco = set("\"likelihood\"").unwrap();
    assert_eq!(pilco.gp.model_selection, ModelSelection::Likelihood);
    assert!(!pilco.ours_keys().contains(&"gp.model_selection"));
    // PILCO's rule is the default and is not written, so runs made before the key resume.
    let written = serde_json::to_value(&pilco).unwrap();
    assert!(written["gp"].get("model_selection").is_none(), "{written}");
    // The rule on the predicted states is ours too.
    let states = set("\"last-rollout-states\"").unwrap();
    assert_eq!(states.gp.model_selection, ModelSelection::LastRolloutStates);
    assert!(states.ours_keys().contains(&"gp.model_selection"));
    let robust = set("\"last-rollout-states-robust\"").unwrap();
    assert_eq!(
        robust.gp.model_selection,
        ModelSelection::LastRolloutStatesRobust
    );
    let (setup, _) = arm::setup(&robust, arm::rbf_policy(&robust, 1).unwrap(), 1).unwrap();
    assert_eq!(
        setup.model_selection,
        ModelSelection::LastRolloutStatesRobust
    );
    let huber = set("\"last-rollout-states-huber\"").unwrap();
    assert_eq!(
        huber.gp.model_selection,
        ModelSelection::LastRolloutStatesHuber
    );
    assert!(huber.ours_keys().contains(&"gp.model_selection"));
    let crps = set("\"last-rollout-crps\"").unwrap();
    assert_eq!(crps.gp.model_selection, ModelSelection::LastRolloutCrps);
    assert!(crps.ours_keys().contains(&"gp.model_selection"));
    let (setup, _) = arm::setup(&crps, arm::rbf_policy(&crps, 1).unwrap(), 1).unwrap();
    assert_eq!(setup.model_selection, ModelSelection::LastRolloutCrps);
    let err = set("\"best-guess\"").unwrap_err().to_string();
    assert!(
        err.contains("model_selection") && err.contains("test.toml"),
        "{err}"
    );
}

#[test]
fn scan_jitter_is_a_positive_vilta_only_option() {
    let text = config::shipped("vilta").unwrap().1;
    assert_eq!(shipped("vilta").initial.scan_jitter, None);
    let anchor = "ou_theta = 0.5";
    let with = |table: &str| with_line_after(text, anchor, table);
    let cfg = config::parse(
        &with("scan_jitter = { std = 0.02, theta = 2.0 }"),
        "test.toml",
    )
    .unwrap();
    let j = cfg.initial.scan_jitter.as_ref().unwrap();
    assert_eq!((j.std, j.theta), (0.02, 2.0));
    assert!(cfg.ours_keys().contains(&"initial.scan_jitter"));
    let e = error_of(&with("scan_jitter = { std = 0.0, theta = 2.0 }"));
    assert!(e.contains("initial.scan_jitter.std"), "{e}");
    let e = error_of(&with("scan_jitter = { std = 0.02, theta = -1.0 }"));
    assert!(e.contains("initial.scan_jitter.theta"), "{e}");
    let e = error_of(&with("scan_jitter = { std = 0.02, theta = 2.0, sd = 1 }"));
    assert!(e.contains("sd"), "{e}");
    let vil = config::shipped("vil-gic").unwrap().1;
    let e = error_of(&with_line_after(
        vil,
        anchor,
        "scan_jitter = { std = 0.02, theta = 2.0 }",
    ));
    assert!(e.contains("initial.scan_jitter"), "{e}");
}

#[test]
fn force_width_far_is_an_optional_width_wider_than_force_width() {
    let text = config::shipped("vilta").unwrap().1;
    assert_eq!(shipped("vilta").cost.force_width_far, None);
    let with = |line: &str| with_line_after(text, "force_width = 20.0", line);
    let cfg = config::parse(&with("force_width_far = 250.0"), "test.toml").unwrap();
    assert_eq!(cfg.cost.force_width_far, Some(250.0));
    assert!(cfg.ours_keys().contains(&"cost.force_width_far"));
    for bad in ["force_width_far = 0.0", "force_width_far = 10.0"] {
        let e = error_of(&with(bad));
        assert!(e.contains("cost.force_width_far"), "{bad}: {e}");
    }
}

#[test]
fn vilta_var_hands_over_its_most_successful_policy_and_only_runs_with_fresh_starts_may_choose() {
    use config::FinalPolicy;
    let var = shipped("vilta-var");
    assert_eq!(
        var.vilta.as_ref().unwrap().final_policy,
        FinalPolicy::MostSuccessful
    );
    assert!(var.ours_keys().contains(&"vilta.final_policy"));
    let fixed = shipped("vilta");
    assert_eq!(
        fixed.vilta.as_ref().unwrap().final_policy,
        FinalPolicy::Last
    );
    assert!(!fixed.ours_keys().contains(&"vilta.final_policy"));
    // Not written when "last", so runs made before the key keep their identity.
    let written = serde_json::to_value(&fixed).unwrap();
    assert!(written["vilta"].get("final_policy").is_none(), "{written}");

    let set = |value: &str| vilta_with_vilta_line(&format!("final_policy = {value}"));
    let last = config::parse(&set("\"last\""), "test.toml").unwrap();
    assert_eq!(last, fixed);
    for bad in ["\"most-successful\"", "\"best\""] {
        let err = error_of(&set(bad));
        assert!(
            err.contains("final_policy") && err.contains("test.toml"),
            "{bad}: {err}"
        );
    }
}

/// `policy.init_from_scan` makes the untrained VILTA policy send, at each RBF centre, the
/// reference increments the search roll-out sends there; the gains stay the random ones.
#[test]
fn init_from_scan_starts_the_policy_on_the_search_roll_outs_increments() {
    let base = shipped("vilta");
    assert!(!base.policy.init_from_scan);
    assert!(!base.ours_keys().contains(&"policy.init_from_scan"));
    let set = |name: &str, value: &str| {
        with_line_after(
            config::shipped(name).unwrap().1,
            "snr = 100.0",
            &format!("init_from_scan = {value}"),
        )
    };
    let cfg = config::parse(&set("vilta", "true"), "test.toml").unwrap();
    assert!(cfg.ours_keys().contains(&"policy.init_from_scan"));
    let err = error_of(&set("vil-gic-rbf10", "true"));
    assert!(
        err.contains("policy.init_from_scan") && err.contains("test.toml"),
        "{err}"
    );

    let seed = 3;
    let scanned = arm::rbf_policy(&cfg, seed).unwrap();
    let random = arm::rbf_policy(&base, seed).unwrap();
    let (setup, _) = arm::setup(&cfg, scanned.clone(), seed).unwrap();
    let delta_max = cfg.policy.delta_max.unwrap();
    // The search roll-out's increments at each step, along its own path (as the arm starts
    // at rest on the path's first point, the observations only fix where the path begins).
    let start = [cfg.start.state[0], cfg.start.state[1], 0.0, 0.0, 0.0, 0.0];
    let scan: Vec<Vec<f64>> = (0..cfg.horizon)
        .map(|t| (setup.explore)(seed, t, &start))
        .collect();
    let centres = scanned.centres();
    assert_eq!(2 * centres.nrows(), cfg.horizon, "one centre per two steps");
    let mut worst: f64 = 0.0;
    let mut moved = false;
    for i in 0..centres.nrows() {
        let obs = [
            centres[(i, 0)],
            centres[(i, 1)],
            centres[(i, 2)],
            centres[(i, 3)],
            0.0,
            0.0,
        ];
        let a = setup.act(&scanned, None, 0, &obs);
        let r = setup.act(&random, None, 0, &obs);
        assert_eq!(a[..2], r[..2], "centre {i}: the gains stay the random ones");
        // Centre i sits at t = (2i + 1) · 0.1 s, between steps 2i and 2i + 1.
        for axis in 0..2 {
            let want = 0.5 * (scan[2 * i][2 + axis] + scan[2 * i + 1][2 + axis]);
            worst = worst.max((a[2 + axis] - want).abs() / delta_max);
            moved |= want.abs() > 0.1 * delta_max;
        }
    }
    assert!(moved, "the scan moves");
    assert!(worst < 0.05, "largest error {worst} of delta_max");
}
