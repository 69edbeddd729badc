//! The boundary guard: no Rust panic reaches Python as PyO3's `PanicException` (a
//! `BaseException` that `except Exception` does not catch).
//!
//! Every `#[pymethods]` block and `#[pyfunction]` carries `#[guarded]` (crate `ttkin-py-guard`),
//! which runs the function body through [`call`]. A panic (a bug: conversion and validation are
//! meant to make them unreachable) becomes `ttmanip.InternalError` naming the call; a
//! `NumericalError` from the output checks of `convert` gets the call's name in front.

use std::panic::{catch_unwind, AssertUnwindSafe};

use pyo3::prelude::*;

use crate::errors::{InternalError, NumericalError};

/// Runs `f`, the body of the Python-visible function `name`, turning a panic into `InternalError`.
pub fn call<T>(name: &str, f: impl FnOnce() -> PyResult<T>) -> PyResult<T> {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(Ok(v)) => Ok(v),
        Ok(Err(e)) => Err(Python::attach(|py| {
            if e.is_instance_of::<NumericalError>(py) {
                NumericalError::new_err(format!("{name}: {}", e.value(py)))
            } else {
                e
            }
        })),
        Err(payload) => {
            let msg = payload
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown panic payload".to_string());
            Err(InternalError::new_err(format!(
                "{name}: internal error (a bug in ttmanip; please report it with the call that caused it): {msg}"
            )))
        }
    }
}

/// Test hook: panics inside a guarded call, so that the tests can see the guard at work.
#[ttkin_py_guard::guarded]
#[pyfunction]
#[pyo3(name = "_panic_for_test")]
fn panic_for_test(message: &str) -> PyResult<()> {
    if message.is_empty() {
        return Ok(());
    }
    panic!("{message}")
}

/// Adds the test hook to the module (private: `ttmanip._ttmanip._panic_for_test`).
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(panic_for_test, m)?)
}
