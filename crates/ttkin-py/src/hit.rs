//! Hit-pipeline bindings: `HitPlan` and the functions behind `ttmanip.plan_hit`, `plan_hits`
//! and `Hit.from_normal` (conversion only; the maths is `ttkin::hit`).

use std::sync::Arc;

use nalgebra::Vector3;
use pyo3::prelude::*;
use pyo3::types::PyList;
use ttkin::hit::{self, Hit, HitOptions, HitPlan, HitPlanner, HitTask, StrokeProfile};
use ttkin::traj::JointState;
use ttkin::Dynamics;

use crate::convert::{
    array_getters, f64_array, filled_without_gil, pose_to_numpy, to_numpy, transform, value_getters, vector,
};
use crate::errors::{PyResultExt, ShapeError, TtmanipError};
use crate::robot::PyRobot;
use crate::traj::{samples_to_py, violations_to_py, PyJointTrajectory};

/// One planned hit: every intermediate product of `ttkin::hit` (SI units, base frame).
#[pyclass(name = "HitPlan", module = "ttmanip", frozen)]
pub struct PyHitPlan {
    plan: HitPlan,
    planner: Arc<HitPlanner>,
}

value_getters!(PyHitPlan, |h| {
    /// True when the hit is on time and within every limit.
    ok: bool => h.plan.ok();
    /// "ok", "too_early", "unreachable", "singular", "hit_speed_limit", "position_limit",
    /// "effort_limit" or "no_stroke".
    status: &'static str => h.plan.status.name();
    /// One line on what limited the plan ("" when ok).
    message: &str => h.plan.message.as_str();
    /// Planned hit time (s from now); NaN when no stroke.
    t_hit: f64 => h.plan.t_hit;
    /// Requested hit time (s from now).
    requested_t_hit: f64 => h.plan.hit.t;
    /// Earliest feasible hit time (s), computed on first need when planning did not find it;
    /// NaN when there is no hit state.
    earliest_t_hit: f64 => h.planner.earliest_t_hit(&h.plan);
    /// Profile of the hit leg: "quintic" or "jerk" ("auto" when no stroke).
    profile: &'static str => h.plan.profile.name();
    /// Smallest singular value of the (task) Jacobian at the hit.
    sigma_min: f64 => h.plan.sigma_min;
    /// Number of IK branches within the limits.
    branches: usize => h.plan.branches;
    /// Duration of the return leg (s); NaN when no stroke.
    return_duration: f64 => h.plan.return_duration;
    /// Total stroke duration (s); NaN when no stroke.
    duration: f64 => h.plan.trajectory.as_ref().map_or(f64::NAN, |t| t.duration());
    /// Largest |τ(t)|/effective effort limit over joints and every instant of the stroke
    /// (certified to the planner's effort tolerance, 1e-4).
    effort_ratio: f64 => h.plan.effort_ratio;
    /// The stroke as a `JointTrajectory` (None when no stroke was planned).
    trajectory: Option<PyJointTrajectory> => h.plan.trajectory.clone().map(|inner| PyJointTrajectory { inner });
});

array_getters!(PyHitPlan, |h| {
    /// (n,) hit configuration (m, rad); NaN when unreachable.
    q_hit => h.plan.q_hit, [h.plan.q_hit.len()];
    /// (n,) hit joint velocities (m/s, rad/s); NaN when unreachable.
    qd_hit => h.plan.qd_hit, [h.plan.qd_hit.len()];
    /// (6,) requested racket-centre twist [v; ω] (m/s, rad/s, base axes).
    hit_twist => h.plan.hit.twist, [6];
    /// (n,) start configuration (m, rad).
    start => h.plan.start.q, [h.plan.start.q.len()];
    /// (n,) ready (rest) configuration the stroke returns to (m, rad).
    ready => h.plan.ready, [h.plan.ready.len()];
    /// (n,) largest |joint torque| (N·m or N, friction included) over the stroke.
    peak_effort => h.plan.peak_effort, [h.plan.peak_effort.len()];
});

