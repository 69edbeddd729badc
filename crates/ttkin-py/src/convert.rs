//! numpy ↔ Rust conversion helpers shared by every binding module.
//!
//! Inputs: any array-like of real numbers is accepted: lists, integer and float arrays of any
//! width (float16/32/64, int, uint), any byte order, any strides (views, Fortran order, negative
//! steps), unaligned buffers (`np.frombuffer` at an odd offset, structured records, memory maps)
//! and read-only arrays. What is not an aligned, native-byte-order, C-contiguous float64 array is
//! copied once into one; the values (and so every result) are those of
//! `np.ascontiguousarray(x, dtype=np.float64)`. An aligned C-contiguous float64 array passes
//! without a copy. Complex, boolean, string and object data are refused, never cast.
//!
//! Rotations: the precision of the dtype the caller handed over is kept ([`F64Array::precision`])
//! and decides how orthonormal a rotation block must be ([`rigid_tolerance`]).
//!
//! Outputs are fresh numpy arrays owned by Python; [`finite_to_numpy`] and
//! [`filled_without_gil`] refuse a non-finite result with `NumericalError` (overflow of finite
//! inputs), so a NaN or an infinity never leaves silently.

use nalgebra::{IsometryMatrix3, Matrix4};
use numpy::ndarray::ArrayView;
use numpy::{IxDyn, PyArray, PyArrayDyn, PyArrayMethods, PyReadonlyArrayDyn, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::PyDict;

use crate::errors::{InternalError, NumericalError, PyResultExt, ShapeError};

/// Any Python object a binding receives, before conversion.
pub type Any<'py> = Bound<'py, PyAny>;

/// A numpy float64 array of any shape handed back to Python.
pub type Array<'py> = Bound<'py, PyArrayDyn<f64>>;

/// Arrays of at most this many values are copied when read instead of borrowed: the copy (one
/// small allocation, made with the GIL held) costs far less than rust-numpy's dynamic borrow
/// tracking, about 570 instructions an array (a third of a single `rnea` call's binding cost).
const COPY_AT_MOST: usize = 256;

/// The values of an [`F64Array`].
enum Values<'py> {
    /// A borrowed view of a large array (no copy).
    View(PyReadonlyArrayDyn<'py, f64>),
    /// A copy of a small array.
    Copy(Vec<f64>),
}

/// An aligned, C-contiguous, native float64 view (or, when small, copy) of a Python array-like.
pub struct F64Array<'py> {
    /// Aligned and C-contiguous: checked where it is made (`f64_array`).
    array: Bound<'py, PyArrayDyn<f64>>,
    /// Its values in C order.
    values: Values<'py>,
    /// Machine epsilon of the dtype the caller handed over (float64's for integers).
    precision: f64,
}

impl<'py> F64Array<'py> {
    /// Reads an aligned C-contiguous `array`: copied when small, else borrowed (`None` when it
    /// cannot be, e.g. while Rust holds it mutably).
    fn read(array: &Bound<'py, PyArrayDyn<f64>>, precision: f64) -> Option<Self> {
        let values = if array.len() <= COPY_AT_MOST {
            Values::Copy(array.to_vec().ok()?)
        } else {
            Values::View(array.try_readonly().ok()?)
        };
        Some(F64Array {
            array: array.clone(),
            values,
            precision,
        })
    }

    /// The array's shape.
    pub fn shape(&self) -> &[usize] {
        self.array.shape()
    }

    /// The values in C order.
    pub fn data(&self) -> &[f64] {
        match &self.values {
            Values::Copy(v) => v,
            // `f64_array` only builds aligned C-contiguous arrays, for which `as_slice` cannot
            // fail; should it ever, the empty slice makes the caller's length check fail (a
            // ShapeError), never a panic.
            Values::View(a) => a.as_slice().unwrap_or(&[]),
        }
    }

    /// The shape as Python would print it: `(8,)`, `(10, 8)`.
    pub fn shape_str(&self) -> String {
        shape_str(self.shape())
    }

