//! `ttmanip.CartesianTrajectory`: tool-pose lines and arcs under a time law, sampled, mapped
//! through a Python IK callable into joint space, and checked against a robot's limits
//! (conversion only; the maths is `ttkin::traj::cartesian`).

use nalgebra::Vector3;
use pyo3::prelude::*;
use pyo3::types::PyList;
use ttkin::traj::cartesian::{CartesianState, CartesianTrajectory, TimeLaw};
use ttkin::traj::Samples;

use crate::convert::vector_of_len;
use crate::convert::{column, pose_to_numpy, row_major, rows, to_numpy, transform, vector, Any};
use crate::errors::{Callback, PyResultExt};
use crate::robot::PyRobot;
use crate::traj::{robot_limits, samples_to_py, violations_to_py};

/// A task-space trajectory: tool pose (4×4, base frame, m) along a line or arc under a time law.
#[pyclass(name = "CartesianTrajectory", module = "ttmanip", frozen)]
pub struct PyCartesianTrajectory {
    inner: CartesianTrajectory,
}

fn law(name: &str, blend: f64) -> PyResult<TimeLaw> {
    Ok(match TimeLaw::from_name(name).py()? {
        TimeLaw::Trapezoid { .. } => TimeLaw::Trapezoid { blend },
        other => other,
    })
}

fn point(obj: &Any<'_>, what: &str) -> PyResult<Vector3<f64>> {
    let v = vector(obj, what, 3)?;
    Ok(Vector3::new(v[0], v[1], v[2]))
}

fn state_to_py<'py>(py: Python<'py>, s: &CartesianState) -> PyResult<Bound<'py, PyAny>> {
    Ok((
        pose_to_numpy(py, &s.pose),
        to_numpy(py, &[6], &s.twist()),
        to_numpy(py, &[6], &s.twist_derivative()),
    )
        .into_pyobject(py)?
        .into_any())
}

#[ttkin_py_guard::guarded]
#[pymethods]
impl PyCartesianTrajectory {
    /// Straight line from pose T0 to pose T1 (4×4) in `duration` s, slerp orientation.
    #[staticmethod]
    #[pyo3(signature = (t0, t1, duration, law="quintic", blend=ttkin::traj::cartesian::TRAPEZOID_BLEND))]
    fn line(t0: &Any<'_>, t1: &Any<'_>, duration: f64, law: &str, blend: f64) -> PyResult<Self> {
        let (a, b) = (transform(t0, "T0")?, transform(t1, "T1")?);
        let inner = CartesianTrajectory::line(&a, &b, duration, self::law(law, blend)?).py()?;
        Ok(PyCartesianTrajectory { inner })
    }

    /// Circular arc from pose T0 through point `via` (3,) to pose T1, slerp orientation.
    #[staticmethod]
    #[pyo3(signature = (t0, via, t1, duration, law="quintic", blend=ttkin::traj::cartesian::TRAPEZOID_BLEND))]
    fn arc_through(t0: &Any<'_>, via: &Any<'_>, t1: &Any<'_>, duration: f64, law: &str, blend: f64) -> PyResult<Self> {
        let (a, b) = (transform(t0, "T0")?, transform(t1, "T1")?);
        let inner =
            CartesianTrajectory::arc_through(&a, &point(via, "via")?, &b, duration, self::law(law, blend)?).py()?;
        Ok(PyCartesianTrajectory { inner })
    }

    /// Circular arc from pose T0 about the axis line (centre (3,), axis (3,)) by `angle` rad; the
    /// tool turns with the arc.
    #[staticmethod]
    #[pyo3(signature = (t0, centre, axis, angle, duration, law="quintic", blend=ttkin::traj::cartesian::TRAPEZOID_BLEND))]
    fn arc_about(
        t0: &Any<'_>,
        centre: &Any<'_>,
        axis: &Any<'_>,
        angle: f64,
        duration: f64,
        law: &str,
        blend: f64,
    ) -> PyResult<Self> {
        let a = transform(t0, "T0")?;
        let inner = CartesianTrajectory::arc_about(
            &a,
            &point(centre, "centre")?,
            &point(axis, "axis")?,
            angle,
            duration,
            self::law(law, blend)?,
        )
        .py()?;
        Ok(PyCartesianTrajectory { inner })
    }

    /// Duration (s).
    #[getter]
    fn duration(&self) -> f64 {
        self.inner.duration()
    }

