//! Validation of scalar arguments, in one place: every message names the argument as the user
//! typed it (`max_iterations`, `racket_offset`, `torque_constant[4]`), and every failure is a
//! `TtmanipError` subclass (never PyO3's `OverflowError` for a negative count).

use pyo3::prelude::*;
use pyo3::types::{PyBool, PyInt};

use crate::convert::f64_array;
use crate::errors::{NonFiniteError, ShapeError, TtmanipError};

/// Reads a non-negative integer argument (`max_iterations`, `max_restarts`, `seed`, ...) that
/// fits in `T`; a negative, too large, boolean or non-integer value is a `TtmanipError` naming it.
pub fn unsigned<T: TryFrom<u64>>(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<T> {
    let got = || obj.repr().map(|r| r.to_string()).unwrap_or_else(|_| "?".to_string());
    let max = || {
        // the largest u64 that converts to T, for the message
        let mut hi = u64::MAX;
        while T::try_from(hi).is_err() {
            hi >>= 1;
        }
        hi
    };
    if obj.is_instance_of::<PyBool>() {
        return Err(TtmanipError::new_err(format!(
            "{what}: expected a non-negative integer, got {}",
            got()
        )));
    }
    match obj.extract::<u64>() {
        Ok(v) => T::try_from(v)
            .map_err(|_| TtmanipError::new_err(format!("{what}: expected an integer in 0..={}, got {v}", max()))),
        Err(_) if obj.is_instance_of::<PyInt>() || obj.hasattr("__index__").unwrap_or(false) => Err(
            TtmanipError::new_err(format!("{what}: expected an integer in 0..={}, got {}", max(), got())),
        ),
        Err(_) => Err(TtmanipError::new_err(format!(
            "{what}: expected a non-negative integer, got {} of type {}",
            got(),
            obj.get_type().name().map(|n| n.to_string()).unwrap_or_default()
        ))),
    }
}

/// A finite float argument.
pub fn finite(what: &str, v: f64) -> PyResult<f64> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(NonFiniteError::new_err(format!(
            "{what}: expected a finite number, got {v}"
        )))
    }
}

/// A finite float argument ≥ 0.
pub fn non_negative(what: &str, v: f64) -> PyResult<f64> {
    finite(what, v)?;
    if v >= 0.0 {
        Ok(v)
    } else {
        Err(TtmanipError::new_err(format!(
            "{what}: expected a finite number ≥ 0, got {v}"
        )))
    }
}

/// A finite float argument > 0.
pub fn positive(what: &str, v: f64) -> PyResult<f64> {
    finite(what, v)?;
    if v > 0.0 {
        Ok(v)
    } else {
        Err(TtmanipError::new_err(format!(
            "{what}: expected a finite number > 0, got {v}"
        )))
    }
}

/// A per-joint vector (n,) whose elements are each NaN (meaning "not given") or finite and > 0,
/// e.g. `torque_constant`; element errors are named `what[i]`.
pub fn positive_or_nan_vector(obj: &Bound<'_, PyAny>, what: &str, n: usize) -> PyResult<Vec<Option<f64>>> {
    let a = f64_array(obj, what)?;
    if a.shape() != [n] {
        return Err(ShapeError::new_err(format!(
            "{what}: expected shape ({n},), got {}",
            a.shape_str()
        )));
    }
    a.data()
        .iter()
        .enumerate()
        .map(|(i, &v)| {
            if v.is_nan() {
                Ok(None)
            } else {
                positive(&format!("{what}[{i}]"), v).map(Some)
            }
        })
        .collect()
}
