//! Mobile manipulation bindings: `DiffDrive`, `Robot.task_jacobian` / `Robot.task_coordinates`,
//! `wls_step`, `task_line` and `track` (one call per motion, the loop in Rust without the GIL).

use pyo3::prelude::*;
use ttkin::clik::{ClikOptions, ClikResult, ClikStatus, TaskTrajectory};
use ttkin::diffdrive::DiffDrive;
use ttkin::redundancy::{Damping, Weighting, WlsStep};
use ttkin::task::Task;
use ttkin::wholebody::WholeBody;

use crate::args;
use crate::convert::{
    array_getters, f64_array, filled_without_gil, finite_to_numpy, to_numpy, transform, value_getters, vector, Any,
    Array,
};
use crate::errors::{PyResultExt, ShapeError, TtmanipError};
use crate::robot::PyRobot;

/// A differential-drive base: wheel speeds (left, right) in rad/s, body velocity (v m/s, ω rad/s),
/// poses (x m, y m, θ rad) of the axle midpoint in the world frame.
#[pyclass(name = "DiffDrive", module = "ttmanip", frozen)]
#[derive(Clone)]
pub struct PyDiffDrive {
    drive: DiffDrive,
}

fn wheel_pair(obj: &Any<'_>, what: &str) -> PyResult<[f64; 2]> {
    let v = vector(obj, what, 2)?;
    Ok([v[0], v[1]])
}

#[ttkin_py_guard::guarded]
#[pymethods]
impl PyDiffDrive {
    /// Wheel radius and track width (m); optional wheel speed (rad/s) and acceleration (rad/s²)
    /// limits. `track` is the deprecated name of `track_width`.
    #[new]
    #[pyo3(signature = (wheel_radius, track_width=None, max_wheel_speed=None, max_wheel_acceleration=None, *, track=None))]
    fn new(
        py: Python<'_>,
        wheel_radius: f64,
        track_width: Option<f64>,
        max_wheel_speed: Option<f64>,
        max_wheel_acceleration: Option<f64>,
        track: Option<f64>,
    ) -> PyResult<Self> {
        let width = match (track_width, track) {
            (Some(w), None) => w,
            (None, Some(w)) => {
                crate::errors::deprecated(py, "DiffDrive(track=...)", "DiffDrive(track_width=...)")?;
                w
            }
            (Some(_), Some(_)) => return Err(TtmanipError::new_err("track: give track_width only")),
            (None, None) => return Err(TtmanipError::new_err("track_width: required (m)")),
        };
        let drive = DiffDrive::new(wheel_radius, width)
            .and_then(|d| {
                d.with_limits(
                    max_wheel_speed.unwrap_or(f64::INFINITY),
                    max_wheel_acceleration.unwrap_or(f64::INFINITY),
                )
            })
            .py()?;
        Ok(PyDiffDrive { drive })
    }

    /// Deprecated name of `track_width`.
    #[getter]
    fn track(&self, py: Python<'_>) -> PyResult<f64> {
        crate::errors::deprecated(py, "DiffDrive.track", "DiffDrive.track_width")?;
        Ok(self.drive.track())
    }

    /// Body velocity (v m/s, ω rad/s) from wheel speeds (left, right) rad/s.
    fn body_velocity(&self, wheel_speeds: &Any<'_>) -> PyResult<(f64, f64)> {
        Ok(self.drive.body_velocity(wheel_pair(wheel_speeds, "wheel_speeds")?))
    }

