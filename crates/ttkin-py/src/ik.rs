//! Inverse kinematics on `ttmanip.Robot`: `ik` (numeric, or analytic where the robot has a closed
//! form), `ik_all` / `ik_nearest` (analytic branches), `joint_velocity` (differential IK).
//! Conversion only: the maths is `ttkin::ik`. Batches over (N, 4, 4) run without the GIL.

use nalgebra::IsometryMatrix3;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use ttkin::ik::batch::{analytic_for, time_budget as time_budget_from};
use ttkin::ik::{Analytic, DifferentialIk, IkBatchSolver, IkMethod, IkSolver, IkStatus, LimitFilter, MAX_BRANCHES};
use ttkin::task::Task;
use ttkin::JacobianFrame;

use crate::args;
use crate::convert::{column, f64_array, list, rigid_tolerance, rows, to_numpy, transform, vector, zeros, Any, Array};
use crate::errors::{PyResultExt, ShapeError};
use crate::robot::PyRobot;

/// Result of `Robot.ik`: arrays for a batch, scalars for one target.
#[pyclass(name = "IkResult", module = "ttmanip", frozen, get_all)]
pub struct PyIkResult {
    /// Joint values (m, rad): (n,) or (N, n).
    q: Py<PyAny>,
    /// True where both errors are within the tolerances: bool or (N,) bool array.
    success: Py<PyAny>,
    /// Position error of `q` (m).
    position_error: Py<PyAny>,
    /// Orientation error of `q` (rad; 0 for task="position").
    orientation_error: Py<PyAny>,
    /// LM steps taken (0 for an analytic solve).
    iterations: Py<PyAny>,
    /// Random restarts used.
    restarts: Py<PyAny>,
    /// "solved", "unreachable" (proven) or "not_converged": str, or a list of str for a batch.
    status: Py<PyAny>,
}

#[ttkin_py_guard::guarded]
#[pymethods]
impl PyIkResult {
    fn __repr__(&self, py: Python<'_>) -> PyResult<String> {
        Ok(format!(
            "IkResult(status={}, success={}, position_error={}, orientation_error={}, iterations={}, q={})",
            self.status.bind(py).repr()?,
            self.success.bind(py).repr()?,
            self.position_error.bind(py).repr()?,
            self.orientation_error.bind(py).repr()?,
            self.iterations.bind(py).repr()?,
            self.q.bind(py).repr()?
        ))
    }

    fn __bool__(&self, py: Python<'_>) -> PyResult<bool> {
        self.success.bind(py).is_truthy()
    }
}

/// Reads T as one pose (4, 4) or a batch (N, 4, 4) of rigid transforms (to the precision of
/// its dtype: see `convert::rigid_tolerance`).
fn poses(t: &Any<'_>) -> PyResult<(Vec<IsometryMatrix3<f64>>, bool)> {
    crate::convert::transforms(t, "T")
}

impl PyRobot {
    fn analytic(&self) -> PyResult<Analytic> {
        analytic_for(&self.chain).py()
    }
}

