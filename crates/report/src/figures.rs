//! Which figures a run directory supports, and why the others are skipped.

use crate::data::{Prediction, Run};
use crate::plot::arm::{FinalEvalPlot, Paths};
use crate::plot::policy::Policy;
use crate::plot::prediction::{CostPrediction, StatePrediction};
use crate::plot::returns::Returns;
use crate::plot::{save, Figure};
use crate::ReportError;
use std::path::{Path, PathBuf};

/// One written figure.
pub(crate) struct Plot {
    pub stem: &'static str,
    pub caption: String,
    pub png: PathBuf,
    pub svg: PathBuf,
}

struct Out<'d> {
    dir: &'d Path,
    plots: Vec<Plot>,
}

impl Out<'_> {
    fn add(
        &mut self,
        fig: &impl Figure,
        stem: &'static str,
        caption: String,
    ) -> Result<(), ReportError> {
        let (png, svg) = save(fig, self.dir, stem)?;
        self.plots.push(Plot {
            stem,
            caption,
            png,
            svg,
        });
        Ok(())
    }
}

pub(crate) fn draw_all(
    run: &Run,
    dir: &Path,
    notes: &mut Vec<String>,
) -> Result<Vec<Plot>, ReportError> {
    let mut out = Out {
        dir,
        plots: Vec::new(),
    };
    let s = &run.summary;
    if s.episodes.is_empty() {
        notes.push("summary.json lists no policy updates yet: no returns plot".into());
    } else {
        let other_rollouts = other_rollout_returns(run);
        let last = s.episodes.last().map(|e| e.index);
        let final_policy = s.final_eval_update.filter(|&u| Some(u) != last);
        let mut caption = "Predicted return (mean, 95 % interval) and recorded return of the \
                           first roll-out per policy update. Green circle: every roll-out of \
                           that update succeeds; yellow diamond: some do; red square: none do."
            .to_string();
        if !other_rollouts.is_empty() {
            caption.push_str(
                " Small circles: the returns of the update's further roll-outs (from other \
                 starts; they test the policy and do not train the model).",
            );
        }
        let starts = run
            .predictions
            .iter()
            .flatten()
            .map(|p| p.starts.len())
            .max();
        if let Some(k) = starts.filter(|&k| k > 1) {
            caption.push_str(&format!(
                " The policy is optimised over {k} start distributions; the predicted return \
                 shown is the one from the start nearest the first roll-out's start (summed from \
                 predictions.jsonl; the first start's, as summary.json records it, where the \
                 roll-out or that start's step costs are not recorded)."
            ));
        }
        if let Some(u) = final_policy {
            caption.push_str(&format!(
                " Dashed line: update {u}, whose policy the run hands over (vilta.final_policy)."
            ));
        }
        out.add(
            &Returns {
                episodes: &s.episodes,
                predicted: s
                    .episodes
                    .iter()
                    .map(|e| {
                        let (mean, std, _) = run.predicted_return(e);
                        (mean, std)
                    })
                    .collect(),
                initial_return: s.initial_return,
                other_rollouts,
                final_policy,
            },
            "returns",
            caption,
        )?;
        if s.initial_return.is_none() {
            notes.push("summary.json has no initial_return: no initial roll-out line".into());
        }
    }

    let preds = run.predictions.as_deref().unwrap_or_default();
    if let (Some(first), Some(last)) = (preds.first(), preds.last()) {
        // The final policy is the one the final evaluation chose (`vilta.final_policy`), else
        // the last update's.
        let chosen = s
            .final_eval_update
            .and_then(|u| preds.iter().find(|p| p.episode == u));
        if let (Some(u), None) = (s.final_eval_update, chosen) {
            notes.push(format!(
                "no prediction of update {u}, the final evaluation's: policy plot of the last update"
            ));
        }
        let final_policy = chosen.unwrap_or(last);
        policy(run, final_policy, &mut out, notes)?;
        let why_final = if final_policy.episode == last.episode {
            String::new()
        } else {
            format!(
                ", the final evaluation's choice; the last update is {}",
                last.episode
            )
        };
        prediction(run, Which::First, first, &mut out, notes)?;
        prediction(run, Which::Final(why_final), final_policy, &mut out, notes)?;
    } else if run.predictions.is_some() {
        notes.push("predictions.jsonl is empty: no policy or prediction plots".into());
    }

    arm(run, &mut out, notes)?;
    Ok(out.plots)
}

