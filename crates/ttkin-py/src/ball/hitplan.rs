//! Bindings of `ttkin::ball::hitplan` and the rally's correction: a return planned, and planned
//! again with the stroke under way.

use super::*;
use ttkin::ball::rally;

/// Plans `robot`'s return of the ball `state` for a stroke starting at time `now` (s), landing at
/// `target` (x, y, m, world) (`ttkin::ball::hitplan::ReturnPlanner::new`: a robot with analytic IK
/// that reaches the ready pose at the rally's placement, else `ModelError`).
#[ttkin_py_guard::guarded]
#[pyfunction]
#[pyo3(signature = (robot, state, now, target, model = "default"))]
fn ball_plan_return<'py>(
    py: Python<'py>,
    robot: &PyRobot,
    state: &Bound<'py, PyAny>,
    now: f64,
    target: &Bound<'py, PyAny>,
    model: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let s = state_arg(state, "state")?;
    let tg = vector(target, "target", 2)?;
    let planner = ReturnPlanner::new(Chain::clone(&robot.chain), flight(model)?).py()?;
    let plan = py.detach(|| planner.plan(&s, now, [tg[0], tg[1]])).py()?;
    let d = PyDict::new(py);
    d.set_item("status", plan.status.name())?;
    d.set_item("candidates", plan.candidates)?;
    d.set_item("ready", to_numpy(py, &[planner.ready.len()], &planner.ready))?;
    if let Some(h) = plan.hit {
        hit_items(py, &d, &h)?;
    }
    Ok(d)
}

fn hit_items<'py>(py: Python<'py>, d: &Bound<'py, PyDict>, h: &ReturnHit) -> PyResult<()> {
    let (b, qdd) = (&h.branch, &h.branch.leg.qdd_hit);
    d.set_item("pose", pose_to_numpy(py, &h.hit.pose))?;
    d.set_item("twist", to_numpy(py, &[6], &h.hit.twist))?;
    d.set_item("t_hit", h.hit.t)?;
    d.set_item("q_hit", to_numpy(py, &[b.q.len()], &b.q))?;
    d.set_item("qd_hit", to_numpy(py, &[b.qd.len()], &b.qd))?;
    d.set_item("qdd_hit", to_numpy(py, &[qdd.len()], qdd))?;
    d.set_item("ball", to_numpy(py, &[10], &state_vec(&h.ball)))?;
    d.set_item("v_out", to_numpy(py, &[3], h.v_out.as_slice()))?;
    d.set_item("normal", to_numpy(py, &[3], h.racket.normal.as_slice()))?;
    d.set_item("racket_velocity", to_numpy(py, &[3], h.racket.velocity.as_slice()))?;
    d.set_item("spin_out", to_numpy(py, &[3], h.racket.spin_out.as_slice()))?;
    d.set_item("margin", b.margin)?;
    d.set_item("landing", to_numpy(py, &[3], h.landing.as_slice()))?;
    Ok(())
}

/// The correction of a planned hit (`ttkin::ball::rally::correct_hit`, `plan_near`): `robot`'s
/// return of the ball `state` planned for a stroke from rest at `now` (s) landing at `target`,
/// then, with that stroke under way, planned again at `t_c` (s) for the ball `state_new` (e.g.
/// `ball.update`'s state; `after_bounce` when past its bounce) near the first hit. Returns
/// `first` and `corrected` (the plan dicts of `ball_plan_return`).
#[ttkin_py_guard::guarded]
#[pyfunction]
#[pyo3(signature = (robot, state, now, target, state_new, t_c, after_bounce, model = "default"))]
#[allow(clippy::too_many_arguments)]
fn ball_plan_correct<'py>(
    py: Python<'py>,
    robot: &PyRobot,
    state: &Bound<'py, PyAny>,
    now: f64,
    target: &Bound<'py, PyAny>,
    state_new: &Bound<'py, PyAny>,
    t_c: f64,
    after_bounce: bool,
    model: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let s = state_arg(state, "state")?;
    let s_new = state_arg(state_new, "state_new")?;
    s.validate("state").py()?;
    s_new.validate("state_new").py()?;
    let tg = vector(target, "target", 2)?;
    let planner = ReturnPlanner::new(Chain::clone(&robot.chain), flight(model)?).py()?;
    let first = py.detach(|| planner.plan(&s, now, [tg[0], tg[1]])).py()?;
    let d = PyDict::new(py);
    let fd = PyDict::new(py);
    fd.set_item("status", first.status.name())?;
    if let Some(h) = &first.hit {
        hit_items(py, &fd, h)?;
    }
    d.set_item("first", fd)?;
    let Some(h) = first.hit.filter(|_| first.status == ReturnStatus::Ok) else {
        return Err(TtmanipError::new_err(format!(
            "ball_plan_correct: the first plan has no feasible hit (status {}): nothing to correct",
            first.status.name()
        )));
    };
    let c = py
        .detach(|| rally::correct_hit(&planner, &h, now, &s_new, t_c, after_bounce))
        .py()?;
    let cd = PyDict::new(py);
    cd.set_item("status", c.status.name())?;
    if let Some(h) = &c.hit {
        hit_items(py, &cd, h)?;
    }
    d.set_item("corrected", cd)?;
    Ok(d)
}

/// Adds these functions to the module.
pub(super) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(ball_plan_correct, m)?)?;
    m.add_function(wrap_pyfunction!(ball_plan_return, m)?)?;
    Ok(())
}
