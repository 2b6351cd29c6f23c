//! Reading a run directory's files: JSON and JSON-lines with every error naming the file and
//! line, and the parsers of each line's record.

use super::{FinalEval, PathPoint, PredStep, Prediction, Rollout, Rows};
use crate::json::Node;
use crate::jsonl::parse_json_lines;
use crate::ReportError;
use serde_json::Value;
use std::path::{Path, PathBuf};

fn read_text(file: &Path) -> Result<Option<String>, ReportError> {
    match std::fs::read_to_string(file) {
        Ok(s) => Ok(Some(s)),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
        Err(error) => Err(ReportError::Read {
            file: file.to_path_buf(),
            error,
        }),
    }
}

pub(super) fn read_json(file: &Path) -> Result<Value, ReportError> {
    let text = read_text(file)?.ok_or_else(|| ReportError::Read {
        file: file.to_path_buf(),
        error: std::io::Error::new(
            std::io::ErrorKind::NotFound,
            "no such file (is this a run directory?)",
        ),
    })?;
    serde_json::from_str(&text).map_err(|error| ReportError::Json {
        file: file.to_path_buf(),
        location: "whole file".into(),
        error,
    })
}

/// The parsed lines of a .jsonl file, each with its 1-based line number; `None` if the file
/// does not exist.
pub(super) struct Lines {
    file: PathBuf,
    values: Vec<(usize, Value)>,
}

pub(super) fn read_lines(
    file: &Path,
    notes: &mut Vec<String>,
) -> Result<Option<Lines>, ReportError> {
    let Some(text) = read_text(file)? else {
        return Ok(None);
    };
    let name = file.file_name().map(|n| n.to_string_lossy().into_owned());
    let name = name.unwrap_or_default();
    let read = parse_json_lines(&text).map_err(|e| ReportError::Json {
        file: file.to_path_buf(),
        location: format!("line {}", e.line),
        error: e.error,
    })?;
    if let Some(line) = read.torn {
        notes.push(format!(
            "{name}: ignored the incomplete last line {line} (run still writing?)"
        ));
    }
    let values = read
        .lines
        .into_iter()
        .map(|l| (l.number, l.value))
        .collect();
    Ok(Some(Lines {
        file: file.to_path_buf(),
        values,
    }))
}

