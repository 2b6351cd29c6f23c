use super::*;
use crate::summary::EpisodeSummary;
use vicpilco_learn::record::EpisodeRecord;

fn summary(returns: &[(f64, bool)]) -> Summary {
    let episodes = returns
        .iter()
        .enumerate()
        .map(|(i, &(r, ok))| EpisodeSummary {
            record: EpisodeRecord {
                index: i + 1,
                predicted_return_mean: r * 1.05,
                predicted_return_std: 1.0,
                recorded_return: r,
                success: ok,
                rollouts: 1,
                success_fraction: if ok { 1.0 } else { 0.0 },
                interaction_s: 10.0,
                train_s: 1.0,
                optimise_s: 10.0,
                evaluations: 60,
                line_searches: 50,
                slope_capped: None,
                termination: "test".into(),
                objective_start: r,
                objective_end: r,
                n_train: 100,
                sparse: false,
                cold_restarts: 0,
                model_selection: None,
            },
            colour: crate::summary::colour(if ok { 1.0 } else { 0.0 }).into(),
            final_x: None,
            max_force: None,
            start_y: None,
        })
        .collect();
    Summary {
        initial_return: Some(120.0),
        episodes,
        wall_s: 100.0 * returns.len() as f64,
        constant_gain_return: Some(110.0),
        ..Summary::new(
            "vil-gic-rbf10",
            1,
            Some("gic".into()),
            "rbf",
            68,
            serde_json::Value::Null,
        )
    }
}

fn cfg(name: &str) -> ArmExperiment {
    crate::load_config(name, None).unwrap().unwrap()
}

fn verdict(checks: &[ThesisCheck], claim: &str) -> Option<bool> {
    checks
        .iter()
        .find(|c| c.claim.contains(claim))
        .unwrap_or_else(|| panic!("no claim `{claim}` in {checks:?}"))
        .pass
}

#[test]
fn vil_claims_pass_fail_or_wait_for_enough_updates() {
    let c = cfg("vil-gic-rbf10");
    let good: Vec<_> = (0..25)
        .map(|i| (if i < 3 { 90.0 } else { 62.0 }, i >= 3))
        .collect();
    let checks = thesis_checks("vil-gic-rbf10", &c, 25, &summary(&good));
    assert_eq!(verdict(&checks, "updates 6-10 inserts"), Some(true));
    assert_eq!(verdict(&checks, "updates 6-10 <= 75"), Some(true));
    assert_eq!(verdict(&checks, "updates 21-25 <= 70"), Some(true));
    assert_eq!(verdict(&checks, "within 15 %"), Some(true));
    assert_eq!(verdict(&checks, "initial OU"), Some(true));
    assert_eq!(verdict(&checks, "wall time"), Some(true));

    let mut bad = good.clone();
    bad[7] = (80.0, false);
    let checks = thesis_checks("vil-gic-rbf10", &c, 25, &summary(&bad));
    assert_eq!(verdict(&checks, "updates 6-10 inserts"), Some(false));

    let short = thesis_checks("vil-gic-rbf10", &c, 25, &summary(&good[..4]));
    assert_eq!(verdict(&short, "updates 6-10 inserts"), None);
    assert_eq!(verdict(&short, "initial OU"), None);
    // The first updates are the cheapest: the time is judged over the whole run only.
    assert_eq!(verdict(&short, "wall time"), None);
}

#[test]
fn linear_policy_needs_five_inserting_updates_in_a_row_by_update_20() {
    let c = cfg("vil-gic-lin");
    let late: Vec<_> = (1..=25).map(|i| (70.0, i >= 17)).collect();
    let checks = thesis_checks("vil-gic-lin", &c, 25, &summary(&late));
    assert_eq!(verdict(&checks, "5 consecutive"), Some(false));
    let early: Vec<_> = (1..=25).map(|i| (70.0, i >= 12)).collect();
    let checks = thesis_checks("vil-gic-lin", &c, 25, &summary(&early));
    assert_eq!(verdict(&checks, "5 consecutive"), Some(true));
    // Stopped part-way: open while updates 16-20 could still all insert, failed once not.
    let part = |n: usize, inserting: &[usize]| {
        let eps: Vec<_> = (1..=n).map(|i| (70.0, inserting.contains(&i))).collect();
        verdict(
            &thesis_checks("vil-gic-lin", &c, 25, &summary(&eps)),
            "5 consecutive",
        )
    };
    assert_eq!(part(15, &[]), None);
    assert_eq!(part(16, &[16]), None);
    assert_eq!(part(16, &[]), Some(false));
    assert_eq!(part(17, &[11, 12, 13, 16]), Some(false));
    assert_eq!(part(17, &[13, 14, 15, 16, 17]), Some(true));
}

