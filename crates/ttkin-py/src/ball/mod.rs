//! Bindings of `ttkin::ball`: conversion only. A ball state is a (10,) array
//! [t, px, py, pz, vx, vy, vz, wx, wy, wz] (s, m, m/s, rad/s, world frame of `ttkin::ball`),
//! `ttkin::ball::BallState::to_array`.

mod fit;
mod hitplan;
mod rally;
mod table;

use numpy::PyArrayDyn;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use ttkin::ball::estimate::{estimate, EstimateOptions};
use ttkin::ball::flight::{BallState, Flight, Plane};
use ttkin::ball::hitplan::{ReturnHit, ReturnPlanner, ReturnStatus};
use ttkin::ball::model::{BallModel, Table};
use ttkin::ball::predict::{crossing_until, predict_batch_into, predict_until, CrossingOutcome, CROSSING_HORIZON};
use ttkin::ball::reach::Placement;

use crate::args;
use crate::convert::{pose_to_numpy, rows_array, serde_to_python, str_refs, to_numpy, vector};
use crate::errors::{PyResultExt, TtmanipError};
use crate::robot::PyRobot;
use ttkin::Chain;

fn flight(model: &str) -> PyResult<Flight> {
    Ok(Flight::new(BallModel::by_name(model).py()?))
}

fn state_vec(s: &BallState) -> [f64; 10] {
    s.to_array()
}

fn state_arg(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<BallState> {
    Ok(BallState::from_row(&vector(obj, what, 10)?))
}

/// (N, 3) rows of `obj` (named `what` in errors) as triples.
fn rows3(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<[f64; 3]>> {
    Ok(crate::convert::triples(rows_array(obj, what, "N", &[3])?.data()))
}

/// Observation times (`rows`,) and positions (`rows`, 3) (s, m) from `t` and `p`, the arguments
/// named `names`.
fn observations(
    t: &Bound<'_, PyAny>,
    p: &Bound<'_, PyAny>,
    names: [&str; 2],
    rows: &str,
) -> PyResult<(Vec<f64>, Vec<[f64; 3]>)> {
    Ok((rows_array(t, names[0], rows, &[])?.data().to_vec(), rows3(p, names[1])?))
}

/// The estimator's options for the ball model named `model` (the rest `EstimateOptions::default()`).
fn estimate_options(model: &str) -> PyResult<EstimateOptions> {
    Ok(EstimateOptions {
        flight: flight(model)?,
        ..EstimateOptions::default()
    })
}

/// Fits a ball state to observed positions `p` (N, 3) at times `t` (N,); see `ttkin::ball::estimate`.
#[ttkin_py_guard::guarded]
#[pyfunction]
#[pyo3(signature = (t, p, model = "default"))]
fn ball_estimate<'py>(
    py: Python<'py>,
    t: &Bound<'py, PyAny>,
    p: &Bound<'py, PyAny>,
    model: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let (times, obs) = observations(t, p, ["t", "p"], "N")?;
    let opts = estimate_options(model)?;
    let e = py
        .detach(|| estimate(&times, &obs, &opts))
        .map_err(ttkin::Error::from)
        .py()?;
    let d = PyDict::new(py);
    d.set_item("state", to_numpy(py, &[10], &state_vec(&e.state)))?;
    d.set_item("covariance", to_numpy(py, &[6, 6], e.covariance.as_flattened()))?;
    d.set_item("spin_std", e.spin_std)?;
    d.set_item("spin_fitted", e.spin_fitted)?;
    d.set_item("sigma", e.sigma)?;
    d.set_item("used", e.used)?;
    d.set_item("outliers", e.outliers)?;
    d.set_item("nonfinite", e.nonfinite)?;
    d.set_item("bounce_time", e.bounce_time)?;
    d.set_item("segment", e.segment.name())?;
    Ok(d)
}

/// Positions (K, 3) of the ball from `state` at `times` (K,), the events met and the terminal event.
#[ttkin_py_guard::guarded]
#[pyfunction]
#[pyo3(signature = (state, times, model = "default"))]
fn ball_predict<'py>(
    py: Python<'py>,
    state: &Bound<'py, PyAny>,
    times: &Bound<'py, PyAny>,
    model: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let s = state_arg(state, "state")?;
    let ts = rows_array(times, "times", "K", &[])?.data().to_vec();
    let f = flight(model)?;
    // Ctrl-C stops a long flight within about a millisecond of work (issue 29).
    let pred = crate::interrupt::detach_interruptible(py, |cancel| {
        predict_until(&f, &s, &ts, &|| crate::interrupt::cancelled(cancel))
    })?
    .py()?;
    let d = PyDict::new(py);
    d.set_item("positions", to_numpy(py, &[ts.len(), 3], pred.positions.as_flattened()))?;
    d.set_item("events", serde_to_python(py, &pred.events)?)?;
    d.set_item("end", pred.end.map(|k| k.name()))?;
    Ok(d)
}

