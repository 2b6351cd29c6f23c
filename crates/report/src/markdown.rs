//! report.md: the report's tables as GitHub Markdown, so a run's results can go into
//! EXPERIMENTS.md (or an issue) as they were written, not retyped. No plots: they live in
//! report.html and the PNG/SVG files beside it.

use crate::data::{num, Colour, Rollout, Run};
use std::fmt::Write;

/// A table cell: a `|` would end the cell and a line break the row.
pub(crate) fn cell(s: &str) -> String {
    s.replace('|', "\\|").replace(['\n', '\r'], " ")
}

pub(crate) fn row(h: &mut String, cells: &[String]) {
    let _ = writeln!(h, "| {} |", cells.join(" | "));
}

pub(crate) fn header(h: &mut String, names: &[&str]) {
    let _ = writeln!(h, "| {} |", names.join(" | "));
    let _ = writeln!(h, "|{}", "---|".repeat(names.len()));
}

pub(crate) fn render(run: &Run) -> String {
    let s = &run.summary;
    // Writing into a String cannot fail; the results are ignored for that reason only.
    let mut h = String::new();
    let _ = writeln!(h, "# {} — seed {}\n", cell(&s.experiment), s.seed);
    let mut sub = Vec::new();
    if let Some(p) = &s.policy {
        sub.push(format!("policy: {}", cell(p)));
    }
    if let Some(n) = s.n_params {
        sub.push(format!("{n} parameters"));
    }
    if let Some(c) = &s.controller {
        sub.push(format!("controller: {}", cell(c)));
    }
    if !sub.is_empty() {
        let _ = writeln!(h, "{}\n", sub.join(" · "));
    }
    episodes(&mut h, run);
    thesis(&mut h, run);
    totals(&mut h, run);
    h
}

fn episodes(h: &mut String, run: &Run) {
    h.push_str("## Policy updates\n\n");
    let eps = &run.summary.episodes;
    if eps.is_empty() {
        h.push_str("No policy updates recorded yet.\n\n");
        return;
    }
    // Columns only arm runs fill (final x, force, GP size) are left out when no update has them.
    let arm = eps.iter().any(|e| e.final_x.is_some());
    let gp = eps.iter().any(|e| e.n_train.is_some());
    // Columns read from the recorded roll-outs: the final y (where a VILTA run that did not
    // insert is pressing: below or above the hole) and the gains.
    let recorded = arm && run.rollouts.is_some();
    let mut names = vec!["update", "predicted (mean ± 1σ)", "recorded", "colour"];
    if arm {
        names.push("final x (m)");
    }
    if recorded {
        names.push("final y (m)");
    }
    if arm {
        names.push("max force (N)");
    }
    names.extend(["train (s)", "optimise (s)", "value+grad evaluations"]);
    if gp {
        names.push("GP points");
    }
    // Runs that choose their model on the newest roll-out say which model each update used.
    let chosen = eps.iter().any(|e| e.kept_previous_model.is_some());
    if chosen {
        names.push("model");
    }
    // Arm runs: each gain's mean ± std over the roll-out; a std of 0 is a policy output that
    // has died at the middle of its range (EXPERIMENTS.md, "The RBF policy's k_x output dies").
    if recorded {
        names.extend(["k_x mean ± std (N/m)", "k_y mean ± std (N/m)"]);
    }
    header(h, &names);
    for e in eps {
        let mut cells = vec![
            e.index.to_string(),
            format!("{:.1} ± {:.1}", e.pred_mean, e.pred_std),
            format!("{:.1}", e.recorded),
            e.colour().map_or("–", Colour::name).to_string(),
        ];
        let rollout = run.rollout_of(e.index);
        if arm {
            cells.push(num(e.final_x, 3));
        }
        if recorded {
            cells.push(num(rollout.and_then(Rollout::final_y), 3));
        }
        if arm {
            cells.push(num(e.max_force, 0));
        }
        cells.extend([
            num(e.train_s, 0),
            num(e.optimise_s, 0),
            e.evaluations.map_or_else(|| "–".into(), |v| v.to_string()),
        ]);
        if gp {
            cells.push(match (e.n_train, e.sparse) {
                (Some(n), Some(true)) => format!("{n} (FITC)"),
                (Some(n), _) => n.to_string(),
                (None, _) => "–".into(),
            });
        }
        if chosen {
            cells.push(
                match e.kept_previous_model {
                    Some(true) => "previous",
                    Some(false) => "refit",
                    None => "–",
                }
                .into(),
            );
        }
        if recorded {
            for j in 0..2 {
                cells.push(
                    rollout
                        .and_then(|r| r.action_mean_std(j))
                        .map_or_else(|| "–".into(), |(m, sd)| format!("{m:.1} ± {sd:.1}")),
                );
            }
        }
        row(h, &cells);
    }
    h.push('\n');
}

fn thesis(h: &mut String, run: &Run) {
    h.push_str("## Against the thesis\n\n");
    let Some(claims) = &run.summary.thesis_reference else {
        h.push_str("summary.json has no thesis_reference.\n\n");
        return;
    };
    if claims.is_empty() {
        h.push_str("No thesis claims apply to this experiment yet.\n\n");
        return;
    }
    header(
        h,
        &["claim", "thesis", "measured", "verdict", "accepted when"],
    );
    for c in claims {
        let verdict = crate::acceptance::Verdict::of_run(c.pass).name();
        row(
            h,
            &[
                cell(&c.claim),
                cell(&c.thesis),
                cell(&c.measured),
                verdict.into(),
                crate::acceptance::rule_text(c.across_seeds),
            ],
        );
    }
    h.push('\n');
}

fn totals(h: &mut String, run: &Run) {
    let s = &run.summary;
    h.push_str("## Totals\n\n");
    let n = s.episodes.len();
    let mean = |f: fn(&crate::data::Episode) -> Option<f64>| {
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
    header(h, &["quantity", "value"]);
    for (k, v) in [
        ("policy updates", n.to_string()),
        (
            "updates whose every roll-out succeeds",
            format!("{inserting} of {n}"),
        ),
        ("solved at", s.solved_text()),
        ("initial roll-out's return", num(s.initial_return, 1)),
        ("constant gains' return", constant),
        ("interaction time (s)", num(s.interaction_s, 1)),
        ("wall time (s)", num(s.wall_s, 0)),
        ("code (commit, subnormals) per update", s.sessions_text()),
        ("updates from a recorded run", s.replayed_text()),
        (
            "roll-outs the system ended early",
            cell(&run.ended_early_text()),
        ),
        ("mean wall time per update (s)", num(s.wall_per_update(), 0)),
        ("mean train per update (s)", num(mean(|e| e.train_s), 0)),
        (
            "mean optimise per update (s)",
            num(mean(|e| e.optimise_s), 0),
        ),
    ] {
        row(h, &[k.into(), v]);
    }
}
