//! A cohort: every cell of a study fitted once, in parallel, resumably.
//!
//! Layout of an output directory:
//! - `cells/<group>/<file>.json`: one [`CellResult`] per cell, written
//!   atomically when its fit ends; a re-run reuses every file whose study
//!   hash matches and fits only the missing cells;
//! - `results.csv`: one row per cell in the format of docs/cli/compare.md,
//!   sorted by group then file, written once every cell is done;
//! - `cohort.json`: the settings and the input list (read by the report).
//!
//! Every cell is fitted with the same seed, so a cell's result does not
//! depend on the order, the thread count or an interruption.

use std::fs;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::cell::{CellModel, CellResult, CellStatus, fit_cell};
use crate::error::{ReportError, Result};
use crate::settings::CohortSettings;

/// One cell to fit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CellInput {
    /// Group name.
    pub group: String,
    /// File as named in the input (relative to the folder or manifest).
    pub file: String,
    /// Path to read.
    pub path: PathBuf,
    /// Geometry measurements from the manifest (App. B.2), if any.
    #[serde(default)]
    pub geometry: Geometry,
}

/// A cell's geometry measurements as given in a manifest (App. B.2).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Geometry {
    /// JPK approach curves on the cell and on the nearby glass (same
    /// z-stepper position): columns `height_cell_curve`, `height_glass_curve`.
    pub height_curves: Option<(PathBuf, PathBuf)>,
    /// Two distances on an optical image, m: columns `d1_um`, `d2_um`
    /// (or `d1_m`, `d2_m`).
    pub image_distances: Option<(f64, f64)>,
}

/// The cells of a cohort input: a folder whose sub-folders are the groups
/// (each `*.csv` in them a cell), or a manifest CSV with columns `group`
/// and `file` (relative to the manifest's directory) and optionally the
/// geometry columns of [`Geometry`]. Sorted by group, file.
///
/// # Errors
/// Unreadable folder or manifest, a manifest row without group or file
/// (naming the line), a missing data file, duplicate cells, no cells.
pub fn discover(input: &Path) -> Result<Vec<CellInput>> {
    let mut cells = if input.is_dir() {
        from_folder(input)?
    } else {
        from_manifest(input)?
    };
    cells.sort_by(|a, b| (&a.group, &a.file).cmp(&(&b.group, &b.file)));
    if let Some(w) = cells
        .windows(2)
        .find(|w| w[0].group == w[1].group && w[0].file == w[1].file)
    {
        return Err(ReportError::Data {
            path: input.to_path_buf(),
            line: 0,
            message: format!(
                "cell `{}` of group `{}` is listed twice",
                w[0].file, w[0].group
            ),
        });
    }
    if cells.is_empty() {
        return Err(ReportError::Data {
            path: input.to_path_buf(),
            line: 0,
            message: "no cells: expected group sub-folders with *.csv files, or a manifest \
                      with columns group,file"
                .into(),
        });
    }
    Ok(cells)
}

fn sorted_entries(dir: &Path) -> Result<Vec<PathBuf>> {
    let mut v: Vec<PathBuf> = fs::read_dir(dir)
        .map_err(|e| ReportError::io(dir, e))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .collect();
    v.sort();
    Ok(v)
}

fn from_folder(dir: &Path) -> Result<Vec<CellInput>> {
    let mut cells = Vec::new();
    for sub in sorted_entries(dir)? {
        if !sub.is_dir() {
            continue;
        }
        let group = sub
            .file_name()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        for f in sorted_entries(&sub)? {
            if f.is_file() && f.extension().is_some_and(|e| e.eq_ignore_ascii_case("csv")) {
                let name = f
                    .file_name()
                    .map(|s| s.to_string_lossy().into_owned())
                    .unwrap_or_default();
                cells.push(CellInput {
                    group: group.clone(),
                    file: format!("{group}/{name}"),
                    path: f,
                    geometry: Geometry::default(),
                });
            }
        }
    }
    Ok(cells)
}