    /// Wheel speeds (left, right) in rad/s for a body velocity (v m/s, ω rad/s), shape (2,).
    fn wheel_speeds<'py>(&self, py: Python<'py>, v: f64, omega: f64) -> PyResult<Array<'py>> {
        let w = self
            .drive
            .wheel_speeds(args::finite("v", v)?, args::finite("omega", omega)?);
        finite_to_numpy(py, &[2], &w)
    }

    /// Pose (x, y, θ) after `duration` s at constant wheel speeds (left, right) rad/s from `pose`:
    /// the exact arc (no singularity when driving straight or spinning in place), shape (3,).
    fn integrate<'py>(
        &self,
        py: Python<'py>,
        pose: &Any<'py>,
        wheel_speeds: &Any<'py>,
        duration: f64,
    ) -> PyResult<Array<'py>> {
        let p = vector(pose, "pose", 3)?;
        let w = wheel_pair(wheel_speeds, "wheel_speeds")?;
        let out = self.drive.try_integrate([p[0], p[1], p[2]], w, duration).py()?;
        finite_to_numpy(py, &[3], &out)
    }

    /// Wheel speeds scaled together to the speed limit (curvature kept), shape (2,).
    fn saturate<'py>(&self, py: Python<'py>, wheel_speeds: &Any<'py>) -> PyResult<Array<'py>> {
        let (w, _) = self.drive.saturate_speeds(wheel_pair(wheel_speeds, "wheel_speeds")?);
        finite_to_numpy(py, &[2], &w)
    }

    /// Wheel speeds reachable from `previous` toward `command` in `dt` s under both limits, (2,).
    fn limit_step<'py>(
        &self,
        py: Python<'py>,
        previous: &Any<'py>,
        command: &Any<'py>,
        dt: f64,
    ) -> PyResult<Array<'py>> {
        let w = self
            .drive
            .limit_step_checked(wheel_pair(previous, "previous")?, wheel_pair(command, "command")?, dt)
            .py()?;
        finite_to_numpy(py, &[2], &w)
    }

    fn __repr__(&self) -> String {
        format!(
            "DiffDrive(wheel_radius={}, track_width={}, max_wheel_speed={}, max_wheel_acceleration={})",
            self.drive.wheel_radius(),
            self.drive.track(),
            self.drive.max_wheel_speed(),
            self.drive.max_wheel_acceleration()
        )
    }
}

value_getters!(PyDiffDrive, |d| {
    /// Wheel radius (m).
    wheel_radius: f64 => d.drive.wheel_radius();
    /// Distance between the wheel contact points (m).
    track_width: f64 => d.drive.track();
    /// Wheel speed limit (rad/s; inf when none).
    max_wheel_speed: f64 => d.drive.max_wheel_speed();
    /// Wheel acceleration limit (rad/s²; inf when none).
    max_wheel_acceleration: f64 => d.drive.max_wheel_acceleration();
});

/// The whole-body model of a robot, optionally on a diff-drive base with a mount transform.
fn model(robot: &PyRobot, base: Option<&PyDiffDrive>, mount: Option<&Any<'_>>) -> PyResult<WholeBody> {
    match base {
        None => {
            if mount.is_some() {
                return Err(TtmanipError::new_err(
                    "mount: only meaningful together with base=DiffDrive(...)",
                ));
            }
            Ok(WholeBody::fixed(robot.chain.clone()))
        }
        Some(b) => {
            let m = match mount {
                Some(m) => transform(m, "mount")?,
                None => nalgebra::IsometryMatrix3::identity(),
            };
            Ok(WholeBody::on_diff_drive(b.drive, m, robot.chain.clone()))
        }
    }
}

