//! After an arm run: the final policy's evaluations (fresh starts for `vilta-var`, constant
//! gains for comparison) and the thesis's claims beside what the run measured (issue 6's
//! acceptance numbers; `pass` is `null` while the run is too short to decide).

use crate::config::{ArmExperiment, FinalPolicy, PolicyKind, Task};
use crate::summary::{EpisodeSummary, FinalEval, SeedRule, Summary, ThesisCheck};
use crate::{arm, ExperimentError, RunOptions};
use vicpilco_env::Environment;
use vicpilco_learn::data::Rollout;
use vicpilco_learn::outer::{derive_seed, rollout, LoopOutcome, LoopSetup};
use vicpilco_pilco::policy::Policy;
// The vil-sic claim that needs a GIC run of the same seed: `vicpilco acceptance` decides it by
// comparing the two runs' `final_mean_gains` k_y.
use vicpilco_report::{FINAL_BELOW_INITIAL, SIC_MEAN_K_Y_ABOVE_GIC};

/// Stiffness (N/m) of the constant-gain comparison: the middle of the VIL range.
pub const CONSTANT_GAIN: f64 = 127.5;
/// Seconds at the start and end of an episode over which the final gains are averaged.
pub const GAIN_WINDOW_S: f64 = 2.0;
/// Upper bound on the mean time per policy update of vil-gic-rbf10 (s) (issue 6).
pub const EPISODE_TIME_BAR_S: f64 = 240.0;
/// Most claims: at least 3 of the 5 acceptance seeds pass (issue 6).
pub const THREE_OF_FIVE: SeedRule = SeedRule {
    passing: 3,
    seeds: 5,
};
/// "Every VIL run's final return ...": all 5 acceptance seeds pass.
pub const EVERY_RUN: SeedRule = SeedRule {
    passing: 5,
    seeds: 5,
};

/// Evaluate the final policy where the config asks for it, and the constant-gain roll-out of
/// VIL runs; add them and the thesis checks to the summary.
pub fn after_run<P>(
    cfg: &ArmExperiment,
    mut summary: Summary,
    outcome: &LoopOutcome<P>,
    opts: &RunOptions,
) -> Result<Summary, ExperimentError>
where
    P: Policy + Clone + Sync,
    P::Cache: Send,
{
    let (setup, mut env) = arm::setup(cfg, outcome.policy.clone(), opts.seed)?;
    if cfg.task == Task::Vil {
        let start = setup
            .env_start
            .sample(derive_seed(opts.seed, 0, arm::PURPOSE_EVALUATION))?;
        let r = rollout(
            &mut env,
            &start,
            derive_seed(opts.seed, 1, arm::PURPOSE_EVALUATION),
            |_, _| Ok(vec![CONSTANT_GAIN, CONSTANT_GAIN]),
        )?;
        summary.constant_gain_return = Some(setup.recorded_return(&r));
        summary.constant_gain_inserted = Some(arm::inserted(&r));
    }
    let n_eval = cfg.vilta.as_ref().map_or(0, |v| v.evaluation_starts);
    if n_eval > 0 {
        let rule = cfg
            .vilta
            .as_ref()
            .map_or(FinalPolicy::Last, |v| v.final_policy);
        let update = final_update(rule, &summary.episodes);
        let mut policy = outcome.policy.clone();
        if update != final_update(FinalPolicy::Last, &summary.episodes) {
            // Every update's policy is in the run directory, also those of earlier sessions
            // of a resumed run.
            let params = crate::replay::read_policies(&opts.out, summary.episodes.len())?;
            policy.set_params(&params[update])?;
        }
        let path = opts.out.join("final_eval.jsonl");
        let mut lines = String::new();
        let mut successes = 0;
        for (start_y, r) in fresh_start_rollouts(&setup, &mut env, &policy, opts.seed, n_eval)? {
            let ok = arm::inserted(&r);
            successes += usize::from(ok);
            let line = serde_json::json!({ "start_y": start_y, "success": ok, "rollout": r });
            lines.push_str(&line.to_string());
            lines.push('\n');
        }
        std::fs::write(&path, lines).map_err(|e| ExperimentError::Io { path, source: e })?;
        summary.final_eval = Some(FinalEval {
            starts: n_eval,
            successes,
            fraction: successes as f64 / n_eval as f64,
            update: Some(update),
        });
    }
    Ok(summary)
}

