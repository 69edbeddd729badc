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
pub fn positive_or_nan_vector(obj: &Bound<'_, PyAny>, what: &str, n: usize) -> PyResult<Vec<f64>> {
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
                Ok(v)
            } else {
                positive(&format!("{what}[{i}]"), v)
            }
        })
        .collect()
}

/// The range a scalar argument of this Rust type accepts, as the error message writes it.
pub trait ScalarRange {
    /// `"a real number of magnitude at most 1.8e308"`, `"an integer in 0..=18446744073709551615"`.
    fn accepted() -> String;
}

macro_rules! integer_range {
    ($($t:ty),*) => {$(
        impl ScalarRange for $t {
            fn accepted() -> String {
                format!("an integer in {}..={}", <$t>::MIN, <$t>::MAX)
            }
        }
    )*};
}
integer_range!(i64, i32, u64, u32, u16, u8, usize);

impl ScalarRange for i128 {
    fn accepted() -> String {
        String::from("an integer of magnitude below 2**127 (counts and seeds are checked further)")
    }
}

impl ScalarRange for f64 {
    fn accepted() -> String {
        format!("a real number of magnitude at most {:e} (a float64)", f64::MAX)
    }
}

impl<T: ScalarRange> ScalarRange for Option<T> {
    fn accepted() -> String {
        format!("{} or None", T::accepted())
    }
}

/// Extracts the scalar argument `what` (a float, an integer or an optional one) as PyO3 would,
/// but a Python int out of the type's range (`10**400` for a float64, `-1` or `2**64` for a
/// count) is a `TtmanipError` naming the argument and the accepted range instead of PyO3's bare
/// `OverflowError`, and a value of the wrong Python type is a `TypeError` that names it.
///
/// The `#[guarded]` attribute puts this extractor (through a small function per argument,
/// `#[pyo3(from_py_with = ...)]`) on every scalar parameter of every binding, so no binding can
/// forget it.
pub fn scalar<'py, T>(obj: &Bound<'py, PyAny>, what: &str) -> PyResult<T>
where
    T: for<'a> FromPyObject<'a, 'py> + ScalarRange,
{
    obj.extract::<T>().map_err(|e| {
        let e: PyErr = e.into();
        let py = obj.py();
        if e.is_instance_of::<pyo3::exceptions::PyOverflowError>(py) {
            let shown = obj.repr().map(|r| r.to_string()).unwrap_or_else(|_| String::from("?"));
            let shown = if shown.len() > 40 {
                format!(
                    "{}… (an integer of {} digits)",
                    &shown[..20],
                    shown.trim_start_matches('-').len()
                )
            } else {
                shown
            };
            TtmanipError::new_err(format!("{what}: {shown} is out of range; expected {}", T::accepted()))
        } else if e.get_type(py).is(py.get_type::<pyo3::exceptions::PyTypeError>()) {
            pyo3::exceptions::PyTypeError::new_err(format!("{what}: {}", e.value(py)))
        } else {
            e
        }
    })
}

/// The value of a renamed keyword argument: the new keyword's `value`, or the deprecated
/// keyword's `old` when given (it wins, with a `DeprecationWarning` naming both).
pub fn renamed<T>(py: Python<'_>, value: T, old: Option<T>, old_name: &str, new_name: &str) -> PyResult<T> {
    match old {
        None => Ok(value),
        Some(v) => {
            crate::errors::deprecated(py, old_name, new_name)?;
            Ok(v)
        }
    }
}

/// The value of a renamed argument without a default: the new keyword's `value`, or the
/// deprecated keyword's `old` (with a `DeprecationWarning` naming both); a `TypeError` naming
/// `arg` when neither is given, as Python's own for a missing argument.
pub fn renamed_required<T>(
    py: Python<'_>,
    value: Option<T>,
    old: Option<T>,
    old_name: &str,
    new_name: &str,
    arg: &str,
) -> PyResult<T> {
    match (value, old) {
        (Some(v), None) => Ok(v),
        (None, Some(v)) => {
            crate::errors::deprecated(py, old_name, new_name)?;
            Ok(v)
        }
        (Some(_), Some(_)) => Err(pyo3::exceptions::PyTypeError::new_err(format!(
            "{arg}: given twice (once by its deprecated name {old_name})"
        ))),
        (None, None) => Err(pyo3::exceptions::PyTypeError::new_err(format!(
            "missing required argument '{arg}'"
        ))),
    }
}

/// (q, qd, qdd) from `torques`' arguments: three arrays, a (q, qd, qdd) tuple, or an object with
/// attributes q, qd, qdd (or position, velocity, acceleration).
pub fn trajectory_arrays<'py>(
    trajectory: &Bound<'py, PyAny>,
    qd: Option<&Bound<'py, PyAny>>,
    qdd: Option<&Bound<'py, PyAny>>,
) -> PyResult<[Bound<'py, PyAny>; 3]> {
    match (qd, qdd) {
        (Some(qd), Some(qdd)) => Ok([trajectory.clone(), qd.clone(), qdd.clone()]),
        (None, None) => {
            if let Ok((q, qd, qdd)) = trajectory.extract::<(Bound<'py, PyAny>, Bound<'py, PyAny>, Bound<'py, PyAny>)>()
            {
                return Ok([q, qd, qdd]);
            }
            for names in [["q", "qd", "qdd"], ["position", "velocity", "acceleration"]] {
                let got: PyResult<Vec<Bound<'py, PyAny>>> = names.iter().map(|n| trajectory.getattr(*n)).collect();
                if let Ok(v) = got {
                    if let Ok([q, qd, qdd]) = <[Bound<'py, PyAny>; 3]>::try_from(v) {
                        return Ok([q, qd, qdd]);
                    }
                }
            }
            Err(TtmanipError::new_err(
                "torques: expected (q, qd, qdd) arrays, a (q, qd, qdd) tuple, or an object with attributes \
                 q, qd, qdd (or position, velocity, acceleration)",
            ))
        }
        _ => Err(TtmanipError::new_err("torques: give both qd and qdd, or neither")),
    }
}
