//! The one error type of `ttcan`: every fallible constructor returns [`Result`].
//!
//! Errors happen only when something is built (a motor model, a controller, a stepper). The control
//! loops themselves never return errors: a bad value at run time (a NaN reference, a NaN current
//! reading, an encoder jump) is a [`crate::axis::Fault`] that brings the axis to a controlled stop.

/// Result alias used across `ttcan`.
pub type Result<T> = std::result::Result<T, Error>;

/// Everything that can be wrong with a motor model, a controller configuration or a stepper.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A parameter is NaN or infinite.
    #[error("{what} = {value}: every parameter must be finite")]
    NonFinite {
        /// Name of the parameter, with its unit.
        what: String,
        /// The offending value.
        value: f64,
    },
    /// A parameter is finite but not physical or not allowed (negative resistance, zero inertia, ...).
    #[error("{what} = {}: {reason}", number(*.value))]
    InvalidParameter {
        /// Name of the parameter, with its unit.
        what: String,
        /// The offending value.
        value: f64,
        /// What is accepted.
        reason: String,
    },
    /// A configuration entry (given as nested changes, e.g. from a Python dict) that the type does
    /// not take: an unknown key or a value of the wrong kind, named by its path (`motor.resistance`).
    #[error("{path}: {reason}")]
    Config {
        /// Dotted path of the entry.
        path: String,
        /// What is wrong.
        reason: String,
    },
    /// Loop rates that the multi-rate stepper cannot schedule (not integer multiples of each other).
    #[error("loop rates: {0}")]
    Rates(String),
    /// Several axes given to one stepper disagree (different loop rates, ...).
    #[error("stepper: {0}")]
    Stepper(String),
    /// The robot model (`ttkin`) rejected something: a chain without inertias or drives, a bad
    /// trajectory, a configuration it cannot reach.
    #[error("robot model: {0}")]
    Model(String),
}

/// The error of a run that a caller's [`ttkin::budget::Stop`] ended (Ctrl-C seen by the Python
/// binding, which raises `KeyboardInterrupt` instead).
pub fn stopped() -> Error {
    Error::Model(ttkin_reason(ttkin::budget::stopped("duration")))
}

/// Checks that `value` is finite and strictly positive.
pub fn positive(what: &str, value: f64) -> Result<f64> {
    finite_with(what, value, value > 0.0, || "must be > 0".to_string())
}

/// Checks that `value` is finite and not negative.
pub fn non_negative(what: &str, value: f64) -> Result<f64> {
    finite_with(what, value, value >= 0.0, || "must be >= 0".to_string())
}

/// Checks that `value` is finite and at least `lo`.
pub fn at_least(what: &str, value: f64, lo: f64) -> Result<f64> {
    finite_with(what, value, value >= lo, || format!("must be >= {lo}"))
}

/// Checks that a loop bandwidth `bandwidth_hz` (what: its name) is at most a sixth of the
/// current-loop rate 1/`period` (s): the discrete designs assume it.
pub fn sixth_of_rate(what: &str, bandwidth_hz: f64, period: f64) -> Result<f64> {
    finite_with(what, bandwidth_hz, bandwidth_hz * period <= 1.0 / 6.0, || {
        format!("must be at most a sixth of the current loop rate ({} Hz)", 1.0 / period)
    })
}

/// Checks that `value` is finite and that `ok` holds; otherwise `reason` says what it must be.
fn finite_with(what: &str, value: f64, ok: bool, reason: impl FnOnce() -> String) -> Result<f64> {
    finite(what, value)?;
    if ok {
        Ok(value)
    } else {
        Err(Error::InvalidParameter {
            what: what.to_string(),
            value,
            reason: reason(),
        })
    }
}

/// Checks that `value` is finite.
pub fn finite(what: &str, value: f64) -> Result<f64> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(Error::NonFinite {
            what: what.to_string(),
            value,
        })
    }
}

/// Checks that `lo < value <= hi` (finite).
pub fn in_range(what: &str, value: f64, lo: f64, hi: f64) -> Result<f64> {
    finite_with(what, value, value > lo && value <= hi, || {
        format!("must be in ({lo}, {hi}]")
    })
}

/// The reason of a `ttkin` argument error without its argument name (the caller names the
/// parameter its own way, with its unit).
pub(crate) fn ttkin_reason(e: ttkin::Error) -> String {
    match e {
        ttkin::Error::InvalidArgument { reason, .. } => reason,
        other => other.to_string(),
    }
}

/// A parameter's value as a message prints it: plainly in an ordinary range, in scientific
/// notation beyond it (1e300 rather than its 301 digits).
fn number(v: f64) -> String {
    if v != 0.0 && v.is_finite() && !(1e-4..1e6).contains(&v.abs()) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}
