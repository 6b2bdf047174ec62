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
use crate::input::sorted_entries;
pub use crate::input::{CellInput, Geometry, default_out, discover};
use crate::settings::CohortSettings;

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
    /// What was written as `cohort.json` (settings, inputs, study).
    pub record: CohortRecord,
}

impl CohortOutcome {
    fn count(&self, s: CellStatus) -> usize {
        self.cells.iter().filter(|c| c.status == s).count()
    }

    fn listed(&self) -> impl Iterator<Item = &CellResult> {
        self.cells.iter().filter(|c| c.status != CellStatus::Ok)
    }

    /// The `--json` summary of the run written into `out`.
    pub fn to_json(&self, out: &Path) -> serde_json::Value {
        let s = &self.record.settings;
        serde_json::json!({
            "study_sha256": s.study_hash,
            "forward_model": s.model.describe(),
            "out": out,
            "cells": self.cells.len(),
            "fitted": self.fitted,
            "reused": self.reused,
            "ok": self.count(CellStatus::Ok),
            "suspicious": self.count(CellStatus::Suspicious),
            "failed": self.count(CellStatus::Failed),
            "listed": self.listed().map(|c| serde_json::json!({
                "group": c.group, "file": c.file, "status": c.status.as_str(), "reason": c.reason,
            })).collect::<Vec<_>>(),
            "results_csv": self.results_csv,
        })
    }

    /// When cells failed: their summary for stderr (`n of m cells failed`,
    /// then the first ten as `group/cell: reason`); `None` when all were
    /// fitted.
    pub fn failures_text(&self) -> Option<String> {
        use std::fmt::Write as _;
        let failed: Vec<&CellResult> = (self.cells.iter())
            .filter(|c| c.status == CellStatus::Failed)
            .collect();
        if failed.is_empty() {
            return None;
        }
        let mut t = format!(
            "error: {} of {} cells failed (status `failed` in results.csv):\n",
            failed.len(),
            self.cells.len()
        );
        for c in failed.iter().take(10) {
            let _ = writeln!(t, "  {}/{}: {}", c.group, c.cell, c.reason);
        }
        if failed.len() > 10 {
            let _ = writeln!(t, "  … and {} more", failed.len() - 10);
        }
        Some(t)
    }

