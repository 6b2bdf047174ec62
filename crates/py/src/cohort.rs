//! Cohorts: the per-cell results table (`nlvid_stats::read_results`) as a
//! dict of numpy arrays, a whole cohort fit (`nlvid cohort`:
//! `nlvid_report::cohort::run_cohort`) and the group comparison
//! (`nlvid compare`: `nlvid_report::compare::compare`).

use std::path::{Path, PathBuf};

use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::arrays::quantity;
use crate::errors::{IntoPy, input};
use nlvid_study::Dimension;

/// The table as columns: `cell`, `group` (lists of str), `line` (int
/// array), `G0` (Pa), `g1`, `tau1` (s), … (float64 arrays), `excluded`
/// (list of dicts `cell`, `group`, `line`, `reason`), `terms`.
fn table_dict<'py>(py: Python<'py>, t: &nlvid_stats::ResultsTable) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let cells: Vec<&str> = t.cells.iter().map(|c| c.cell.as_str()).collect();
    let groups: Vec<&str> = t.cells.iter().map(|c| c.group.as_str()).collect();
    let lines: Vec<u64> = t.cells.iter().map(|c| c.line).collect();
    d.set_item("cell", cells)?;
    d.set_item("group", groups)?;
    d.set_item("line", PyArray1::from_vec(py, lines))?;
    let g0: Vec<f64> = t.cells.iter().map(|c| c.relaxation.g0()).collect();
    d.set_item("G0", PyArray1::from_vec(py, g0))?;
    for k in 0..t.terms {
        let term = |c: &nlvid_stats::CellRow| c.relaxation.prony().terms().get(k).copied();
        let g: Vec<f64> = t
            .cells
            .iter()
            .map(|c| term(c).map_or(f64::NAN, |p| p.weight))
            .collect();
        let tau: Vec<f64> = t
            .cells
            .iter()
            .map(|c| term(c).map_or(f64::NAN, |p| p.tau))
            .collect();
        d.set_item(format!("g{}", k + 1), PyArray1::from_vec(py, g))?;
        d.set_item(format!("tau{}", k + 1), PyArray1::from_vec(py, tau))?;
    }
    let excluded = pyo3::types::PyList::empty(py);
    for e in &t.excluded {
        let x = PyDict::new(py);
        x.set_item("cell", &e.cell)?;
        x.set_item("group", &e.group)?;
        x.set_item("line", e.line)?;
        x.set_item("reason", &e.reason)?;
        excluded.append(x)?;
    }
    d.set_item("excluded", excluded)?;
    d.set_item("terms", t.terms)?;
    let units = PyDict::new(py);
    units.set_item("G0", "Pa")?;
    for k in 0..t.terms {
        units.set_item(format!("g{}", k + 1), "1")?;
        units.set_item(format!("tau{}", k + 1), "s")?;
    }
    d.set_item("units", units)?;
    Ok(d)
}

/// Reads a per-cell results table (`results.csv` of a cohort; format of
/// docs/cli/compare.md) into a dict of columns (SI): `cell`, `group`,
/// `line`, `G0` (Pa), `g1`, `tau1` (s), …, `excluded`, `terms`, `units`.
#[pyfunction]
fn read_results<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyDict>> {
    let t = nlvid_stats::read_results(&path).py()?;
    table_dict(py, &t)
}

