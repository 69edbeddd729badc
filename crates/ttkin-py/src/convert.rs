//! numpy ↔ Rust conversion helpers shared by every binding module.
//!
//! Inputs: any array-like of numbers (lists, integer arrays, non-contiguous views) is accepted and
//! converted once to a C-contiguous float64 array; float64 C-contiguous numpy arrays pass without a
//! copy. Outputs are fresh numpy arrays owned by Python.

use nalgebra::{IsometryMatrix3, Matrix4};
use numpy::ndarray::ArrayView;
use numpy::{IxDyn, PyArray, PyArrayDyn, PyArrayMethods, PyReadonlyArrayDyn, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::PyDict;

use crate::errors::{PyResultExt, ShapeError};

/// A C-contiguous float64 view of a Python array-like.
pub struct F64Array<'py> {
    array: PyReadonlyArrayDyn<'py, f64>,
}

impl<'py> F64Array<'py> {
    /// The array's shape.
    pub fn shape(&self) -> &[usize] {
        self.array.shape()
    }

    /// The values in C order.
    pub fn data(&self) -> &[f64] {
        self.array.as_slice().expect("F64Array is C-contiguous by construction")
    }

    /// The shape as Python would print it: `(8,)`, `(10, 8)`.
    pub fn shape_str(&self) -> String {
        shape_str(self.shape())
    }
}

/// Formats a shape like Python: `(8,)`, `(10, 8)`.
pub fn shape_str(shape: &[usize]) -> String {
    match shape {
        [n] => format!("({n},)"),
        s => format!("({})", s.iter().map(|v| v.to_string()).collect::<Vec<_>>().join(", ")),
    }
}

struct NumpyFns {
    asarray: Py<PyAny>,
    ascontiguousarray: Py<PyAny>,
}

/// Converts any array-like of real numbers (float or integer dtype) to a C-contiguous float64
/// array; complex, boolean, string and object data are refused rather than silently cast.
fn as_contiguous_f64<'py>(obj: &Bound<'py, PyAny>, what: &str) -> PyResult<Bound<'py, PyAny>> {
    static NUMPY: PyOnceLock<NumpyFns> = PyOnceLock::new();
    let py = obj.py();
    let np = NUMPY.get_or_try_init(py, || -> PyResult<NumpyFns> {
        let m = py.import("numpy")?;
        Ok(NumpyFns {
            asarray: m.getattr("asarray")?.unbind(),
            ascontiguousarray: m.getattr("ascontiguousarray")?.unbind(),
        })
    })?;
    let ty = || {
        obj.get_type()
            .name()
            .map(|n| n.to_string())
            .unwrap_or_else(|_| "?".into())
    };
    let arr =
        np.asarray.bind(py).call1((obj,)).map_err(|e| {
            ShapeError::new_err(format!("{what}: expected an array of real numbers, got {} ({e})", ty()))
        })?;
    let kind: String = arr.getattr("dtype")?.getattr("kind")?.extract()?;
    if !matches!(kind.as_str(), "f" | "i" | "u") {
        let dtype = arr.getattr("dtype")?.str()?.to_string();
        return Err(ShapeError::new_err(format!(
            "{what}: expected an array of real numbers (float or integer), got {} of dtype {dtype}",
            ty()
        )));
    }
    let kwargs = PyDict::new(py);
    kwargs.set_item("dtype", "float64")?;
    np.ascontiguousarray.bind(py).call((arr,), Some(&kwargs))
}

/// Reads `obj` as a float64 array named `what` in error messages.
pub fn f64_array<'py>(obj: &Bound<'py, PyAny>, what: &str) -> PyResult<F64Array<'py>> {
    if let Ok(a) = obj.cast::<PyArrayDyn<f64>>() {
        if a.is_c_contiguous() {
            return Ok(F64Array { array: a.readonly() });
        }
    }
    let converted = as_contiguous_f64(obj, what)?;
    let a = converted
        .cast::<PyArrayDyn<f64>>()
        .map_err(|_| ShapeError::new_err(format!("{what}: could not convert to a float64 array")))?;
    Ok(F64Array { array: a.readonly() })
}

/// Reads a vector of exactly `n` finite values.
pub fn vector(obj: &Bound<'_, PyAny>, what: &str, n: usize) -> PyResult<Vec<f64>> {
    let a = f64_array(obj, what)?;
    if a.shape() != [n] {
        return Err(ShapeError::new_err(format!(
            "{what}: expected shape ({n},), got {}",
            a.shape_str()
        )));
    }
    ttkin::error::check_finite(what, a.data()).py()?;
    Ok(a.data().to_vec())
}

/// Reads a 4×4 homogeneous matrix and checks that it is a rigid transform.
pub fn transform(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<IsometryMatrix3<f64>> {
    let a = f64_array(obj, what)?;
    if a.shape() != [4, 4] {
        return Err(ShapeError::new_err(format!(
            "{what}: expected shape (4, 4), got {}",
            a.shape_str()
        )));
    }
    let m = Matrix4::from_row_slice(a.data());
    ttkin::transform::isometry_from_matrix(what, &m).py()
}

/// A new numpy array of the given shape holding `data` (C order).
pub fn to_numpy<'py>(py: Python<'py>, shape: &[usize], data: &[f64]) -> Bound<'py, PyArrayDyn<f64>> {
    let view = ArrayView::from_shape(IxDyn(shape), data).expect("shape matches data length");
    PyArray::from_array(py, &view)
}

/// A 4×4 numpy array of a transform.
pub fn pose_to_numpy<'py>(py: Python<'py>, t: &IsometryMatrix3<f64>) -> Bound<'py, PyArrayDyn<f64>> {
    let mut buf = [0.0; 16];
    ttkin::transform::write_row_major(t, &mut buf);
    to_numpy(py, &[4, 4], &buf)
}

/// A zero-filled numpy array to be filled by Rust (possibly without the GIL).
pub fn zeros<'py>(py: Python<'py>, shape: &[usize]) -> Bound<'py, PyArrayDyn<f64>> {
    PyArrayDyn::zeros(py, IxDyn(shape), false)
}

/// A new float64 array of `shape` filled by `fill` with the GIL released (batch work).
pub fn filled_without_gil<'py, F>(py: Python<'py>, shape: &[usize], fill: F) -> PyResult<Bound<'py, PyArrayDyn<f64>>>
where
    F: FnOnce(&mut [f64]) -> ttkin::Result<()> + Send,
{
    let out = zeros(py, shape);
    {
        let mut w = out.readwrite();
        let o = w.as_slice_mut().expect("a fresh array is contiguous");
        py.detach(|| fill(o)).py()?;
    }
    Ok(out)
}
