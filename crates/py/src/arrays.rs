//! Checked numpy input. A float64 array is read in place (a read-only
//! view: no copy) when it is C-contiguous; other float64 layouts are
//! copied once. Anything else — another dtype, a list, a 0-d array, NaN or
//! ±inf, the wrong number of dimensions — raises an exception naming the
//! argument, never a crash. Quantities with units come in as strings such
//! as `"5 um"`; a bare number where a unit is needed is refused.

use std::borrow::Cow;

use numpy::{
    PyArrayDescrMethods, PyArrayDyn, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2,
    PyUntypedArray, PyUntypedArrayMethods,
};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;

use crate::errors::input;

/// A float64 vector borrowed from numpy (or copied if not contiguous).
pub(crate) struct Vector<'py> {
    array: PyReadonlyArray1<'py, f64>,
}

impl Vector<'_> {
    /// The values: the numpy buffer itself when contiguous.
    pub(crate) fn values(&self) -> Cow<'_, [f64]> {
        match self.array.as_slice() {
            Ok(s) => Cow::Borrowed(s),
            Err(_) => Cow::Owned(self.array.as_array().iter().copied().collect()),
        }
    }

    /// Number of values.
    pub(crate) fn len(&self) -> usize {
        self.array.len()
    }
}

/// A float64 matrix (rows are points) borrowed from numpy; a 1-d array
/// is one row.
pub(crate) enum Matrix<'py> {
    /// A 2-d array.
    Rows(PyReadonlyArray2<'py, f64>),
    /// A 1-d array: one point.
    Row(PyReadonlyArray1<'py, f64>),
}

impl Matrix<'_> {
    /// (rows, columns).
    pub(crate) fn shape(&self) -> (usize, usize) {
        match self {
            Matrix::Rows(a) => {
                let s = a.shape();
                (s[0], s[1])
            }
            Matrix::Row(a) => (1, a.len()),
        }
    }

    /// The values in row-major order: the numpy buffer itself when
    /// C-contiguous.
    pub(crate) fn row_major(&self) -> Cow<'_, [f64]> {
        match self {
            Matrix::Rows(a) => match a.as_slice() {
                Ok(s) => Cow::Borrowed(s),
                Err(_) => Cow::Owned(a.as_array().iter().copied().collect()),
            },
            Matrix::Row(a) => match a.as_slice() {
                Ok(s) => Cow::Borrowed(s),
                Err(_) => Cow::Owned(a.as_array().iter().copied().collect()),
            },
        }
    }
}

fn dtype_error(name: &str, obj: &Bound<'_, PyAny>) -> PyErr {
    let what = match obj.cast::<PyUntypedArray>() {
        Ok(a) => format!("a numpy array of dtype {}", a.dtype()),
        Err(_) => format!(
            "a {}",
            obj.get_type()
                .name()
                .map_or_else(|_| "?".into(), |n| n.to_string())
        ),
    };
    PyTypeError::new_err(format!(
        "{name}: expected a numpy float64 array, got {what} \
         (convert with numpy.asarray({name}, dtype=float))"
    ))
}

/// `obj` as a float64 array of any dimension, type-checked.
fn float_array<'py>(obj: &Bound<'py, PyAny>, name: &str) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    let Ok(untyped) = obj.cast::<PyUntypedArray>() else {
        return Err(dtype_error(name, obj));
    };
    let f64_dtype = numpy::dtype::<f64>(obj.py());
    if !untyped.dtype().is_equiv_to(&f64_dtype) {
        return Err(dtype_error(name, obj));
    }
    obj.cast::<PyArrayDyn<f64>>()
        .cloned()
        .map_err(|_| dtype_error(name, obj))
}

/// Rejects NaN and ±inf, naming the first (flat) index.
fn finite(name: &str, values: &[f64]) -> PyResult<()> {
    match values.iter().position(|v| !v.is_finite()) {
        Some(i) => Err(input(format!(
            "{name}: value {} at index {i} is not finite (NaN or ±inf are not data)",
            values[i]
        ))),
        None => Ok(()),
    }
}

/// A 1-d float64 array argument, finite, read in place.
pub(crate) fn vector<'py>(obj: &Bound<'py, PyAny>, name: &str) -> PyResult<Vector<'py>> {
    let a = float_array(obj, name)?;
    if a.ndim() != 1 {
        return Err(input(format!(
            "{name}: expected a 1-d array, got {} dimension(s) of shape {:?}",
            a.ndim(),
            a.shape()
        )));
    }
    let array: PyReadonlyArray1<'py, f64> = a
        .cast_into::<numpy::PyArray1<f64>>()
        .map_err(|_| dtype_error(name, obj))?
        .try_readonly()
        .map_err(|e| input(format!("{name}: {e}")))?;
    let v = Vector { array };
    finite(name, &v.values())?;
    Ok(v)
}

/// A 2-d float64 array argument (a 1-d one is one row), finite.
pub(crate) fn matrix<'py>(obj: &Bound<'py, PyAny>, name: &str) -> PyResult<Matrix<'py>> {
    let a = float_array(obj, name)?;
    let m = match a.ndim() {
        1 => Matrix::Row(
            a.cast_into::<numpy::PyArray1<f64>>()
                .map_err(|_| dtype_error(name, obj))?
                .try_readonly()
                .map_err(|e| input(format!("{name}: {e}")))?,
        ),
        2 => Matrix::Rows(
            a.cast_into::<numpy::PyArray2<f64>>()
                .map_err(|_| dtype_error(name, obj))?
                .try_readonly()
                .map_err(|e| input(format!("{name}: {e}")))?,
        ),
        n => {
            return Err(input(format!(
                "{name}: expected a 2-d array (one row per point), got {n} dimension(s)"
            )));
        }
    };
    finite(name, &m.row_major())?;
    Ok(m)
}

/// Arrays that must have one length: names and lengths.
pub(crate) fn same_length(items: &[(&str, usize)]) -> PyResult<()> {
    let Some(&(first, n)) = items.first() else {
        return Ok(());
    };
    for &(name, m) in &items[1..] {
        if m != n {
            return Err(input(format!(
                "{first} has {n} values but {name} has {m}: give arrays of one length"
            )));
        }
    }
    Ok(())
}

/// A quantity string such as `"5 um"` in SI, of dimension `dim`; a bare
/// number (or a string without a unit) is refused with an example.
pub(crate) fn quantity(
    obj: &Bound<'_, PyAny>,
    name: &str,
    dim: nlvid_study::Dimension,
) -> PyResult<f64> {
    let example = format!("\"1 {}\"", dim.example_unit());
    let Ok(text) = obj.extract::<String>() else {
        return Err(input(format!(
            "{name}: give a quantity with a unit as a string, e.g. {name}={example} (got {})",
            obj.repr().map_or_else(|_| "?".into(), |r| r.to_string())
        )));
    };
    let q =
        nlvid_study::Quantity::parse(&text).map_err(|e| input(format!("{name}: `{text}`: {e}")))?;
    if q.dim == dim {
        if !q.value.is_finite() {
            return Err(input(format!("{name}: `{text}` is not finite")));
        }
        Ok(q.value)
    } else if q.dim == nlvid_study::Dimension::NONE {
        Err(input(format!(
            "{name}: `{text}` has no unit; expected a {dim}, e.g. {name}=\"{text} {}\"",
            dim.example_unit()
        )))
    } else {
        Err(input(format!(
            "{name}: `{text}` is a {}, expected a {dim}",
            q.dim
        )))
    }
}
