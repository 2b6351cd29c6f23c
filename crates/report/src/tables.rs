//! The report's tables (policy updates, thesis claims, totals) as data, so report.md and
//! report.html show the same columns and numbers and differ only in markup.

use crate::acceptance::{rule_text, Verdict};
use crate::data::{num, Colour, Episode, Rollout, Run};

/// One table cell, by what it holds: the renderers align numbers and mark outcomes.
pub(crate) enum Cell {
    Num(String),
    Text(String),
    /// Which roll-outs of an update succeeded (`None`: not recorded).
    Outcome(Option<Colour>),
    /// One run's verdict on a claim.
    Verdict(Verdict),
}

pub(crate) struct Table {
    pub header: Vec<&'static str>,
    pub rows: Vec<Vec<Cell>>,
}

/// Words for an update's outcome.
pub(crate) fn outcome_words(c: Option<Colour>) -> &'static str {
    match c {
        Some(Colour::Green) => "all succeed",
        Some(Colour::Yellow) => "some succeed",
        Some(Colour::Red) => "none succeed",
        None => "–",
    }
}

/// One row per policy update. Columns only arm runs fill (final x and y, force, GP size,
/// gains) are left out when no update has them.
pub(crate) fn episodes(run: &Run) -> Table {
    let eps = &run.summary.episodes;
    let arm = eps.iter().any(|e| e.final_x.is_some());
    let gp = eps.iter().any(|e| e.n_train.is_some());
    // Read from the recorded roll-outs: the final y (where a VILTA run that did not insert is
    // pressing: below or above the hole) and the gains.
    let recorded = arm && run.rollouts.is_some();
    // Where some but not all roll-outs of an update succeeded, the fraction that did.
    let several = eps.iter().any(|e| e.colour() == Some(Colour::Yellow));
    // Runs that choose their model on the newest roll-out say which model each update used.
    let chosen = eps.iter().any(|e| e.kept_previous_model.is_some());

    let predicted: Vec<_> = eps.iter().map(|e| run.predicted_return(e)).collect();
    // With several start distributions the prediction beside the roll-out is its nearest
    // start's where that can be told, and each cell names its start (k of K).
    let several_starts = predicted.iter().any(|p| p.2.is_some());
    let mut header = vec![
        "update",
        if several_starts {
            "predicted (mean ± 1σ; start nearest the roll-out)"
        } else {
            "predicted (mean ± 1σ)"
        },
        "recorded",
        "outcome",
    ];
    if several {
        header.push("success fraction");
    }
    if arm {
        header.push("final x (m)");
    }
    if recorded {
        header.push("final y (m)");
    }
    if arm {
        header.push("max force (N)");
    }
    header.extend(["train (s)", "optimise (s)", "value+grad evaluations"]);
    if gp {
        header.push("GP points");
    }
    if chosen {
        header.push("model");
    }
    // A gain's std of 0 is a policy output that has died at the middle of its range
    // (EXPERIMENTS.md, "The RBF policy's k_x output dies").
    if recorded {
        header.extend(["k_x mean ± std (N/m)", "k_y mean ± std (N/m)"]);
    }

    let rows = eps
        .iter()
        .zip(&predicted)
        .map(|(e, &(mean, std, start))| {
            let rollout = run.rollout_of(e.index);
            let from = match start {
                Some((k, n)) => format!(" (start {} of {n})", k + 1),
                None => String::new(),
            };
            let mut cells = vec![
                Cell::Num(e.index.to_string()),
                Cell::Num(format!("{mean:.2} ± {std:.2}{from}")),
                Cell::Num(format!("{:.2}", e.recorded)),
                Cell::Outcome(e.colour()),
            ];
            if several {
                cells.push(Cell::Num(num(e.success_fraction, 2)));
            }
            if arm {
                cells.push(Cell::Num(num(e.final_x, 3)));
            }
            if recorded {
                cells.push(Cell::Num(num(rollout.and_then(Rollout::final_y), 3)));
            }
            if arm {
                cells.push(Cell::Num(num(e.max_force, 0)));
            }
            cells.extend([
                Cell::Num(num(e.train_s, 1)),
                Cell::Num(num(e.optimise_s, 1)),
                Cell::Num(e.evaluations.map_or_else(|| "–".into(), |v| v.to_string())),
            ]);
            if gp {
                cells.push(Cell::Num(gp_points(e)));
            }
            if chosen {
                let model = match e.kept_previous_model {
                    Some(true) => "previous",
                    Some(false) => "refit",
                    None => "–",
                };
                cells.push(Cell::Text(model.into()));
            }
            if recorded {
                for j in 0..2 {
                    let gains = rollout.and_then(|r| r.action_mean_std(j));
                    cells.push(Cell::Num(
                        gains.map_or_else(|| "–".into(), |(m, sd)| format!("{m:.1} ± {sd:.1}")),
                    ));
                }
            }
            cells
        })
        .collect();
    Table { header, rows }
}

