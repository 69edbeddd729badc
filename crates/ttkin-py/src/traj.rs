//! Trajectory bindings: `JointTrajectory`, `CartesianTrajectory` and the constructor functions
//! behind `ttmanip.traj` (conversion only; the maths is `ttkin::traj`).

use numpy::ndarray::{Array2, ShapeBuilder};
use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::PyList;

use ttkin::traj::duration::{self, SegmentKind};
use ttkin::traj::limits::{KinematicLimits, Violation};
use ttkin::traj::via::{self, ViaKind};
use ttkin::traj::{JointState, JointTrajectory, Samples};

use crate::convert::{column, f64_array, table, to_numpy, value_getters, vector, vector_of_len, zeros, Any, Array};
use crate::errors::{PyResultExt, ShapeError};
use crate::robot::PyRobot;

fn opt_vector(obj: Option<&Any<'_>>, what: &str, n: usize) -> PyResult<Option<Vec<f64>>> {
    obj.map(|o| vector(o, what, n)).transpose()
}

/// Reads an (m, n) array; returns (data, m, n).
fn matrix(obj: &Any<'_>, what: &str) -> PyResult<(Vec<f64>, usize, usize)> {
    let a = f64_array(obj, what)?;
    match a.shape() {
        [m, n] => Ok((a.data().to_vec(), *m, *n)),
        [m] => Ok((a.data().to_vec(), *m, 1)),
        _ => Err(ShapeError::new_err(format!(
            "{what}: expected shape (m, n), got {}",
            a.shape_str()
        ))),
    }
}

pub(crate) fn samples_to_py<'py>(py: Python<'py>, s: &Samples) -> PyResult<Bound<'py, PyAny>> {
    let m = s.t.len();
    let t = to_numpy(py, &[m], &s.t);
    let q = to_numpy(py, &[m, s.dof], &s.q);
    let qd = to_numpy(py, &[m, s.dof], &s.qd);
    let qdd = to_numpy(py, &[m, s.dof], &s.qdd);
    Ok((t, q, qd, qdd).into_pyobject(py)?.into_any())
}

/// Violations as a list of dicts (joint, quantity, time, value, limit) in their serde form.
pub(crate) fn violations_to_py<'py>(py: Python<'py>, v: &[Violation]) -> PyResult<Bound<'py, PyList>> {
    Ok(crate::convert::serde_to_python(py, v)?.cast_into::<PyList>()?)
}

pub(crate) fn robot_limits(robot: &PyRobot, jerk: Option<&Any<'_>>) -> PyResult<KinematicLimits> {
    let n = robot.chain.dof();
    let jerk = opt_vector(jerk, "jerk", n)?;
    KinematicLimits::from_chain(&robot.chain, jerk.as_deref()).py()
}

/// A joint-space trajectory: piecewise polynomials of degree ≤ 5 per joint (rad or m, s).
#[pyclass(name = "JointTrajectory", module = "ttmanip", frozen)]
pub struct PyJointTrajectory {
    pub(crate) inner: JointTrajectory,
}