/// Positions (N, K, 3) of N balls (`states` (N, 10)) at `times` (K,), in parallel; NaN after a
/// terminal event.
#[ttkin_py_guard::guarded]
#[pyfunction]
#[pyo3(signature = (states, times, model = "default"))]
fn ball_predict_batch<'py>(
    py: Python<'py>,
    states: &Bound<'py, PyAny>,
    times: &Bound<'py, PyAny>,
    model: &str,
) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    let list = BallState::from_rows(rows_array(states, "states", "N", &[10])?.data());
    let ts = rows_array(times, "times", "K", &[])?.data().to_vec();
    let f = flight(model)?;
    let shape = [list.len(), ts.len(), 3];
    crate::convert::check_result_size(&shape)?;
    let out = crate::convert::zeros(py, &shape);
    // Ctrl-C stops the batch within one ball per thread (issue 29).
    crate::convert::fill_fresh(&out, |o| {
        crate::interrupt::detach_interruptible(py, |cancel| {
            predict_batch_into(&f, &list, &ts, o, &|| crate::interrupt::cancelled(cancel))
        })?
        .py()
    })?;
    Ok(out)
}

/// Where and when the ball from `state` crosses the plane through `point` with normal `normal`
/// (from its positive side), searching until `t_max` (s).
#[ttkin_py_guard::guarded]
#[pyfunction]
#[pyo3(signature = (state, point, normal, t_max = CROSSING_HORIZON, model = "default"))]
fn ball_crossing<'py>(
    py: Python<'py>,
    state: &Bound<'py, PyAny>,
    point: &Bound<'py, PyAny>,
    normal: &Bound<'py, PyAny>,
    t_max: f64,
    model: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let s = state_arg(state, "state")?;
    let plane = Plane::new(vec3(point, "point")?, vec3(normal, "normal")?).py()?;
    let f = flight(model)?;
    // Ctrl-C stops a long flight within about a millisecond of work (issue 29).
    let out = crate::interrupt::detach_interruptible(py, |cancel| {
        crossing_until(&f, &s, &plane, t_max, &|| crate::interrupt::cancelled(cancel))
    })?
    .py()?;
    let d = PyDict::new(py);
    match out {
        CrossingOutcome::Crossed { state, bounces } => {
            d.set_item("outcome", "crossed")?;
            d.set_item("state", to_numpy(py, &[10], &state_vec(&state)))?;
            d.set_item("bounces", ttkin::ball::flight::Event::names(&bounces))?;
        }
        CrossingOutcome::Ended(e) => {
            d.set_item("outcome", e.kind.name())?;
            d.set_item("state", to_numpy(py, &[10], &state_vec(&e.before)))?;
        }
        CrossingOutcome::Timeout => d.set_item("outcome", "timeout")?,
    }
    Ok(d)
}