#[ttkin_py_guard::guarded]
#[pymethods]
impl PyRobot {
    /// Task Jacobian J_e (m, n) of `task` ("pose", "position", "racket5") at `q` (n,), or (N, m, n)
    /// for q of shape (N, n) (in parallel), rows in the task's residual coordinates (base axes):
    /// the residual against `target` (4×4, default: the current pose) changes as ė = −J_e q̇; for
    /// the current pose as target, J_e q̇ is the task velocity.
    #[pyo3(signature = (q, task="racket5", target=None))]
    fn task_jacobian<'py>(
        &self,
        py: Python<'py>,
        q: &Any<'py>,
        task: &str,
        target: Option<&Any<'py>>,
    ) -> PyResult<Array<'py>> {
        let task = Task::from_name(task).py()?;
        let target = target.map(|m| transform(m, "target")).transpose()?;
        let (a, batch) = self.configs(q, "q")?;
        let (qs, chain, n) = (a.data(), &*self.chain, self.chain.dof());
        let shape = match batch {
            None => vec![task.dim(), n],
            Some(count) => vec![count, task.dim(), n],
        };
        filled_without_gil(py, &shape, |o| task.jacobian_batch(chain, qs, target.as_ref(), o))
    }

    /// Jacobian (5, n) of seed 000's racket coordinates [centre x, y, z (m), polar, azimuth (rad)]
    /// at `q` (n,), or (N, 5, n) for q of shape (N, n) (`ttkin::task::racket_angle_jacobian_batch`,
    /// racket centre 0.15 m along tool z): their rates are ẋ = J q̇ (unlike `task_jacobian`'s
    /// residual rows); an error where the face normal is along ±z (the azimuth is undefined there).
    fn racket_angle_jacobian<'py>(&self, py: Python<'py>, q: &Any<'py>) -> PyResult<Array<'py>> {
        let (a, batch) = self.configs(q, "q")?;
        let (qs, chain, n) = (a.data(), &*self.chain, self.chain.dof());
        let shape = match batch {
            None => vec![5, n],
            Some(count) => vec![count, 5, n],
        };
        filled_without_gil(py, &shape, |o| {
            ttkin::task::racket_angle_jacobian_batch(chain, qs, ttkin::task::SEED_RACKET_OFFSET, o)
        })
    }

    /// Task coordinates of the tool pose at `q` (n,): position (3,); position and rotation vector
    /// (6,); or seed 000's racket 5-vector [centre x, y, z (m), polar, azimuth (rad)]; (N, dim) for
    /// q of shape (N, n), in parallel.
    #[pyo3(signature = (q, task="racket5"))]
    fn task_coordinates<'py>(&self, py: Python<'py>, q: &Any<'py>, task: &str) -> PyResult<Array<'py>> {
        let task = Task::from_name(task).py()?;
        let (a, batch) = self.configs(q, "q")?;
        let (qs, chain) = (a.data(), &*self.chain);
        let shape = match batch {
            None => vec![task.dim()],
            Some(count) => vec![count, task.dim()],
        };
        filled_without_gil(py, &shape, |o| task.coordinates_batch(chain, qs, o))
    }
}

/// One weighted least-norm step: inputs q̇ (nu,) that realise task velocity `xdot` (residual
/// coordinates, see `Robot.task_jacobian`) at `q`, with Chan–Dubey joint-limit weights (or none) and
/// singularity-robust damping (rising to `lambda_max` below σ_min = `epsilon`); `qd_prev` (nu,)
/// the previous step's inputs. `damping` and `qdot_prev` are the deprecated names of `lambda_max`
/// and `qd_prev`.
#[ttkin_py_guard::guarded]
#[pyfunction]
#[pyo3(signature = (robot, q, xdot, task="racket5", weights="chan-dubey", lambda_max=Damping::default().lambda_max, epsilon=Damping::default().epsilon, qd_prev=None, base=None, mount=None, *, damping=None, qdot_prev=None))]
#[allow(clippy::too_many_arguments)]
fn wls_step<'py>(
    py: Python<'py>,
    robot: &PyRobot,
    q: &Any<'py>,
    xdot: &Any<'py>,
    task: &str,
    weights: &str,
    lambda_max: f64,
    epsilon: f64,
    qd_prev: Option<&Any<'py>>,
    base: Option<PyRef<'py, PyDiffDrive>>,
    mount: Option<&Any<'py>>,
    damping: Option<f64>,
    qdot_prev: Option<&Any<'py>>,
) -> PyResult<Array<'py>> {
    let lambda_max = crate::args::renamed(py, lambda_max, damping, "wls_step(damping=...)", "lambda_max=...")?;
    let qd_prev = crate::args::renamed(
        py,
        qd_prev,
        qdot_prev.map(Some),
        "wls_step(qdot_prev=...)",
        "qd_prev=...",
    )?;
    let task = Task::from_name(task).py()?;
    let weighting = Weighting::from_name(weights).py()?;
    let model = model(robot, base.as_deref(), mount)?;
    let q = vector(q, "q", model.nq())?;
    let xdot = vector(xdot, "xdot", task.dim())?;
    let prev = qd_prev.map(|p| vector(p, "qd_prev", model.nu())).transpose()?;
    let prev = prev.unwrap_or_else(|| vec![0.0; model.nu()]);
    let mut step = WlsStep::new(&model, task, weighting, Damping::new(epsilon, lambda_max).py()?).py()?;
    let (qd, _) = step.try_solve(&q, &xdot, &prev).py()?;
    finite_to_numpy(py, &[qd.len()], &qd)
}