#[ttkin_py_guard::guarded]
#[pymethods]
impl PyJointTrajectory {
    /// Segment boundaries (s), from 0 to the duration.
    #[getter]
    fn knots<'py>(&self, py: Python<'py>) -> Array<'py> {
        to_numpy(py, &[self.inner.knots().len()], self.inner.knots())
    }

    /// (segments, dof, 6) coefficients in ascending powers of the local time τ = t − knot (s).
    #[getter]
    fn coefficients<'py>(&self, py: Python<'py>) -> PyResult<Array<'py>> {
        let (k, n) = (self.inner.segments(), self.inner.dof());
        let flat = self.inner.coefficient_table();
        Ok(to_numpy(py, &[k, n, 6], &flat))
    }

    /// (q, qd, qdd) at time `t` (s): each (dof,) for a scalar t, (N, dof) for an array of N times.
    fn sample<'py>(&self, py: Python<'py>, t: &Any<'py>) -> PyResult<Bound<'py, PyAny>> {
        let n = self.inner.dof();
        if let Ok(t) = t.extract::<f64>() {
            let (q, qd, qdd) = (zeros(py, &[n]), zeros(py, &[n]), zeros(py, &[n]));
            crate::convert::fill_fresh(&q, |a| {
                crate::convert::fill_fresh(&qd, |b| {
                    crate::convert::fill_fresh(&qdd, |c| {
                        self.inner.sample(t, a, b, c).py()?;
                        crate::convert::check_finite_outputs(&[a, b, c])
                    })
                })
            })?;
            return Ok((q, qd, qdd).into_pyobject(py)?.into_any());
        }
        let times = vector_of_len(t, "t", 0)?;
        let s = self.inner.sample_times(&times).py()?;
        let m = times.len();
        Ok((
            crate::convert::finite_to_numpy(py, &[m, n], &s.q)?,
            crate::convert::finite_to_numpy(py, &[m, n], &s.qd)?,
            crate::convert::finite_to_numpy(py, &[m, n], &s.qdd)?,
        )
            .into_pyobject(py)?
            .into_any())
    }

    /// Jerk (rad/s³ or m/s³) at time `t` (s), (dof,).
    fn jerk<'py>(&self, py: Python<'py>, t: f64) -> PyResult<Array<'py>> {
        let out = zeros(py, &[self.inner.dof()]);
        crate::convert::fill_fresh(&out, |o| {
            self.inner.jerk(t, o).py()?;
            crate::convert::check_finite_output(o)
        })?;
        Ok(out)
    }

    /// (t, q, qd, qdd) at a control rate of `rate_hz` (Hz): t (N,), the others (N, dof); the end
    /// time is always included. `hz` is the deprecated name of `rate_hz`.
    #[pyo3(signature = (rate_hz=None, *, hz=None))]
    fn sample_rate<'py>(&self, py: Python<'py>, rate_hz: Option<f64>, hz: Option<f64>) -> PyResult<Bound<'py, PyAny>> {
        let rate_hz = crate::args::renamed_required(
            py,
            rate_hz,
            hz,
            "JointTrajectory.sample_rate(hz=...)",
            "rate_hz=...",
            "rate_hz",
        )?;
        let s = self.inner.sample_rate(rate_hz).py()?;
        samples_to_py(py, &s)
    }

    /// (t, q, qd, qdd) at `n` ≥ 2 evenly spaced times from 0 to the duration; q, qd, qdd are
    /// (n, dof) arrays in Fortran order.
    fn sample_uniform<'py>(&self, py: Python<'py>, n: i128) -> PyResult<Bound<'py, PyAny>> {
        sample_uniform(py, &self.inner, crate::args::sample_count(n, "n")?)
    }

    /// Exact peaks of velocity (order 1), acceleration (2) or jerk (3): (values, times), each
    /// (dof,), values signed.
    fn peaks<'py>(&self, py: Python<'py>, order: i128) -> PyResult<Bound<'py, PyAny>> {
        let p = self.inner.peaks(crate::args::unsigned(order, "order")?).py()?;
        Ok((column(py, &p, |x| x.value), column(py, &p, |x| x.time))
            .into_pyobject(py)?
            .into_any())
    }

    /// Exact limit check against the robot's position, velocity and acceleration limits and the
    /// optional jerk limits (dof,): a list of dicts (joint, quantity, time, value, limit), the
    /// worst violation per joint and quantity; empty when every limit holds.
    #[pyo3(signature = (robot, jerk=None))]
    fn check_limits<'py>(
        &self,
        py: Python<'py>,
        robot: &PyRobot,
        jerk: Option<&Any<'py>>,
    ) -> PyResult<Bound<'py, PyList>> {
        let limits = robot_limits(robot, jerk)?;
        violations_to_py(py, &self.inner.check_limits(&limits).py()?)
    }

    fn __repr__(&self) -> String {
        format!(
            "JointTrajectory(dof={}, duration={} s, segments={})",
            self.inner.dof(),
            self.inner.duration(),
            self.inner.segments()
        )
    }
}

value_getters!(PyJointTrajectory, |j| {
    /// Duration (s).
    duration: f64 => j.inner.duration();
    /// Number of joints.
    dof: usize => j.inner.dof();
});

