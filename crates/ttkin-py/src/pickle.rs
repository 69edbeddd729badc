//! Pickle and copy support (issue 31): every class of the extension reduces to
//! `_unpickle_<class>(state)`, a function of `ttmanip._ttmanip`, where `state` is the serde form of
//! the core value (plain Python lists, dicts and floats through `pythonize`, so f64 values, NaN and
//! ±inf travel bit for bit). `copy.copy` and `copy.deepcopy` go through the same `__reduce__`.
//!
//! Conversion only: each class's module says what its state is (`__reduce__`) and how it is
//! rebuilt (`from_state`, and its `_unpickle_<class>`); this module turns values into Python
//! objects and back. Like any pickle, a state is trusted input: it comes from `__reduce__`.

use pyo3::prelude::*;
use pyo3::types::PyTuple;
use serde::{de::DeserializeOwned, Serialize};

use crate::errors::TtmanipError;

/// The serde form of `value` as plain Python objects.
pub fn to_state<'py, T: Serialize + ?Sized>(py: Python<'py>, value: &T) -> PyResult<Bound<'py, PyAny>> {
    pythonize::pythonize(py, value).map_err(|e| TtmanipError::new_err(format!("pickle: {e}")))
}

/// A value back from its serde form; a state of the wrong shape is a `TtmanipError` naming `kind`
/// (the class).
pub fn from_state<T: DeserializeOwned>(state: &Bound<'_, PyAny>, kind: &str) -> PyResult<T> {
    serde_path_to_error::deserialize(&mut pythonize::Depythonizer::from_object(state))
        .map_err(|e| TtmanipError::new_err(format!("unpickle {kind}: not a state of this version ({e})")))
}

/// `(ttmanip._ttmanip.<unpickler>, (state,))`: the value `__reduce__` returns.
pub fn reduce<'py>(py: Python<'py>, unpickler: &str, state: Bound<'py, PyAny>) -> PyResult<Bound<'py, PyTuple>> {
    let f = py.import("ttmanip._ttmanip")?.getattr(unpickler)?;
    PyTuple::new(py, [f, PyTuple::new(py, [state])?.into_any()])
}

/// A value back from a state of Python objects (a class whose fields are Python objects, such as
/// `IkResult`); a state of the wrong shape is a `TtmanipError` naming `kind` (the class).
pub fn from_python_state<'py, T>(state: &Bound<'py, PyAny>, kind: &str) -> PyResult<T>
where
    T: for<'a> FromPyObject<'a, 'py>,
{
    state.extract::<T>().map_err(|e| {
        let e: PyErr = e.into();
        TtmanipError::new_err(format!("unpickle {kind}: not a state of this version ({e})"))
    })
}

/// The state of a class whose fields are Python objects: those objects, as they are.
pub fn to_python_state<'py, T: pyo3::IntoPyObjectExt<'py>>(py: Python<'py>, value: T) -> PyResult<Bound<'py, PyAny>> {
    value.into_bound_py_any(py)
}

/// Pickle and copy of one class in one line: `__reduce__` returning `(_unpickle_<class>, (state,))`
/// and the module function `_unpickle_<class>` that rebuilds the object, to be registered with
/// `m.add_function(wrap_pyfunction!(_unpickle_<class>, m)?)`.
///
/// `pickled!(serde PyRobot, _unpickle_robot, "Robot", |r| *r.chain, |_, chain: ttkin::Chain| Ok(PyRobot::new(chain)))`:
/// the state is the serde form of the first closure's value ([`to_state`]), read back as the
/// second closure's type ([`from_state`]) and turned into the object by its body (its first
/// argument is `py`). With `python` instead of `serde`, the first closure also gets `py` and gives
/// Python objects ([`to_python_state`]), read back by [`from_python_state`].
macro_rules! pickled {
    (serde $class:ty, $unpickler:ident, $name:literal, |$s:ident| $state:expr, |$py:tt, $st:tt: $ty:ty| $rebuild:expr) => {
        $crate::pickle::pickled!(@impl $class, $unpickler, $name, |$s, _py| &$state, to_state, from_state, |$py, $st: $ty| $rebuild);
    };
    (python $class:ty, $unpickler:ident, $name:literal, |$s:ident, $spy:ident| $state:expr, |$py:tt, $st:tt: $ty:ty| $rebuild:expr) => {
        $crate::pickle::pickled!(@impl $class, $unpickler, $name, |$s, $spy| $state, to_python_state, from_python_state, |$py, $st: $ty| $rebuild);
    };
    (@impl $class:ty, $unpickler:ident, $name:literal, |$s:ident, $spy:ident| $state:expr, $to:ident, $from:ident, |$py:tt, $st:tt: $ty:ty| $rebuild:expr) => {
        #[ttkin_py_guard::guarded]
        #[pyo3::pymethods]
        impl $class {
            /// Pickle and copy (issue 31): `(_unpickle_<class>, (state,))`.
            fn __reduce__<'py>(
                &self,
                py: pyo3::Python<'py>,
            ) -> pyo3::PyResult<pyo3::Bound<'py, pyo3::types::PyTuple>> {
                let ($s, $spy) = (self, py);
                $crate::pickle::reduce(py, stringify!($unpickler), $crate::pickle::$to(py, $state)?)
            }
        }

        #[doc = concat!("Rebuilds a `", $name, "` from its pickle state (`", $name, ".__reduce__`; not meant to be called directly).")]
        #[ttkin_py_guard::guarded]
        #[pyo3::pyfunction]
        fn $unpickler(py: pyo3::Python<'_>, state: &pyo3::Bound<'_, pyo3::PyAny>) -> pyo3::PyResult<$class> {
            let $st: $ty = $crate::pickle::$from(state, $name)?;
            let $py = py;
            $rebuild
        }
    };
}
pub(crate) use pickled;