fn from_manifest(path: &Path) -> Result<Vec<CellInput>> {
    let base = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let mut rdr = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .comment(Some(b'#'))
        .from_path(path)
        .map_err(|e| ReportError::io(path, e))?;
    let headers = rdr.headers().map_err(|e| ReportError::io(path, e))?.clone();
    let col = |name: &str| {
        headers
            .iter()
            .position(|h| h == name)
            .ok_or_else(|| ReportError::Data {
                path: path.to_path_buf(),
                line: 1,
                message: format!("manifest has no column `{name}` (needs group,file)"),
            })
    };
    let (gi, fi) = (col("group")?, col("file")?);
    let find = |name: &str| headers.iter().position(|h| h == name);
    let curves = (find("height_cell_curve"), find("height_glass_curve"));
    let (dist, dist_scale) = match (find("d1_um"), find("d2_um"), find("d1_m"), find("d2_m")) {
        (Some(a), Some(b), _, _) => (Some((a, b, "d1_um", "d2_um")), 1e-6),
        (_, _, Some(a), Some(b)) => (Some((a, b, "d1_m", "d2_m")), 1.0),
        _ => (None, 1.0),
    };
    if curves.0.is_some() != curves.1.is_some() {
        return Err(ReportError::Data {
            path: path.to_path_buf(),
            line: 1,
            message: "cell height needs both columns height_cell_curve and height_glass_curve"
                .into(),
        });
    }
    let mut cells = Vec::new();
    for rec in rdr.records() {
        let rec = rec.map_err(|e| ReportError::io(path, e))?;
        let line = rec.position().map_or(0, |p| p.line());
        let get = |i: usize, what: &str| match rec.get(i) {
            Some(s) if !s.is_empty() => Ok(s.to_string()),
            _ => Err(ReportError::Data {
                path: path.to_path_buf(),
                line,
                message: format!("empty `{what}`"),
            }),
        };
        let (group, file) = (get(gi, "group")?, get(fi, "file")?);
        let p = base.join(&file);
        if !p.is_file() {
            return Err(ReportError::Data {
                path: path.to_path_buf(),
                line,
                message: format!("column `file`: no such file {}", p.display()),
            });
        }
        let mut geometry = Geometry::default();
        if let (Some(ci), Some(gi)) = curves {
            let (c, g) = (rec.get(ci).unwrap_or(""), rec.get(gi).unwrap_or(""));
            if !c.is_empty() || !g.is_empty() {
                let cp = base.join(get(ci, "height_cell_curve")?);
                let gp = base.join(get(gi, "height_glass_curve")?);
                for (p, name) in [(&cp, "height_cell_curve"), (&gp, "height_glass_curve")] {
                    if !p.is_file() {
                        return Err(ReportError::Data {
                            path: path.to_path_buf(),
                            line,
                            message: format!("column `{name}`: no such file {}", p.display()),
                        });
                    }
                }
                geometry.height_curves = Some((cp, gp));
            }
        }
        if let Some((a, b, na, nb)) = dist {
            let num = |i: usize, name: &str| -> Result<Option<f64>> {
                match rec.get(i).unwrap_or("") {
                    "" => Ok(None),
                    v => v.parse::<f64>().map(Some).map_err(|_| ReportError::Data {
                        path: path.to_path_buf(),
                        line,
                        message: format!("column `{name}`: `{v}` is not a number"),
                    }),
                }
            };
            match (num(a, na)?, num(b, nb)?) {
                (Some(x), Some(y)) => {
                    geometry.image_distances = Some((x * dist_scale, y * dist_scale))
                }
                (None, None) => {}
                _ => {
                    return Err(ReportError::Data {
                        path: path.to_path_buf(),
                        line,
                        message: format!("give both `{na}` and `{nb}` or neither"),
                    });
                }
            }
        }
        cells.push(CellInput {
            group,
            file,
            path: p,
            geometry,
        });
    }
    Ok(cells)
}

/// Path of the per-cell result file of `cell` under `out_dir`.
pub fn cell_result_path(out_dir: &Path, cell: &CellInput) -> PathBuf {
    let clean = |s: &str| -> String {
        s.chars()
            .map(|c| {
                if c.is_ascii_alphanumeric() || "-_.".contains(c) {
                    c
                } else {
                    '_'
                }
            })
            .collect()
    };
    let file = cell.file.replace(['/', '\\'], "__");
    out_dir
        .join("cells")
        .join(clean(&cell.group))
        .join(format!("{}.json", clean(&file)))
}

/// Writes `bytes` to `path` via a temporary file in the same directory and
/// a rename: readers (and a resumed run) see the old file or the whole new
/// one, never a part.
///
/// # Errors
/// [`ReportError::Io`].
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        fs::create_dir_all(dir).map_err(|e| ReportError::io(dir, e))?;
    }
    nlvid_study::write_atomic(path, bytes).map_err(|e| ReportError::io(path, e))
}

/// A finished cell from an earlier run, if its file is complete and was
/// fitted with the same study (anything else is fitted again).
fn reuse(path: &Path, input: &CellInput, hash: &str) -> Option<CellResult> {
    let bytes = fs::read(path).ok()?;
    let r: CellResult = serde_json::from_slice(&bytes).ok()?;
    (r.study_hash == hash && r.group == input.group && r.file == input.file).then_some(r)
}