/// Samples (N, dim) and rates (N, dim) of a straight task-space line from `x0` to `x1` over
/// `duration` s with the quintic rest-to-rest time law, at `rate_hz` (both ends included).
#[ttkin_py_guard::guarded]
#[pyfunction]
#[pyo3(signature = (x0, x1, duration, rate_hz=ttkin::traj::SAMPLE_HZ, task="racket5"))]
fn task_line<'py>(
    py: Python<'py>,
    x0: &Any<'py>,
    x1: &Any<'py>,
    duration: f64,
    rate_hz: f64,
    task: &str,
) -> PyResult<(Array<'py>, Array<'py>)> {
    let task = Task::from_name(task).py()?;
    let d = task.dim();
    let (a, b) = (vector(x0, "x0", d)?, vector(x1, "x1", d)?);
    let traj = TaskTrajectory::line(task, &a, &b, duration, rate_hz).py()?;
    let n = traj.len();
    Ok((
        finite_to_numpy(py, &[n, d], traj.positions())?,
        finite_to_numpy(py, &[n, d], traj.rates())?,
    ))
}

/// The arrays of a tracked motion (one row per control sample) and how it ended.
#[pyclass(name = "TrackResult", module = "ttmanip", frozen)]
pub struct PyTrackResult {
    r: ClikResult,
    joint_names: Vec<String>,
}

array_getters!(PyTrackResult, |t| {
    /// Sample times (N,), s.
    time => t.r.time, [t.r.len()];
    /// Configurations (N, nq): m for prismatic, rad for revolute joints (base x, y, θ first).
    q => t.r.q, [t.r.len(), t.r.nq];
    /// Commanded inputs (N, nu): joint rates (m/s, rad/s), base (v, ω) first.
    qd => t.r.qd, [t.r.len(), t.r.nu];
    /// Task coordinates reached (N, dim).
    x => t.r.x, [t.r.len(), t.r.dim];
    /// Norm of the task residual (N,), task units.
    error => t.r.error, [t.r.len()];
    /// Position residual (N,), m.
    position_error => t.r.position_error, [t.r.len()];
    /// Orientation residual (N,), rad.
    orientation_error => t.r.orientation_error, [t.r.len()];
    /// Distance of each arm joint to its nearer limit (N, n), m or rad; negative beyond a limit.
    margin => t.r.margin, [t.r.len(), t.r.n_margin];
    /// Fraction of the task velocity achieved at each sample (N,), 1 = full.
    scale => t.r.scale, [t.r.len()];
    /// Smallest singular value estimate of the weighted task Jacobian (N,).
    sigma_min => t.r.sigma_min, [t.r.len()];
});

#[ttkin_py_guard::guarded]
#[pymethods]
impl PyTrackResult {
    /// Deprecated name of `qd`.
    #[getter]
    fn qdot<'py>(&self, py: Python<'py>) -> PyResult<Array<'py>> {
        crate::errors::deprecated(py, "TrackResult.qdot", "TrackResult.qd")?;
        Ok(to_numpy(py, &[self.r.len(), self.r.nu], &self.r.qd))
    }
    fn __len__(&self) -> usize {
        self.r.len()
    }
    fn __repr__(&self) -> PyResult<String> {
        Ok(format!("TrackResult({} samples, {})", self.r.len(), self.message()?))
    }
}

value_getters!(PyTrackResult, |t| {
    /// "completed", "saturated" (finished, task velocity scaled at some samples) or "failed".
    status: &'static str => t.r.status.name();
    /// True when the motion completed with the full task velocity at every sample.
    ok: bool => t.r.status == ClikStatus::Completed;
    /// A sentence on how the motion ended.
    message: String => t.r.status.to_string();
    /// Names of the arm joints (columns of `margin`).
    joint_names: Vec<String> => t.joint_names.clone();
});