#[test]
fn vilta_needs_an_early_insertion_three_more_in_a_row_and_a_low_final_return() {
    let c = cfg("vilta");
    let run = |returns: &[(f64, bool)]| thesis_checks("vilta", &c, 20, &summary(returns));
    let row = |checks: &[ThesisCheck], id: &str| {
        let r = checks.iter().find(|c| c.id == id).unwrap();
        (r.measured.clone(), r.pass)
    };
    // The thesis's course: found at 3, lost at 4, consistent from 5, final 20.
    let thesis: Vec<_> = (1..=20)
        .map(|i| (if i >= 5 { 20.0 } else { 60.0 }, i == 3 || i >= 5))
        .collect();
    let checks = run(&thesis);
    assert_eq!(
        row(&checks, "vilta_first_insertion"),
        ("update 3".into(), Some(true))
    );
    assert_eq!(
        row(&checks, "vilta_three_after_first"),
        ("from update 5".into(), Some(true))
    );
    assert_eq!(
        row(&checks, "vilta_final_return"),
        ("20.0".into(), Some(true))
    );

    // Complete and never inserting: every part fails, and says "never", not "not yet".
    let never = run(&[(100.0, false); 20]);
    assert_eq!(
        row(&never, "vilta_first_insertion"),
        ("never".into(), Some(false))
    );
    assert_eq!(
        row(&never, "vilta_three_after_first"),
        ("never".into(), Some(false))
    );
    assert_eq!(row(&never, "vilta_final_return").1, Some(false));

    // Inserting late, or only once, fails; a final return of 25.01 fails.
    let late: Vec<_> = (1..=20).map(|i| (20.0, i >= 13)).collect();
    assert_eq!(row(&run(&late), "vilta_first_insertion").1, Some(false));
    let once: Vec<_> = (1..=20).map(|i| (20.0, i == 2)).collect();
    assert_eq!(
        row(&run(&once), "vilta_three_after_first"),
        ("never".into(), Some(false))
    );
    let mut close = thesis.clone();
    close[19].0 = 25.01;
    assert_eq!(row(&run(&close), "vilta_final_return").1, Some(false));

    // Stopped part-way: undecided until 12 updates have passed without an insertion.
    let partial = run(&[(100.0, false); 8]);
    assert_eq!(
        row(&partial, "vilta_first_insertion"),
        ("not yet (8 updates)".into(), None)
    );
    assert_eq!(
        row(&partial, "vilta_three_after_first"),
        ("not yet (8 updates)".into(), None)
    );
    assert_eq!(row(&partial, "vilta_final_return").1, None);
    let stalled = run(&[(100.0, false); 12]);
    assert_eq!(
        row(&stalled, "vilta_first_insertion"),
        ("not yet (12 updates)".into(), Some(false))
    );
}

#[test]
fn gain_means_cover_the_windows_and_the_whole_episode() {
    // k_x = 10 t, k_y = 100 − t/2 over t = 0..99 (steps of 0.1 s: 20 steps per 2 s window).
    let actions: Vec<Vec<f64>> = (0..100)
        .map(|t| vec![10.0 * t as f64, 100.0 - 0.5 * t as f64])
        .collect();
    let r = Rollout {
        observations: vec![vec![0.0]; 101],
        actions: actions.clone(),
        true_states: vec![vec![0.0]; 101],
        infos: Vec::new(),
        used_for_training: true,
    };
    let [first, last] = gains_first_last(&r, 0.1);
    assert_eq!(first, [95.0, 95.25]);
    assert_eq!(last, [895.0, 55.25]);
    assert_eq!(mean_gains(&actions), [495.0, 75.25]);

    let mut s = summary(&[(70.0, true)]);
    s.final_gains = Some([first, last]);
    s.final_mean_gains = Some(mean_gains(&actions));
    let checks = thesis_checks("vil-sic", &cfg("vil-sic"), 25, &s);
    let row = checks
        .iter()
        .find(|c| c.claim.contains("mean k_y"))
        .unwrap();
    assert_eq!(row.measured, "75 N/m (first 2 s 95, last 2 s 55)");
    assert_eq!(row.pass, None);
}

