//! Library errors as Python exceptions. Every exception is an
//! `nlvid.NlvidError`; errors of a study file are `nlvid.StudyError` with
//! `file`, `line`, `column` and `key` attributes (None where the error has
//! none); bad arguments from Python are `nlvid.InputError` (also a
//! `ValueError`) or `TypeError`. Messages are the ones the CLI prints
//! after `error: ` (the error and its causes joined by `: `).

use pyo3::create_exception;
use pyo3::exceptions::{PyException, PyValueError};
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::{PyDict, PyTuple, PyType};

create_exception!(
    nlvid,
    NlvidError,
    PyException,
    "Any error reported by nlvid."
);
create_exception!(
    nlvid,
    StudyError,
    NlvidError,
    "An error in a study file: attributes file, line, column, key."
);
/// `InputError(NlvidError, ValueError)`: made at import ([`register`]),
/// since a Rust-declared exception has one base.
static INPUT_ERROR: PyOnceLock<Py<PyType>> = PyOnceLock::new();

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("NlvidError", py.get_type::<NlvidError>())?;
    m.add("StudyError", py.get_type::<StudyError>())?;
    let bases = PyTuple::new(
        py,
        [py.get_type::<NlvidError>(), py.get_type::<PyValueError>()],
    )?;
    let attrs = PyDict::new(py);
    attrs.set_item(
        "__doc__",
        "A bad argument given from Python (also a ValueError).",
    )?;
    attrs.set_item("__module__", "nlvid")?;
    let input = py
        .get_type::<PyType>()
        .call1(("InputError", bases, attrs))?
        .cast_into::<PyType>()?;
    let input = INPUT_ERROR.get_or_init(py, || input.unbind());
    m.add("InputError", input.bind(py))?;
    Ok(())
}

/// The message the CLI prints for `err` ([`nlvid_study::error_message`]).
pub(crate) fn message(err: &(dyn std::error::Error + 'static)) -> String {
    nlvid_study::error_message(err)
}

/// The study error `e` is, or wraps transparently (a transparent variant
/// hides it from the `source()` chain).
fn as_study_error<'a>(
    e: &'a (dyn std::error::Error + 'static),
) -> Option<&'a nlvid_study::StudyError> {
    if let Some(s) = e.downcast_ref::<nlvid_study::StudyError>() {
        return Some(s);
    }
    if let Some(nlvid_forward::ForwardError::Study(s)) = e.downcast_ref() {
        return Some(s);
    }
    if let Some(nlvid_report::ReportError::Study(s)) = e.downcast_ref() {
        return Some(s);
    }
    None
}

/// The first `nlvid_study::StudyError` in `err`'s chain.
fn find_study_error<'a>(
    err: &'a (dyn std::error::Error + 'static),
) -> Option<&'a nlvid_study::StudyError> {
    let mut e: Option<&(dyn std::error::Error + 'static)> = Some(err);
    while let Some(x) = e {
        if let Some(s) = as_study_error(x) {
            return Some(s);
        }
        e = x.source();
    }
    None
}

/// `err` as a Python exception: `StudyError` (with its location and key)
/// when a study error is in the chain, else `NlvidError`; `context`, when
/// given, is prefixed as the CLI does (`context: message`).
pub(crate) fn to_py(err: &(dyn std::error::Error + 'static), context: Option<&str>) -> PyErr {
    let text = match context {
        Some(c) => format!("{c}: {}", message(err)),
        None => message(err),
    };
    let Some(study) = find_study_error(err) else {
        return NlvidError::new_err(text);
    };
    let e = StudyError::new_err(text);
    Python::attach(|py| {
        let v = e.value(py);
        let loc = study.location();
        let file = match study {
            nlvid_study::StudyError::Io { path, .. } => Some(path.display().to_string()),
            _ => loc.map(|l| l.file.clone()),
        };
        let _ = v.setattr("file", file);
        let _ = v.setattr("line", loc.map(|l| l.line));
        let _ = v.setattr("column", loc.map(|l| l.column));
        let _ = v.setattr("key", study.key());
    });
    e
}

/// Converts library results into Python results.
pub(crate) trait IntoPy<T> {
    /// The error as an nlvid exception.
    fn py(self) -> PyResult<T>;
    /// The error, prefixed by `context`, as an nlvid exception.
    fn py_ctx(self, context: impl FnOnce() -> String) -> PyResult<T>;
}

impl<T, E: std::error::Error + 'static> IntoPy<T> for Result<T, E> {
    fn py(self) -> PyResult<T> {
        self.map_err(|e| to_py(&e, None))
    }
    fn py_ctx(self, context: impl FnOnce() -> String) -> PyResult<T> {
        self.map_err(|e| to_py(&e, Some(&context())))
    }
}

/// An `InputError` with `message`.
pub(crate) fn input(message: impl Into<String>) -> PyErr {
    let message = message.into();
    Python::attach(|py| match INPUT_ERROR.get(py) {
        Some(t) => PyErr::from_type(t.bind(py).clone(), message),
        None => PyValueError::new_err(message),
    })
}
