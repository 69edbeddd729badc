//! Rust errors → Python exceptions, in one place, for both core crates (`ttkin` and `ttcan`).
//! Every exception derives from `ttmanip.TtmanipError`, itself a `ValueError`.
//!
//! One kind of mistake, one class, whichever crate finds it:
//!
//! | kind | `ttkin::Error` | `ttcan::Error` | Python |
//! | --- | --- | --- | --- |
//! | wrong length or shape | `Shape` | – | `ShapeError` |
//! | NaN or infinity | `NonFinite` | `NonFinite` | `NonFiniteError` |
//! | non-physical or inconsistent model / configuration | `Model` | `InvalidParameter`, `Rates`, `Stepper`, `Model` | `ModelError` |
//! | robot file or URDF unreadable | `File`, `Urdf` | – | `RobotFileError` |
//! | target proven out of reach | `Unreachable` | – | `UnreachableError` |
//! | solver did not converge (maybe reachable) | (an [`IkStatus`]) | – | `NotConvergedError` |
//! | singular configuration | `Singular` | – | `SingularError` |
//! | any other bad argument | `InvalidArgument` | `Config` | `TtmanipError` |
//! | finite inputs, non-finite result (overflow) | – | – | `NumericalError` (`convert`) |
//! | a Rust panic (a bug) caught at the boundary | – | – | `InternalError` (`guard`) |
//!
//! An exception raised by a user's Python callback that Rust calls (an IK callable) is not
//! turned into text: [`Callback`] keeps it and re-raises it with its own type and traceback.

use std::cell::RefCell;

use pyo3::create_exception;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use ttkin::ik::IkStatus;

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
    NotConvergedError,
    TtmanipError,
    "A solver stopped before converging; the target may still be reachable."
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

/// Converts a `ttcan` error to the matching Python exception (same classes as [`to_py`]).
pub fn ttcan_to_py(e: ttcan::Error) -> PyErr {
    use ttcan::Error as E;
    let msg = e.to_string();
    match e {
        E::NonFinite { .. } => NonFiniteError::new_err(msg),
        E::InvalidParameter { .. } | E::Rates(_) | E::Stepper(_) | E::Model(_) => ModelError::new_err(msg),
        _ => TtmanipError::new_err(msg),
    }
}

/// The exception of an IK outcome that is not solved: `UnreachableError` when proven out of reach,
/// `NotConvergedError` otherwise.
pub fn ik_failure(status: IkStatus, msg: String) -> PyErr {
    match status {
        IkStatus::Unreachable => UnreachableError::new_err(msg),
        _ => NotConvergedError::new_err(msg),
    }
}

/// Keeps the first exception a Python callback raised while Rust called it, so that it reaches
/// the caller with its own type and traceback instead of as text.
#[derive(Default)]
pub struct Callback {
    raised: RefCell<Option<PyErr>>,
}

impl Callback {
    /// A ttkin error standing for a callback's exception: ttmanip's own exceptions keep their
    /// variant (so Rust can add where it happened); any other exception is stored.
    pub fn error(&self, py: Python<'_>, e: PyErr) -> ttkin::Error {
        let msg = e.value(py).to_string();
        let core = if e.is_instance_of::<UnreachableError>(py) {
            ttkin::Error::Unreachable(msg)
        } else if e.is_instance_of::<SingularError>(py) {
            ttkin::Error::Singular(msg)
        } else {
            ttkin::Error::invalid("ik", format!("{}: {msg}", e.get_type(py)))
        };
        self.raised.borrow_mut().get_or_insert(e);
        core
    }

    /// The result for Python: a ttmanip exception raised by the callback comes back as the
    /// mapped core error (with the context Rust added) chained to the original (`__cause__`);
    /// any other exception is re-raised as it was raised.
    pub fn finish<T>(self, py: Python<'_>, r: ttkin::Result<T>) -> PyResult<T> {
        let raised = self.raised.into_inner();
        match (r, raised) {
            (Ok(v), _) => Ok(v),
            (Err(e), Some(original)) if original.is_instance_of::<TtmanipError>(py) => {
                let mapped = to_py(e);
                mapped.set_cause(py, Some(original));
                Err(mapped)
            }
            (Err(_), Some(original)) => Err(original),
            (Err(e), None) => Err(to_py(e)),
        }
    }
}

/// Warns that the Python name `old` is deprecated in favour of `new` (a `DeprecationWarning`
/// pointing at the caller's line); renamed names keep working for one release.
pub fn deprecated(py: Python<'_>, old: &str, new: &str) -> PyResult<()> {
    let msg = std::ffi::CString::new(format!("{old} is deprecated; use {new}")).expect("no NUL in names");
    PyErr::warn(py, &py.get_type::<pyo3::exceptions::PyDeprecationWarning>(), &msg, 1)
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

impl<T> PyResultExt<T> for ttcan::Result<T> {
    fn py(self) -> PyResult<T> {
        self.map_err(ttcan_to_py)
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
    m.add("NotConvergedError", py.get_type::<NotConvergedError>())?;
    m.add("NumericalError", py.get_type::<NumericalError>())?;
    m.add("InternalError", py.get_type::<InternalError>())?;
    Ok(())
}
