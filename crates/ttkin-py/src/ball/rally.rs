//! Bindings of `ttkin::ball::rally`: the simulated rally, its statistics and settings, one ball as
//! the camera sees it and scored against an executed stroke.

use super::*;
use ttkin::ball::rally::{self, Outcomes, Rally, RallyConfig};

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

/// Adds these functions to the module.
pub(super) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("MAX_RALLY_BALLS", rally::MAX_BALLS)?;
    m.add_function(wrap_pyfunction!(ball_camera, m)?)?;
    m.add_function(wrap_pyfunction!(ball_rally_config, m)?)?;
    m.add_function(wrap_pyfunction!(ball_rally_observations, m)?)?;
    m.add_function(wrap_pyfunction!(ball_rally_score, m)?)?;
    m.add_function(wrap_pyfunction!(ball_rally, m)?)?;
    m.add_function(wrap_pyfunction!(ball_rally_stats, m)?)?;
    Ok(())
}