pub(super) fn parse_lines<T>(
    lines: &Lines,
    parse: impl Fn(Node<'_>) -> Result<T, ReportError>,
) -> Result<Vec<T>, ReportError> {
    lines
        .values
        .iter()
        .map(|(line, v)| {
            let prefix = format!("line {line}: ");
            parse(Node::root(&lines.file, &prefix, v))
        })
        .collect()
}

/// The applied actions and the true states of one roll-out.
fn parse_trajectory(r: Node<'_>) -> Result<(Rows, Rows), ReportError> {
    Ok((
        r.req("actions", |a| a.f64_rows())?,
        r.req("true_states", |s| s.f64_rows())?,
    ))
}

pub(super) fn parse_rollout_line(n: Node<'_>) -> Result<Rollout, ReportError> {
    let (actions, true_states, (stopped_early, path)) = n.req("rollout", |r| {
        let (actions, true_states) = parse_trajectory(r)?;
        let infos = parse_infos(r, &true_states)?;
        Ok((actions, true_states, infos))
    })?;
    Ok(Rollout {
        episode: n.req_u64("episode")?,
        costs: n.with("costs", |c| c.map(|c| c.f64_vec()).transpose())?,
        actions,
        true_states,
        stopped_early,
        path,
    })
}

/// From a roll-out's per-step `infos`: why its last step ended early, if it did, and its
/// within-step path.
fn parse_infos(
    r: Node<'_>,
    true_states: &Rows,
) -> Result<(Option<String>, Vec<PathPoint>), ReportError> {
    r.with("infos", |infos| match infos {
        None => Ok((None, Vec::new())),
        Some(infos) => {
            let steps = infos.map_array(|i| {
                let path = i.with("path", |p| p.map(xy_pairs).transpose())?;
                Ok((i.opt_string("stopped_early")?, path.unwrap_or_default()))
            })?;
            let (mut stopped, paths): (Vec<_>, Vec<_>) = steps.into_iter().unzip();
            let stopped_early = stopped.pop().flatten();
            Ok((stopped_early, within_step_path(true_states, &paths)))
        }
    })
}

/// An array of `[x, y]` pairs.
fn xy_pairs(n: Node<'_>) -> Result<Vec<(f64, f64)>, ReportError> {
    n.map_array(|q| match q.f64_vec()?[..] {
        [x, y] => Ok((x, y)),
        _ => Err(q.malformed("an [x, y] pair")),
    })
}

/// The start's (x, y) followed by every step's within-step samples, timed as
/// [`PathPoint::step`] says, when each step (one info per true state after the first) has
/// them; otherwise empty, and plots fall back to the steps' true states.
fn within_step_path(true_states: &Rows, steps: &[Vec<(f64, f64)>]) -> Vec<PathPoint> {
    let start = true_states
        .first()
        .and_then(|s| Some((*s.first()?, *s.get(1)?)));
    let every_step = !steps.is_empty() && steps.len() + 1 == true_states.len();
    match start {
        Some((x, y)) if every_step && steps.iter().all(|p| !p.is_empty()) => {
            let within = steps.iter().enumerate().flat_map(|(k, samples)| {
                let n = samples.len() as f64;
                samples
                    .iter()
                    .enumerate()
                    .map(move |(j, &(x, y))| PathPoint {
                        step: k as f64 + (j + 1) as f64 / n,
                        x,
                        y,
                    })
            });
            std::iter::once(PathPoint { step: 0.0, x, y })
                .chain(within)
                .collect()
        }
        _ => Vec::new(),
    }
}

/// Runs before rollouts.jsonl wrote one `{"initial": [...], "learned": [...]}` document with
/// one learned roll-out per update.
pub(super) fn read_old_rollouts(
    file: &Path,
    notes: &mut Vec<String>,
) -> Result<Option<Vec<Rollout>>, ReportError> {
    if !file.exists() {
        return Ok(None);
    }
    let v = read_json(file)?;
    let n = Node::root(file, "", &v);
    let list = |key: &str, episode: &dyn Fn(usize) -> u64| {
        n.with(key, |l| match l {
            None => Ok(Vec::new()),
            Some(l) => {
                let mut i = 0;
                l.map_array(|r| {
                    let (actions, true_states) = parse_trajectory(r)?;
                    i += 1;
                    Ok(Rollout {
                        episode: episode(i - 1),
                        costs: None,
                        actions,
                        true_states,
                        stopped_early: None,
                        path: Vec::new(),
                    })
                })
            }
        })
    };
    let mut all = list("initial", &|_| 0)?;
    all.extend(list("learned", &|i| i as u64 + 1)?);
    notes.push("read the older rollouts.json (no recorded costs)".into());
    Ok(Some(all))
}

pub(super) fn parse_prediction(n: Node<'_>) -> Result<Prediction, ReportError> {
    // Every step of every start must have the first step's dimensions, or the plots would
    // silently mix up state components.
    let mut dims: Option<(usize, usize)> = None;
    let starts = n.req("starts", |s| {
        s.map_array(|start| {
            start.map_array(|node| {
                let step = parse_step(node)?;
                let d = (step.mean.len(), step.action_mean.len());
                let d_var = (step.var.len(), step.action_var.len());
                let want = *dims.get_or_insert(d);
                if d != want || d_var != want {
                    return Err(node.malformed(format!(
                        "mean/var of {} and action_mean/action_var of {} numbers, as in the first step",
                        want.0, want.1
                    )));
                }
                Ok(step)
            })
        })
    })?;
    if starts.is_empty() || starts.iter().any(Vec::is_empty) {
        return n.req("starts", |s| {
            Err(s.malformed("start distributions of at least one step each"))
        });
    }
    let steps = &starts[0];
    let (ds, da) = dims.unwrap_or_default();
    let names = |key: &str, d: usize, fallback: &str| -> Result<Vec<String>, ReportError> {
        n.with(key, |v| match v {
            None => Ok((1..=d).map(|i| format!("{fallback} {i}")).collect()),
            Some(v) => {
                let names = v.string_vec()?;
                if names.len() != d {
                    return Err(v.malformed(format!("{d} names (one per dimension)")));
                }
                Ok(names)
            }
        })
    };
    let dt = match n.opt_f64("dt")? {
        Some(dt) => dt,
        None => match steps.as_slice() {
            [a, b, ..] => b.t - a.t,
            [a] => a.t,
            [] => 1.0,
        },
    };
    Ok(Prediction {
        episode: n.req_u64("episode")?,
        dt,
        state_names: names("state_names", ds, "state")?,
        action_names: names("action_names", da, "action")?,
        action_bounds: n.with("action_bounds", |v| {
            v.map(|v| {
                let rows = v.f64_rows()?;
                if rows.len() != da || rows.iter().any(|r| r.len() != 2 || r[0] > r[1]) {
                    return Err(
                        v.malformed(format!("{da} [lowest, highest] pairs (one per action)"))
                    );
                }
                Ok(rows.iter().map(|r| (r[0], r[1])).collect())
            })
            .transpose()
        })?,
        starts,
    })
}

fn parse_step(n: Node<'_>) -> Result<PredStep, ReportError> {
    let wm = n.opt_f64("weighted_cost_mean")?;
    let ws = n.opt_f64("weighted_cost_std")?;
    Ok(PredStep {
        t: n.req_f64("t")?,
        mean: n.req("mean", |v| v.f64_vec())?,
        var: n.req("var", |v| v.f64_vec())?,
        action_mean: n.req("action_mean", |v| v.f64_vec())?,
        action_var: n.req("action_var", |v| v.f64_vec())?,
        weighted_cost: wm.zip(ws),
    })
}

pub(super) fn parse_final_eval(n: Node<'_>) -> Result<FinalEval, ReportError> {
    let (true_states, (_, path)) = n.req("rollout", |r| {
        let true_states = r.req("true_states", |s| s.f64_rows())?;
        let infos = parse_infos(r, &true_states)?;
        Ok((true_states, infos))
    })?;
    Ok(FinalEval {
        success: n.req("success", |s| s.bool())?,
        true_states,
        path,
    })
}
