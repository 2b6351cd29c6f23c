use super::*;
use std::collections::BTreeMap;
use vicpilco_env::StepInfo;

fn cfg(name: &str) -> ArmExperiment {
    crate::load_config(name, None).unwrap().unwrap()
}

#[test]
fn vilta_search_rollout_scans_from_the_start_to_the_last_via_point() {
    let c = cfg("vilta");
    let arm = arm_config(&c);
    let explore = explore_policy(&c, &arm, OuParams::default());
    let ticks = c.dt / c.vilta.as_ref().unwrap().delta_tick;
    let start = [0.5, 0.0, 0.0, 0.0, 0.0, 0.0];
    let (mut x, mut y) = (start[0], start[1]);
    for t in 0..c.horizon {
        let a = explore(7, t, &start);
        assert_eq!(a.len(), 4);
        assert!((c.policy.k_min..=c.policy.k_max).contains(&a[0]));
        for d in &a[2..] {
            assert!(d.abs() <= c.policy.delta_max.unwrap(), "step {t}: {d}");
        }
        x += a[2] * ticks;
        y += a[3] * ticks;
    }
    assert!(
        (x - 0.75).abs() < 1e-12 && (y - 0.30).abs() < 1e-12,
        "({x}, {y})"
    );
}

/// With `initial.scan_jitter` the integrated reference leaves the scan by a seeded offset
/// bounded by 3 std (the clip), and without it follows the scan exactly.
#[test]
fn scan_jitter_moves_the_reference_off_the_scan_within_three_std() {
    let plain = cfg("vilta");
    let mut c = plain.clone();
    let std = 0.02;
    c.initial.scan_jitter = Some(crate::config::ScanJitter { std, theta: 2.0 });
    c.validate("test").unwrap();
    let arm = arm_config(&c);
    let ticks = c.dt / c.vilta.as_ref().unwrap().delta_tick;
    let start = [0.5, 0.0, 0.0, 0.0, 0.0, 0.0];
    let references = |c: &ArmExperiment, seed: u64| {
        let explore = explore_policy(c, &arm, OuParams::default());
        let (mut x, mut y) = (start[0], start[1]);
        let mut out = vec![];
        for t in 0..c.horizon {
            let a = explore(seed, t, &start);
            for d in &a[2..] {
                assert!(d.abs() <= c.policy.delta_max.unwrap(), "step {t}: {d}");
            }
            x += a[2] * ticks;
            y += a[3] * ticks;
            out.push([x, y]);
        }
        out
    };
    let scan = references(&plain, 7);
    let jittered = references(&c, 7);
    let mut largest = 0.0_f64;
    for (s, j) in scan.iter().zip(&jittered) {
        for i in 0..2 {
            let off = (j[i] - s[i]).abs();
            assert!(off <= 3.0 * std + 1e-12, "offset {off}");
            largest = largest.max(off);
        }
    }
    assert!(largest > 0.5 * std, "largest offset {largest}");
    assert_eq!(jittered, references(&c, 7));
    assert_ne!(jittered, references(&c, 8));
}

/// `cost.force_width_far` adds `1 − exp(−½|f|²/w²)` to the immediate cost, and leaves the
/// rest of the cost as it was.
#[test]
fn force_width_far_adds_a_wide_saturating_force_cost() {
    let plain = cfg("vilta");
    let mut c = plain.clone();
    let far = 250.0;
    c.cost.force_width_far = Some(far);
    c.validate("test").unwrap();
    let cost = |c: &ArmExperiment, x: &[f64]| {
        let p = problem(c, &arm_config(c)).unwrap();
        p.ret.state_cost.unwrap().eval(x)
    };
    for f in [[0.0, 0.0], [9.0, 0.0], [178.0, -40.0], [1500.0, 0.0]] {
        let x = [0.77, 0.2, 0.0, 0.0, f[0], f[1]];
        let added = 1.0 - (-0.5 * (f[0] * f[0] + f[1] * f[1]) / (far * far)).exp();
        let diff = cost(&c, &x) - cost(&plain, &x);
        assert!(
            (diff - added).abs() < 1e-12,
            "f = {f:?}: {diff} against {added}"
        );
    }
}

#[test]
fn gp_input_names_follow_the_issue_tables() {
    let names = |name: &str| {
        let c = cfg(name);
        let (setup, env) = setup(&c, rbf_policy(&c, 0).unwrap(), 0).unwrap();
        gp_input_names(&setup.spec, &env)
    };
    assert_eq!(
        names("vil-gic-rbf10"),
        ["x", "y", "xd", "yd", "t", "k_x", "k_y"]
    );
    assert_eq!(
        names("vilta"),
        ["x", "y", "xd", "yd", "k_x", "k_y", "dx_ref", "dy_ref"]
    );
}

#[test]
fn success_needs_the_inserted_flag_at_the_end_of_a_full_episode() {
    let info = |inserted: bool, singular: bool| StepInfo {
        flags: BTreeMap::from([
            ("inserted".to_string(), inserted),
            ("singular".to_string(), singular),
        ]),
        ..StepInfo::default()
    };
    let rollout = |infos: Vec<StepInfo>| Rollout {
        observations: vec![],
        actions: vec![],
        true_states: vec![],
        infos,
        used_for_training: true,
    };
    assert!(inserted(&rollout(vec![
        info(false, false),
        info(true, false)
    ])));
    assert!(!inserted(&rollout(vec![
        info(true, false),
        info(false, false)
    ])));
    assert!(!inserted(&rollout(vec![
        info(false, true),
        info(true, false)
    ])));
    let mut runaway = info(true, false);
    runaway.stopped_early = Some("simulation diverged".into());
    assert!(!inserted(&rollout(vec![info(false, false), runaway])));
    assert!(!inserted(&rollout(vec![])));
}
