//! The one error type of `ttkin`: every fallible call returns [`Result`].

/// Result alias used across `ttkin`.
pub type Result<T> = std::result::Result<T, Error>;

/// Everything that can go wrong in `ttkin`, each variant with a message that says what to fix.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// An argument has the wrong length or shape.
    #[error("{what}: expected {expected}, got {got}")]
    Shape {
        /// Name of the argument.
        what: String,
        /// The length or shape that was expected.
        expected: String,
        /// The length or shape that was given.
        got: String,
    },
    /// An argument holds NaN or an infinity.
    #[error("{what}: element {index} is {value} (every value must be finite)")]
    NonFinite {
        /// Name of the argument.
        what: String,
        /// Flat index of the first offending element.
        index: usize,
        /// The offending value.
        value: f64,
    },
    /// An argument is finite but outside what is allowed (negative duration, bad option, ...).
    #[error("{what}: {reason}")]
    InvalidArgument {
        /// Name of the argument.
        what: String,
        /// What is wrong and what is accepted.
        reason: String,
    },
    /// A robot model is inconsistent (bad limits, non-physical inertia, empty chain, ...).
    #[error("invalid model: {0}")]
    Model(String),
    /// A robot file could not be read or parsed.
    #[error("robot file {path}: {reason}")]
    File {
        /// Path of the file (or `<string>` for text).
        path: String,
        /// What failed.
        reason: String,
    },
    /// A URDF document could not be turned into a serial chain.
    #[error("URDF: {0}")]
    Urdf(String),
    /// A target is outside the robot's reach; the message names the constraint.
    #[error("unreachable: {0}")]
    Unreachable(String),
    /// A computation needs a non-singular configuration and did not get one.
    #[error("singular configuration: {0}")]
    Singular(String),
}

impl Error {
    /// Shorthand for [`Error::Shape`].
    pub fn shape(what: impl Into<String>, expected: impl ToString, got: impl ToString) -> Self {
        Error::Shape {
            what: what.into(),
            expected: expected.to_string(),
            got: got.to_string(),
        }
    }

    /// Shorthand for [`Error::InvalidArgument`].
    pub fn invalid(what: impl Into<String>, reason: impl Into<String>) -> Self {
        Error::InvalidArgument {
            what: what.into(),
            reason: reason.into(),
        }
    }

    /// The same error with the argument's name prefixed by `outer` (`hits[2].` + `t` →
    /// `hits[2].t`), for an element of a batch or a field of a record; other kinds unchanged.
    pub fn within(self, outer: &str) -> Self {
        match self {
            Error::Shape { what, expected, got } => Error::Shape {
                what: format!("{outer}{what}"),
                expected,
                got,
            },
            Error::NonFinite { what, index, value } => Error::NonFinite {
                what: format!("{outer}{what}"),
                index,
                value,
            },
            Error::InvalidArgument { what, reason } => Error::InvalidArgument {
                what: format!("{outer}{what}"),
                reason,
            },
            other => other,
        }
    }
}

/// Checks that a scalar is finite and > 0; the error gives its `unit` ("m", "s", "Hz", "1/s").
pub fn check_positive(what: &str, value: f64, unit: &str) -> Result<f64> {
    if value > 0.0 && value.is_finite() {
        Ok(value)
    } else {
        Err(Error::invalid(
            what,
            format!("must be finite and > 0 {unit}, got {value}"),
        ))
    }
}

/// Checks that `values` has `expected` elements, all finite.
pub fn check_vector(what: &str, values: &[f64], expected: usize) -> Result<()> {
    if values.len() != expected {
        return Err(Error::shape(
            what,
            format!("{expected} values"),
            format!("{} values", values.len()),
        ));
    }
    check_finite(what, values)
}

/// Checks that `values` holds N × `per_row` finite values (a batch of N rows, row-major) and
/// returns N: the one shape check of every batch (chain, task and dynamics batches).
pub(crate) fn check_rows(what: &str, values: &[f64], per_row: usize) -> Result<usize> {
    if !values.len().is_multiple_of(per_row) {
        return Err(Error::shape(
            what,
            format!("N × {per_row} values"),
            format!("{} values", values.len()),
        ));
    }
    check_finite(what, values)?;
    Ok(values.len() / per_row)
}

/// Checks that a buffer of `len` values holds `count` rows of `per_row` (a batch's other inputs
/// and its output).
pub(crate) fn check_len(what: &str, len: usize, count: usize, per_row: usize) -> Result<()> {
    if len != count * per_row {
        return Err(Error::shape(what, count * per_row, len));
    }
    Ok(())
}

/// Checks that every element of `values` is finite.
pub fn check_finite(what: &str, values: &[f64]) -> Result<()> {
    match values.iter().position(|v| !v.is_finite()) {
        None => Ok(()),
        Some(index) => Err(Error::NonFinite {
            what: what.to_string(),
            index,
            value: values[index],
        }),
    }
}
