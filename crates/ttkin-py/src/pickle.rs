//! Pickle and copy support (issue 31): every class of the extension reduces to
//! `_unpickle_<class>(state)`, a function of `ttmanip._ttmanip`, where `state` is the serde form of
//! the core value (plain Python lists, dicts and floats through `pythonize`, so f64 values, NaN and
//! ±inf travel bit for bit). `copy.copy` and `copy.deepcopy` go through the same `__reduce__`.
//!
//! Conversion only: each class's module says what its state is (`__reduce__`) and how it is
//! rebuilt (`from_state`, and its `_unpickle_<class>`); this module turns values into Python
//! objects and back. Like any pickle, a state is trusted input: it comes from `__reduce__`.

use pyo3::prelude::*;
use pyo3::types::PyTuple;
use serde::{de::DeserializeOwned, Serialize};

use crate::errors::TtmanipError;

/// The serde form of `value` as plain Python objects.
pub fn to_state<'py, T: Serialize + ?Sized>(py: Python<'py>, value: &T) -> PyResult<Bound<'py, PyAny>> {
    pythonize::pythonize(py, value).map_err(|e| TtmanipError::new_err(format!("pickle: {e}")))
}

/// A value back from its serde form; a state of the wrong shape is a `TtmanipError` naming `kind`
/// (the class).
pub fn from_state<T: DeserializeOwned>(state: &Bound<'_, PyAny>, kind: &str) -> PyResult<T> {
    serde_path_to_error::deserialize(&mut pythonize::Depythonizer::from_object(state))
        .map_err(|e| TtmanipError::new_err(format!("unpickle {kind}: not a state of this version ({e})")))
}

/// `(ttmanip._ttmanip.<unpickler>, (state,))`: the value `__reduce__` returns.
pub fn reduce<'py>(py: Python<'py>, unpickler: &str, state: Bound<'py, PyAny>) -> PyResult<Bound<'py, PyTuple>> {
    let f = py.import("ttmanip._ttmanip")?.getattr(unpickler)?;
    PyTuple::new(py, [f, PyTuple::new(py, [state])?.into_any()])
}
