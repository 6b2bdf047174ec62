//! Study files: load and validate (a file: exactly `nlvid check`,
//! `nlvid_report::check::check_study`), every value in SI.

use std::path::PathBuf;

use nlvid_report::check::leaf_json;
use nlvid_study::Study as RStudy;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use serde_json::json;

use crate::errors::{IntoPy, StudyError};

/// Where a study comes from: a file, or text with a name (base directory
/// for relative paths: the current one).
#[derive(Clone, Debug)]
pub(crate) enum Source {
    File(PathBuf),
    Text { name: String, text: String },
}

impl Source {
    /// Reads the study afresh (file, line and key in every error).
    pub(crate) fn load(&self) -> PyResult<RStudy> {
        match self {
            Source::File(p) => RStudy::load(p).py(),
            Source::Text { name, text } => RStudy::parse(name, text).py(),
        }
    }

    /// A study given from Python: a `Study`, or a path (str or PathLike).
    pub(crate) fn from_py(obj: &Bound<'_, PyAny>) -> PyResult<Self> {
        if let Ok(s) = obj.cast::<Study>() {
            return Ok(s.borrow().source.clone());
        }
        match obj.extract::<PathBuf>() {
            Ok(p) => Ok(Source::File(p)),
            Err(_) => Err(pyo3::exceptions::PyTypeError::new_err(
                "study: expected a path (str or os.PathLike) or an nlvid.Study",
            )),
        }
    }
}

/// Section readers `check` runs (crates/cli/src/cmd/check.rs `STAGE_READERS`).
fn check_schemas(study: &mut RStudy) -> PyResult<Vec<&'static str>> {
    let mut checked = Vec::new();
    if let Some(mut s) = study.opt_section("protocol").py()? {
        <nlvid_protocol::ProtocolSettings as nlvid_study::FromSection>::from_section(&mut s)
            .py()?;
        s.finish().py()?;
        checked.push("protocol");
    }
    Ok(checked)
}

/// The first lint error as a `StudyError` with its leaf's place and key.
fn lint_error(study: &RStudy, message: &str) -> PyErr {
    let e = StudyError::new_err(message.to_string());
    Python::attach(|py| {
        let v = e.value(py);
        let leaf = study.leaves().into_iter().find(|l| {
            message.starts_with(&format!(
                "{}:{}:{}: key `{}`",
                study.name(),
                l.line,
                l.column,
                l.key
            ))
        });
        let _ = v.setattr("file", study.name());
        let _ = v.setattr("line", leaf.as_ref().map(|l| l.line));
        let _ = v.setattr("column", leaf.as_ref().map(|l| l.column));
        let _ = v.setattr("key", leaf.map(|l| l.key));
    });
    e
}

/// A validated study file: its values in SI, hash and warnings.
///
/// Made by `load_study(path)` or `parse_study(text)`; pass it (or a path)
/// to `simulate`, `fit`, ... Raises `StudyError` (attributes `file`,
/// `line`, `column`, `key`) on syntax, unit, number or schema errors.
#[pyclass(module = "nlvid", frozen)]
pub(crate) struct Study {
    source: Source,
    name: String,
    sha256: String,
    values: serde_json::Value,
    schema_checked: Vec<&'static str>,
    warnings: Vec<String>,
    table: String,
}

impl Study {
    fn validate(source: Source) -> PyResult<Self> {
        if let Source::File(path) = &source {
            // A file: exactly `nlvid check` (every stage's validation).
            let c = match nlvid_report::check::check_study(path) {
                Ok(c) => c,
                Err(e) => {
                    let message = crate::errors::message(e.as_ref());
                    if let Ok(study) = RStudy::load(path)
                        && study.lint().errors.first() == Some(&message)
                    {
                        return Err(lint_error(&study, &message));
                    }
                    return Err(crate::errors::to_py(e.as_ref(), None));
                }
            };
            let name = RStudy::load(path).py()?.name().to_string();
            return Ok(Study {
                name,
                sha256: c.hash,
                values: c.leaves.iter().map(leaf_json).collect(),
                schema_checked: c.schema_checked,
                warnings: c.warnings,
                table: c.table,
                source,
            });
        }
        // Text: syntax, units, numbers and the [protocol] schema (the stages'
        // validations read files named relative to a study file).
        let mut study = source.load()?;
        let schema_checked = check_schemas(&mut study)?;
        let lint = study.lint();
        if let Some(e) = lint.errors.first() {
            return Err(lint_error(&study, e));
        }
        Ok(Study {
            name: study.name().to_string(),
            sha256: study.hash().to_string(),
            values: study.leaves().iter().map(leaf_json).collect(),
            schema_checked,
            warnings: lint.warnings,
            table: study.values_table(),
            source,
        })
    }
}

#[pymethods]
impl Study {
    /// The file name (or the name given to `parse_study`).
    #[getter]
    fn name(&self) -> &str {
        &self.name
    }
    /// SHA-256 of the study text (the provenance hash of every output).
    #[getter]
    fn sha256(&self) -> &str {
        &self.sha256
    }
    /// Strings that look like quantities but cannot be read.
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.warnings.clone()
    }
    /// Every value as read: list of dicts `key`, `line`, `value` (SI),
    /// `unit` (SI), `written` (the text of a quantity, else None).
    fn values<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        crate::pyjson::to_py(py, &self.values)
    }
    /// The values as a dict key → SI value.
    fn as_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for v in self.values.as_array().into_iter().flatten() {
            d.set_item(v["key"].as_str(), crate::pyjson::to_py(py, &v["value"])?)?;
        }
        Ok(d)
    }
    /// The document `nlvid --json check` prints.
    fn check_report<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        crate::pyjson::dict(
            py,
            &json!({
                "study": self.name,
                "sha256": self.sha256,
                "schema_checked_sections": self.schema_checked,
                "values": self.values,
                "warnings": self.warnings,
            }),
        )
    }
    /// The table `nlvid check` prints (line, key, SI value, as written).
    fn table(&self) -> &str {
        &self.table
    }
    fn __repr__(&self) -> String {
        format!(
            "<nlvid.Study {} sha256 {}>",
            self.name,
            &self.sha256[..12.min(self.sha256.len())]
        )
    }
}

/// Loads and validates a study file (`nlvid check`). With `strict`,
/// warnings are errors.
#[pyfunction]
#[pyo3(signature = (path, strict = false))]
fn load_study(path: PathBuf, strict: bool) -> PyResult<Study> {
    strict_check(Study::validate(Source::File(path))?, strict)
}

/// Validates study text given as a string; `name` is used in messages.
#[pyfunction]
#[pyo3(signature = (text, name = "<string>".to_string(), strict = false))]
fn parse_study(text: String, name: String, strict: bool) -> PyResult<Study> {
    strict_check(Study::validate(Source::Text { name, text })?, strict)
}

fn strict_check(s: Study, strict: bool) -> PyResult<Study> {
    if strict && !s.warnings.is_empty() {
        return Err(StudyError::new_err(format!(
            "{} warning(s) with strict=True: {}",
            s.warnings.len(),
            s.warnings.join("; ")
        )));
    }
    Ok(s)
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Study>()?;
    m.add_function(wrap_pyfunction!(load_study, m)?)?;
    m.add_function(wrap_pyfunction!(parse_study, m)?)?;
    Ok(())
}
