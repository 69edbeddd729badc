//! Bindings of `ttkin::ball`: conversion only. A ball state is a (10,) array
//! [t, px, py, pz, vx, vy, vz, wx, wy, wz] (s, m, m/s, rad/s, world frame of `ttkin::ball`),
//! `ttkin::ball::BallState::to_array`.

use numpy::PyArrayDyn;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use ttkin::ball::estimate::{estimate, EstimateOptions};
use ttkin::ball::fit::{self, FitOptions, Recording};
use ttkin::ball::flight::{BallState, Flight, Plane};
use ttkin::ball::hitplan::{ReturnHit, ReturnPlanner, ReturnStatus};
use ttkin::ball::model::{BallModel, Table};
use ttkin::ball::predict::{crossing_until, predict_batch_into, predict_until, CrossingOutcome, CROSSING_HORIZON};
use ttkin::ball::rally::{self, Outcomes, Rally, RallyConfig};
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

/// Plays balls `start`..`start + n` of a simulated rally (`ttkin::ball::rally::Rally::play_range`)
/// in parallel; the settings not given are `RallyConfig::default()`'s.
#[ttkin_py_guard::guarded]
#[pyfunction]
#[pyo3(signature = (n, seed = RallyConfig::default().seed as i128, start = rally::FIRST_BALL as i128, target = (RallyConfig::default().target[0], RallyConfig::default().target[1]),
    max_spin_rps = RallyConfig::default().max_spin_rps, paths = RallyConfig::default().paths as i128,
    world = RallyConfig::default().world.is_some(), incoming = None, drives = false))]
#[allow(clippy::too_many_arguments)]
fn ball_rally<'py>(
    py: Python<'py>,
    n: i128,
    seed: i128,
    start: i128,
    target: (f64, f64),
    max_spin_rps: f64,
    paths: i128,
    world: bool,
    incoming: Option<&Bound<'py, PyAny>>,
    drives: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let n: usize = args::sample_count(n, "n")?;
    let start: u64 = args::unsigned(start, "start")?;
    let config = RallyConfig {
        target: [target.0, target.1],
        max_spin_rps,
        seed: args::unsigned(seed, "seed")?,
        paths: args::unsigned(paths, "paths")?,
        world: world.then(rally::WorldSpread::measured),
        ..RallyConfig::default()
    };
    let rally = Rally::new(config).py()?;
    let given = incoming
        .map(|a| rows_array(a, "incoming", "N", &[10]).map(|a| BallState::from_rows(a.data())))
        .transpose()?;
    let executor = drives
        .then(|| ttcan::coupled::execute::DriveExecutor::with_defaults(rally.planner.chain()))
        .transpose()
        .py()?;
    // Ctrl-C stops the rally within one ball per thread (issue 29).
    let out = crate::interrupt::detach_interruptible(py, |cancel| {
        let ex = executor.as_ref().map(|e| e as &dyn rally::Executor);
        rally.play_range(start, n, given.as_deref(), ex, &|| crate::interrupt::cancelled(cancel))
    })?
    .py()?;
    let o = Outcomes::new(&out);
    let d = PyDict::new(py);
    d.set_item("incoming", to_numpy(py, &[o.n, 10], &o.incoming))?;
    d.set_item("in_reach", o.in_reach)?;
    d.set_item("reach", o.reach)?;
    d.set_item("reach_names", ttkin::ball::reach::Reachability::NAMES.to_vec())?;
    d.set_item("returned", o.returned)?;
    d.set_item("contact", o.contact)?;
    d.set_item("status", o.status)?;
    d.set_item("racket_error", to_numpy(py, &[o.n], &o.racket_error))?;
    d.set_item("plan_time_us", to_numpy(py, &[o.n], &o.plan_time_us))?;
    d.set_item("plan_wall_time_us", to_numpy(py, &[o.n], &o.plan_wall_time_us))?;
    d.set_item("correction_time_us", to_numpy(py, &[o.n], &o.correction_time_us))?;
    d.set_item("landing_error", to_numpy(py, &[o.n], &o.landing_error))?;
    d.set_item("velocity_error", to_numpy(py, &[o.n], &o.velocity_error))?;
    d.set_item("landing", to_numpy(py, &[o.n, 3], &o.landing))?;
    d.set_item("paths", serde_to_python(py, &o.paths)?)?;
    d.set_item("in_reach_definition", rally.region.definition())?;
    Ok(d)
}