impl PyHitPlan {
    fn stroke(&self) -> PyResult<&ttkin::traj::JointTrajectory> {
        self.plan.trajectory.as_ref().ok_or_else(|| {
            TtmanipError::new_err(format!(
                "plan: no stroke was planned (status '{}': {})",
                self.plan.status.name(),
                self.plan.message
            ))
        })
    }
}

#[ttkin_py_guard::guarded]
#[pymethods]
impl PyHitPlan {
    /// (4, 4) requested racket pose (racket frame in the base frame, m).
    #[getter]
    fn hit_pose<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        pose_to_numpy(py, &self.plan.hit.pose).into_any()
    }

    /// (4, 4) tool pose that puts the racket at the hit pose (base frame, m).
    #[getter]
    fn tool_target<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        pose_to_numpy(py, &self.plan.tool_target).into_any()
    }

    /// Kinematic limit violations (exact peaks): list of dicts (joint, quantity, time, value, limit).
    #[getter]
    fn violations<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        violations_to_py(py, &self.plan.violations)
    }

    /// Samples the stroke at `rate_hz` (Hz): (t (K,), q, qd, qdd (K, n)). TtmanipError when no
    /// stroke. `rate` is the deprecated name of `rate_hz`.
    #[pyo3(signature = (rate_hz=ttkin::traj::SAMPLE_HZ, *, rate=None))]
    fn sample<'py>(&self, py: Python<'py>, rate_hz: f64, rate: Option<f64>) -> PyResult<Bound<'py, PyAny>> {
        let rate_hz = crate::args::renamed(py, rate_hz, rate, "HitPlan.sample(rate=...)", "rate_hz=...")?;
        samples_to_py(py, &self.stroke()?.sample_rate(rate_hz).py()?)
    }

    /// (K, n) joint torques (N·m or N, inverse dynamics with friction and gravity: the drives'
    /// feed-forward) at `rate_hz` (Hz) samples of the stroke. `rate` is the deprecated name of
    /// `rate_hz`.
    #[pyo3(signature = (rate_hz=ttkin::traj::SAMPLE_HZ, *, rate=None))]
    fn torques<'py>(&self, py: Python<'py>, rate_hz: f64, rate: Option<f64>) -> PyResult<Bound<'py, PyAny>> {
        let rate_hz = crate::args::renamed(py, rate_hz, rate, "HitPlan.torques(rate=...)", "rate_hz=...")?;
        let s = self.stroke()?.sample_rate(rate_hz).py()?;
        let dy = Dynamics::new(self.planner.chain()).py()?;
        let profile = py
            .detach(|| dy.torque_profile(&s.q, &s.qd, &s.qdd, &self.planner.gravity(), None))
            .py()?;
        Ok(to_numpy(py, &[s.t.len(), s.dof], &profile.joint).into_any())
    }

    /// (K, n) joint torques at the 1 kHz samples of `sample()`.
    #[getter]
    fn tau<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.torques(py, ttkin::traj::SAMPLE_HZ, None)
    }

    /// Name of the robot this plan was made for.
    #[getter]
    fn robot_name(&self) -> &str {
        self.planner.chain().name()
    }

    /// Whether this plan was made for `robot` (the same chain: joints, geometry, limits, masses).
    fn made_for(&self, robot: &PyRobot) -> bool {
        *self.planner.chain() == *robot.chain
    }

    fn __repr__(&self) -> String {
        format!(
            "HitPlan(status='{}', t_hit={:.4}, earliest_t_hit={:.4}, profile='{}')",
            self.plan.status.name(),
            self.plan.t_hit,
            self.plan.earliest_t_hit,
            self.plan.profile.name()
        )
    }
}

