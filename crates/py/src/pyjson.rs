//! The library's JSON documents (the ones `nlvid --json` prints) as Python
//! objects: objects → dict (key order kept), arrays → list, numbers → int
//! or float, null → None. Curves are added as numpy arrays by the callers.

use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use serde_json::Value;

/// `v` as a Python object.
pub(crate) fn to_py<'py>(py: Python<'py>, v: &Value) -> PyResult<Bound<'py, PyAny>> {
    Ok(match v {
        Value::Null => py.None().into_bound(py),
        Value::Bool(b) => b.into_pyobject(py)?.to_owned().into_any(),
        Value::Number(n) => match (n.as_i64(), n.as_u64()) {
            (Some(i), _) => i.into_pyobject(py)?.into_any(),
            (None, Some(u)) => u.into_pyobject(py)?.into_any(),
            _ => n.as_f64().unwrap_or(f64::NAN).into_pyobject(py)?.into_any(),
        },
        Value::String(s) => s.into_pyobject(py)?.into_any(),
        Value::Array(a) => {
            let list = PyList::empty(py);
            for x in a {
                list.append(to_py(py, x)?)?;
            }
            list.into_any()
        }
        Value::Object(o) => {
            let d = PyDict::new(py);
            for (k, x) in o {
                d.set_item(k, to_py(py, x)?)?;
            }
            d.into_any()
        }
    })
}

/// `v` (a JSON object) as a dict.
pub(crate) fn dict<'py>(py: Python<'py>, v: &Value) -> PyResult<Bound<'py, PyDict>> {
    Ok(to_py(py, v)?.cast_into::<PyDict>()?)
}

/// A curve as `{"time": array, <channel>: array, ...}` plus
/// `{"units": {name: unit}}` (SI).
pub(crate) fn curve<'py>(py: Python<'py>, c: &nlvid_model::Curve) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let units = PyDict::new(py);
    d.set_item("time", PyArray1::from_slice(py, c.time()))?;
    units.set_item("time", "s")?;
    for ch in c.channels() {
        d.set_item(&ch.name, PyArray1::from_slice(py, &ch.values))?;
        units.set_item(&ch.name, &ch.unit)?;
    }
    d.set_item("units", units)?;
    Ok(d)
}