/// Options of [`run_cohort`].
#[derive(Default)]
pub struct RunOptions<'a> {
    /// Stop starting new fits after this many (the run is then incomplete:
    /// no results table). Simulates an interrupted run in tests.
    pub max_new_fits: Option<usize>,
    /// Called after each cell (fitted or reused), from worker threads.
    pub on_cell: Option<&'a (dyn Fn(&CellResult) + Sync)>,
}

/// What a run did.
#[derive(Debug, Clone, PartialEq)]
pub struct CohortOutcome {
    /// Results of the cells done, sorted by group, file.
    pub cells: Vec<CellResult>,
    /// Cells fitted in this run.
    pub fitted: usize,
    /// Cells reused from an earlier run.
    pub reused: usize,
    /// Cells not done (only with `max_new_fits`).
    pub pending: usize,
    /// `results.csv`, when every cell is done.
    pub results_csv: Option<PathBuf>,
}

/// The run record written as `cohort.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CohortRecord {
    /// Settings used.
    pub settings: CohortSettings,
    /// Cells of the input.
    pub cells: Vec<CellInput>,
    /// Study file.
    pub study: PathBuf,
    /// Cohort input (folder or manifest).
    pub input: PathBuf,
}

/// Fits every cell not already done in `out_dir` (in parallel), writes one
/// result file per cell as it finishes, then `results.csv` and
/// `cohort.json`.
///
/// # Errors
/// The output directory cannot be written. Failing cells are results, not
/// errors.
pub fn run_cohort(
    settings: &CohortSettings,
    study: &Path,
    input: &Path,
    cells: &[CellInput],
    out_dir: &Path,
    opts: &RunOptions<'_>,
) -> Result<CohortOutcome> {
    fs::create_dir_all(out_dir).map_err(|e| ReportError::io(out_dir, e))?;
    let record = CohortRecord {
        settings: settings.clone(),
        cells: cells.to_vec(),
        study: study.to_path_buf(),
        input: input.to_path_buf(),
    };
    let json = serde_json::to_vec_pretty(&record)
        .map_err(|e| ReportError::io(out_dir.join("cohort.json"), e))?;
    write_atomic(&out_dir.join("cohort.json"), &json)?;

    let model = CellModel::load(settings)?;
    let started = AtomicUsize::new(0);
    let done: Vec<Result<Option<(CellResult, bool)>>> = cells
        .par_iter()
        .map(|c| {
            let path = cell_result_path(out_dir, c);
            if let Some(r) = reuse(&path, c, &settings.study_hash) {
                if let Some(f) = opts.on_cell {
                    f(&r);
                }
                return Ok(Some((r, false)));
            }
            if let Some(max) = opts.max_new_fits
                && started.fetch_add(1, Ordering::SeqCst) >= max
            {
                return Ok(None);
            }
            let r = fit_cell(settings, &model, c);
            let bytes = serde_json::to_vec(&r).map_err(|e| ReportError::io(&path, e))?;
            write_atomic(&path, &bytes)?;
            if let Some(f) = opts.on_cell {
                f(&r);
            }
            Ok(Some((r, true)))
        })
        .collect();
    let mut out = CohortOutcome {
        cells: Vec::new(),
        fitted: 0,
        reused: 0,
        pending: 0,
        results_csv: None,
    };
    for d in done {
        match d? {
            Some((r, new)) => {
                if new {
                    out.fitted += 1;
                } else {
                    out.reused += 1;
                }
                out.cells.push(r);
            }
            None => out.pending += 1,
        }
    }
    if out.pending == 0 {
        let path = out_dir.join("results.csv");
        write_atomic(&path, results_csv(&out.cells)?.as_bytes())?;
        out.results_csv = Some(path);
    }
    Ok(out)
}

/// Column name with its unit suffix, as docs/cli/compare.md reads it
/// (none for a dimensionless parameter, unit `1`).
fn column(name: &str, unit: &str) -> String {
    if unit.is_empty() || unit == "1" {
        name.to_string()
    } else {
        format!("{name}_{}", unit.replace('/', "_per_"))
    }
}

/// `(name, unit)` of the fitted parameters, from the first cell that has
/// any (all cells of a cohort share one model); `None` when none has.
pub(crate) fn parameter_names(cells: &[CellResult]) -> Option<Vec<(String, String)>> {
    cells.iter().find(|c| !c.parameters.is_empty()).map(|c| {
        c.parameters
            .iter()
            .map(|p| (p.name.clone(), p.unit.clone()))
            .collect()
    })
}

