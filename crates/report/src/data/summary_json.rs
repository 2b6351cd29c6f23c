//! Parsing `summary.json` (the one file a run directory must have) into [`Summary`].

use super::{Claim, Colour, Episode, Geometry, ReplaySource, SeedRule, Session, Summary};
use crate::json::Node;
use crate::ReportError;
use serde_json::Value;

pub(super) fn parse_summary(n: Node<'_>) -> Result<Summary, ReportError> {
    let episodes = n.req("episodes", |e| e.map_array(parse_episode))?;
    let (geometry, start_y_range, config_dt, config_episodes) = n.with("config", |c| match c {
        None => Ok((None, None, None, None)),
        Some(c) => Ok((
            c.with("geometry", |g| g.map(parse_geometry).transpose())?,
            c.with("start_y_range", |r| r.map(parse_interval).transpose())?,
            c.opt_f64("dt")?,
            c.opt_u64("episodes")?,
        )),
    })?;
    Ok(Summary {
        experiment: n.req("experiment", |e| e.string())?,
        seed: n.req_u64("seed")?,
        controller: n.opt_string("controller")?,
        policy: n.opt_string("policy")?,
        n_params: n.opt_u64("n_params")?,
        initial_return: n.opt_f64("initial_return")?,
        constant_gain_return: n.opt_f64("constant_gain_return")?,
        constant_gain_inserted: n.opt_bool("constant_gain_inserted")?,
        episodes,
        solved_at_episode: n.opt_u64("solved_at_episode")?,
        solved_streak: n.opt_u64("solved_streak")?,
        interaction_s: n.opt_f64("interaction_s")?,
        wall_s: n.opt_f64("wall_s")?,
        config: n.v.get("config").cloned(),
        geometry,
        start_y_range,
        config_dt,
        config_episodes,
        thesis_reference: n.with("thesis_reference", |t| {
            t.map(|t| t.map_array(parse_claim)).transpose()
        })?,
        final_mean_gains: n.with("final_mean_gains", |g| g.map(parse_pair).transpose())?,
        final_eval_update: n.with("final_eval", |e| match e {
            None => Ok(None),
            Some(e) => e.opt_u64("update"),
        })?,
        sessions: n.with("sessions", |s| {
            s.map(|s| s.map_array(parse_session))
                .transpose()
                .map(Option::unwrap_or_default)
        })?,
        replayed_from: n.with("replayed_from", |r| r.map(parse_replay_source).transpose())?,
    })
}

fn parse_replay_source(n: Node<'_>) -> Result<ReplaySource, ReportError> {
    Ok(ReplaySource {
        run: n.req("run", |c| c.string())?,
        recorded_final: n.with("recorded_returns", |c| {
            c.map(|c| c.f64_vec())
                .transpose()
                .map(|r| r.and_then(|r| r.last().copied()))
        })?,
        recorded_rule: n.req("recorded_rule", |c| c.string())?,
        recorded_updates: n.req_u64("recorded_updates")?,
        agreed: n.req_u64("agreed")?,
    })
}

fn parse_session(n: Node<'_>) -> Result<Session, ReportError> {
    Ok(Session {
        first_update: n.req_u64("first_update")?,
        commit: n.req("commit", |c| c.string())?,
        subnormals: n.req("subnormals", |c| c.string())?,
    })
}

fn parse_episode(n: Node<'_>) -> Result<Episode, ReportError> {
    Ok(Episode {
        index: n.req_u64("index")?,
        pred_mean: n.req_f64("predicted_return_mean")?,
        pred_std: n.req_f64("predicted_return_std")?,
        recorded: n.req_f64("recorded_return")?,
        success: n.opt_bool("success")?,
        success_fraction: n.opt_f64("success_fraction")?,
        colour: n.with("colour", |c| c.map(Colour::parse).transpose())?,
        train_s: n.opt_f64("train_s")?,
        optimise_s: n.opt_f64("optimise_s")?,
        evaluations: n.opt_u64("evaluations")?,
        final_x: n.opt_f64("final_x")?,
        max_force: n.opt_f64("max_force")?,
        n_train: n.opt_u64("n_train")?,
        sparse: n.opt_bool("sparse")?,
        kept_previous_model: n.with("model_selection", |m| {
            m.map(|m| m.req("kept_previous", |k| k.bool())).transpose()
        })?,
    })
}

fn parse_geometry(n: Node<'_>) -> Result<Geometry, ReportError> {
    Ok(Geometry {
        wall_x: n.req_f64("wall_x")?,
        hole_y: n.req_f64("hole_y")?,
        hole_r: n.req_f64("hole_r")?,
        end_x: n.req_f64("end_x")?,
    })
}

fn parse_interval(n: Node<'_>) -> Result<(f64, f64), ReportError> {
    parse_pair(n).map(|[a, b]| (a, b))
}

fn parse_pair(n: Node<'_>) -> Result<[f64; 2], ReportError> {
    match n.f64_vec()?.as_slice() {
        &[a, b] => Ok([a, b]),
        _ => Err(n.malformed("an array of two numbers")),
    }
}

fn parse_claim(n: Node<'_>) -> Result<Claim, ReportError> {
    // Free-text columns may be numbers in hand-written summaries; show them as written.
    let text = |key: &str| {
        n.with(key, |v| match v {
            None => String::new(),
            Some(v) => match v.v {
                Value::String(s) => s.clone(),
                other => other.to_string(),
            },
        })
    };
    Ok(Claim {
        id: n.opt_string("id")?.filter(|id| !id.is_empty()),
        claim: text("claim"),
        thesis: text("thesis"),
        measured: text("measured"),
        pass: n.opt_bool("pass")?,
        across_seeds: n.with("across_seeds", |r| r.map(parse_seed_rule).transpose())?,
    })
}

fn parse_seed_rule(r: Node<'_>) -> Result<SeedRule, ReportError> {
    let rule = SeedRule {
        passing: r.req_u64("passing")?,
        seeds: r.req_u64("seeds")?,
    };
    if rule.passing == 0 || rule.passing > rule.seeds {
        return Err(r.malformed("{passing, seeds} with 1 <= passing <= seeds"));
    }
    Ok(rule)
}