    /// Machine epsilon of the input's dtype: 2.2e-16 for float64 and integers, 1.2e-7 for
    /// float32, 9.8e-4 for float16.
    pub fn precision(&self) -> f64 {
        self.precision
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
    array: Py<PyAny>,
}

fn numpy_fns(py: Python<'_>) -> PyResult<&NumpyFns> {
    static NUMPY: PyOnceLock<NumpyFns> = PyOnceLock::new();
    NUMPY.get_or_try_init(py, || -> PyResult<NumpyFns> {
        let m = py.import("numpy")?;
        Ok(NumpyFns {
            asarray: m.getattr("asarray")?.unbind(),
            ascontiguousarray: m.getattr("ascontiguousarray")?.unbind(),
            array: m.getattr("array")?.unbind(),
        })
    })
}

/// Machine epsilon of a float dtype of `itemsize` bytes (integers convert exactly: float64's).
fn dtype_precision(kind: &str, itemsize: usize) -> f64 {
    match (kind, itemsize) {
        ("f", 2) => 9.765625e-4, // 2⁻¹⁰, IEEE half
        ("f", 4) => f64::from(f32::EPSILON),
        _ => f64::EPSILON,
    }
}

/// Converts any array-like of real numbers to an aligned, native, C-contiguous float64 array
/// (a copy); returns it with the machine epsilon of the original dtype.
fn as_contiguous_f64<'py>(obj: &Bound<'py, PyAny>, what: &str) -> PyResult<(Bound<'py, PyAny>, f64)> {
    let py = obj.py();
    let np = numpy_fns(py)?;
    let ty = || {
        obj.get_type()
            .name()
            .map(|n| n.to_string())
            .unwrap_or_else(|_| "?".into())
    };
    let refuse = |detail: String| {
        ShapeError::new_err(format!(
            "{what}: expected an array of real numbers (float or integer), got {} {detail}",
            ty()
        ))
    };
    let arr = np
        .asarray
        .bind(py)
        .call1((obj,))
        .map_err(|e| refuse(format!("({e})")))?;
    let dtype = arr.getattr("dtype")?;
    let kind: String = dtype.getattr("kind")?.extract()?;
    if !matches!(kind.as_str(), "f" | "i" | "u") {
        return Err(refuse(format!("of dtype {}", dtype.str()?)));
    }
    let itemsize: usize = dtype.getattr("itemsize")?.extract()?;
    // Native-endian float64, C order: a fresh (aligned) array unless `arr` already was one; an
    // unaligned one (a buffer at an odd offset) is then copied by `np.array`.
    let kwargs = PyDict::new(py);
    kwargs.set_item("dtype", "float64")?;
    let mut converted = np.ascontiguousarray.bind(py).call((arr,), Some(&kwargs))?;
    if converted.cast::<PyArrayDyn<f64>>().is_ok_and(|a| !a.is_aligned()) {
        converted = np.array.bind(py).call1((converted,))?;
    }
    Ok((converted, dtype_precision(&kind, itemsize)))
}

/// Reads `obj` as a float64 array named `what` in error messages (copying only when it must).
pub fn f64_array<'py>(obj: &Bound<'py, PyAny>, what: &str) -> PyResult<F64Array<'py>> {
    if let Ok(a) = obj.cast::<PyArrayDyn<f64>>() {
        if a.is_c_contiguous() && a.is_aligned() {
            if let Some(array) = F64Array::read(a, f64::EPSILON) {
                return Ok(array);
            }
        }
    }
    let (converted, precision) = as_contiguous_f64(obj, what)?;
    let a = converted
        .cast::<PyArrayDyn<f64>>()
        .map_err(|_| ShapeError::new_err(format!("{what}: could not convert to a float64 array")))?;
    if !(a.is_c_contiguous() && a.is_aligned()) {
        return Err(ShapeError::new_err(format!(
            "{what}: could not make an aligned C-contiguous float64 copy"
        )));
    }
    F64Array::read(a, precision).ok_or_else(|| ShapeError::new_err(format!("{what}: cannot read the array")))
}

