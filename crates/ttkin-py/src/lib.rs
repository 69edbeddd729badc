//! PyO3 bindings of ttkin (and later ttcan): conversion only. numpy in, numpy out, Rust errors
//! to Python exceptions (`errors`), the GIL released around batch work. The Python package
//! `ttmanip` imports this module as `ttmanip._ttmanip`.

use pyo3::prelude::*;

mod cartesian;
mod convert;
mod drives;
mod dynamics;
mod errors;
mod hit;
mod ik;
mod mobile;
mod motor;
mod online;
mod profile;
mod robot;
mod traj;
// issue 14: argument validation and the boundary panic guard
mod args;
mod guard;
// issue 29: long calls that Ctrl-C stops
mod interrupt;
// issue 13
mod ball;
// issue 31: pickle and copy
mod pickle;

/// The native extension module `ttmanip._ttmanip`.
#[pymodule]
fn _ttmanip(m: &Bound<'_, PyModule>) -> PyResult<()> {
    errors::register(m)?;
    robot::register(m)?;
    mobile::register(m)?;
    profile::register(m)?;
    motor::register(m)?;
    ik::register(m)?;
    traj::register(m)?;
    cartesian::register(m)?;
    guard::register(m)?;
    hit::register(m)?;
    drives::register(m)?;
    ball::register(m)?;
    online::register(m)?;
    m.add_function(wrap_pyfunction!(convert::real_array, m)?)?;
    Ok(())
}