fn gp_points(e: &Episode) -> String {
    match (e.n_train, e.sparse) {
        (Some(n), Some(true)) => format!("{n} (FITC)"),
        (Some(n), _) => n.to_string(),
        (None, _) => "–".into(),
    }
}

/// One row per thesis claim, or `None` when summary.json has no thesis_reference.
pub(crate) fn thesis(run: &Run) -> Option<Table> {
    let claims = run.summary.thesis_reference.as_ref()?;
    let rows = claims
        .iter()
        .map(|c| {
            vec![
                Cell::Text(c.claim.clone()),
                Cell::Text(c.thesis.clone()),
                Cell::Text(c.measured.clone()),
                Cell::Verdict(Verdict::of_claim(c)),
                Cell::Text(match Verdict::of_claim(c) {
                    Verdict::Reported => "reported only".into(),
                    _ => rule_text(c.across_seeds),
                }),
            ]
        })
        .collect();
    Some(Table {
        header: vec!["claim", "thesis", "measured", "verdict", "accepted when"],
        rows,
    })
}

/// The run's totals as (quantity, value) rows.
pub(crate) fn totals(run: &Run) -> Vec<(&'static str, Cell)> {
    let s = &run.summary;
    let n = s.episodes.len();
    let mean = |f: fn(&Episode) -> Option<f64>| {
        let v: Vec<f64> = s.episodes.iter().filter_map(f).collect();
        (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
    };
    let inserting = s
        .episodes
        .iter()
        .filter(|e| e.colour() == Some(Colour::Green))
        .count();
    let constant = match (s.constant_gain_return, s.constant_gain_inserted) {
        (Some(r), Some(true)) => format!("{r:.1} (inserts)"),
        (Some(r), Some(false)) => format!("{r:.1} (does not insert)"),
        (r, _) => num(r, 1),
    };
    vec![
        ("policy updates", Cell::Num(n.to_string())),
        (
            "updates whose every roll-out succeeds",
            Cell::Num(format!("{inserting} of {n}")),
        ),
        ("solved at", Cell::Text(s.solved_text())),
        (
            "initial roll-out's return",
            Cell::Num(num(s.initial_return, 1)),
        ),
        ("constant gains' return", Cell::Num(constant)),
        ("interaction time (s)", Cell::Num(num(s.interaction_s, 1))),
        ("wall time (s)", Cell::Num(num(s.wall_s, 1))),
        (
            "code (commit, subnormals) per update",
            Cell::Text(s.sessions_text()),
        ),
        ("updates from a recorded run", Cell::Text(s.replayed_text())),
        (
            "roll-outs the system ended early",
            Cell::Text(run.ended_early_text()),
        ),
        (
            "mean wall time per update (s)",
            Cell::Num(num(s.wall_per_update(), 1)),
        ),
        (
            "mean train per update (s)",
            Cell::Num(num(mean(|e| e.train_s), 1)),
        ),
        (
            "mean optimise per update (s)",
            Cell::Num(num(mean(|e| e.optimise_s), 1)),
        ),
    ]
}