#[ttkin_py_guard::guarded]
#[pymethods]
impl PyRobot {
    /// Inverse kinematics of a tool pose T (4, 4), or of a batch (N, 4, 4) in parallel.
    ///
    /// task: "pose" (6-D), "racket5" (racket centre `racket_offset` m along tool z, default 0.15,
    /// and face normal = tool x; 5-D) or "position" (3-D). q0: start (n,) or (N, n); default the
    /// middle of the joint ranges. method: "auto" (analytic nearest branch within limits for
    /// task="pose" on robots with a closed form, else numeric), "numeric" or "analytic".
    /// time_budget in s (None: unlimited, then fully deterministic for a seed).
    /// Returns an IkResult; an unreachable target gives success=False with the best q found,
    /// never an exception (unless raise_on_failure=True: UnreachableError).
    #[pyo3(signature = (T, q0=None, task="pose", *, method="auto", position_tolerance=IkSolver::default().position_tolerance,
        orientation_tolerance=IkSolver::default().orientation_tolerance, max_iterations=IkSolver::default().max_iterations as i128,
        max_restarts=IkSolver::default().max_restarts as i128, time_budget=IkSolver::default().time_budget.map(|d| d.as_secs_f64()),
        seed=IkSolver::default().seed as i128, racket_offset=None, raise_on_failure=false))]
    #[allow(non_snake_case, clippy::too_many_arguments)]
    fn ik(
        &self,
        py: Python<'_>,
        T: &Any<'_>,
        q0: Option<&Any<'_>>,
        task: &str,
        method: &str,
        position_tolerance: f64,
        orientation_tolerance: f64,
        max_iterations: i128,
        max_restarts: i128,
        time_budget: Option<f64>,
        seed: i128,
        racket_offset: Option<f64>,
        raise_on_failure: bool,
    ) -> PyResult<PyIkResult> {
        let max_iterations: usize = args::unsigned(max_iterations, "max_iterations")?;
        let max_restarts: usize = args::unsigned(max_restarts, "max_restarts")?;
        let seed: u64 = args::unsigned(seed, "seed")?;
        let racket_offset = racket_offset.map(|v| args::finite("racket_offset", v)).transpose()?;
        let solver = IkSolver {
            task: Task::from_name_with_offset(task, racket_offset).py()?,
            position_tolerance,
            orientation_tolerance,
            max_iterations,
            max_restarts,
            time_budget: time_budget_from(time_budget).py()?,
            seed,
        };
        let front = IkBatchSolver::new(&self.chain, solver, method.parse::<IkMethod>().py()?).py()?;
        let (targets, batch) = poses(T)?;
        let n = self.chain.dof();
        let q0s = match q0 {
            None => Vec::new(),
            Some(q) => {
                let (a, rows) = self.configs(q, "q0")?;
                ttkin::ik::batch::starts(a.data(), n, rows, targets.len(), batch).py()?
            }
        };
        let chain = &*self.chain;
        // Ctrl-C stops a batch within one target per thread (issue 29).
        let outcomes = crate::interrupt::detach_interruptible(py, |cancel| {
            front.solve_until(chain, &targets, &q0s, &|| crate::interrupt::cancelled(cancel))
        })?
        .py()?;
        if raise_on_failure {
            if let Some((i, o)) = ttkin::ik::batch::first_failure(&outcomes) {
                return Err(crate::errors::ik_failure(o.status, o.failure_message(i)));
            }
        }
        let any = |o: Bound<'_, PyAny>| o.unbind();
        if !batch {
            let (r, status) = (&outcomes[0].result, outcomes[0].status);
            return Ok(PyIkResult {
                q: any(to_numpy(py, &[n], &r.q).into_any()),
                success: any(r.success.into_pyobject(py)?.to_owned().into_any()),
                position_error: any(r.position_error.into_pyobject(py)?.into_any()),
                orientation_error: any(r.orientation_error.into_pyobject(py)?.into_any()),
                iterations: any(r.iterations.into_pyobject(py)?.into_any()),
                restarts: any(r.restarts.into_pyobject(py)?.into_any()),
                status: any(status_str(py, status).clone().into_any()),
            });
        }
        let o = &outcomes[..];
        Ok(PyIkResult {
            q: any(rows(py, o, &[n], |o| &o.result.q).into_any()),
            success: any(column(py, o, |o| o.result.success).into_any()),
            position_error: any(column(py, o, |o| o.result.position_error).into_any()),
            orientation_error: any(column(py, o, |o| o.result.orientation_error).into_any()),
            iterations: any(column(py, o, |o| o.result.iterations as i64).into_any()),
            restarts: any(column(py, o, |o| o.result.restarts as i64).into_any()),
            status: any(list(py, o, |o| o.status.as_str())?.into_any()),
        })
    }

    /// Every analytic IK branch of a tool pose T (4, 4) as a (k, n) array (gantry6: up to 4,
    /// σ1 = +1 first, then σ2 = +1 first; arm4: 1 or 2). limits=True keeps only branches within the
    /// joint limits (revolute angles shifted by 2π into them). hint (n,): on the gantry's s45 = 0
    /// family, θ3 is taken from it (0 otherwise). For a batch T (N, 4, 4), returns (q, count):
    /// q (N, 4, n) padded with NaN and count (N,) branches per pose, 0 where unreachable.
    /// Raises UnreachableError (single pose) naming the failed constraint; TtmanipError when the
    /// robot has no analytic solver.
    #[pyo3(signature = (T, limits=false, hint=None))]
    #[allow(non_snake_case)]
    fn ik_all<'py>(
        &self,
        py: Python<'py>,
        T: &Any<'py>,
        limits: bool,
        hint: Option<&Any<'py>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let ik = self.analytic()?;
        let n = self.chain.dof();
        let filter = if limits { LimitFilter::Enforce } else { LimitFilter::Off };
        let a = f64_array(T, "T")?;
        let hint = hint.map(|h| vector(h, "hint", n)).transpose()?;
        match a.shape() {
            [4, 4] => {
                let t = transform(T, "T")?;
                let sols = ik.solve(&t, hint.as_deref(), filter).py()?;
                Ok(to_numpy(py, &[sols.len(), n], &sols.flat()).into_any())
            }
            [count, 4, 4] => {
                let count = *count;
                let out = zeros(py, &[count, MAX_BRANCHES, n]);
                let mut counts = vec![0usize; count];
                let (data, tolerance, h) = (a.data(), rigid_tolerance(a.precision()), hint.as_deref());
                crate::convert::fill_fresh(&out, |o| {
                    py.detach(|| ik.solve_matrices(data, tolerance, h, filter, o, &mut counts))
                        .py()
                })?;
                let counts = column(py, &counts, |&c| c as i64);
                Ok((out, counts).into_pyobject(py)?.into_any())
            }
            _ => Err(ShapeError::new_err(format!(
                "T: expected shape (4, 4) or (N, 4, 4), got {}",
                a.shape_str()
            ))),
        }
    }

    /// The analytic branch nearest to the configuration q (n,) for the tool pose T (4, 4): joint
    /// distance with revolute angles taken modulo 2π towards q; limits=True (default) keeps to the
    /// joint limits. Raises UnreachableError when no branch exists.
    #[pyo3(signature = (T, q, limits=true))]
    #[allow(non_snake_case)]
    fn ik_nearest<'py>(&self, py: Python<'py>, T: &Any<'py>, q: &Any<'py>, limits: bool) -> PyResult<Array<'py>> {
        let ik = self.analytic()?;
        let q = vector(q, "q", self.chain.dof())?;
        let filter = if limits { LimitFilter::Enforce } else { LimitFilter::Off };
        let sol = ik.nearest(&transform(T, "T")?, &q, filter).py()?;
        Ok(to_numpy(py, &[sol.len()], &sol))
    }

    /// Name of the analytic IK solver of this robot ("gantry6", "arm4"), found from the structure
    /// of its DH table, or None.
    #[getter]
    fn analytic_ik(&self) -> Option<&'static str> {
        match Analytic::for_chain(&self.chain)? {
            Analytic::Gantry6(_) => Some("gantry6"),
            Analytic::Arm4(_) => Some("arm4"),
        }
    }

    /// Joint velocities (n,) (m/s, rad/s) that produce the tool twist [v (m/s); ω (rad/s)] (6,)
    /// at q (n,): J⁻¹V for a square robot, the weighted least-norm solution for a redundant one
    /// (weights (n,) > 0, default 1), least squares for fewer than 6 joints. Near a singularity
    /// (σ_min < epsilon) the inverse is damped up to lambda_max. frame: axes of the twist,
    /// "base" or "tool". With info=True returns (qdot, {"singular", "sigma_min", "damping",
    /// "residual"}). `threshold` and `max_damping` are the deprecated names of `epsilon` and
    /// `lambda_max`.
    #[pyo3(signature = (q, twist, frame="base", weights=None, epsilon=DifferentialIk::default().epsilon,
        lambda_max=DifferentialIk::default().lambda_max, info=false, *, threshold=None, max_damping=None))]
    #[allow(clippy::too_many_arguments)]
    fn joint_velocity<'py>(
        &self,
        py: Python<'py>,
        q: &Any<'py>,
        twist: &Any<'py>,
        frame: &str,
        weights: Option<&Any<'py>>,
        epsilon: f64,
        lambda_max: f64,
        info: bool,
        threshold: Option<f64>,
        max_damping: Option<f64>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let epsilon = args::renamed(py, epsilon, threshold, "joint_velocity(threshold=...)", "epsilon=...")?;
        let lambda_max = args::renamed(
            py,
            lambda_max,
            max_damping,
            "joint_velocity(max_damping=...)",
            "lambda_max=...",
        )?;
        let n = self.chain.dof();
        let q = vector(q, "q", n)?;
        let twist = vector(twist, "twist", 6)?;
        let weights = weights.map(|w| vector(w, "weights", n)).transpose()?;
        let frame: JacobianFrame = frame.parse::<JacobianFrame>().py()?;
        let d = DifferentialIk {
            epsilon,
            lambda_max,
            frame,
        };
        let r = d.solve(&self.chain, &q, &twist, weights.as_deref()).py()?;
        let qdot = to_numpy(py, &[n], &r.qd);
        if !info {
            return Ok(qdot.into_any());
        }
        let dict = PyDict::new(py);
        dict.set_item("singular", r.singular)?;
        dict.set_item("sigma_min", r.sigma_min)?;
        dict.set_item("damping", r.damping)?;
        dict.set_item("residual", r.residual)?;
        Ok((qdot, dict).into_pyobject(py)?.into_any())
    }
}

/// The status as an interned Python string (no allocation per call).
fn status_str(py: Python<'_>, status: IkStatus) -> &Bound<'_, pyo3::types::PyString> {
    match status {
        IkStatus::Solved => pyo3::intern!(py, "solved"),
        IkStatus::Unreachable => pyo3::intern!(py, "unreachable"),
        IkStatus::NotConverged => pyo3::intern!(py, "not_converged"),
    }
}

crate::pickle::pickled!(python PyIkResult, _unpickle_ik_result, "IkResult",
    |r, py| [&r.q, &r.success, &r.position_error, &r.orientation_error, &r.iterations, &r.restarts, &r.status].map(|f| f.clone_ref(py)),
    |_, [q, success, position_error, orientation_error, iterations, restarts, status]: [Py<PyAny>; 7]|
        Ok(PyIkResult { q, success, position_error, orientation_error, iterations, restarts, status }));

/// Adds `IkResult` to the module (the methods live on `Robot`).
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(_unpickle_ik_result, m)?)?;
    m.add_class::<PyIkResult>()
}