/// The statistics of a rally's outcome columns (`ttkin::ball::rally::RallyStats::new`): the
/// columns of `ball_rally`, one value per ball (concatenated over its chunks); returns the counts,
/// the return rate, `reach` as [verdict, count] pairs in the region's order, `statuses` and the
/// medians (None when no ball has a finite value).
#[ttkin_py_guard::guarded]
#[pyfunction]
#[allow(clippy::too_many_arguments)]
fn ball_rally_stats<'py>(
    py: Python<'py>,
    in_reach: Vec<bool>,
    returned: Vec<bool>,
    reach: Vec<String>,
    status: Vec<String>,
    racket_error: &Bound<'py, PyAny>,
    plan_time_us: &Bound<'py, PyAny>,
    plan_wall_time_us: &Bound<'py, PyAny>,
    correction_time_us: &Bound<'py, PyAny>,
    landing_error: &Bound<'py, PyAny>,
    velocity_error: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyAny>> {
    let column = |a: &Bound<'py, PyAny>, what: &str| rows_array(a, what, "N", &[]).map(|a| a.data().to_vec());
    let (reach, status) = (str_refs(&reach), str_refs(&status));
    let (racket_error, landing_error) = (
        column(racket_error, "racket_error")?,
        column(landing_error, "landing_error")?,
    );
    let (plan_time_us, plan_wall_time_us) = (
        column(plan_time_us, "plan_time_us")?,
        column(plan_wall_time_us, "plan_wall_time_us")?,
    );
    let correction_time_us = column(correction_time_us, "correction_time_us")?;
    let velocity_error = column(velocity_error, "velocity_error")?;
    let stats = rally::RallyStats::new(&rally::OutcomeColumns {
        in_reach: &in_reach,
        returned: &returned,
        reach: &reach,
        status: &status,
        racket_error: &racket_error,
        plan_time_us: &plan_time_us,
        plan_wall_time_us: &plan_wall_time_us,
        correction_time_us: &correction_time_us,
        landing_error: &landing_error,
        velocity_error: &velocity_error,
    })
    .py()?;
    serde_to_python(py, &stats)
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

/// The rally's camera of `ttkin::ball::rally::Camera::default()`: rate_hz (frame rate, Hz),
/// latency (s), noise (m, σ per axis), outlier_rate, outlier_size (m), start and window (s).
#[ttkin_py_guard::guarded]
#[pyfunction]
fn ball_camera(py: Python<'_>) -> PyResult<Bound<'_, PyAny>> {
    serde_to_python(py, &rally::Camera::default())
}

/// The rally's settings of `ttkin::ball::rally::RallyConfig::default()`: camera (as
/// `ball_camera`), target (x, y, m, world), max_spin_rps, corkscrew, seed, paths, replan_period,
/// max_window, correction_delay and second_correction (s), world (None: the world is the model).
#[ttkin_py_guard::guarded]
#[pyfunction]
fn ball_rally_config(py: Python<'_>) -> PyResult<Bound<'_, PyAny>> {
    serde_to_python(py, &RallyConfig::default())
}

/// The ITTF table of `ttkin::ball::model::Table::default()` (m): length, width, height (surface
/// above the floor), thickness, net_height, net_overhang.
#[ttkin_py_guard::guarded]
#[pyfunction]
fn ball_table(py: Python<'_>) -> PyResult<Bound<'_, PyAny>> {
    serde_to_python(py, &Table::default())
}

/// The table of the serde form `table` (a dict of `ttkin::ball::model::Table`'s fields, m; those
/// left out are the default table's), checked (`Table::validate`).
fn table_arg(table: &Bound<'_, PyAny>) -> PyResult<Table> {
    let t: Table = serde_path_to_error::deserialize(&mut pythonize::Depythonizer::from_object(table))
        .map_err(|e| TtmanipError::new_err(format!("table: {e}")))?;
    t.validate().py()?;
    Ok(t)
}

/// Checks the table `table` (a dict of `Table`'s fields, m) as the core does (`Table::validate`).
#[ttkin_py_guard::guarded]
#[pyfunction]
fn ball_table_check(table: &Bound<'_, PyAny>) -> PyResult<()> {
    table_arg(table).map(|_| ())
}

/// Whether (`x`, `y`) (m, world) lies on the opponent's half of `table`'s surface
/// (`ttkin::ball::model::Table::on_opponent_half`).
#[ttkin_py_guard::guarded]
#[pyfunction]
fn ball_on_opponent_half(table: &Bound<'_, PyAny>, x: f64, y: f64) -> PyResult<bool> {
    let (x, y) = (args::finite("x", x)?, args::finite("y", y)?);
    Ok(table_arg(table)?.on_opponent_half(x, y))
}

/// The outline of `table` to draw (`ttkin::ball::model::Table::outline`): "surface" and "net"
/// (closed loops, 5 points) and "centre_line" (2 points), m, world frame.
#[ttkin_py_guard::guarded]
#[pyfunction]
fn ball_table_outline<'py>(py: Python<'py>, table: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
    serde_to_python(py, &table_arg(table)?.outline())
}

/// (4, 4) base frame of the rally's robot in the world (table) frame, m
/// (`ttkin::ball::reach::Placement::default()`).
#[ttkin_py_guard::guarded]
#[pyfunction]
fn ball_placement(py: Python<'_>) -> Bound<'_, PyAny> {
    pose_to_numpy(py, &Placement::default().world_from_base()).into_any()
}

/// (4, 4) base frame of `robot` in the world (table) frame where the rally places it, m, or `None`
/// for a robot the ball planner does not play (`ttkin::ball::reach::Placement::for_chain`).
#[ttkin_py_guard::guarded]
#[pyfunction]
fn ball_placement_for<'py>(py: Python<'py>, robot: &PyRobot) -> Option<Bound<'py, PyAny>> {
    Placement::for_chain(&robot.chain).map(|p| pose_to_numpy(py, &p.world_from_base()).into_any())
}

/// The served rally of `seed` (`world`: the measured world spread), the other settings the core's
/// defaults.
fn rally_of(seed: i128, world: bool) -> PyResult<Rally> {
    Rally::new(RallyConfig {
        seed: args::unsigned(seed, "seed")?,
        world: world.then(rally::WorldSpread::measured),
        ..RallyConfig::default()
    })
    .py()
}

/// Ball `index` of the rally of `seed` (`world`: the measured world spread) as its camera sees it
/// (`ttkin::ball::rally::Rally::observe`): the incoming state (10,), the exposure times and the
/// time stamps (K,) (s from the opponent's hit), the observed positions (K, 3) (m, world), and the
/// camera's rate_hz (frame rate, Hz), latency (s) and window (s).
#[ttkin_py_guard::guarded]
#[pyfunction]
#[pyo3(signature = (index, seed = RallyConfig::default().seed as i128, world = RallyConfig::default().world.is_some()))]
fn ball_rally_observations(py: Python<'_>, index: i128, seed: i128, world: bool) -> PyResult<Bound<'_, PyDict>> {
    let index: u64 = args::unsigned(index, "index")?;
    let rally = rally_of(seed, world)?;
    let cfg = &rally.config;
    let o = py.detach(|| rally.observe(index));
    let d = PyDict::new(py);
    d.set_item("incoming", to_numpy(py, &[10], &state_vec(&o.incoming)))?;
    d.set_item("exposures", to_numpy(py, &[o.exposures.len()], &o.exposures))?;
    d.set_item("times", to_numpy(py, &[o.times.len()], &o.times))?;
    d.set_item(
        "positions",
        to_numpy(py, &[o.positions.len(), 3], o.positions.as_flattened()),
    )?;
    d.set_item("rate_hz", cfg.camera.rate_hz)?;
    d.set_item("latency", cfg.camera.latency)?;
    d.set_item("window", cfg.camera.window)?;
    d.set_item("target", (cfg.target[0], cfg.target[1]))?;
    Ok(d)
}

/// Scores ball `index` of the rally of `seed` as the rally does (`ttkin::ball::rally::Rally::score_executed`)
/// against the rally robot's racket following the joint states `q`, `qd` (K, dof) at times `t` (K,)
/// (s on the ball's clock: 0 at the opponent's hit), the hit expected at `t_hit` (s, same clock).
#[ttkin_py_guard::guarded]
#[pyfunction]
#[pyo3(signature = (index, t_hit, t, q, qd, seed = RallyConfig::default().seed as i128, world = RallyConfig::default().world.is_some()))]
#[allow(clippy::too_many_arguments)]
fn ball_rally_score<'py>(
    py: Python<'py>,
    index: i128,
    t_hit: f64,
    t: &Bound<'py, PyAny>,
    q: &Bound<'py, PyAny>,
    qd: &Bound<'py, PyAny>,
    seed: i128,
    world: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let index: u64 = args::unsigned(index, "index")?;
    let t_hit = args::finite("t_hit", t_hit)?;
    let rally = rally_of(seed, world)?;
    let dof = rally.planner.chain().dof();
    let times = rows_array(t, "t", "K", &[])?.data().to_vec();
    let executed = rally::Executed {
        dof,
        q: rows_array(q, "q", "K", &[dof])?.data().to_vec(),
        qd: rows_array(qd, "qd", "K", &[dof])?.data().to_vec(),
        t: times,
    };
    let sc = py.detach(|| rally.score_executed(index, t_hit, &executed)).py()?;
    let d = PyDict::new(py);
    d.set_item("status", &sc.status)?;
    d.set_item("contact", sc.contact)?;
    d.set_item("returned", sc.returned)?;
    d.set_item("racket_error", sc.racket_error)?;
    d.set_item("landing", to_numpy(py, &[3], &sc.landing))?;
    d.set_item("landing_error", sc.landing_error)?;
    d.set_item("after", sc.after.map(|a| to_numpy(py, &[10], &state_vec(&a))))?;
    Ok(d)
}

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

/// Adds the ball functions to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(ball_fit, m)?)?;
    m.add_function(wrap_pyfunction!(ball_racket_impact, m)?)?;
    m.add_function(wrap_pyfunction!(ball_update, m)?)?;
    m.add_function(wrap_pyfunction!(ball_plan_correct, m)?)?;
    m.add("MAX_RALLY_BALLS", rally::MAX_BALLS)?;
    // the rally's prior spread of the bounce's velocity kick (m/s, world x, y, z)
    m.add("BOUNCE_SPREAD", ttkin::ball::update::BOUNCE_SPREAD.to_vec())?;
    m.add_function(wrap_pyfunction!(ball_table, m)?)?;
    m.add_function(wrap_pyfunction!(ball_table_check, m)?)?;
    m.add_function(wrap_pyfunction!(ball_on_opponent_half, m)?)?;
    m.add_function(wrap_pyfunction!(ball_table_outline, m)?)?;
    m.add_function(wrap_pyfunction!(ball_camera, m)?)?;
    m.add_function(wrap_pyfunction!(ball_rally_config, m)?)?;
    m.add_function(wrap_pyfunction!(ball_placement, m)?)?;
    m.add_function(wrap_pyfunction!(ball_placement_for, m)?)?;
    m.add_function(wrap_pyfunction!(ball_rally_observations, m)?)?;
    m.add_function(wrap_pyfunction!(ball_rally_score, m)?)?;
    m.add_function(wrap_pyfunction!(ball_estimate, m)?)?;
    m.add_function(wrap_pyfunction!(ball_predict, m)?)?;
    m.add_function(wrap_pyfunction!(ball_predict_batch, m)?)?;
    m.add_function(wrap_pyfunction!(ball_crossing, m)?)?;
    m.add_function(wrap_pyfunction!(ball_plan_return, m)?)?;
    m.add_function(wrap_pyfunction!(ball_rally, m)?)?;
    m.add_function(wrap_pyfunction!(ball_rally_stats, m)?)?;
    Ok(())
}
