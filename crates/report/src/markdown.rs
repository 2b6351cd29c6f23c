//! report.md: the report's tables as GitHub Markdown, so a run's results can go into
//! EXPERIMENTS.md (or an issue) as they were written, not retyped. No plots: they live in
//! report.html and the PNG/SVG files beside it.

use crate::data::{Colour, Run};
use crate::tables::{self, Cell, Table};
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

fn text(c: &Cell) -> String {
    match c {
        Cell::Num(t) | Cell::Text(t) => cell(t),
        Cell::Outcome(colour) => colour.map_or("–", Colour::name).to_string(),
        Cell::Verdict(v) => v.name().to_string(),
    }
}

fn table(h: &mut String, t: &Table) {
    header(h, &t.header);
    for r in &t.rows {
        row(h, &r.iter().map(text).collect::<Vec<_>>());
    }
    h.push('\n');
}

fn episodes(h: &mut String, run: &Run) {
    h.push_str("## Policy updates\n\n");
    if run.summary.episodes.is_empty() {
        h.push_str("No policy updates recorded yet.\n\n");
        return;
    }
    table(h, &tables::episodes(run));
}

fn thesis(h: &mut String, run: &Run) {
    h.push_str("## Against the thesis\n\n");
    match tables::thesis(run) {
        None => h.push_str("summary.json has no thesis_reference.\n\n"),
        Some(t) if t.rows.is_empty() => {
            h.push_str("No thesis claims apply to this experiment yet.\n\n");
        }
        Some(t) => table(h, &t),
    }
}

fn totals(h: &mut String, run: &Run) {
    h.push_str("## Totals\n\n");
    header(h, &["quantity", "value"]);
    for (k, v) in tables::totals(run) {
        row(h, &[k.into(), text(&v)]);
    }
}
