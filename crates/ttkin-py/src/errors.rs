//! Rust errors → Python exceptions, in one place. Every exception derives from
//! `ttmanip.TtmanipError`, itself a `ValueError`.

use pyo3::create_exception;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

create_exception!(
    ttmanip,
    TtmanipError,
    PyValueError,
    "Base of every ttmanip error (a ValueError)."
);
create_exception!(
    ttmanip,
    ShapeError,
    TtmanipError,
    "An array has the wrong length, shape or dtype."
);
create_exception!(
    ttmanip,
    NonFiniteError,
    TtmanipError,
    "An input holds NaN or an infinity."
);
create_exception!(
    ttmanip,
    ModelError,
    TtmanipError,
    "A robot model is inconsistent or non-physical."
);
create_exception!(
    ttmanip,
    RobotFileError,
    TtmanipError,
    "A robot file or URDF cannot be read."
);
create_exception!(
    ttmanip,
    UnreachableError,
    TtmanipError,
    "A target is outside the robot's reach."
);
create_exception!(
    ttmanip,
    SingularError,
    TtmanipError,
    "A configuration is singular for the request."
);

create_exception!(
    ttmanip,
    NumericalError,
    TtmanipError,
    "A computation on finite inputs gave a non-finite result (overflow)."
);
create_exception!(
    ttmanip,
    InternalError,
    TtmanipError,
    "A bug inside ttmanip (a Rust panic caught at the boundary); please report it."
);

/// Converts a `ttkin` error to the matching Python exception.
pub fn to_py(e: ttkin::Error) -> PyErr {
    use ttkin::Error as E;
    let msg = e.to_string();
    match e {
        E::Shape { .. } => ShapeError::new_err(msg),
        E::NonFinite { .. } => NonFiniteError::new_err(msg),
        E::Model(_) => ModelError::new_err(msg),
        E::File { .. } | E::Urdf(_) => RobotFileError::new_err(msg),
        E::Unreachable(_) => UnreachableError::new_err(msg),
        E::Singular(_) => SingularError::new_err(msg),
        _ => TtmanipError::new_err(msg),
    }
}

/// `.py()` on a `ttkin::Result` gives a `PyResult`.
pub trait PyResultExt<T> {
    /// Maps the error to its Python exception.
    fn py(self) -> PyResult<T>;
}

impl<T> PyResultExt<T> for ttkin::Result<T> {
    fn py(self) -> PyResult<T> {
        self.map_err(to_py)
    }
}

/// Adds the exception classes to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("TtmanipError", py.get_type::<TtmanipError>())?;
    m.add("ShapeError", py.get_type::<ShapeError>())?;
    m.add("NonFiniteError", py.get_type::<NonFiniteError>())?;
    m.add("ModelError", py.get_type::<ModelError>())?;
    m.add("RobotFileError", py.get_type::<RobotFileError>())?;
    m.add("UnreachableError", py.get_type::<UnreachableError>())?;
    m.add("SingularError", py.get_type::<SingularError>())?;
    m.add("NumericalError", py.get_type::<NumericalError>())?;
    m.add("InternalError", py.get_type::<InternalError>())?;
    Ok(())
}
