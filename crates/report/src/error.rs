//! Errors of `write_report`: each names the file and, for content, the field at fault.
//!
//! The underlying error is part of each message rather than a `source()`, so the message is
//! complete however it is printed and anyhow's chain does not repeat it.

use std::path::PathBuf;

/// Why a report could not be written.
///
/// Absent optional files and fields are not errors (the report skips that part and says so);
/// present but malformed content is, so a writer bug is not hidden behind a missing plot.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ReportError {
    /// The file (summary.json, or an optional file that exists) could not be read.
    #[error("{}: cannot read: {error}", file.display())]
    Read {
        /// The file, or the PNG being inlined into report.html.
        file: PathBuf,
        /// The I/O error (`NotFound` for an absent summary.json).
        error: std::io::Error,
    },
    /// The file, or one line of a .jsonl file, is not JSON.
    #[error("{}: {location}: not valid JSON: {error}", file.display())]
    Json {
        /// The file at fault.
        file: PathBuf,
        /// "whole file" or "line N".
        location: String,
        /// serde_json's parse error, with its line and column in the file or line.
        error: serde_json::Error,
    },
    /// A required field is absent (or null).
    #[error("{}: missing field `{field}`", file.display())]
    Missing {
        /// The file the field was looked for in.
        file: PathBuf,
        /// Path of the field, e.g. `episodes[3].recorded_return`, prefixed `line N: ` in a
        /// .jsonl file.
        field: String,
    },
    /// A field has the wrong type or shape.
    #[error("{}: field `{field}`: expected {expected}, found {found}", file.display())]
    Malformed {
        /// The file at fault.
        file: PathBuf,
        /// Path of the field as for [`ReportError::Missing`]; `(top level)` for the document.
        field: String,
        /// What the field must be, e.g. `a number`.
        expected: String,
        /// What it is, e.g. `the string "blue"` or `an array of 3 elements`.
        found: String,
    },
    /// An output file could not be written.
    #[error("{}: cannot write: {error}", file.display())]
    Write {
        /// The output file: report.html or report.md in the run directory.
        file: PathBuf,
        /// The I/O error.
        error: std::io::Error,
    },
    /// Two run directories of one experiment have the same seed, so the acceptance table
    /// would count that seed twice.
    #[error(
        "{} and {}: both are {experiment} seed {seed}; give one run per seed",
        first.display(),
        second.display()
    )]
    DuplicateSeed {
        /// The experiment name both summary.json files give.
        experiment: String,
        /// The seed they share.
        seed: u64,
        /// The run directory given first.
        first: PathBuf,
        /// The later run directory with the same experiment and seed.
        second: PathBuf,
    },
    /// plotters failed while drawing an image.
    #[error("{}: drawing failed: {message}", file.display())]
    Plot {
        /// The PNG or SVG being drawn.
        file: PathBuf,
        /// plotters' error, as text.
        message: String,
    },
}