/// Compares the groups of a results table (`nlvid compare`): G(t),
/// G(t)/G(0), E(t) mean ± sd on a time grid (`t_end` with a unit and
/// `points`, or `times` as quantity strings) and the rank-sum p(t) between
/// two groups (`groups=("A", "B")`, default: the only two). `method`:
/// matlab, scipy, exact, asymptotic. Writes `<stem>.groups.csv` and
/// `<stem>.pvalues.csv` to `out_dir` (default: next to the table).
/// Returns the document `nlvid --json compare` prints plus `curves`:
/// per group `times`, `G_mean`, `G_sd`, `G_norm_mean`, `G_norm_sd`,
/// `E_mean`, `E_sd` arrays and, with a pair, `p_G`, `p_G_norm` arrays.
#[pyfunction]
#[pyo3(signature = (results, groups = None, t_end = None, points = 53, times = None, method = "matlab", out_dir = None))]
#[allow(clippy::too_many_arguments)]
fn compare<'py>(
    py: Python<'py>,
    results: PathBuf,
    groups: Option<Vec<String>>,
    t_end: Option<Bound<'py, PyAny>>,
    points: usize,
    times: Option<Vec<Bound<'py, PyAny>>>,
    method: &str,
    out_dir: Option<PathBuf>,
) -> PyResult<Bound<'py, PyDict>> {
    nlvid_report::compare::method(method).py()?;
    let grid = match (times, t_end) {
        (Some(_), Some(_)) => {
            return Err(input("give either times or t_end (with points), not both"));
        }
        (Some(ts), None) => ts
            .iter()
            .enumerate()
            .map(|(i, t)| quantity(t, &format!("times[{i}]"), Dimension::TIME))
            .collect::<PyResult<Vec<f64>>>()?,
        (None, t_end) => {
            let t_end = match t_end {
                Some(t) => quantity(&t, "t_end", Dimension::TIME)?,
                None => 52.0,
            };
            if t_end <= 0.0 {
                return Err(input("t_end: give a positive time, e.g. \"52 s\""));
            }
            nlvid_protocol::grid::uniform(0.0, t_end, points)
                .map_err(|e| input(format!("points {points}: {e}")))?
        }
    };
    let out_dir =
        out_dir.unwrap_or_else(|| results.parent().map(Path::to_path_buf).unwrap_or_default());
    let table = nlvid_stats::read_results(&results).py()?;
    let out = py
        .detach(|| {
            nlvid_report::compare::compare(
                &results,
                table,
                groups.as_deref(),
                &grid,
                method,
                &out_dir,
            )
        })
        .py()?;
    let d = crate::pyjson::dict(py, &out.to_json())?;
    let curves = PyDict::new(py);
    for g in &out.comparison.groups {
        let c = &g.curves;
        let e = PyDict::new(py);
        let col = |v: &[nlvid_stats::MeanSd], sd: bool| -> Vec<f64> {
            v.iter().map(|m| if sd { m.sd } else { m.mean }).collect()
        };
        e.set_item("times", PyArray1::from_slice(py, &c.times))?;
        e.set_item("n", c.n)?;
        e.set_item("G_mean", PyArray1::from_vec(py, col(&c.shear, false)))?;
        e.set_item("G_sd", PyArray1::from_vec(py, col(&c.shear, true)))?;
        e.set_item(
            "G_norm_mean",
            PyArray1::from_vec(py, col(&c.normalised, false)),
        )?;
        e.set_item(
            "G_norm_sd",
            PyArray1::from_vec(py, col(&c.normalised, true)),
        )?;
        e.set_item("E_mean", PyArray1::from_vec(py, col(&c.young, false)))?;
        e.set_item("E_sd", PyArray1::from_vec(py, col(&c.young, true)))?;
        curves.set_item(&c.name, e)?;
    }
    if let Some(p) = &out.comparison.pair {
        let pg: Vec<f64> = p.over_time.iter().map(|r| r.shear.p).collect();
        let pn: Vec<f64> = p.over_time.iter().map(|r| r.normalised.p).collect();
        curves.set_item("p_G", PyArray1::from_vec(py, pg))?;
        curves.set_item("p_G_norm", PyArray1::from_vec(py, pn))?;
    }
    d.set_item("curves", curves)?;
    Ok(d)
}

/// Fits every cell of a cohort (`nlvid cohort`): `input` a folder with one
/// sub-folder per group (each *.csv a cell) or a manifest CSV
/// (group,file); results in `out` (default `<study stem>-cohort` in the
/// current directory; re-running fits only the cells not yet done), without
/// the GIL. Returns the document `nlvid --json cohort` prints and
/// `results`: the results table as `read_results` gives it.
#[pyfunction]
#[pyo3(signature = (study, input, out = None))]
fn run_cohort<'py>(
    py: Python<'py>,
    study: PathBuf,
    input: PathBuf,
    out: Option<PathBuf>,
) -> PyResult<Bound<'py, PyDict>> {
    let settings = nlvid_report::settings::CohortSettings::load(&study).py()?;
    let cells = nlvid_report::cohort::discover(&input).py()?;
    let out = out.unwrap_or_else(|| {
        let stem = study
            .file_stem()
            .map_or_else(|| "study".into(), |s| s.to_string_lossy().into_owned());
        PathBuf::from(format!("{stem}-cohort"))
    });
    let opts = nlvid_report::cohort::RunOptions {
        max_new_fits: None,
        on_cell: None,
    };
    let run = py
        .detach(|| nlvid_report::cohort::run_cohort(&settings, &study, &input, &cells, &out, &opts))
        .py()?;
    let d = crate::pyjson::dict(py, &run.to_json(&out))?;
    let results = out.join("results.csv");
    if results.exists() {
        let t = nlvid_stats::read_results(&results).py()?;
        d.set_item("results", table_dict(py, &t)?)?;
    }
    Ok(d)
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(read_results, m)?)?;
    m.add_function(wrap_pyfunction!(compare, m)?)?;
    m.add_function(wrap_pyfunction!(run_cohort, m)?)?;
    Ok(())
}
