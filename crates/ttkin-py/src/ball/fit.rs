//! Bindings of `ttkin::ball::fit`: the calibration experiment on recorded flights.

use super::*;
use ttkin::ball::fit::{self, FitOptions, Recording};

/// The ball-model calibration experiment of `ttkin::ball::fit::experiment` on recorded flights:
/// `names` (F,), `positions` F arrays (N_i, 3) (m), `velocities` F arrays (N_i, 3) (m/s) or None;
/// the prediction window (frames) and the frame period (s; estimated from the data when None).
#[ttkin_py_guard::guarded]
#[pyfunction]
#[pyo3(signature = (names, positions, velocities = None, window = fit::WINDOW, period = None))]
fn ball_fit<'py>(
    py: Python<'py>,
    names: Vec<String>,
    positions: &Bound<'py, PyList>,
    velocities: Option<&Bound<'py, PyList>>,
    window: usize,
    period: Option<f64>,
) -> PyResult<Bound<'py, PyAny>> {
    let positions = crate::convert::each(positions, "positions", rows3)?;
    let velocities = velocities
        .map(|v| crate::convert::each(v, "velocities", rows3))
        .transpose()?;
    let recs = Recording::from_columns(names, positions, velocities).py()?;
    let e = py
        .detach(|| fit::experiment(&recs, window, period, &FitOptions::default()))
        .py()?;
    crate::convert::serde_to_python(py, &e)
}

/// Adds these functions to the module.
pub(super) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(ball_fit, m)?)?;
    Ok(())
}
