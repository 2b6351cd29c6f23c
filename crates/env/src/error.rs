//! The one error type of this crate. Every variant names the offending field or event.

/// Errors from environments, their configuration and their output writers.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum EnvError {
    /// A configuration value is out of range, e.g. `arm.mass[1] = -1 must be > 0`.
    #[error("config {field} = {value} must be {requirement}")]
    InvalidConfig {
        /// Dotted path of the field, e.g. `arm.mass[1]`.
        field: String,
        /// The value given, formatted.
        value: String,
        /// What it must satisfy.
        requirement: String,
    },
    /// A controller name that is not known.
    #[error("unknown controller {0:?}: expected one of gic, sic, off")]
    UnknownController(String),
    /// An action entry is out of range, e.g. `stiffness k_x = -3 must be > 0`. Actions are
    /// never clipped silently.
    #[error("{kind} {field} = {value} must be {requirement}")]
    InvalidAction {
        /// What the entry is (`stiffness`, `reference increment`).
        kind: &'static str,
        /// Name of the entry, e.g. `k_x`.
        field: String,
        /// The value given.
        value: f64,
        /// What it must satisfy.
        requirement: String,
    },
    /// A vector has the wrong length.
    #[error("{what} has {got} entries, expected {expected}")]
    Dimension {
        /// Which vector (`action`, `start state`).
        what: &'static str,
        /// Its length.
        got: usize,
        /// The required length.
        expected: usize,
    },
    /// A start-state entry is not finite.
    #[error("start state {field} = {value} must be finite")]
    NonFiniteStart {
        /// Name of the entry.
        field: String,
        /// The value given.
        value: f64,
    },
    /// The start pose cannot be reached by the arm.
    #[error("start pose (x, y) = ({x}, {y}) is out of reach: {reason}")]
    OutOfReach {
        /// Requested x (m).
        x: f64,
        /// Requested y (m).
        y: f64,
        /// Why (too far, too close, singular).
        reason: String,
    },
    /// The simulation produced a non-finite or runaway state.
    #[error("simulation diverged at t = {t:.4} s: {detail}")]
    Diverged {
        /// Simulated time of detection (s).
        t: f64,
        /// What was detected.
        detail: String,
    },
    /// `step` was called before `reset`.
    #[error("step called before reset")]
    NotReset,
    /// `step` was called after the episode ended (`done`); call `reset`.
    #[error("the episode is over (t = {t} s); call reset before stepping again")]
    EpisodeOver {
        /// Time at which it ended (s).
        t: f64,
    },
    /// A stiffness or other input source could not be parsed or read.
    #[error("{0}")]
    Input(String),
    /// Writing an output file failed.
    #[error("writing {path}: {message}")]
    Output {
        /// The file.
        path: String,
        /// The underlying error.
        message: String,
    },
}

impl EnvError {
    /// Shorthand for [`EnvError::InvalidConfig`].
    pub(crate) fn config(
        field: impl Into<String>,
        value: impl std::fmt::Display,
        requirement: impl Into<String>,
    ) -> Self {
        EnvError::InvalidConfig {
            field: field.into(),
            value: value.to_string(),
            requirement: requirement.into(),
        }
    }
}

/// A number in an error message: as Rust prints it for everyday magnitudes, in exponent form
/// outside them (plain `{}` spells 1e-300 with 300 digits).
pub(crate) struct Num(pub f64);

impl std::fmt::Display for Num {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let v = self.0;
        if v.is_finite() && v != 0.0 && !(1e-6..1e15).contains(&v.abs()) {
            write!(f, "{v:e}")
        } else {
            write!(f, "{v}")
        }
    }
}

/// `v` as a config value for `field`: finite.
pub(crate) fn finite(field: &str, v: f64) -> Result<(), EnvError> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(EnvError::config(field, Num(v), "finite"))
    }
}

/// `v` as a config value for `field`: finite and > 0.
pub(crate) fn positive(field: &str, v: f64) -> Result<(), EnvError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(EnvError::config(field, Num(v), "> 0"))
    }
}

/// `v` as a config value for `field`: finite and ≥ 0.
pub(crate) fn non_negative(field: &str, v: f64) -> Result<(), EnvError> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err(EnvError::config(field, Num(v), "≥ 0"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_in_messages_stay_short() {
        for (v, shown) in [
            (0.1, "0.1"),
            (1000.0, "1000"),
            (-5.0, "-5"),
            (0.0, "0"),
            (1e-300, "1e-300"),
            (2.5e20, "2.5e20"),
            (f64::NAN, "NaN"),
        ] {
            assert_eq!(Num(v).to_string(), shown);
        }
        let err = positive("control_hz", -1e-300).unwrap_err().to_string();
        assert_eq!(err, "config control_hz = -1e-300 must be > 0");
    }
}
