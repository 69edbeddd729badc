//! Bindings of the table (`ttkin::ball::model::Table`) and of where the rally places the robot
//! (`ttkin::ball::reach::Placement`).

use super::*;

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

/// Adds these functions to the module.
pub(super) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(ball_table, m)?)?;
    m.add_function(wrap_pyfunction!(ball_table_check, m)?)?;
    m.add_function(wrap_pyfunction!(ball_on_opponent_half, m)?)?;
    m.add_function(wrap_pyfunction!(ball_table_outline, m)?)?;
    m.add_function(wrap_pyfunction!(ball_placement, m)?)?;
    m.add_function(wrap_pyfunction!(ball_placement_for, m)?)?;
    Ok(())
}