    /// (pose (4, 4), twist [v; ω] (6,), twist derivative (6,)) at time `t` (s); base frame.
    fn sample<'py>(&self, py: Python<'py>, t: f64) -> PyResult<Bound<'py, PyAny>> {
        state_to_py(py, &self.inner.sample(t).py()?)
    }

    /// (t (N,), poses (N, 4, 4), twists (N, 6), twist derivatives (N, 6)) at `rate_hz` (Hz);
    /// `hz` is its deprecated name.
    #[pyo3(signature = (rate_hz=None, *, hz=None))]
    fn sample_rate<'py>(&self, py: Python<'py>, rate_hz: Option<f64>, hz: Option<f64>) -> PyResult<Bound<'py, PyAny>> {
        let rate_hz = crate::args::renamed_required(
            py,
            rate_hz,
            hz,
            "CartesianTrajectory.sample_rate(hz=...)",
            "rate_hz=...",
            "rate_hz",
        )?;
        let states = self.inner.sample_rate(rate_hz).py()?;
        let s = &states[..];
        Ok((
            column(py, s, |s| s.t),
            rows(py, s, &[4, 4], |s| row_major(&s.pose)),
            rows(py, s, &[6], |s| s.twist()),
            rows(py, s, &[6], |s| s.twist_derivative()),
        )
            .into_pyobject(py)?
            .into_any())
    }

    /// Joint samples (t, q, qd, qdd) at `rate_hz` (Hz) from `ik(pose (4, 4), seed (n,)) -> q (n,)`,
    /// seeded with `q_start` then the previous solution; qd, qdd by finite differences. The first
    /// sample the IK cannot solve raises, naming its index and time. `hz` is the deprecated name
    /// of `rate_hz`.
    #[pyo3(signature = (rate_hz=None, q_start=None, ik=None, *, hz=None))]
    fn to_joint<'py>(
        &self,
        py: Python<'py>,
        rate_hz: Option<f64>,
        q_start: Option<&Any<'py>>,
        ik: Option<&Any<'py>>,
        hz: Option<f64>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let rate_hz = crate::args::renamed_required(
            py,
            rate_hz,
            hz,
            "CartesianTrajectory.to_joint(hz=...)",
            "rate_hz=...",
            "rate_hz",
        )?;
        let missing = |arg: &str| pyo3::exceptions::PyTypeError::new_err(format!("missing required argument '{arg}'"));
        let q_start = q_start.ok_or_else(|| missing("q_start"))?;
        let ik = ik.ok_or_else(|| missing("ik"))?;
        samples_to_py(py, &self.joint_samples(py, rate_hz, q_start, ik)?)
    }

    /// Sampled limit check through IK (see `to_joint`) against the robot's position, velocity and
    /// acceleration limits: the worst violation per joint and quantity, as dicts.
    /// Samples at `rate_hz` (Hz); `hz` is its deprecated name.
    #[pyo3(signature = (robot, ik, q_start, rate_hz=ttkin::traj::SAMPLE_HZ, *, hz=None))]
    fn check_limits<'py>(
        &self,
        py: Python<'py>,
        robot: &PyRobot,
        ik: &Any<'py>,
        q_start: &Any<'py>,
        rate_hz: f64,
        hz: Option<f64>,
    ) -> PyResult<Bound<'py, PyList>> {
        let rate_hz = crate::args::renamed(
            py,
            rate_hz,
            hz,
            "CartesianTrajectory.check_limits(hz=...)",
            "rate_hz=...",
        )?;
        let limits = robot_limits(robot, None)?;
        let samples = self.joint_samples(py, rate_hz, q_start, ik)?;
        violations_to_py(py, &samples.check_limits(&limits).py()?)
    }

    fn __repr__(&self) -> String {
        let kind = match self.inner.path() {
            ttkin::traj::Path::Line { .. } => "line",
            ttkin::traj::Path::Arc { .. } => "arc",
        };
        format!(
            "CartesianTrajectory({kind}, {:.4} m, duration={} s, law={:?})",
            self.inner.path().length(),
            self.inner.duration(),
            self.inner.law()
        )
    }
}

impl PyCartesianTrajectory {
    /// Joint samples through the Python callable `ik` (see `to_joint`).
    fn joint_samples<'py>(
        &self,
        py: Python<'py>,
        rate_hz: f64,
        q_start: &Any<'py>,
        ik: &Any<'py>,
    ) -> PyResult<Samples> {
        let q0 = vector_of_len(q_start, "q_start", 1)?;
        let n = q0.len();
        let callback = Callback::default();
        let result = self.inner.to_joint(rate_hz, &q0, |pose, seed| {
            let call = ik.call1((pose_to_numpy(py, pose), to_numpy(py, &[n], seed)));
            call.and_then(|r| vector_of_len(&r, "ik result", 1))
                .map_err(|e| callback.error(py, e))
        });
        callback.finish(py, result)
    }
}

crate::pickle::pickled!(serde PyCartesianTrajectory, _unpickle_cartesian_trajectory, "CartesianTrajectory", |c| c.inner, |_, inner: _| Ok(PyCartesianTrajectory { inner }));

/// Adds `CartesianTrajectory` to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(_unpickle_cartesian_trajectory, m)?)?;
    m.add_class::<PyCartesianTrajectory>()
}