    /// What the run did, for people: counts, cells not ok with the reason.
    pub fn text(&self) -> String {
        use std::fmt::Write as _;
        let mut t = format!(
            "forward model: {}\n{} cells: {} fitted now, {} reused from an earlier run; \
             {} ok, {} suspicious, {} failed\n",
            self.record.settings.model.describe(),
            self.cells.len(),
            self.fitted,
            self.reused,
            self.count(CellStatus::Ok),
            self.count(CellStatus::Suspicious),
            self.count(CellStatus::Failed)
        );
        for c in self.listed() {
            let _ = writeln!(t, "  {} {}: {}", c.status.as_str(), c.file, c.reason);
        }
        if let Some(r) = &self.results_csv {
            let _ = writeln!(t, "wrote {}", r.display());
        }
        t
    }
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
        record,
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
/// `base_diameter_m`), the posterior when sampled (`post_*`: lower,
/// median and upper of the credible intervals of G0, g1 + g2 and G(t_end),
/// the noise sd estimated from the curve, the largest split R̂ and the
/// smallest effective sample size), `status`, `reason`, `flags`. Numbers
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
            "post_G0_lo_Pa",
            "post_G0_median_Pa",
            "post_G0_hi_Pa",
            "post_g_sum_lo",
            "post_g_sum_median",
            "post_g_sum_hi",
            "post_G_end_lo_Pa",
            "post_G_end_median_Pa",
            "post_G_end_hi_Pa",
            "post_noise_N",
            "post_rhat_max",
            "post_ess_min",
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
        let p = c.posterior.as_ref();
        for iv in [p.map(|p| p.g0), p.map(|p| p.g_sum), p.map(|p| p.g_end)] {
            row.push(num(iv.map(|i| i.lower)));
            row.push(num(iv.map(|i| i.median)));
            row.push(num(iv.map(|i| i.upper)));
        }
        row.push(num(p.map(|p| p.noise_sd)));
        row.push(num(p.map(|p| p.rhat_max)));
        row.push(num(p.map(|p| p.ess_min)));
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

/// The results table of `cells` in memory, as [`nlvid_stats::read_results`]
/// would read it back from [`results_csv`] (same rows, same order, lines
/// numbered as in that file): cells with status `ok` are used, the others
/// listed as excluded with their status and reason.
///
/// # Errors
/// A fitted cell without `G0` or with inadmissible Prony parameters.
pub fn results_table(cells: &[CellResult]) -> Result<nlvid_stats::ResultsTable> {
    use nlvid_model::{Prony, Relaxation, names};
    use nlvid_stats::{CellRow, Excluded, ResultsTable};
    let mut sorted: Vec<&CellResult> = cells.iter().collect();
    sorted.sort_by(|a, b| (&a.group, &a.file).cmp(&(&b.group, &b.file)));
    let terms = parameter_names(cells).map_or(0, |names| {
        (1..)
            .take_while(|k| names.iter().any(|(n, _)| *n == format!("tau{k}")))
            .count()
    });
    let mut table = ResultsTable {
        cells: Vec::new(),
        excluded: Vec::new(),
        terms,
    };
    for (i, c) in sorted.into_iter().enumerate() {
        let line = i as u64 + 2;
        if c.status != CellStatus::Ok {
            table.excluded.push(Excluded {
                cell: c.cell.clone(),
                group: c.group.clone(),
                line,
                reason: if c.reason.is_empty() {
                    c.status.as_str().to_string()
                } else {
                    format!("{}: {}", c.status.as_str(), c.reason)
                },
            });
            continue;
        }
        let missing = |name: &str| {
            ReportError::InvalidSetting(format!(
                "cell {} of group {}: no fitted `{name}`",
                c.cell, c.group
            ))
        };
        let g0 = c.parameter("G0").ok_or_else(|| missing("G0"))?;
        let mut prony_terms = Vec::with_capacity(terms);
        for k in 1..=terms {
            let (g, tau) = (format!("g{k}"), format!("tau{k}"));
            prony_terms.push((
                c.parameter(&g).ok_or_else(|| missing(&g))?,
                c.parameter(&tau).ok_or_else(|| missing(&tau))?,
            ));
        }
        table.cells.push(CellRow {
            cell: c.cell.clone(),
            group: c.group.clone(),
            line,
            relaxation: Relaxation::new(names::G0, g0, Prony::new("G", &prony_terms)?)?,
        });
    }
    Ok(table)
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cell::ParamValue;

    fn cell(group: &str, file: &str, status: CellStatus, p: [f64; 5]) -> CellResult {
        let names = [
            ("G0", "Pa"),
            ("g1", ""),
            ("g2", ""),
            ("tau1", "s"),
            ("tau2", "s"),
        ];
        let reason = if status == CellStatus::Ok {
            String::new()
        } else {
            "misfit 0.2 above fit.suspicious_misfit = 0.05".into()
        };
        let cell = file.trim_end_matches(".csv");
        CellResult {
            status,
            parameters: names
                .iter()
                .zip(p)
                .map(|((n, u), value)| ParamValue {
                    name: n.to_string(),
                    unit: u.to_string(),
                    value,
                })
                .collect(),
            misfit: Some(0.01),
            peak_force: Some(1e-9),
            relaxation: Some(0.4),
            ..CellResult::failed(group, file, cell, "h", reason)
        }
    }

    /// The in-memory table is what `nlvid compare` reads back from
    /// results.csv: same cells, values bit for bit, same lines, same
    /// exclusions (the CSV reader is the second method).
    #[test]
    fn the_in_memory_results_table_equals_the_csv_read_back() {
        let cells = vec![
            cell(
                "b",
                "b/2.csv",
                CellStatus::Ok,
                [1234.5, 0.31, 0.2, 0.37, 7.1],
            ),
            cell(
                "a",
                "a/1.csv",
                CellStatus::Ok,
                [1.0 / 3.0 * 1e3, 0.1, 0.45, 0.02, 3.0],
            ),
            cell(
                "a",
                "a/2.csv",
                CellStatus::Suspicious,
                [900.0, 0.2, 0.2, 0.1, 9.0],
            ),
            cell("b", "b/1.csv", CellStatus::Ok, [2e3, 0.25, 0.25, 1.1, 39.0]),
        ];
        let csv = results_csv(&cells).expect("csv");
        let read = nlvid_stats::parse_results(csv.as_bytes(), Path::new("results.csv"))
            .expect("read back");
        let memory = results_table(&cells).expect("memory");
        assert_eq!(memory, read);
        assert_eq!(memory.cells.len(), 3);
        assert_eq!(memory.excluded.len(), 1);
        assert_eq!(memory.terms, 2);
    }
}
