//! Validation of scalar arguments, in one place: every message names the argument as the user
//! typed it (`max_iterations`, `racket_offset`, `torque_constant[4]`), and every failure is a
//! `TtmanipError` subclass (never PyO3's `OverflowError` for a negative count).

use pyo3::prelude::*;

use crate::convert::f64_array;
use crate::errors::{NonFiniteError, ShapeError, TtmanipError};

/// A non-negative integer argument (`max_iterations`, `max_restarts`, `seed`, ...) that fits in
/// `T`. Bind the parameter as `i128` (PyO3 then takes any Python int, negative included, and
/// keeps literal defaults in the signature) and convert here: a negative or too large value is a
/// `TtmanipError` naming the argument, not PyO3's `OverflowError`.
pub fn unsigned<T: TryFrom<i128>>(v: i128, what: &str) -> PyResult<T> {
    T::try_from(v).map_err(|_| {
        let max = (0..128)
            .rev()
            .map(|b| (1i128 << b).wrapping_sub(1).max(0))
            .find(|&m| T::try_from(m).is_ok())
            .unwrap_or(0);
        TtmanipError::new_err(format!("{what}: expected an integer in 0..={max}, got {v}"))
    })
}

/// Most samples one call may ask for (10⁸: 800 MB per float64 column); more is refused rather
/// than left to fail the allocation, which aborts the process.
pub const MAX_SAMPLES: usize = 100_000_000;

/// A sample count (`n`, `samples`): an integer in 0..=[`MAX_SAMPLES`], named in the error.
pub fn sample_count(v: i128, what: &str) -> PyResult<usize> {
    let n: usize = unsigned(v, what)?;
    if n > MAX_SAMPLES {
        return Err(TtmanipError::new_err(format!(
            "{what}: at most {MAX_SAMPLES} samples per call, got {n}"
        )));
    }
    Ok(n)
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
    finite_with(what, v, v >= 0.0, "≥ 0")
}

/// A finite float argument > 0.
pub fn positive(what: &str, v: f64) -> PyResult<f64> {
    finite_with(what, v, v > 0.0, "> 0")
}

/// A finite float argument for which `ok` holds, the bound written `bound` in the error.
fn finite_with(what: &str, v: f64, ok: bool, bound: &str) -> PyResult<f64> {
    finite(what, v)?;
    if ok {
        Ok(v)
    } else {
        Err(TtmanipError::new_err(format!(
            "{what}: expected a finite number {bound}, got {v}"
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