/// The Python keywords `hit_plan` and `hit_plan_batch` share: start state, ready configuration
/// and planner options.
struct Keywords<'a, 'py> {
    q: Option<&'a Bound<'py, PyAny>>,
    qd: Option<&'a Bound<'py, PyAny>>,
    qdd: Option<&'a Bound<'py, PyAny>>,
    ready: Option<&'a Bound<'py, PyAny>>,
    profile: &'a str,
    task: &'a str,
    jerk: Option<&'a Bound<'py, PyAny>>,
    effort: bool,
}

/// What the keywords turn into: the start state, the ready configuration and the planner.
type Prepared = (Option<JointState>, Option<Vec<f64>>, Arc<HitPlanner>);

impl Keywords<'_, '_> {
    /// Reads the keywords for `robot` and builds its planner.
    fn prepare(self, robot: &PyRobot) -> PyResult<Prepared> {
        let n = robot.chain.dof();
        let state = self.start_state(n)?;
        let ready = self.ready.map(|r| vector(r, "ready", n)).transpose()?;
        let planner = Arc::new(HitPlanner::new(&robot.chain, self.options(n)?).py()?);
        Ok((state, ready, planner))
    }

    /// Options from the Python keywords.
    fn options(&self, n: usize) -> PyResult<HitOptions> {
        let jerk = self.jerk.map(|j| vector(j, "jerk", n)).transpose()?;
        Ok(HitOptions {
            profile: self.profile.parse::<StrokeProfile>().py()?,
            task: self.task.parse::<HitTask>().py()?,
            jerk,
            check_effort: self.effort,
            ..Default::default()
        })
    }

    /// The start state from optional q, qd, qdd.
    fn start_state(&self, n: usize) -> PyResult<Option<JointState>> {
        let Some(q) = self.q else { return Ok(None) };
        let mut state = JointState::rest(&vector(q, "state.q", n)?);
        if let Some(qd) = self.qd {
            state.qd = vector(qd, "state.qd", n)?;
        }
        if let Some(qdd) = self.qdd {
            state.qdd = vector(qdd, "state.qdd", n)?;
        }
        Ok(Some(state))
    }
}

/// Plans one hit: racket pose (4, 4), racket-centre twist (6,), hit time (s); optional start
/// state (q, qd, qdd), ready configuration, profile ("auto", "quintic", "jerk"), task ("auto",
/// "pose", "racket5"), jerk limits (n,), effort (check the effort limits).
#[ttkin_py_guard::guarded]
#[pyfunction]
#[pyo3(signature = (robot, pose, twist, t, q=None, qd=None, qdd=None, ready=None, profile="auto", task="auto", jerk=None, effort=true))]
#[allow(clippy::too_many_arguments)]
fn hit_plan(
    py: Python<'_>,
    robot: &PyRobot,
    pose: &Bound<'_, PyAny>,
    twist: &Bound<'_, PyAny>,
    t: f64,
    q: Option<&Bound<'_, PyAny>>,
    qd: Option<&Bound<'_, PyAny>>,
    qdd: Option<&Bound<'_, PyAny>>,
    ready: Option<&Bound<'_, PyAny>>,
    profile: &str,
    task: &str,
    jerk: Option<&Bound<'_, PyAny>>,
    effort: bool,
) -> PyResult<PyHitPlan> {
    let pose = transform(pose, "hit.pose")?;
    let tw = vector(twist, "hit.twist", 6)?;
    let hit = Hit::new(pose, [tw[0], tw[1], tw[2], tw[3], tw[4], tw[5]], t)
        .map_err(|e| e.within("hit."))
        .py()?;
    let keywords = Keywords {
        q,
        qd,
        qdd,
        ready,
        profile,
        task,
        jerk,
        effort,
    };
    let (state, ready, planner) = keywords.prepare(robot)?;
    let plan = py
        .detach(|| planner.plan(&hit, state.as_ref(), ready.as_deref()))
        .py()?;
    Ok(PyHitPlan { plan, planner })
}