/// A (3,) vector argument as an array.
fn vec3(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<[f64; 3]> {
    let v = vector(obj, what, 3)?;
    Ok([v[0], v[1], v[2]])
}

/// The ball after a racket impact (`ttkin::ball::impact::RacketImpact::hit_state` with the default
/// impact model): `state` (10,) just before, the racket's unit face `normal` (3,) and the face point's
/// `velocity` (3,, m/s, world); returns the state (10,) just after.
#[ttkin_py_guard::guarded]
#[pyfunction]
#[pyo3(signature = (state, normal, velocity, model = "default"))]
fn ball_racket_impact<'py>(
    py: Python<'py>,
    state: &Bound<'py, PyAny>,
    normal: &Bound<'py, PyAny>,
    velocity: &Bound<'py, PyAny>,
    model: &str,
) -> PyResult<Bound<'py, PyAny>> {
    let s = state_arg(state, "state")?;
    let n = nalgebra::Vector3::from(vec3(normal, "normal")?);
    let rv = nalgebra::Vector3::from(vec3(velocity, "velocity")?);
    let f = flight(model)?;
    let out = ttkin::ball::impact::RacketImpact::default()
        .hit_state(&f.model, &s, &n, &rv)
        .py()?;
    Ok(to_numpy(py, &[10], &state_vec(&out)).into_any())
}

/// The estimate from the observations `t` (N,), `p` (N, 3) updated with later ones `t_new`
/// (M,), `p_new` (M, 3), through a bounce between them (`ttkin::ball::update::update_kick`):
/// with `bounce_spread` (3,) (m/s, world x, y, z, each > 0) the bounce's velocity kick is
/// fitted too and kept past the χ² gate, as the rally's correction does; None: the plain update.
#[ttkin_py_guard::guarded]
#[pyfunction]
#[pyo3(signature = (t, p, t_new, p_new, model = "default", bounce_spread = None))]
#[allow(clippy::too_many_arguments)]
fn ball_update<'py>(
    py: Python<'py>,
    t: &Bound<'py, PyAny>,
    p: &Bound<'py, PyAny>,
    t_new: &Bound<'py, PyAny>,
    p_new: &Bound<'py, PyAny>,
    model: &str,
    bounce_spread: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let (times, obs) = observations(t, p, ["t", "p"], "N")?;
    let (times_new, obs_new) = observations(t_new, p_new, ["t_new", "p_new"], "M")?;
    let spread = bounce_spread.map(|s| vec3(s, "bounce_spread")).transpose()?;
    let opts = estimate_options(model)?;
    let up = py
        .detach(|| {
            let est = estimate(&times, &obs, &opts)?;
            ttkin::ball::update::update_kick(&est, &times_new, &obs_new, &opts, spread)
        })
        .map_err(ttkin::Error::from)
        .py()?;
    let d = PyDict::new(py);
    d.set_item("state", to_numpy(py, &[10], &state_vec(&up.state)))?;
    d.set_item("at_prior", to_numpy(py, &[10], &state_vec(&up.at_prior)))?;
    d.set_item("covariance", to_numpy(py, &[9, 9], up.covariance.as_flattened()))?;
    d.set_item("used", up.used)?;
    d.set_item("outliers", up.outliers)?;
    d.set_item("bounced", up.bounced)?;
    Ok(d)
}

/// Adds the ball functions to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    // the rally's prior spread of the bounce's velocity kick (m/s, world x, y, z)
    m.add("BOUNCE_SPREAD", ttkin::ball::update::BOUNCE_SPREAD.to_vec())?;
    m.add_function(wrap_pyfunction!(ball_racket_impact, m)?)?;
    m.add_function(wrap_pyfunction!(ball_update, m)?)?;
    m.add_function(wrap_pyfunction!(ball_estimate, m)?)?;
    m.add_function(wrap_pyfunction!(ball_predict, m)?)?;
    m.add_function(wrap_pyfunction!(ball_predict_batch, m)?)?;
    m.add_function(wrap_pyfunction!(ball_crossing, m)?)?;
    fit::register(m)?;
    hitplan::register(m)?;
    rally::register(m)?;
    table::register(m)?;
    Ok(())
}