/// (update, recorded return) of every roll-out after the first of each policy update: the
/// roll-outs summary.json does not describe. Roll-outs without recorded costs are left out.
pub(crate) fn other_rollout_returns(run: &Run) -> Vec<(f64, f64)> {
    let Some(rollouts) = &run.rollouts else {
        return Vec::new();
    };
    let mut seen = std::collections::BTreeSet::new();
    rollouts
        .iter()
        .filter(|r| r.episode > 0 && !seen.insert(r.episode))
        .filter_map(|r| Some((r.episode as f64, r.costs.as_ref()?.iter().sum())))
        .collect()
}

/// The optimised policy whose predictions (c, d) show.
enum Which {
    First,
    /// The final policy, with why it is not the last update's (or "").
    Final(String),
}

/// ", from the start distribution nearest the roll-out's start (k of K)" when a prediction
/// has several start distributions, else "".
fn start_words(p: &Prediction, start: usize) -> String {
    match p.starts.len() {
        1 => String::new(),
        n => format!(
            " It was optimised over {n} start distributions; shown is the prediction from \
             start {} of {n}, the one nearest the recorded roll-out's start.",
            start + 1
        ),
    }
}

fn policy(
    run: &Run,
    shown: &Prediction,
    out: &mut Out,
    notes: &mut Vec<String>,
) -> Result<(), ReportError> {
    let final_rollout = run.rollout_of(shown.episode);
    let start = shown.start_nearest(final_rollout);
    let initial = run.rollout_of(0);
    if run.rollouts.is_some() && final_rollout.is_none() {
        notes.push(format!(
            "no roll-out of update {} recorded: policy plot without its applied actions",
            shown.episode
        ));
    }
    if run.rollouts.is_some() && initial.is_none() {
        notes.push("no initial roll-out (episode 0) recorded: policy plot without it".into());
    }
    out.add(
        &Policy {
            pred: shown,
            start,
            last: final_rollout,
            initial,
        },
        "policy",
        format!(
            "Final policy (update {}): predicted action distribution (mean ± 2σ{}) over time, \
             with the actions applied in that update's roll-out and in the initial exploration \
             roll-out.{}{}",
            shown.episode,
            if shown.action_bounds.is_some() {
                ", clipped to the saturation range"
            } else {
                ""
            },
            if shown.action_names.iter().any(|a| a.ends_with("_ref")) {
                " Δx_ref and Δy_ref are the reference's increments per controller tick \
                 (vilta.delta_tick in the settings), held over each step."
            } else {
                ""
            },
            start_words(shown, start)
        ),
    )
}

