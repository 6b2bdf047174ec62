//! NLV fits on Kriging meta-models (`nlvid fit`): one parameter set fitted
//! to one or several curves (`nlvid_report::fit`), then re-checked with the
//! real model each experiment of the study's `[fit]` names.

use std::path::PathBuf;

use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::arrays::{same_length, vector};
use crate::errors::{IntoPy, input};
use crate::study::Source;

/// One curve given as a dict of arrays (SI): `time` (s, increasing),
/// `displacement` (m: piezo Z or plate displacement), `force` (N),
/// optional `indentation` (m, AFM: δ = Z − d), optional `label`.
fn curve_from_dict(
    d: &Bound<'_, PyDict>,
    i: usize,
) -> PyResult<(String, nlvid_inverse::MeasuredCurve)> {
    let name = |k: &str| format!("data[{i}][\"{k}\"]");
    for key in d.keys() {
        let k: String = key.extract()?;
        if !["time", "displacement", "force", "indentation", "label"].contains(&k.as_str()) {
            return Err(input(format!(
                "data[{i}]: unknown key `{k}` (expected time, displacement, force, indentation, label; arrays in SI: s, m, N)"
            )));
        }
    }
    let get = |k: &str| -> PyResult<Bound<'_, PyAny>> {
        d.get_item(k)?.ok_or_else(|| {
            input(format!(
                "data[{i}]: missing `{k}` (give time [s], displacement [m], force [N] as float64 arrays)"
            ))
        })
    };
    let (t, z, f) = (get("time")?, get("displacement")?, get("force")?);
    let (t, z, f) = (
        vector(&t, &name("time"))?,
        vector(&z, &name("displacement"))?,
        vector(&f, &name("force"))?,
    );
    let ind = match d.get_item("indentation")? {
        Some(x) => Some(vector(&x, &name("indentation"))?),
        None => None,
    };
    let mut lens = vec![
        (name("time"), t.len()),
        (name("displacement"), z.len()),
        (name("force"), f.len()),
    ];
    if let Some(x) = &ind {
        lens.push((name("indentation"), x.len()));
    }
    same_length(
        &lens
            .iter()
            .map(|(n, l)| (n.as_str(), *l))
            .collect::<Vec<_>>(),
    )?;
    let time = t.values().into_owned();
    if time.len() < 2 {
        return Err(input(format!("{}: need at least 2 samples", name("time"))));
    }
    if let Some(j) = time.windows(2).position(|w| w[1] <= w[0]) {
        return Err(input(format!(
            "{}: not strictly increasing at index {} ({} after {})",
            name("time"),
            j + 1,
            time[j + 1],
            time[j]
        )));
    }
    let label = match d.get_item("label")? {
        Some(l) => l.extract::<String>()?,
        None => format!("curve{i}"),
    };
    let n = time.len();
    let columns = (time, z.values().into_owned(), f.values().into_owned());
    let curve = nlvid_inverse::MeasuredCurve::from_columns(
        &PathBuf::from(format!("<{label}>")),
        (0..n).collect(),
        columns,
        ind.map(|x| x.values().into_owned()),
        None,
    )
    .map_err(|e| input(format!("data[{i}]: {e}")))?;
    Ok((label, curve))
}

/// Fits one NLV parameter set to `data` on the meta-models of the study's
/// `[fit]`, without the GIL.
///
/// `data`: a list whose items are data file paths (CSV with the columns of
/// `[fit.columns]`, or `.jpk-force`) or dicts of float64 arrays in SI
/// (`time` s, `displacement` m, `force` N, optional `indentation` m and
/// `label`); a single item may be given alone. `starts`, `seed` override
/// `[fit]`. Returns the document `nlvid --json fit` prints.
#[pyfunction]
#[pyo3(signature = (study, data, starts = None, seed = None))]
fn fit<'py>(
    py: Python<'py>,
    study: &Bound<'py, PyAny>,
    data: &Bound<'py, PyAny>,
    starts: Option<usize>,
    seed: Option<u64>,
) -> PyResult<Bound<'py, PyDict>> {
    let path = match Source::from_py(study)? {
        Source::File(p) => p,
        Source::Text { .. } => {
            return Err(input(
                "study: fit reads paths relative to the study file: give its path (or load_study(path))",
            ));
        }
    };
    let items: Vec<Bound<'py, PyAny>> = match data.cast::<PyList>() {
        Ok(l) => l.iter().collect(),
        Err(_) => vec![data.clone()],
    };
    if items.is_empty() {
        return Err(input(
            "data: give at least one curve (a path or a dict of arrays)",
        ));
    }
    let (mut files, mut curves) = (Vec::new(), Vec::new());
    for (i, item) in items.iter().enumerate() {
        if let Ok(d) = item.cast::<PyDict>() {
            curves.push(curve_from_dict(d, i)?);
        } else if let Ok(p) = item.extract::<PathBuf>() {
            files.push(p);
        } else {
            return Err(pyo3::exceptions::PyTypeError::new_err(format!(
                "data[{i}]: expected a path or a dict of arrays, got {}",
                item.get_type().name()?
            )));
        }
    }
    if !files.is_empty() && !curves.is_empty() {
        return Err(input(
            "data: give either paths or dicts of arrays, not both",
        ));
    }
    let mut settings = nlvid_report::settings::FitSettings::load(&path).py()?;
    settings.starts = starts.unwrap_or(settings.starts);
    settings.seed = seed.unwrap_or(settings.seed);
    let outcome = py
        .detach(|| {
            let experiments = if files.is_empty() {
                nlvid_report::fit::load_curves(&settings, curves)?
            } else {
                nlvid_report::fit::load(&settings, &files)?
            };
            nlvid_report::fit::fit(&settings, &experiments)?.to_json()
        })
        .py()?;
    crate::pyjson::dict(py, &outcome)
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(fit, m)?)?;
    Ok(())
}