#[test]
fn the_most_successful_rule_keeps_the_latest_best_update_and_else_the_last() {
    let with_fractions = |fractions: &[f64]| {
        let mut s = summary(&vec![(100.0, false); fractions.len()]);
        for (e, &f) in s.episodes.iter_mut().zip(fractions) {
            e.record.success_fraction = f;
        }
        s.episodes
    };
    let mixed = with_fractions(&[0.0, 0.5, 1.0, 0.25, 1.0, 0.75, 0.0]);
    assert_eq!(final_update(FinalPolicy::MostSuccessful, &mixed), 5);
    assert_eq!(final_update(FinalPolicy::Last, &mixed), 7);
    let never = with_fractions(&[0.0; 4]);
    assert_eq!(final_update(FinalPolicy::MostSuccessful, &never), 4);
    assert_eq!(final_update(FinalPolicy::MostSuccessful, &[]), 0);
    assert_eq!(final_update(FinalPolicy::Last, &[]), 0);
}

/// Every claim has an id of its own and an acceptance rule, but the reported-only ones
/// (`REPORTED_ONLY`), which have neither rule nor verdict.
#[test]
fn every_claim_has_a_unique_id_and_a_seed_rule() {
    for name in [
        "vil-gic-rbf10",
        "vil-gic-lin",
        "vil-sic",
        "vilta",
        "vilta-var",
    ] {
        let c = cfg(name);
        let mut s = summary(&[(70.0, true); 25]);
        s.final_eval = Some(FinalEval {
            starts: 20,
            successes: 18,
            fraction: 0.9,
            update: Some(25),
        });
        let checks = thesis_checks(name, &c, 25, &s);
        assert!(!checks.is_empty(), "{name}");
        for (i, a) in checks.iter().enumerate() {
            assert!(!a.id.is_empty(), "{name}: {}", a.claim);
            let reported = vicpilco_report::REPORTED_ONLY.contains(&a.id.as_str());
            assert_eq!(a.across_seeds.is_none(), reported, "{name}: {}", a.claim);
            if reported {
                assert_eq!(a.pass, None, "{name}: {}", a.claim);
            }
            assert!(
                checks[i + 1..].iter().all(|b| b.id != a.id),
                "{name}: {}",
                a.id
            );
        }
        let rule = |id: &str| checks.iter().find(|c| c.id == id).map(|c| c.across_seeds);
        if name.starts_with("vil-") {
            assert_eq!(rule(FINAL_BELOW_INITIAL), Some(Some(EVERY_RUN)));
        }
        if name == "vil-sic" {
            assert_eq!(rule(SIC_MEAN_K_Y_ABOVE_GIC), Some(Some(THREE_OF_FIVE)));
        }
        if name == "vilta" {
            assert_eq!(rule(vicpilco_report::VILTA_GAINS_LOWERED), Some(None));
        }
    }
}

/// The acceptance table's same-seed bundles name claims by id: each bundle's ids are claims one
/// shipped experiment makes, all with the same seed rule, so a renamed claim cannot drop a
/// bundle's row unnoticed.
#[test]
fn every_same_seed_bundle_names_claims_one_experiment_makes() {
    let made: Vec<Vec<ThesisCheck>> = crate::config::CONFIGS
        .iter()
        .map(|(name, _)| {
            let c = cfg(name);
            thesis_checks(name, &c, c.episodes, &summary(&[(60.0, true); 25]))
        })
        .collect();
    for (label, ids) in vicpilco_report::SAME_SEED_BUNDLES {
        let owner = made
            .iter()
            .find(|checks| ids.iter().all(|id| checks.iter().any(|c| c.id == *id)))
            .unwrap_or_else(|| panic!("no experiment makes every claim of `{label}`: {ids:?}"));
        let rules: Vec<_> = ids
            .iter()
            .map(|id| owner.iter().find(|c| c.id == *id).unwrap().across_seeds)
            .collect();
        assert!(
            rules[0].is_some() && rules.iter().all(|r| *r == rules[0]),
            "{label}: {rules:?}"
        );
    }
}