/// (t, q, qd, qdd) at `n` evenly spaced times. q, qd, qdd are (n, dof) arrays in Fortran (column)
/// order: Rust fills them joint by joint, which vectorises over the samples, then hands them to
/// numpy without a copy.
fn sample_uniform<'py>(py: Python<'py>, traj: &JointTrajectory, n: usize) -> PyResult<Bound<'py, PyAny>> {
    let dof = traj.dof();
    let (mut t, mut q, mut qd, mut qdd) = (vec![0.0; n], vec![0.0; n * dof], vec![0.0; n * dof], vec![0.0; n * dof]);
    traj.sample_uniform_columns_into(&mut t, &mut q, &mut qd, &mut qdd)
        .py()?;
    if !traj.samples_cannot_overflow() {
        // e.g. a duration of 1e-200: 1/T³ overflows
        crate::convert::check_finite_outputs(&[&t, &q, &qd, &qdd])?;
    }
    let matrix = |v: Vec<f64>| -> PyResult<_> {
        let a = Array2::from_shape_vec((n, dof).f(), v)
            .map_err(|e| crate::errors::InternalError::new_err(format!("sample_uniform: {e}")))?;
        Ok(PyArray2::from_owned_array(py, a))
    };
    Ok((PyArray1::from_vec(py, t), matrix(q)?, matrix(qd)?, matrix(qdd)?)
        .into_pyobject(py)?
        .into_any())
}

/// Cubic from q0 to q1 in `duration` s with boundary velocities v0, v1 (zero when None).
/// Seed 001's formulas, corrected: a2 = 3h/tf² − (2v0 + v1)/tf, a3 = −2h/tf³ + (v0 + v1)/tf².
#[ttkin_py_guard::guarded]
#[pyfunction]
#[pyo3(signature = (q0, q1, duration, v0=None, v1=None))]
fn traj_cubic(
    q0: &Any<'_>,
    q1: &Any<'_>,
    duration: f64,
    v0: Option<&Any<'_>>,
    v1: Option<&Any<'_>>,
) -> PyResult<PyJointTrajectory> {
    let q0 = vector_of_len(q0, "q0", 1)?;
    let n = q0.len();
    let q1 = vector(q1, "q1", n)?;
    let (v0, v1) = (opt_vector(v0, "v0", n)?, opt_vector(v1, "v1", n)?);
    let inner = JointTrajectory::cubic(&q0, &q1, v0.as_deref(), v1.as_deref(), duration).py()?;
    Ok(PyJointTrajectory { inner })
}

struct QuinticArgs<'a, 'py> {
    v0: Option<&'a Bound<'py, PyAny>>,
    v1: Option<&'a Bound<'py, PyAny>>,
    a0: Option<&'a Bound<'py, PyAny>>,
    a1: Option<&'a Bound<'py, PyAny>>,
}

/// Reads a boundary vector without copying when it is a contiguous float64 array.
fn build_quintic(q0: &Any<'_>, q1: &Any<'_>, duration: f64, o: QuinticArgs<'_, '_>) -> PyResult<JointTrajectory> {
    let q0 = f64_array(q0, "q0")?;
    let n = match q0.shape() {
        [n] if *n > 0 => *n,
        _ => {
            return Err(ShapeError::new_err(format!(
                "q0: expected shape (n,) with n ≥ 1, got {}",
                q0.shape_str()
            )))
        }
    };
    let q1 = f64_array(q1, "q1")?;
    if q1.shape() != [n] {
        return Err(ShapeError::new_err(format!(
            "q1: expected shape ({n},), got {}",
            q1.shape_str()
        )));
    }
    let read = |x: Option<&Any<'_>>, what: &str| -> PyResult<Option<Vec<f64>>> { opt_vector(x, what, n) };
    let (v0, v1, a0, a1) = (
        read(o.v0, "v0")?,
        read(o.v1, "v1")?,
        read(o.a0, "a0")?,
        read(o.a1, "a1")?,
    );
    JointTrajectory::quintic(
        q0.data(),
        q1.data(),
        v0.as_deref(),
        v1.as_deref(),
        a0.as_deref(),
        a1.as_deref(),
        duration,
    )
    .py()
}