/// Reads a vector (n,) of finite values of any length n ≥ `min` (1 for a state, 0 for a batch).
pub fn vector_of_len(obj: &Bound<'_, PyAny>, what: &str, min: usize) -> PyResult<Vec<f64>> {
    let a = f64_array(obj, what)?;
    if !matches!(a.shape(), [n] if *n >= min) {
        let got = a.shape_str();
        return Err(ShapeError::new_err(format!(
            "{what}: expected shape (n,) with n ≥ {min}, got {got}"
        )));
    }
    ttkin::error::check_finite(what, a.data()).py()?;
    Ok(a.data().to_vec())
}

/// Reads an array of `rows` × `item` values for any number of rows: shape (N,) when `item` is
/// empty, else (N, *item); `rows` names N in the error ("N", "K"). Values are not checked.
pub fn rows_array<'py>(obj: &Bound<'py, PyAny>, what: &str, rows: &str, item: &[usize]) -> PyResult<F64Array<'py>> {
    let a = f64_array(obj, what)?;
    if a.shape().len() != 1 + item.len() || a.shape()[1..] != *item {
        let dims: Vec<String> = std::iter::once(rows.to_string())
            .chain(item.iter().map(usize::to_string))
            .collect();
        let expected = if item.is_empty() {
            format!("({rows},)")
        } else {
            format!("({})", dims.join(", "))
        };
        return Err(ShapeError::new_err(format!(
            "{what}: expected shape {expected}, got {}",
            a.shape_str()
        )));
    }
    Ok(a)
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

/// How far from rigid (|RᵀR − I|, bottom row) a 4×4 read at machine epsilon `precision` may be:
/// `ttkin::transform::RIGID_TOLERANCE` (1e-9) for float64, 16·ε for coarser dtypes (1.9e-6 for
/// float32: rounding each entry of an exact rotation to float32 leaves |RᵀR − I| ≤ 3ε).
pub fn rigid_tolerance(precision: f64) -> f64 {
    ttkin::transform::RIGID_TOLERANCE.max(16.0 * precision)
}

/// Reads a 4×4 homogeneous matrix and checks that it is a rigid transform (to the precision of
/// its dtype; a float32 rotation is re-orthonormalised, see [`rigid_tolerance`]).
pub fn transform(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<IsometryMatrix3<f64>> {
    let a = f64_array(obj, what)?;
    if a.shape() != [4, 4] {
        return Err(ShapeError::new_err(format!(
            "{what}: expected shape (4, 4), got {}",
            a.shape_str()
        )));
    }
    let m = Matrix4::from_row_slice(a.data());
    ttkin::transform::isometry_from_matrix_within(what, &m, rigid_tolerance(a.precision())).py()
}

/// Reads one pose (4, 4) or a batch (N, 4, 4) of rigid transforms named `what` (`what[i]` for
/// element i in messages); returns them and whether the input was a batch.
pub fn transforms(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<(Vec<IsometryMatrix3<f64>>, bool)> {
    let a = f64_array(obj, what)?;
    let tol = rigid_tolerance(a.precision());
    let read =
        |name: &str, m: &[f64]| ttkin::transform::isometry_from_matrix_within(name, &Matrix4::from_row_slice(m), tol);
    match a.shape() {
        [4, 4] => Ok((vec![read(what, a.data()).py()?], false)),
        [_, 4, 4] => {
            let v = a
                .data()
                .chunks_exact(16)
                .enumerate()
                .map(|(i, m)| read(&format!("{what}[{i}]"), m))
                .collect::<ttkin::Result<Vec<_>>>()
                .py()?;
            Ok((v, true))
        }
        _ => Err(ShapeError::new_err(format!(
            "{what}: expected shape (4, 4) or (N, 4, 4), got {}",
            a.shape_str()
        ))),
    }
}

/// A new numpy array of the given shape holding `data` (C order).
///
/// Values pass as they are (limits may be ±inf); results of computations go through
/// [`finite_to_numpy`]. A shape that does not match the data is a bug in the caller; it
/// panics, which the boundary guard turns into `InternalError`.
pub fn to_numpy<'py>(py: Python<'py>, shape: &[usize], data: &[f64]) -> Bound<'py, PyArrayDyn<f64>> {
    match ArrayView::from_shape(IxDyn(shape), data) {
        Ok(view) => PyArray::from_array(py, &view),
        Err(e) => panic!(
            "to_numpy: shape {} does not match {} values ({e})",
            shape_str(shape),
            data.len()
        ),
    }
}