/// The results table (docs/cli/compare.md format): `group, cell, file`,
/// the parameters with unit-suffixed names, `misfit`, `alternatives`,
/// `peak_force_N`, `relaxation_pct`, the Hertz baseline (`hertz_E_Pa`,
/// `hertz_misfit`, `hertz_window`), the geometry (`cell_height_m`,
/// `base_diameter_m`), `status`, `reason`, `flags`. Numbers
/// in shortest round-trip form; empty cells where a value is missing.
///
/// # Errors
/// Never in practice (CSV into memory).
pub fn results_csv(cells: &[CellResult]) -> Result<String> {
    let names: Vec<(String, String)> = parameter_names(cells).unwrap_or_else(|| {
        [
            ("G0", "Pa"),
            ("g1", ""),
            ("tau1", "s"),
            ("g2", ""),
            ("tau2", "s"),
        ]
        .iter()
        .map(|(a, b)| (a.to_string(), b.to_string()))
        .collect()
    });
    let mut w = csv::Writer::from_writer(Vec::new());
    let mut header = vec!["group".to_string(), "cell".into(), "file".into()];
    header.extend(names.iter().map(|(n, u)| column(n, u)));
    header.extend(
        [
            "misfit",
            "alternatives",
            "peak_force_N",
            "relaxation_pct",
            "hertz_E_Pa",
            "hertz_misfit",
            "hertz_window",
            "cell_height_m",
            "base_diameter_m",
            "status",
            "reason",
            "flags",
        ]
        .map(String::from),
    );
    let err = |e: csv::Error| ReportError::io("results.csv", e);
    w.write_record(&header).map_err(err)?;
    let num = |v: Option<f64>| v.map_or_else(String::new, |x| format!("{x}"));
    let mut sorted: Vec<&CellResult> = cells.iter().collect();
    sorted.sort_by(|a, b| (&a.group, &a.file).cmp(&(&b.group, &b.file)));
    for c in sorted {
        let mut row = vec![c.group.clone(), c.cell.clone(), c.file.clone()];
        for (n, _) in &names {
            row.push(num(c.parameter(n)));
        }
        row.push(num(c.misfit));
        row.push(if c.status == CellStatus::Failed {
            String::new()
        } else {
            c.alternatives.to_string()
        });
        row.push(num(c.peak_force));
        row.push(num(c.relaxation.map(|r| 100.0 * r)));
        row.push(num(c.hertz.as_ref().map(|h| h.youngs_modulus)));
        row.push(num(c.hertz.as_ref().map(|h| h.misfit)));
        row.push(
            c.hertz
                .as_ref()
                .map_or_else(String::new, |h| h.window.clone()),
        );
        row.push(num(c.cell_height));
        row.push(num(c.base_diameter));
        row.push(c.status.as_str().into());
        row.push(c.reason.clone());
        row.push(c.flags.join("; "));
        w.write_record(&row).map_err(err)?;
    }
    let bytes = w
        .into_inner()
        .map_err(|e| ReportError::io("results.csv", e.error()))?;
    String::from_utf8(bytes).map_err(|e| ReportError::io("results.csv", e))
}

/// Reads every per-cell result of a cohort output directory, sorted by
/// group, file.
///
/// # Errors
/// Unreadable directory or a result file that is not valid JSON (naming it).
pub fn read_cells(out_dir: &Path) -> Result<Vec<CellResult>> {
    let root = out_dir.join("cells");
    let mut cells = Vec::new();
    for g in sorted_entries(&root)? {
        if !g.is_dir() {
            continue;
        }
        for f in sorted_entries(&g)? {
            if f.extension().is_some_and(|e| e == "json")
                && !f
                    .file_name()
                    .is_some_and(|n| n.to_string_lossy().starts_with('.'))
            {
                let bytes = fs::read(&f).map_err(|e| ReportError::io(&f, e))?;
                let r: CellResult =
                    serde_json::from_slice(&bytes).map_err(|e| ReportError::Data {
                        path: f.clone(),
                        line: e.line() as u64,
                        message: format!("not a cell result: {e}"),
                    })?;
                cells.push(r);
            }
        }
    }
    cells.sort_by(|a, b| (&a.group, &a.file).cmp(&(&b.group, &b.file)));
    Ok(cells)
}

/// Reads `cohort.json` of a cohort output directory.
///
/// # Errors
/// Missing or malformed file.
pub fn read_record(out_dir: &Path) -> Result<CohortRecord> {
    let p = out_dir.join("cohort.json");
    let bytes = fs::read(&p).map_err(|e| {
        ReportError::io(
            &p,
            format!("{e} (is this the output directory of `nlvid cohort`?)"),
        )
    })?;
    serde_json::from_slice(&bytes).map_err(|e| ReportError::Data {
        path: p.clone(),
        line: e.line() as u64,
        message: e.to_string(),
    })
}