/// Quintic from q0 to q1 in `duration` s with boundary velocities and accelerations (zero when None).
#[ttkin_py_guard::guarded]
#[pyfunction]
#[pyo3(signature = (q0, q1, duration, v0=None, v1=None, a0=None, a1=None))]
#[allow(clippy::too_many_arguments)]
fn traj_quintic(
    q0: &Any<'_>,
    q1: &Any<'_>,
    duration: f64,
    v0: Option<&Any<'_>>,
    v1: Option<&Any<'_>>,
    a0: Option<&Any<'_>>,
    a1: Option<&Any<'_>>,
) -> PyResult<PyJointTrajectory> {
    let inner = build_quintic(q0, q1, duration, QuinticArgs { v0, v1, a0, a1 })?;
    Ok(PyJointTrajectory { inner })
}

/// Builds a quintic and samples it at `n` evenly spaced times in one call: (t, q, qd, qdd), the
/// last three (n, dof) in Fortran order.
#[ttkin_py_guard::guarded]
#[pyfunction]
#[pyo3(signature = (q0, q1, duration, n=ttkin::traj::SAMPLES as i128, v0=None, v1=None, a0=None, a1=None))]
#[allow(clippy::too_many_arguments)]
fn traj_quintic_samples<'py>(
    py: Python<'py>,
    q0: &Any<'py>,
    q1: &Any<'py>,
    duration: f64,
    n: i128,
    v0: Option<&Any<'py>>,
    v1: Option<&Any<'py>>,
    a0: Option<&Any<'py>>,
    a1: Option<&Any<'py>>,
) -> PyResult<Bound<'py, PyAny>> {
    let traj = build_quintic(q0, q1, duration, QuinticArgs { v0, v1, a0, a1 })?;
    sample_uniform(py, &traj, crate::args::sample_count(n, "n")?)
}

/// Trajectory through via points (m, n) at strictly increasing times (m,): kind "cubic" (C¹,
/// heuristic or given velocities), "spline" (C², clamped end velocities) or "quintic" (C²).
/// The trajectory's time starts at 0 at times[0].
#[ttkin_py_guard::guarded]
#[pyfunction]
#[pyo3(signature = (points, times, kind="cubic", velocities=None, accelerations=None, v_start=None, v_end=None))]
#[allow(clippy::too_many_arguments)]
fn traj_via(
    points: &Any<'_>,
    times: &Any<'_>,
    kind: &str,
    velocities: Option<&Any<'_>>,
    accelerations: Option<&Any<'_>>,
    v_start: Option<&Any<'_>>,
    v_end: Option<&Any<'_>>,
) -> PyResult<PyJointTrajectory> {
    let (p, m, n) = matrix(points, "points")?;
    let t = vector_of_len(times, "times", 1)?;
    if t.len() != m {
        return Err(ShapeError::new_err(format!(
            "times: expected {m} times (one per via point), got {}",
            t.len()
        )));
    }
    let read_m = |x: Option<&Any<'_>>, what: &str| -> PyResult<Option<Vec<f64>>> {
        x.map(|o| {
            let (d, rm, rn) = matrix(o, what)?;
            if (rm, rn) != (m, n) {
                return Err(ShapeError::new_err(format!(
                    "{what}: expected shape ({m}, {n}), got ({rm}, {rn})"
                )));
            }
            Ok(d)
        })
        .transpose()
    };
    let (vel, acc) = (
        read_m(velocities, "velocities")?,
        read_m(accelerations, "accelerations")?,
    );
    let inner = match ViaKind::from_name(kind).py()? {
        ViaKind::Cubic => via::cubic(&p, &t, n, vel.as_deref()),
        ViaKind::Spline => {
            let (vs, ve) = (opt_vector(v_start, "v_start", n)?, opt_vector(v_end, "v_end", n)?);
            via::spline(&p, &t, n, vs.as_deref(), ve.as_deref())
        }
        ViaKind::Quintic => via::quintic(&p, &t, n, vel.as_deref(), acc.as_deref()),
    }
    .py()?;
    Ok(PyJointTrajectory { inner })
}

/// Minimal duration (s) of a rest-to-rest "cubic" or "quintic" from q0 to q1 under the robot's
/// velocity and acceleration limits and optional jerk limits (closed form).
#[ttkin_py_guard::guarded]
#[pyfunction]
#[pyo3(signature = (robot, q0, q1, kind="quintic", jerk=None))]
fn traj_minimal_duration(
    robot: &PyRobot,
    q0: &Any<'_>,
    q1: &Any<'_>,
    kind: &str,
    jerk: Option<&Any<'_>>,
) -> PyResult<f64> {
    let n = robot.chain.dof();
    let (q0, q1) = (vector(q0, "q0", n)?, vector(q1, "q1", n)?);
    let kind = kind.parse::<SegmentKind>().py()?;
    duration::minimal_duration_rest(&q0, &q1, &robot_limits(robot, jerk)?, kind).py()
}