/// The update whose policy is the run's result under `rule` (0 when there are no updates:
/// the untrained policy). Under [`FinalPolicy::MostSuccessful`] it is the update with the
/// largest fraction of inserting roll-outs, the latest of equals: with no insertion at all,
/// the last update, as under [`FinalPolicy::Last`].
pub fn final_update(rule: FinalPolicy, episodes: &[EpisodeSummary]) -> usize {
    match rule {
        FinalPolicy::Last => episodes.last().map_or(0, |e| e.index),
        // `max_by` returns the last of equal elements.
        FinalPolicy::MostSuccessful => episodes
            .iter()
            .max_by(|a, b| a.success_fraction.total_cmp(&b.success_fraction))
            .map_or(0, |e| e.index),
    }
}

/// `policy` rolled out from `n` fresh starts of the run's start distribution, with each start's
/// y: the final evaluation's roll-outs, and `vicpilco evaluate`'s for any update. Start i draws
/// from its own seeds, which no learning roll-out uses and which do not depend on the policy,
/// so every policy of a run meets the same starts with the same noise.
pub fn fresh_start_rollouts<P: Policy + Clone + Sync>(
    setup: &LoopSetup<P>,
    env: &mut dyn Environment,
    policy: &P,
    seed: u64,
    n: usize,
) -> Result<Vec<(f64, Rollout)>, ExperimentError> {
    (0..n)
        .map(|i| {
            let base = derive_seed(seed, 1000 + i as u64, arm::PURPOSE_EVALUATION);
            let start = setup.env_start.sample(derive_seed(base, 0, 1))?;
            let r = rollout(env, &start, derive_seed(base, 0, 2), |t, obs| {
                Ok(setup.act(policy, None, t, obs))
            })?;
            Ok((start[1], r))
        })
        .collect()
}

/// Mean (k_x, k_y) over the first and the last [`GAIN_WINDOW_S`] seconds of a roll-out.
pub fn gains_first_last(r: &Rollout, dt: f64) -> [[f64; 2]; 2] {
    let n = ((GAIN_WINDOW_S / dt).round() as usize).clamp(1, r.len().max(1));
    let len = r.actions.len();
    [
        mean_gains(&r.actions[..n.min(len)]),
        mean_gains(&r.actions[len.saturating_sub(n)..]),
    ]
}

/// Mean (k_x, k_y), the first two action components, over `actions`.
pub fn mean_gains(actions: &[Vec<f64>]) -> [f64; 2] {
    let c = actions.len().max(1) as f64;
    [
        actions.iter().map(|a| a[0]).sum::<f64>() / c,
        actions.iter().map(|a| a[1]).sum::<f64>() / c,
    ]
}

/// A claim decided per seed and accepted under [`THREE_OF_FIVE`].
fn check(id: &str, claim: &str, thesis: &str, measured: String, pass: Option<bool>) -> ThesisCheck {
    ThesisCheck {
        id: id.into(),
        claim: claim.into(),
        thesis: thesis.into(),
        measured,
        pass,
        across_seeds: Some(THREE_OF_FIVE),
    }
}

/// A claim accepted under [`EVERY_RUN`].
fn check_every_run(
    id: &str,
    claim: &str,
    thesis: &str,
    measured: String,
    pass: Option<bool>,
) -> ThesisCheck {
    ThesisCheck {
        across_seeds: Some(EVERY_RUN),
        ..check(id, claim, thesis, measured, pass)
    }
}

/// Mean recorded return over updates `from..=to` (1-based), if the run has them all.
fn mean_return(s: &Summary, from: usize, to: usize) -> Option<f64> {
    let eps: Vec<_> = s
        .episodes
        .iter()
        .filter(|e| (from..=to).contains(&e.index))
        .collect();
    (eps.len() == to - from + 1)
        .then(|| eps.iter().map(|e| e.recorded_return).sum::<f64>() / eps.len() as f64)
}

fn fmt_opt(v: Option<f64>) -> String {
    v.map_or("n.a.".into(), |v| format!("{v:.1}"))
}

/// The first update from which `streak` consecutive updates all inserted (every roll-out).
fn streak_start(s: &Summary, streak: usize) -> Option<usize> {
    let mut run = 0;
    for e in &s.episodes {
        run = if e.all_inserted() { run + 1 } else { 0 };
        if run >= streak {
            return Some(e.index + 1 - streak);
        }
    }
    None
}