/// Plans N hits in parallel (GIL released): poses (N, 4, 4), twists (N, 6), times (N,); the
/// other arguments as for `hit_plan`. Returns a list of N `HitPlan`s.
#[ttkin_py_guard::guarded]
#[pyfunction]
#[pyo3(signature = (robot, poses, twists, times, q=None, qd=None, qdd=None, ready=None, profile="auto", task="auto", jerk=None, effort=true))]
#[allow(clippy::too_many_arguments)]
fn hit_plan_batch(
    py: Python<'_>,
    robot: &PyRobot,
    poses: &Bound<'_, PyAny>,
    twists: &Bound<'_, PyAny>,
    times: &Bound<'_, PyAny>,
    q: Option<&Bound<'_, PyAny>>,
    qd: Option<&Bound<'_, PyAny>>,
    qdd: Option<&Bound<'_, PyAny>>,
    ready: Option<&Bound<'_, PyAny>>,
    profile: &str,
    task: &str,
    jerk: Option<&Bound<'_, PyAny>>,
    effort: bool,
) -> PyResult<Vec<PyHitPlan>> {
    // The plans' bytes bounded before the poses are read (10⁷ hits asked for 1.2 GiB of poses
    // and hours of planning; issue 29).
    if let Ok(count) = poses.len() {
        HitPlanner::check_batch(robot.chain.dof(), count).py()?;
    }
    // Poses rigid to the precision of their dtype, as `hit_plan` reads its one pose (float32
    // accepted in both).
    let (poses, batch) = crate::convert::transforms(poses, "poses")?;
    let k = poses.len();
    if !batch {
        return Err(ShapeError::new_err("poses: expected shape (N, 4, 4), got (4, 4)"));
    }
    let tw = f64_array(twists, "twists")?;
    if tw.shape() != [k, 6] {
        return Err(ShapeError::new_err(format!(
            "twists: expected shape ({k}, 6), got {}",
            tw.shape_str()
        )));
    }
    let ts = vector(times, "times", k)?;
    let hits = Hit::batch(&poses, tw.data(), &ts).py()?;
    let keywords = Keywords {
        q,
        qd,
        qdd,
        ready,
        profile,
        task,
        jerk,
        effort,
    };
    let (state, ready, planner) = keywords.prepare(robot)?;
    // Ctrl-C stops the batch within one hit per thread (issue 29).
    let plans = crate::interrupt::detach_interruptible(py, |cancel| {
        planner.plan_batch_until(&hits, state.as_ref(), ready.as_deref(), &|| {
            crate::interrupt::cancelled(cancel)
        })
    })?
    .py()?;
    Ok(crate::convert::wrap_all(plans, |plan| PyHitPlan {
        plan,
        planner: planner.clone(),
    }))
}

/// Checks that `count` hits fit one `hit_plan_batch` call for `robot`: their plans within
/// `ttkin::budget::MAX_BYTES` (`ttkin::hit::HitPlanner::check_batch`); `plan_hits` asks before it
/// stacks the hits' poses.
#[ttkin_py_guard::guarded]
#[pyfunction]
fn hit_batch_check(robot: &PyRobot, count: usize) -> PyResult<()> {
    HitPlanner::check_batch(robot.chain.dof(), count).py()
}

/// (3, 3) racket orientation (base axes) with z along the face `normal` and x (the handle) as
/// close as possible to `handle`: the one racket-frame convention of `ttkin::hit::racket`.
#[ttkin_py_guard::guarded]
#[pyfunction]
#[pyo3(signature = (normal, handle=None))]
fn racket_frame<'py>(
    py: Python<'py>,
    normal: &Bound<'py, PyAny>,
    handle: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyAny>> {
    let n = vector(normal, "normal", 3)?;
    let h = match handle {
        Some(h) => vector(h, "handle", 3)?,
        None => hit::DEFAULT_HANDLE.to_vec(),
    };
    let r = hit::racket_frame(&Vector3::from_column_slice(&n), &Vector3::from_column_slice(&h)).py()?;
    let m = r.matrix();
    let rows: Vec<f64> = (0..3).flat_map(|i| (0..3).map(move |j| m[(i, j)])).collect();
    Ok(to_numpy(py, &[3, 3], &rows).into_any())
}