/// Checks that a result is finite; otherwise `NumericalError` (the guard adds the call's name).
pub fn check_finite_output(data: &[f64]) -> PyResult<()> {
    // Branch-free within blocks, so that it vectorises (an early-exit scan of every element cost
    // 0.75 µs on 101 samples of an 8-joint quintic); a single state (a few values) is shortest
    // scanned plainly; the position only once something is wrong.
    let finite = if data.len() <= 16 {
        data.iter().all(|v| v.is_finite())
    } else {
        !data
            .chunks(64)
            .any(|c| c.iter().fold(false, |bad, v| bad | !v.is_finite()))
    };
    if finite {
        return Ok(());
    }
    match data.iter().position(|v| !v.is_finite()) {
        None => Ok(()),
        Some(i) => Err(NumericalError::new_err(format!(
            "the result is not finite (element {i} is {}) although the inputs are: they overflow \
             float64 arithmetic here (e.g. speeds of 1e150 or more, a duration of 1e-150 or less)",
            data[i]
        ))),
    }
}

/// A computed scalar, refusing NaN/inf with `NumericalError`.
pub fn finite_scalar(v: f64) -> PyResult<f64> {
    check_finite_output(&[v])?;
    Ok(v)
}

/// [`to_numpy`] of a computed result, refusing NaN/inf with `NumericalError`.
pub fn finite_to_numpy<'py>(py: Python<'py>, shape: &[usize], data: &[f64]) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    check_finite_output(data)?;
    Ok(to_numpy(py, shape, data))
}

/// The 16 values of a transform's 4×4 matrix, row-major (as numpy reads a (4, 4) array).
pub fn row_major(t: &IsometryMatrix3<f64>) -> [f64; 16] {
    let mut buf = [0.0; 16];
    ttkin::transform::write_row_major(t, &mut buf);
    buf
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

/// Runs `fill` on the data of `out`, a fresh array made by [`zeros`] (never borrowed elsewhere,
/// so the borrow and slice cannot fail; if they ever did: `InternalError`, not a panic).
pub fn fill_fresh<R>(out: &Bound<'_, PyArrayDyn<f64>>, fill: impl FnOnce(&mut [f64]) -> PyResult<R>) -> PyResult<R> {
    let mut w = out.try_readwrite().map_err(|e| InternalError::new_err(e.to_string()))?;
    let o = w
        .as_slice_mut()
        .map_err(|e| InternalError::new_err(format!("fresh output array: {e}")))?;
    fill(o)
}

/// Checks that a float64 result of `shape` fits in `ttkin::budget::MAX_BYTES` before it is
/// allocated (N states × K times of a batch could ask for terabytes and abort the process).
pub fn check_result_size(shape: &[usize]) -> PyResult<()> {
    let count: f64 = shape.iter().map(|&d| d as f64).product();
    ttkin::budget::check_bytes(&format!("result of shape {}", shape_str(shape)), count, 8).py()?;
    Ok(())
}

/// A new float64 array of `shape` filled by `fill` with the GIL released (batch work); a
/// non-finite result is refused with `NumericalError`.
pub fn filled_without_gil<'py, F>(py: Python<'py>, shape: &[usize], fill: F) -> PyResult<Bound<'py, PyArrayDyn<f64>>>
where
    F: FnOnce(&mut [f64]) -> ttkin::Result<()> + Send,
{
    check_result_size(shape)?;
    let out = zeros(py, shape);
    fill_fresh(&out, |o| {
        py.detach(|| fill(o)).py()?;
        check_finite_output(o)
    })?;
    Ok(out)
}