fn prediction(
    run: &Run,
    which: Which,
    p: &Prediction,
    out: &mut Out,
    notes: &mut Vec<String>,
) -> Result<(), ReportError> {
    let rollout = run.rollout_of(p.episode);
    let start = p.start_nearest(rollout);
    let also = start_words(p, start);
    if run.rollouts.is_some() && rollout.is_none() {
        notes.push(format!(
            "no roll-out of update {} recorded: its predictions are plotted alone",
            p.episode
        ));
    }
    let (state_stem, cost_stem, which) = match which {
        Which::First => (
            "prediction_first",
            "cost_first",
            format!("first optimised policy (update {})", p.episode),
        ),
        Which::Final(why) => (
            "prediction_last",
            "cost_last",
            format!("final policy (update {}{why})", p.episode),
        ),
    };
    out.add(
        &StatePrediction {
            pred: p,
            start,
            rollout,
        },
        state_stem,
        format!(
            "Long-term prediction of the {which}: each state dimension's predicted mean ± 2σ \
             against the states recorded in its roll-out.{also}"
        ),
    )?;
    if p.steps(start).iter().any(|s| s.weighted_cost.is_none()) {
        notes.push(format!(
            "predictions.jsonl, update {}: no weighted_cost_mean/std per step: no {cost_stem} plot",
            p.episode
        ));
        return Ok(());
    }
    let recorded = rollout.and_then(|r| r.costs.as_deref().map(|c| (c, r.episode)));
    if rollout.is_some() && recorded.is_none() {
        notes.push(format!(
            "roll-out of update {} has no recorded costs: {cost_stem} shows the prediction alone",
            p.episode
        ));
    }
    out.add(
        &CostPrediction {
            pred: p,
            start,
            recorded,
        },
        cost_stem,
        format!(
            "Immediate cost of the {which}: predicted mean ± 2σ against the cost recorded in \
             its roll-out (same weighting).{also}"
        ),
    )
}

fn arm(run: &Run, out: &mut Out, notes: &mut Vec<String>) -> Result<(), ReportError> {
    let s = &run.summary;
    let Some(g) = &s.geometry else {
        if run.final_eval.is_some() {
            notes.push("final_eval.jsonl without config.geometry: plotted without the hole".into());
        }
        return final_eval(run, out, notes);
    };
    match run.rollouts.as_deref() {
        Some(r) if !r.is_empty() => {
            let sampled = sampling(r.iter().filter(|r| r.path.is_empty()).count(), r.len());
            out.add(
                &Paths {
                    rollouts: r,
                    geometry: g,
                    start_y_range: s.start_y_range,
                },
                "paths",
                format!(
                    "TCP x–y path of every roll-out, {sampled} (grey: initial; colour: policy \
                     update, dark to light), with the wall and the hole channel."
                ),
            )?
        }
        _ => notes.push("no recorded roll-outs: no paths plot".into()),
    }
    final_eval(run, out, notes)
}

/// How a plot of `total` roll-outs, `lacking` of which recorded no within-step path, draws
/// them: runs recorded before the arm sampled its path within steps have only the states.
fn sampling(lacking: usize, total: usize) -> String {
    match lacking {
        0 => "sampled within each step".to_string(),
        n if n == total => "joining the states at the ends of the steps (the run recorded no \
                            within-step path)"
            .to_string(),
        n => format!(
            "sampled within each step ({n} of {total} roll-outs recorded no within-step path and \
             join the states at the ends of the steps)"
        ),
    }
}

fn final_eval(run: &Run, out: &mut Out, notes: &mut Vec<String>) -> Result<(), ReportError> {
    let Some(evals) = run.final_eval.as_deref() else {
        return Ok(());
    };
    if evals.is_empty() {
        notes.push("final_eval.jsonl is empty: no final_eval plot".into());
        return Ok(());
    }
    let dt = run.dt();
    if dt.is_none() {
        notes
            .push("no time step (predictions.jsonl or config.dt): final_eval is over steps".into());
    }
    let policy = match run.summary.final_eval_update {
        Some(u) => format!("The final policy (update {u}'s, chosen by vilta.final_policy)"),
        None => "The final policy".to_string(),
    };
    let sampled = sampling(
        evals.iter().filter(|e| e.path.is_empty()).count(),
        evals.len(),
    );
    let caption = format!(
        "{policy} from fresh start positions: y(t) of each roll-out, {sampled}, green if \
         it inserts, red if not; below (when the roll-outs recorded forces), the contact force \
         magnitude |f| at each step's end, which shows how hard an inserting roll-out presses."
    );
    out.add(
        &FinalEvalPlot {
            evals,
            update: run.summary.final_eval_update,
            geometry: run.summary.geometry.as_ref(),
            dt,
        },
        "final_eval",
        caption,
    )
}