/// Hitting stroke: from (q, qd, qdd) reach (q_hit, qd_hit, qdd_hit) at t_hit s (or the earliest
/// feasible time after it), then rest at `ready`. Limits: explicit velocity/acceleration/jerk
/// arrays, or the robot's. Returns (trajectory, t_hit, return_duration, violations).
#[ttkin_py_guard::guarded]
#[pyfunction]
#[pyo3(signature = (start, hit, t_hit, ready, velocity, acceleration, jerk, lower=None, upper=None, return_duration=None))]
#[allow(clippy::too_many_arguments)]
fn traj_stroke<'py>(
    py: Python<'py>,
    start: (Bound<'py, PyAny>, Bound<'py, PyAny>, Bound<'py, PyAny>),
    hit: (Bound<'py, PyAny>, Bound<'py, PyAny>, Bound<'py, PyAny>),
    t_hit: f64,
    ready: &Any<'py>,
    velocity: &Any<'py>,
    acceleration: &Any<'py>,
    jerk: &Any<'py>,
    lower: Option<&Any<'py>>,
    upper: Option<&Any<'py>>,
    return_duration: Option<f64>,
) -> PyResult<Bound<'py, PyAny>> {
    let q = vector_of_len(&start.0, "state.q", 1)?;
    let n = q.len();
    let state = |s: &(Bound<'py, PyAny>, Bound<'py, PyAny>, Bound<'py, PyAny>), w: &str| -> PyResult<JointState> {
        Ok(JointState {
            q: vector(&s.0, &format!("{w}.q"), n)?,
            qd: vector(&s.1, &format!("{w}.qd"), n)?,
            qdd: vector(&s.2, &format!("{w}.qdd"), n)?,
        })
    };
    let (s0, s1) = (state(&start, "state")?, state(&hit, "hit")?);
    let ready = vector(ready, "ready", n)?;
    // Infinite limits are allowed here: `table` reads them without a finiteness check.
    let raw = |x: &Any<'py>, w: &str| table(x, w, n, 1);
    let mut limits = KinematicLimits::new(
        &raw(velocity, "velocity")?,
        &raw(acceleration, "acceleration")?,
        &raw(jerk, "jerk")?,
    )
    .py()?;
    match (lower, upper) {
        (Some(lo), Some(hi)) => limits = limits.with_position(&raw(lo, "lower")?, &raw(hi, "upper")?).py()?,
        (None, None) => {}
        _ => {
            let e = ttkin::Error::invalid(
                "stroke: lower/upper",
                "position limits need both `lower` and `upper`, or neither",
            );
            return Err(e).py();
        }
    }
    let s = py
        .detach(|| ttkin::traj::stroke(&s0, &s1, t_hit, &ready, return_duration, &limits))
        .py()?;
    let violations = violations_to_py(py, &s.violations)?;
    Ok((
        PyJointTrajectory { inner: s.trajectory },
        s.t_hit,
        s.return_duration,
        violations,
    )
        .into_pyobject(py)?
        .into_any())
}

crate::pickle::pickled!(serde PyJointTrajectory, _unpickle_joint_trajectory, "JointTrajectory", |j| j.inner, |_, inner: _| Ok(PyJointTrajectory { inner }));

/// Adds the trajectory classes and functions to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(_unpickle_joint_trajectory, m)?)?;
    m.add_class::<PyJointTrajectory>()?;
    m.add_function(wrap_pyfunction!(traj_cubic, m)?)?;
    m.add_function(wrap_pyfunction!(traj_quintic, m)?)?;
    m.add_function(wrap_pyfunction!(traj_quintic_samples, m)?)?;
    m.add_function(wrap_pyfunction!(traj_via, m)?)?;
    m.add_function(wrap_pyfunction!(traj_minimal_duration, m)?)?;
    m.add_function(wrap_pyfunction!(traj_stroke, m)?)?;
    Ok(())
}
