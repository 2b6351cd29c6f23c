//! Plots and a self-contained HTML report of one run directory.
//!
//! [`write_report`] reads DIR/summary.json (required) and, where present, rollouts.jsonl,
//! predictions.jsonl and final_eval.jsonl (format: `crates/experiments`' run directories), and
//! writes into DIR:
//!
//! * `returns`: predicted return ± 1.96σ per policy update against the recorded return (and
//!   every further roll-out's);
//! * `policy`: the final policy's actions over time against the applied ones;
//! * `prediction_first`, `prediction_last`: long-term state predictions of the first and the
//!   final policy against the recording (from the start distribution nearest the roll-out's);
//! * `cost_first`, `cost_last`: predicted against recorded immediate cost;
//! * arm runs: `paths` (x–y paths with wall and hole) and, with final_eval.jsonl, `final_eval`
//!   (y(t) and the contact force from fresh starts);
//!
//! each as PNG and SVG, `report.html` with the settings, per-update results, the thesis
//! comparison, totals and every PNG inlined, and `report.md` with the same tables as Markdown
//! (both built by one module). Runs from before a file or field existed still get a report;
//! what could not be drawn is listed in it.
//!
//! [`acceptance_markdown`] reads the summary.json of several runs and tabulates each thesis claim
//! over the seeds with its acceptance verdict (issue 6).
//!
//! Three modules serve the experiments crate too: [`jsonl`] reads and trims a run's JSON-lines
//! records (resume, replay), [`atomic`] replaces a file whole (records, checkpoint, report), and
//! [`difference`] says where two settings records first differ
//! (resume, replay, recheck, acceptance).

#![warn(missing_docs)]

mod acceptance;
pub mod atomic;
mod data;
pub mod difference;
mod error;
mod figures;
mod html;
mod json;
pub mod jsonl;
mod markdown;
mod plot;
mod tables;

#[cfg(test)]
#[path = "../tests/common/synthetic.rs"]
mod synthetic;
#[cfg(test)]
mod tests;

pub use acceptance::{
    acceptance_markdown, FINAL_BELOW_INITIAL, REPORTED_ONLY, SAME_SEED_BUNDLES,
    SIC_MEAN_K_Y_ABOVE_GIC, VILTA_GAINS_LOWERED,
};
pub use error::ReportError;
use std::path::{Path, PathBuf};

/// What [`write_report`] wrote.
#[derive(Clone, Debug)]
pub struct ReportFiles {
    /// DIR/report.html: settings, tables and every PNG inlined, readable on its own.
    pub html: PathBuf,
    /// The tables of report.html as Markdown.
    pub markdown: PathBuf,
    /// Every PNG and SVG, in report order.
    pub images: Vec<PathBuf>,
    /// Why a figure or part of one is missing, as shown in the report.
    pub notes: Vec<String>,
}

/// Reads the run directory `dir` and writes the plots, report.html and report.md into it.
pub fn write_report(dir: &Path) -> Result<ReportFiles, ReportError> {
    let run = data::Run::load(dir)?;
    let mut notes = run.notes.clone();
    let plots = figures::draw_all(&run, dir, &mut notes)?;
    let page = html::render(&run, dir, &plots, &notes)?;
    let file = dir.join("report.html");
    write(&file, page)?;
    let markdown = dir.join("report.md");
    write(&markdown, markdown::render(&run))?;
    Ok(ReportFiles {
        html: file,
        markdown,
        images: plots.into_iter().flat_map(|p| [p.png, p.svg]).collect(),
        notes,
    })
}

fn write(file: &Path, text: String) -> Result<(), ReportError> {
    atomic::write_atomic(file, text.as_bytes()).map_err(|error| ReportError::Write {
        file: file.to_path_buf(),
        error,
    })
}