/// The claims of issue 6 that apply to this run. Claims about the end of a run are decided
/// only once it has `planned` updates (the config's number, before `--episodes`/`--quick`).
pub fn thesis_checks(
    name: &str,
    cfg: &ArmExperiment,
    planned: usize,
    s: &Summary,
) -> Vec<ThesisCheck> {
    let n = s.episodes.len();
    let full = n >= planned;
    let last = s.episodes.last();
    let final_return = last.map(|e| e.recorded_return);
    let mut out = Vec::new();
    let vil_rbf = cfg.task == Task::Vil
        && cfg.controller == vicpilco_env::arm::ControllerKind::Gic
        && cfg.policy.kind == PolicyKind::Rbf;
    if vil_rbf {
        let window: Vec<_> = s
            .episodes
            .iter()
            .filter(|e| (6..=10).contains(&e.index))
            .collect();
        let inserted = window.iter().filter(|e| e.all_inserted()).count();
        out.push(check(
            "updates_6_10_insert",
            "every roll-out of updates 6-10 inserts",
            "strategy found before 10 episodes",
            format!("{inserted}/{}", window.len()),
            (window.len() == 5).then_some(inserted == 5),
        ));
        let m = mean_return(s, 6, 10);
        out.push(check(
            "mean_return_6_10",
            "mean recorded return over updates 6-10 <= 75",
            "about 61",
            fmt_opt(m),
            m.map(|m| m <= 75.0),
        ));
        let m = mean_return(s, 21, 25);
        out.push(check(
            "mean_return_21_25",
            "mean recorded return over updates 21-25 <= 70",
            "about 61",
            fmt_opt(m),
            m.map(|m| m <= 70.0),
        ));
        let e10 = s.episodes.iter().find(|e| e.index == 10);
        out.push(check(
            "prediction_at_10",
            "predicted return at update 10 within 15 % of the recorded one",
            "predictions match the system (Fig. 5-8)",
            e10.map_or("n.a.".into(), |e| {
                format!("{:.1} vs {:.1}", e.predicted_return_mean, e.recorded_return)
            }),
            e10.map(|e| {
                (e.predicted_return_mean - e.recorded_return).abs() <= 0.15 * e.recorded_return
            }),
        ));
    }
    if cfg.task == Task::Vil && cfg.policy.kind == PolicyKind::Linear {
        let first = streak_start(s, 5);
        // Decided as soon as the updates left before 20 cannot complete a streak of 5.
        let trailing = s
            .episodes
            .iter()
            .rev()
            .take_while(|e| e.all_inserted())
            .count();
        let out_of_reach = n >= 20 || trailing + (20 - n) < 5;
        out.push(check(
            "five_inserting_by_20",
            "5 consecutive inserting updates by update 20",
            "about 15 trials, 9 failures first; converges to about 61",
            first.map_or("never".into(), |f| format!("updates {f}-{}", f + 4)),
            if first.is_some_and(|f| f + 4 <= 20) {
                Some(true)
            } else {
                out_of_reach.then_some(false)
            },
        ));
    }
    if cfg.task == Task::Vil && cfg.controller == vicpilco_env::arm::ControllerKind::Sic {
        out.push(check(
            "sic_final_return",
            "final return <= 90",
            "78 (80 in the caption of Fig. 5-7)",
            fmt_opt(final_return),
            full.then(|| final_return.is_some_and(|r| r <= 90.0)),
        ));
        let tail: Vec<_> = s.episodes.iter().rev().take(5).collect();
        let ok = tail.iter().filter(|e| e.all_inserted()).count();
        out.push(check(
            "sic_last_5_insert",
            "the last 5 updates insert",
            "inserts with higher stiffness than GIC",
            format!("{ok}/{}", tail.len()),
            (full && tail.len() == 5).then_some(ok == 5),
        ));
        out.push(check(
            SIC_MEAN_K_Y_ABOVE_GIC,
            "mean k_y over the last roll-out above the GIC run's (vicpilco acceptance pairs the seeds)",
            "SIC needs stiffer gains",
            match (s.final_mean_gains, s.final_gains) {
                (Some(m), Some(g)) => format!(
                    "{:.0} N/m (first 2 s {:.0}, last 2 s {:.0})",
                    m[1], g[0][1], g[1][1]
                ),
                _ => "n.a.".into(),
            },
            None,
        ));
    }
    if cfg.task == Task::Vil {
        let bar = [s.initial_return, s.constant_gain_return];
        out.push(check_every_run(
            FINAL_BELOW_INITIAL,
            "final return below the initial OU roll-out's and constant gains' (127.5 N/m)",
            "learning improves on the initial profiles",
            format!(
                "{} vs {} and {}{}",
                fmt_opt(final_return),
                fmt_opt(bar[0]),
                fmt_opt(bar[1]),
                match s.constant_gain_inserted {
                    Some(true) => " (constant gains insert)",
                    Some(false) => " (constant gains do not insert)",
                    None => "",
                }
            ),
            match (final_return, bar) {
                (Some(f), [Some(a), Some(b)]) if full => Some(f < a && f < b),
                _ => None,
            },
        ));
    }
    if cfg.task == Task::Vilta && cfg.start.y_range.is_none() {
        let first = s.episodes.iter().find(|e| e.success).map(|e| e.index);
        out.push(check(
            "vilta_first_insertion",
            "first insertion within 12 policy updates",
            "hole found at update 3",
            first.map_or("never".into(), |f| format!("update {f}")),
            first.map_or((n >= 12).then_some(false), |f| Some(f <= 12)),
        ));
        let after = first.and_then(|f| {
            s.episodes
                .iter()
                .filter(|e| e.index > f)
                .collect::<Vec<_>>()
                .windows(3)
                .find(|w| w.iter().all(|e| e.success))
                .map(|w| w[0].index)
        });
        out.push(check(
            "vilta_three_after_first",
            "3 consecutive inserting updates after the first insertion",
            "lost at 4, consistent from update 11",
            after.map_or("not yet".into(), |a| format!("from update {a}")),
            after.map(|_| true).or(full.then_some(false)),
        ));
        out.push(check(
            "vilta_final_return",
            "final return <= 25",
            "20",
            fmt_opt(final_return),
            full.then(|| final_return.is_some_and(|r| r <= 25.0)),
        ));
        out.push(check(
            "vilta_gains_lowered",
            "final gains lowered after insertion: mean (k_x, k_y) first vs last 2 s",
            "about 60 and 10 N/m at the end",
            s.final_gains.map_or("n.a.".into(), |g| {
                format!(
                    "({:.0}, {:.0}) -> ({:.0}, {:.0}) N/m",
                    g[0][0], g[0][1], g[1][0], g[1][1]
                )
            }),
            None,
        ));
    }
    if let Some(e) = &s.final_eval {
        out.push(check(
            "fresh_starts_insert",
            "the final policy (vilta.final_policy) inserts from >= 80 % of fresh starts y0 ~ U[0.1, 0.3]",
            "hole found over the whole interval after 10 iterations",
            match e.update {
                Some(u) => format!("{}/{} (update {u})", e.successes, e.starts),
                None => format!("{}/{}", e.successes, e.starts),
            },
            full.then_some(e.fraction >= 0.8),
        ));
    }
    if name == "vil-gic" || name == "vil-gic-rbf10" {
        let mean_wall = (n > 0).then(|| s.wall_s / n as f64);
        out.push(check_every_run(
            "time_per_update",
            "mean wall time per policy update <= 4 min",
            "17 min per episode (MATLAB, Xeon E5 3.5 GHz)",
            mean_wall.map_or("n.a.".into(), |w| format!("{w:.0} s")),
            mean_wall.map(|w| w <= EPISODE_TIME_BAR_S),
        ));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::summary::EpisodeSummary;
    use vicpilco_learn::outer::EpisodeRecord;

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
            experiment: "vil-gic-rbf10".into(),
            seed: 1,
            controller: Some("gic".into()),
            policy: "rbf".into(),
            n_params: 68,
            initial_return: Some(120.0),
            episodes,
            solved_at_episode: None,
            interaction_s: 0.0,
            wall_s: 100.0 * returns.len() as f64,
            config: serde_json::Value::Null,
            thesis_reference: Vec::new(),
            constant_gain_return: Some(110.0),
            constant_gain_inserted: None,
            final_eval: None,
            final_gains: None,
            final_mean_gains: None,
            sessions: Vec::new(),
            replayed_from: None,
        }
    }

    fn cfg(name: &str) -> ArmExperiment {
        let (file, text) = crate::config::shipped(name).unwrap();
        crate::config::parse(text, file).unwrap()
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
                assert!(a.across_seeds.is_some(), "{name}: {}", a.claim);
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
        }
    }
}