/// Checks hit parameters as the planner will: pose (4, 4) rigid, twist (6,) finite, t (s) finite,
/// > 0 and at most `ttkin::traj::duration::MAX_DURATION`; the one check of `ttmanip.Hit`.
#[ttkin_py_guard::guarded]
#[pyfunction]
fn hit_check(pose: &Bound<'_, PyAny>, twist: &Bound<'_, PyAny>, t: f64) -> PyResult<()> {
    let pose = transform(pose, "hit.pose")?;
    let tw = vector(twist, "hit.twist", 6)?;
    Hit::new(pose, [tw[0], tw[1], tw[2], tw[3], tw[4], tw[5]], t)
        .map_err(|e| e.within("hit."))
        .py()?;
    Ok(())
}

/// (N, 22) racket states of joint states `q`, `qd` (N, n): per row the racket pose (base frame,
/// m; row-major 4×4) then the racket-centre twist [v (m/s); ω (rad/s)] (base axes).
#[ttkin_py_guard::guarded]
#[pyfunction]
fn racket_states<'py>(
    py: Python<'py>,
    robot: &PyRobot,
    q: &Bound<'py, PyAny>,
    qd: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyAny>> {
    let (qa, batch) = robot.configs(q, "q")?;
    let (qda, batch_d) = robot.configs(qd, "qd")?;
    let count = batch.unwrap_or(1);
    if batch_d.unwrap_or(1) != count {
        return Err(ShapeError::new_err(format!(
            "qd: expected as many rows as q ({count}), got {}",
            qda.shape_str()
        )));
    }
    let (qs, qds, chain) = (qa.data(), qda.data(), &*robot.chain);
    Ok(filled_without_gil(py, &[count, hit::RACKET_STATE_LEN], |o| {
        hit::racket_state_batch(chain, qs, qds, o)
    })?
    .into_any())
}

/// (4, 4) racket frame in the tool frame for `robot` (m): where its racket is mounted.
#[ttkin_py_guard::guarded]
#[pyfunction]
fn racket_mount<'py>(py: Python<'py>, robot: &PyRobot) -> Bound<'py, PyAny> {
    pose_to_numpy(py, &hit::RacketMount::for_chain(&robot.chain).in_tool).into_any()
}

// Pickle and copy: the planner's chain and options and the plan, in their serde forms (issue 31);
// the planner is rebuilt from the first two (`HitPlanner::new` is deterministic).
crate::pickle::pickled!(serde PyHitPlan, _unpickle_hit_plan, "HitPlan", |h| (h.planner.chain(), h.planner.options(), &h.plan),
    |_, (chain, options, plan): (ttkin::Chain, HitOptions, HitPlan)| Ok(PyHitPlan { plan, planner: Arc::new(HitPlanner::new(&chain, options).py()?) }));

/// Adds `HitPlan` and the hit functions to the module.
/// The stroke profile names `plan_hit(profile=...)` accepts (`StrokeProfile::ALL`'s names).
#[ttkin_py_guard::guarded]
#[pyfunction]
fn hit_stroke_profiles() -> Vec<&'static str> {
    StrokeProfile::ALL.map(|p| p.name()).to_vec()
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(hit_stroke_profiles, m)?)?;
    m.add_function(wrap_pyfunction!(_unpickle_hit_plan, m)?)?;
    m.add_class::<PyHitPlan>()?;
    m.add_function(wrap_pyfunction!(hit_plan, m)?)?;
    m.add_function(wrap_pyfunction!(hit_plan_batch, m)?)?;
    m.add_function(wrap_pyfunction!(racket_frame, m)?)?;
    m.add_function(wrap_pyfunction!(racket_mount, m)?)?;
    m.add_function(wrap_pyfunction!(racket_states, m)?)?;
    m.add_function(wrap_pyfunction!(hit_check, m)?)?;
    m.add_function(wrap_pyfunction!(hit_batch_check, m)?)?;
    Ok(())
}
