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
        file: PathBuf,
        error: std::io::Error,
    },
    /// The file, or one line of a .jsonl file, is not JSON.
    #[error("{}: {location}: not valid JSON: {error}", file.display())]
    Json {
        file: PathBuf,
        /// "whole file" or "line N".
        location: String,
        error: serde_json::Error,
    },
    /// A required field is absent (or null).
    #[error("{}: missing field `{field}`", file.display())]
    Missing { file: PathBuf, field: String },
    /// A field has the wrong type or shape.
    #[error("{}: field `{field}`: expected {expected}, found {found}", file.display())]
    Malformed {
        file: PathBuf,
        field: String,
        expected: String,
        found: String,
    },
    /// An output file could not be written.
    #[error("{}: cannot write: {error}", file.display())]
    Write {
        file: PathBuf,
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
        experiment: String,
        seed: u64,
        first: PathBuf,
        second: PathBuf,
    },
    /// plotters failed while drawing an image.
    #[error("{}: drawing failed: {message}", file.display())]
    Plot { file: PathBuf, message: String },
}