/// Reads a per-row table of `rows` × `cols` values as row-major data: shape (rows, cols), or
/// (rows,) when `cols` is 1, or (rows, 3, 3) when `cols` is 9 (a 3 × 3 matrix per row).
pub fn table(obj: &Any<'_>, what: &str, rows: usize, cols: usize) -> PyResult<Vec<f64>> {
    let a = f64_array(obj, what)?;
    let ok = match *a.shape() {
        [r] => cols == 1 && r == rows,
        [r, c] => cols > 1 && r == rows && c == cols,
        [r, 3, 3] => cols == 9 && r == rows,
        _ => false,
    };
    if !ok {
        let expected = if cols == 1 {
            format!("({rows},)")
        } else {
            format!("({rows}, {cols})")
        };
        return Err(ShapeError::new_err(format!(
            "{what}: expected shape {expected}, got {}",
            a.shape_str()
        )));
    }
    Ok(a.data().to_vec())
}

/// A `#[pymethods]` block of read-only numpy properties of a result class, one line each:
/// `/// doc` then `name => data, [dims];`, where `data` and `dims` read the object as `$r`.
macro_rules! array_getters {
    ($ty:ty, |$r:ident| { $( $(#[$doc:meta])* $name:ident => $data:expr, [$($dim:expr),+]; )* }) => {
        #[ttkin_py_guard::guarded]
        #[pyo3::pymethods]
        impl $ty {
            $(
                $(#[$doc])*
                #[getter]
                fn $name<'py>(&self, py: pyo3::Python<'py>) -> $crate::convert::Array<'py> {
                    let $r = self;
                    $crate::convert::to_numpy(py, &[$($dim),+], &$data)
                }
            )*
        }
    };
}
pub(crate) use array_getters;

/// A `#[pymethods]` block of read-only plain-value properties of a result class, one line each:
/// `/// doc` then `name: Type => value;`, where `value` reads the object as `$r`.
macro_rules! value_getters {
    ($ty:ty, |$r:ident| { $( $(#[$doc:meta])* $name:ident: $out:ty => $value:expr; )* }) => {
        #[ttkin_py_guard::guarded]
        #[pyo3::pymethods]
        impl $ty {
            $(
                $(#[$doc])*
                #[getter]
                fn $name(&self) -> $out {
                    let $r = self;
                    $value
                }
            )*
        }
    };
}
pub(crate) use value_getters;

/// `obj` as a fresh float64 numpy array of its own shape, by the one conversion every binding
/// uses ([`f64_array`]: complex, boolean, string and object data refused with `ShapeError` naming
/// `what`); the Python layer's array arguments go through it too.
#[ttkin_py_guard::guarded]
#[pyfunction]
pub fn real_array<'py>(py: Python<'py>, obj: &Bound<'py, PyAny>, what: &str) -> PyResult<Array<'py>> {
    let a = f64_array(obj, what)?;
    Ok(to_numpy(py, a.shape(), a.data()))
}

/// The serde form of `value` as plain Python objects (dicts, lists, floats, strings): the one
/// converter of records (`pythonize`).
pub fn serde_to_python<'py, T: serde::Serialize + ?Sized>(py: Python<'py>, value: &T) -> PyResult<Bound<'py, PyAny>> {
    pythonize::pythonize(py, value).map_err(|e| crate::errors::TtmanipError::new_err(e.to_string()))
}

/// Consecutive triples of `data` (its length a multiple of 3, as `rows_array(.., &[3])` gives).
pub fn triples(data: &[f64]) -> Vec<[f64; 3]> {
    data.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect()
}

/// Records (a `Vec` of core structs) → columns: the one conversion of a list of results into
/// numpy arrays, one field at a time. `column(py, &records, |r| r.x)` is the (N,) array of
/// field `x` of every record (any numpy element type: float64, int64, bool).
pub fn column<'py, T, U: numpy::Element>(
    py: Python<'py>,
    records: &[T],
    field: impl Fn(&T) -> U,
) -> Bound<'py, numpy::PyArray1<U>> {
    numpy::PyArray1::from_iter(py, records.iter().map(field))
}

/// Records → one float64 array (N, *item) of a slice field (or a whole record that is a slice,
/// or values computed from it, e.g. an array) of every record, each `item.product()` long
/// (e.g. `rows(py, &results, &[n], |r| &r.q)`).
pub fn rows<'py, 'r, T, R: AsRef<[f64]>>(
    py: Python<'py>,
    records: &'r [T],
    item: &[usize],
    field: impl Fn(&'r T) -> R,
) -> Array<'py> {
    let data: Vec<f64> = records.iter().flat_map(|r| field(r).as_ref().to_vec()).collect();
    let shape: Vec<usize> = std::iter::once(records.len()).chain(item.iter().copied()).collect();
    to_numpy(py, &shape, &data)
}

/// Records → a Python list of one field of every record (strings, nested values).
pub fn list<'py, T, U>(
    py: Python<'py>,
    records: &[T],
    field: impl Fn(&T) -> U,
) -> PyResult<Bound<'py, pyo3::types::PyList>>
where
    U: IntoPyObject<'py>,
{
    pyo3::types::PyList::new(py, records.iter().map(field))
}

/// Records → Python objects: each core result wrapped in its `#[pyclass]` (`wrap` builds one),
/// for a list returned to Python (e.g. N `HitPlan`s of a batch).
pub fn wrap_all<T, U>(records: Vec<T>, wrap: impl FnMut(T) -> U) -> Vec<U> {
    records.into_iter().map(wrap).collect()
}

/// [`check_finite_output`] of several computed signals (e.g. the columns of a trace).
pub fn check_finite_outputs(signals: &[&[f64]]) -> PyResult<()> {
    signals.iter().try_for_each(|s| check_finite_output(s))
}

/// Reads `q` as one configuration (n,) or a batch (N, n) of an `n`-joint robot; returns the
/// batch size (None for one).
pub fn configs<'py>(q: &Any<'py>, what: &str, n: usize) -> PyResult<(F64Array<'py>, Option<usize>)> {
    let a = f64_array(q, what)?;
    let batch = match a.shape() {
        [m] if *m == n => None,
        [count, m] if *m == n => Some(*count),
        _ => {
            return Err(ShapeError::new_err(format!(
                "{what}: expected shape ({n},) or (N, {n}) for this {n}-joint robot, got {}",
                a.shape_str()
            )))
        }
    };
    Ok((a, batch))
}

