//! `vilta.max_lead_in_search = false` (ours) records VILTA's initial search roll-out without
//! the reference-lead bound and leaves the bound on the learned policy's roll-outs: the search
//! is then the unbounded one, bit for bit, while with the default the bound holds it back.

mod common;

use std::path::Path;
use vicpilco_experiments::{config, run, RunOptions};

/// The bound the test sets: small enough that the scan's reference, which leads the TCP by
/// well over 10 cm once the peg meets the face, is held back by it.
const LEAD: f64 = 0.03;

fn scratch(name: &str) -> common::Scratch {
    common::scratch("search-lead", name)
}

/// The search roll-out of a vilta run with `vilta_lines` added to its `[vilta]` table, and no
/// update (no GP fit or optimisation to pay for).
fn search_rollout(name: &str, vilta_lines: &str) -> serde_json::Value {
    let dir = scratch(name);
    std::fs::create_dir_all(&dir).unwrap();
    let anchor = "rollouts_per_iteration = 1";
    let shipped = config::shipped("vilta").unwrap().1;
    assert!(shipped.contains(anchor));
    let cfg = dir.join("vilta.toml");
    std::fs::write(
        &cfg,
        shipped.replace(anchor, &format!("{anchor}\n{vilta_lines}")),
    )
    .unwrap();
    let opts = RunOptions {
        seed: 3,
        out: dir.join("run"),
        episodes: Some(0),
        config: Some(cfg),
        ..Default::default()
    };
    run("vilta", &opts, &mut ()).expect("vilta with 0 updates");
    first_line(&dir.join("run").join("rollouts.jsonl"))
}

fn first_line(path: &Path) -> serde_json::Value {
    common::json_lines(path)
        .into_iter()
        .next()
        .expect("the search roll-out")
}

/// Largest lead of the reference over the true TCP position, on x or y, at a step's end.
fn largest_lead(record: &serde_json::Value) -> f64 {
    let infos = record["rollout"]["infos"].as_array().unwrap();
    infos
        .iter()
        .flat_map(|i| {
            let r = &i["reference"];
            let s = &i["true_state"];
            (0..2).map(move |a| (r[a].as_f64().unwrap() - s[a].as_f64().unwrap()).abs())
        })
        .fold(0.0, f64::max)
}

#[test]
fn the_search_roll_out_runs_free_of_the_lead_bound_only_when_exempted() {
    let unbounded = search_rollout("unbounded", "");
    let bounded = search_rollout("bounded", &format!("max_lead = {LEAD}"));
    let exempted = search_rollout(
        "exempted",
        &format!("max_lead = {LEAD}\nmax_lead_in_search = false"),
    );
    assert!(
        largest_lead(&unbounded) > 2.0 * LEAD,
        "the unbounded scan leads by {}",
        largest_lead(&unbounded)
    );
    assert!(
        largest_lead(&bounded) <= LEAD + 1e-12,
        "bounded: {}",
        largest_lead(&bounded)
    );
    assert_eq!(
        exempted, unbounded,
        "the exempted search is the unbounded one"
    );
}

#[test]
fn exempting_the_search_needs_a_bound_and_is_an_ours_key() {
    let shipped = config::shipped("vilta").unwrap().1;
    let anchor = "rollouts_per_iteration = 1";
    let with = |lines: &str| shipped.replace(anchor, &format!("{anchor}\n{lines}"));
    let cfg = config::parse(
        &with("max_lead = 0.1\nmax_lead_in_search = false"),
        "test.toml",
    )
    .unwrap();
    assert!(cfg.ours_keys().contains(&"vilta.max_lead_in_search"));
    let base = config::parse(shipped, "test.toml").unwrap();
    assert!(!base.ours_keys().contains(&"vilta.max_lead_in_search"));
    // The default is not written, so stored runs keep their identity.
    let written = serde_json::to_value(&base).unwrap();
    assert!(
        written["vilta"].get("max_lead_in_search").is_none(),
        "{written}"
    );

    let err = config::parse(&with("max_lead_in_search = false"), "test.toml")
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("vilta.max_lead_in_search") && err.contains("test.toml"),
        "{err}"
    );
}

/// The initial roll-outs' environment must match the updates' in layout, step and horizon:
/// a pendulum learner given an arm for its initial roll-out is refused before anything runs.
#[test]
fn an_initial_environment_of_another_layout_is_refused() {
    use vicpilco_env::arm::{ArmConfig, ArmEnv};
    use vicpilco_env::classic::PendulumScenario;
    let (setup, mut env) =
        vicpilco_experiments::classic::setup(PendulumScenario::default(), 1).unwrap();
    let mut arm = ArmEnv::new(ArmConfig::default()).unwrap();
    let err = setup
        .run_with_initial_env(&mut arm, &mut env, &mut ())
        .err()
        .expect("a refusal")
        .to_string();
    assert!(err.contains("initial roll-outs' environment"), "{err}");
}
