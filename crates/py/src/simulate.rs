//! Forward runs (`nlvid simulate`, `nlvid membrane`): one run of a study's
//! `[forward]` model (the cell FE model `afm-fe`, the ch. II membrane, the
//! analytic ones) at the values of `[parameters]`
//! (`nlvid_forward::SimulateStudy`).

use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::errors::IntoPy;
use crate::study::Source;

/// Runs the study's forward model once, without the GIL.
///
/// Returns a dict: `model`, `parameters` (unit-suffixed keys, as
/// `nlvid --json simulate`), `curve` (`time` and every channel as float64
/// arrays, SI, with `units`), the summary keys of the CLI
/// (`peak_force_N`, `final_force_N`, `min_force_N`, `final`, `solver` for
/// afm-fe), `provenance`; for the membrane model `profiles`: list of
/// `(time_s, {column: array})` at `profile_times` (default: the end).
/// `profile_times` are quantity strings (`["10 s", "50 s"]`).
#[pyfunction]
#[pyo3(signature = (study, profile_times = None))]
fn simulate<'py>(
    py: Python<'py>,
    study: &Bound<'py, PyAny>,
    profile_times: Option<Vec<Bound<'py, PyAny>>>,
) -> PyResult<Bound<'py, PyDict>> {
    let source = Source::from_py(study)?;
    let times: Option<Vec<f64>> = profile_times
        .map(|ts| {
            ts.iter()
                .enumerate()
                .map(|(i, t)| {
                    crate::arrays::quantity(
                        t,
                        &format!("profile_times[{i}]"),
                        nlvid_study::Dimension::TIME,
                    )
                })
                .collect()
        })
        .transpose()?;
    let st = source.load()?;
    let (name, provenance) = (st.name().to_string(), st.provenance());
    let sim = nlvid_forward::SimulateStudy::from_study(st).py()?;
    let profile_at = match (&sim.forward.spec, times) {
        (nlvid_forward::ForwardSpec::Membrane(spec), None) => vec![spec.program.end()],
        (_, Some(t)) => t,
        _ => Vec::new(),
    };
    let run = py
        .detach(|| sim.run(&profile_at))
        .py_ctx(|| format!("{name}: simulation failed"))?;
    let curve = run.curve().py()?;
    let params = nlvid_model::parameters_json(&sim.parameters());
    let d = PyDict::new(py);
    d.set_item("provenance", crate::pyjson::to_py(py, &provenance)?)?;
    d.set_item("model", sim.model())?;
    d.set_item("parameters", crate::pyjson::to_py(py, &params)?)?;
    d.set_item("curve", crate::pyjson::curve(py, &curve)?)?;
    let summary = run.summary_json().py()?;
    for (k, v) in summary.as_object().into_iter().flatten() {
        d.set_item(k, crate::pyjson::to_py(py, v)?)?;
    }
    let profiles = pyo3::types::PyList::empty(py);
    for (t, csv) in run.profiles_csv() {
        profiles.append((t, csv_columns(py, &csv)?))?;
    }
    if !profiles.is_empty() {
        d.set_item("profiles", profiles)?;
    }
    Ok(d)
}

/// A numeric CSV text (header row; `#` lines skipped) as column arrays.
fn csv_columns<'py>(py: Python<'py>, csv: &str) -> PyResult<Bound<'py, PyDict>> {
    let mut lines = csv
        .lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty());
    let header: Vec<&str> = lines
        .next()
        .map(|h| h.split(',').collect())
        .unwrap_or_default();
    let mut cols = vec![Vec::new(); header.len()];
    for l in lines {
        for (c, v) in cols.iter_mut().zip(l.split(',')) {
            c.push(v.trim().parse::<f64>().unwrap_or(f64::NAN));
        }
    }
    let d = PyDict::new(py);
    for (h, c) in header.iter().zip(cols) {
        d.set_item(h.trim(), PyArray1::from_vec(py, c))?;
    }
    Ok(d)
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(simulate, m)?)?;
    Ok(())
}