/// Closed-loop tracking of a task trajectory sampled at `rate_hz` (N, dim) from `q0`; the loop
/// runs in Rust without the GIL. `velocities` (N, dim) are the task rates (default: finite
/// differences). See `ttmanip.mobile.track` for the options; `damping` is the deprecated name of
/// `lambda_max`.
#[ttkin_py_guard::guarded]
#[pyfunction]
#[pyo3(signature = (robot, q0, task_trajectory, rate_hz=ttkin::traj::SAMPLE_HZ, task="racket5", velocities=None, weights="chan-dubey",
                    gain=None, lambda_max=Damping::default().lambda_max, epsilon=Damping::default().epsilon, input_weights=None,
                    limit_gain=ClikOptions::default().limit_gain, manipulability_gain=ClikOptions::default().manipulability_gain,
                    respect_limits=ClikOptions::default().respect_limits, max_error=ClikOptions::default().max_error,
                    corrector=ClikOptions::default().corrector, base=None, mount=None, *, damping=None))]
#[allow(clippy::too_many_arguments)]
fn track<'py>(
    py: Python<'py>,
    robot: &PyRobot,
    q0: &Any<'py>,
    task_trajectory: &Any<'py>,
    rate_hz: f64,
    task: &str,
    velocities: Option<&Any<'py>>,
    weights: &str,
    gain: Option<f64>,
    lambda_max: f64,
    epsilon: f64,
    input_weights: Option<&Any<'py>>,
    limit_gain: f64,
    manipulability_gain: f64,
    respect_limits: bool,
    max_error: f64,
    corrector: bool,
    base: Option<PyRef<'py, PyDiffDrive>>,
    mount: Option<&Any<'py>>,
    damping: Option<f64>,
) -> PyResult<PyTrackResult> {
    let lambda_max = crate::args::renamed(py, lambda_max, damping, "track(damping=...)", "lambda_max=...")?;
    let task = Task::from_name(task).py()?;
    let model = model(robot, base.as_deref(), mount)?;
    let q0 = vector(q0, "q0", model.nq())?;
    let d = task.dim();
    let samples = |obj: &Any<'py>, what: &str| -> PyResult<Vec<f64>> {
        let a = f64_array(obj, what)?;
        match a.shape() {
            [_, c] if *c == d => Ok(a.data().to_vec()),
            _ => Err(ShapeError::new_err(format!(
                "{what}: expected shape (N, {d}) for task of dimension {d}, got {}",
                a.shape_str()
            ))),
        }
    };
    let x = samples(task_trajectory, "task_trajectory")?;
    let trajectory = match velocities {
        Some(v) => TaskTrajectory::new(task, rate_hz, x, samples(v, "velocities")?),
        None => TaskTrajectory::from_samples(task, rate_hz, x),
    }
    .py()?;
    let input_weights = input_weights
        .map(|w| vector(w, "input_weights", model.nu()))
        .transpose()?;
    let options = ClikOptions {
        gain,
        weighting: Weighting::from_name(weights).py()?,
        damping: Damping::new(epsilon, lambda_max).py()?,
        input_weights,
        limit_gain,
        manipulability_gain,
        respect_limits,
        max_error,
        corrector,
    };
    let r = py
        .detach(|| ttkin::clik::track(&model, &q0, &trajectory, options))
        .py()?;
    let joint_names = robot.chain.joint_names();
    Ok(PyTrackResult { r, joint_names })
}

crate::pickle::pickled!(serde PyDiffDrive, _unpickle_diff_drive, "DiffDrive", |d| d.drive, |_, drive: _| Ok(PyDiffDrive { drive }));
crate::pickle::pickled!(serde PyTrackResult, _unpickle_track_result, "TrackResult", |t| (&t.r, &t.joint_names), |_, (r, joint_names): _| Ok(PyTrackResult { r, joint_names }));

/// Adds the mobile-manipulation classes and functions to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(_unpickle_track_result, m)?)?;
    m.add_function(wrap_pyfunction!(_unpickle_diff_drive, m)?)?;
    m.add_class::<PyDiffDrive>()?;
    m.add_class::<PyTrackResult>()?;
    m.add_function(wrap_pyfunction!(wls_step, m)?)?;
    m.add_function(wrap_pyfunction!(task_line, m)?)?;
    m.add_function(wrap_pyfunction!(track, m)?)?;
    Ok(())
}
