//! report.html: one file with every image inlined as a data: URI, so it can be mailed or
//! archived alone. Every string from the run files is escaped.

use crate::acceptance::Verdict;
use crate::data::{Colour, Run};
use crate::figures::Plot;
use crate::tables::{self, outcome_words, Cell, Table};
use crate::ReportError;
use base64::Engine;
use serde_json::Value;
use std::fmt::Write;
use std::path::Path;

/// Escapes text for HTML element content and double- or single-quoted attributes.
pub(crate) fn esc(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for ch in s.chars() {
        match ch {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

const STYLE: &str = r#"
body { font-family: "DejaVu Sans", "Segoe UI", Helvetica, Arial, sans-serif; color: #222;
       max-width: 1120px; margin: 1.5em auto; padding: 0 1em; }
h1 { font-size: 1.7em; margin-bottom: 0.1em; }
h2 { font-size: 1.25em; margin-top: 1.8em; border-bottom: 1px solid #ccc; padding-bottom: 0.2em; }
p.sub { color: #555; margin-top: 0; }
table { border-collapse: collapse; margin: 0.5em 0 1em; font-size: 14px; }
th, td { border: 1px solid #c8c8c8; padding: 3px 8px; text-align: left; vertical-align: top; }
th { background: #e8eef5; }
tbody tr:nth-child(even) { background: #f6f6f6; }
td.num { text-align: right; font-variant-numeric: tabular-nums; white-space: nowrap; }
table.totals td { word-break: break-word; }
div.wide { overflow-x: auto; }
table.episodes { font-size: 13px; }
table.episodes td { white-space: nowrap; }
div.columns { display: flex; gap: 1.5em; align-items: flex-start; }
div.columns table { flex: 1 1 0; }
table.settings td { white-space: pre-wrap; word-break: break-word; font-size: 13px; }
table.settings td:first-child { font-family: "DejaVu Sans Mono", monospace; white-space: nowrap; }
.swatch { display: inline-block; width: 13px; height: 13px; border: 1px solid #444;
          border-radius: 3px; vertical-align: -2px; margin-right: 5px; }
.green { background: #229622; } .yellow { background: #ebb900; } .red { background: #d22323; }
.unknown { background: #fff; }
td.pass { background: #d7f0d7; color: #125f12; font-weight: bold; }
td.fail { background: #f6d5d5; color: #8a1010; font-weight: bold; }
td.na { color: #777; }
figure { margin: 1.2em 0 2em; }
figure img { max-width: 100%; height: auto; border: 1px solid #ddd; }
figcaption { font-size: 14px; color: #444; margin-top: 0.3em; }
"#;

/// Config keys as dotted paths (`geometry.wall_x`); arrays stay one JSON value.
fn flatten(prefix: &str, v: &Value, out: &mut Vec<(String, String)>) {
    match v {
        Value::Object(m) if !m.is_empty() => {
            for (k, v) in m {
                let key = if prefix.is_empty() {
                    k.clone()
                } else {
                    format!("{prefix}.{k}")
                };
                flatten(&key, v, out);
            }
        }
        Value::String(s) => out.push((prefix.into(), s.clone())),
        other => out.push((prefix.into(), compact(other))),
    }
}

/// JSON with a space after each array comma, so long vectors can wrap in the table.
fn compact(v: &Value) -> String {
    match v {
        Value::Array(items) => {
            let items: Vec<String> = items.iter().map(compact).collect();
            format!("[{}]", items.join(", "))
        }
        Value::Number(n) => match n.as_f64().filter(|_| n.is_f64()) {
            Some(v) => short_float(v),
            None => n.to_string(),
        },
        other => other.to_string(),
    }
}

/// A float at 12 significant digits, shortest form: settings derived by arithmetic
/// (`geometry.wall_x` = 0.7 − 0.05) read 0.65, not 0.6499999999999999.
fn short_float(v: f64) -> String {
    let rounded = format!("{v:.11e}").parse::<f64>().unwrap_or(v);
    // serde_json's own form: exponents for tiny and huge values, as the run files have them.
    serde_json::Number::from_f64(rounded).map_or_else(|| v.to_string(), |n| n.to_string())
}

fn image(plot: &Plot) -> Result<String, ReportError> {
    let bytes = std::fs::read(&plot.png).map_err(|error| ReportError::Read {
        file: plot.png.clone(),
        error,
    })?;
    Ok(base64::engine::general_purpose::STANDARD.encode(bytes))
}

fn file_name(p: &Path) -> String {
    p.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default()
}

pub(crate) fn render(
    run: &Run,
    dir: &Path,
    plots: &[Plot],
    notes: &[String],
) -> Result<String, ReportError> {
    let s = &run.summary;
    // Writing into a String cannot fail; the results are ignored for that reason only.
    let mut h = String::new();
    let title = format!("{} — seed {}", s.experiment, s.seed);
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
         <title>vicpilco report: {}</title>\n<style>{STYLE}</style>\n</head>\n<body>\n\
         <h1>{}</h1>\n",
        esc(&title),
        esc(&title)
    );
    let mut sub = Vec::new();
    if let Some(p) = &s.policy {
        sub.push(format!("policy: {}", esc(p)));
    }
    if let Some(n) = s.n_params {
        sub.push(format!("{n} parameters"));
    }
    if let Some(c) = &s.controller {
        sub.push(format!("controller: {}", esc(c)));
    }
    let _ = writeln!(h, "<p class=\"sub\">{}</p>", sub.join(" · "));

    settings(&mut h, s.config.as_ref());
    episodes(&mut h, run);
    thesis(&mut h, run);
    totals(&mut h, run);

    h.push_str("<h2>Plots</h2>\n");
    if plots.is_empty() {
        h.push_str("<p>No plots: see the notes below.</p>\n");
    }
    for p in plots {
        let _ = writeln!(
            h,
            "<figure id=\"{stem}\">\n<img alt=\"{stem}\" src=\"data:image/png;base64,{data}\">\n\
             <figcaption>{caption} Files: <a href=\"{svg}\">{svg}</a>, <a href=\"{png}\">{png}</a>.\
             </figcaption>\n</figure>",
            stem = p.stem,
            data = image(p)?,
            caption = esc(&p.caption),
            svg = esc(&file_name(&p.svg)),
            png = esc(&file_name(&p.png)),
        );
    }
    if !notes.is_empty() {
        h.push_str("<h2>Not shown</h2>\n<ul>\n");
        for n in notes {
            let _ = writeln!(h, "<li>{}</li>", esc(n));
        }
        h.push_str("</ul>\n");
    }
    let _ = write!(
        h,
        "<p class=\"sub\">Written by vicpilco-report {} from {}.</p>\n</body>\n</html>\n",
        env!("CARGO_PKG_VERSION"),
        esc(&dir.display().to_string())
    );
    Ok(h)
}

fn settings(h: &mut String, config: Option<&Value>) {
    h.push_str("<h2>Settings</h2>\n");
    let mut rows = Vec::new();
    if let Some(c) = config {
        flatten("", c, &mut rows);
    }
    // A summary adds keys derived from the settings beside them (`start_y_range` for
    // `start.y_range`); one that only repeats its setting is shown once, as the setting.
    let repeats = |(k, v): &(String, String)| {
        !k.contains('.')
            && rows
                .iter()
                .any(|(k2, v2)| k2.contains('.') && k2.replace('.', "_") == *k && v2 == v)
    };
    let rows: Vec<(String, String)> = rows.iter().filter(|r| !repeats(r)).cloned().collect();
    if rows.is_empty() {
        h.push_str("<p>summary.json has no config.</p>\n");
        return;
    }
    // Arm configs have ~80 keys: two tables side by side keep the results within reach.
    let half = if rows.len() > 20 {
        rows.len().div_ceil(2)
    } else {
        rows.len()
    };
    h.push_str("<div class=\"columns\">\n");
    for chunk in rows.chunks(half) {
        h.push_str(
            "<table class=\"settings\">\n<thead><tr><th>setting</th><th>value</th></tr></thead>\n<tbody>\n",
        );
        for (k, v) in chunk {
            let _ = writeln!(h, "<tr><td>{}</td><td>{}</td></tr>", esc(k), esc(v));
        }
        h.push_str("</tbody></table>\n");
    }
    h.push_str("</div>\n");
}

fn html_cell(c: &Cell) -> String {
    match c {
        Cell::Num(t) => format!("<td class=\"num\">{}</td>", esc(t)),
        Cell::Text(t) => format!("<td>{}</td>", esc(t)),
        Cell::Outcome(colour) => format!(
            "<td><span class=\"swatch {}\"></span>{}</td>",
            colour.map_or("unknown", Colour::name),
            outcome_words(*colour)
        ),
        Cell::Verdict(v) => {
            let (class, word) = match v {
                Verdict::Pass => ("pass", "PASS"),
                Verdict::Fail => ("fail", "FAIL"),
                Verdict::Undecided | Verdict::Reported => ("na", v.name()),
            };
            format!("<td class=\"{class}\">{word}</td>")
        }
    }
}

/// A table in a box that scrolls sideways: an arm run's update table has up to 17 columns,
/// wider than the page.
fn table(h: &mut String, class: &str, t: &Table) {
    let _ = write!(
        h,
        "<div class=\"wide\"><table class=\"{class}\">\n<thead><tr>"
    );
    for name in &t.header {
        let _ = write!(h, "<th>{}</th>", esc(name));
    }
    h.push_str("</tr></thead>\n<tbody>\n");
    for r in &t.rows {
        h.push_str("<tr>");
        for c in r {
            h.push_str(&html_cell(c));
        }
        h.push_str("</tr>\n");
    }
    h.push_str("</tbody></table></div>\n");
}

fn episodes(h: &mut String, run: &Run) {
    h.push_str("<h2>Policy updates</h2>\n");
    if run.summary.episodes.is_empty() {
        h.push_str("<p>No policy updates recorded yet.</p>\n");
        return;
    }
    table(h, "episodes", &tables::episodes(run));
}

fn thesis(h: &mut String, run: &Run) {
    h.push_str("<h2>Against the thesis</h2>\n");
    match tables::thesis(run) {
        None => h.push_str("<p>summary.json has no thesis_reference.</p>\n"),
        Some(t) if t.rows.is_empty() => {
            h.push_str("<p>No thesis claims apply to this experiment.</p>\n");
        }
        Some(t) => table(h, "thesis", &t),
    }
}

fn totals(h: &mut String, run: &Run) {
    h.push_str("<h2>Totals</h2>\n<table class=\"totals\"><tbody>\n");
    for (k, v) in tables::totals(run) {
        let _ = writeln!(h, "<tr><th>{}</th>{}</tr>", esc(k), html_cell(&v));
    }
    h.push_str("</tbody></table>\n");
}