/// Reads several per-configuration arrays (`(object, name)` pairs) of an `n`-joint robot that
/// must all be (n,) or all (N, n) with the same N; returns them and N (None for single states).
pub fn same_batch<'py>(arrays: &[(&Any<'py>, &str)], n: usize) -> PyResult<(Vec<F64Array<'py>>, Option<usize>)> {
    let mut out = Vec::with_capacity(arrays.len());
    let mut batch = None;
    for (k, (obj, what)) in arrays.iter().enumerate() {
        let (a, b) = configs(obj, what, n)?;
        if k == 0 {
            batch = b;
        } else if b != batch {
            let first = match batch {
                None => format!("({n},)"),
                Some(c) => format!("({c}, {n})"),
            };
            return Err(ShapeError::new_err(format!(
                "{what}: expected shape {first} like the first argument, got {}",
                a.shape_str()
            )));
        }
        out.push(a);
    }
    Ok((out, batch))
}

/// The shape (count, *item) of a batch result.
pub fn batch_shape(count: usize, item: &[usize]) -> Vec<usize> {
    std::iter::once(count).chain(item.iter().copied()).collect()
}

/// A Python list read element by element with `read` (e.g. a list of (N_i, 3) arrays), element
/// i named `what[i]` in errors.
pub fn each<'py, T>(
    list: &Bound<'py, pyo3::types::PyList>,
    what: &str,
    read: impl Fn(&Bound<'py, PyAny>, &str) -> PyResult<T>,
) -> PyResult<Vec<T>> {
    list.iter()
        .enumerate()
        .map(|(i, item)| read(&item, &format!("{what}[{i}]")))
        .collect()
}

/// Borrowed `&str`s of owned strings (a column of names read from Python).
pub fn str_refs(v: &[String]) -> Vec<&str> {
    v.iter().map(String::as_str).collect()
}
