//! The per-cell results table (`results.csv`, written by `nlvid cohort`,
//! read by `nlvid compare`) and the CSV outputs of a comparison.
//!
//! Input columns (header row, any order, other columns ignored):
//! - `group` (required): group name;
//! - `cell` or `file` (optional): cell identifier (default: `line N`);
//! - `G0_<unit>` (required), a pressure unit (Pa, kPa, MPa): the shear
//!   modulus G(0) of eq. 5.1 (a `C1` column is refused: it is eq. 4.1's
//!   constant, G0 = 2(C1 + C2); `docs/theory/model.md`);
//! - `g1`, `tau1_<unit>`, `g2`, `tau2_<unit>`, … : Prony weights (no unit)
//!   and times (any time unit: s, ms, min), numbered from 1 without gaps;
//! - `status` (optional): empty or `ok` uses the row; any other value
//!   excludes it, and the exclusion is reported with the `reason` column
//!   (optional) — rows are never dropped silently.
//!
//! Units may also be written `G0 [kPa]` or `tau1 (s)`.

use std::io::Write;
use std::path::{Path, PathBuf};

use crate::groups::{GroupCurves, TimeComparison};
use crate::{Result, StatsError};
use nlvid_model::{Prony, Relaxation, names};

/// A cell used in the comparison.
#[derive(Debug, Clone, PartialEq)]
pub struct CellRow {
    /// Cell identifier.
    pub cell: String,
    /// Group name.
    pub group: String,
    /// 1-based line in the file.
    pub line: u64,
    /// Its shear relaxation modulus G(t) of eq. 5.1 (the shared
    /// `nlvid_model::Relaxation`, `G0` the shear modulus).
    pub relaxation: Relaxation,
}

/// A row excluded by its `status`.
#[derive(Debug, Clone, PartialEq)]
pub struct Excluded {
    /// Cell identifier.
    pub cell: String,
    /// Group name.
    pub group: String,
    /// 1-based line in the file.
    pub line: u64,
    /// The status value and reason, as written.
    pub reason: String,
}

/// A parsed results table.
#[derive(Debug, Clone, PartialEq)]
pub struct ResultsTable {
    /// Rows used, in file order.
    pub cells: Vec<CellRow>,
    /// Rows excluded by their status, in file order.
    pub excluded: Vec<Excluded>,
    /// Number of Prony terms per cell.
    pub terms: usize,
}

impl ResultsTable {
    /// Group names in order of first appearance among used rows.
    pub fn groups(&self) -> Vec<String> {
        let mut out: Vec<String> = Vec::new();
        for c in &self.cells {
            if !out.contains(&c.group) {
                out.push(c.group.clone());
            }
        }
        out
    }

    /// The relaxation moduli of one group's cells.
    pub fn group(&self, name: &str) -> Vec<Relaxation> {
        self.cells
            .iter()
            .filter(|c| c.group == name)
            .map(|c| c.relaxation.clone())
            .collect()
    }
}

fn split_header(raw: &str) -> (String, String) {
    let raw = raw.trim();
    for (o, c) in [('[', ']'), ('(', ')')] {
        if let Some(inner) = raw.strip_suffix(c)
            && let Some(open) = inner.rfind(o)
        {
            return (
                inner[..open].trim().to_string(),
                inner[open + 1..].trim().to_string(),
            );
        }
    }
    match raw.rsplit_once('_') {
        Some((n, u)) => (n.to_string(), u.to_string()),
        None => (raw.to_string(), String::new()),
    }
}

/// SI factor of `unit` if it has dimension `dim` (study crate's parser).
fn unit_factor(unit: &str, dim: nlvid_study::Dimension) -> Option<f64> {
    if unit.trim().is_empty() {
        return None;
    }
    match nlvid_study::parse_unit(unit) {
        Ok((f, d)) if d == dim => Some(f),
        _ => None,
    }
}

fn modulus_unit(u: &str) -> Option<f64> {
    unit_factor(u, nlvid_study::Dimension::PRESSURE)
}

fn time_unit(u: &str) -> Option<f64> {
    unit_factor(u, nlvid_study::Dimension::TIME)
}

/// Read a results table from a file.
///
/// # Errors
/// Unreadable file, malformed CSV, missing columns or units, a cell value
/// that is not a finite number, inadmissible Prony parameters — each
/// naming the file, line and column.
pub fn read_results(path: &Path) -> Result<ResultsTable> {
    let file = std::fs::File::open(path).map_err(|source| StatsError::Io {
        file: path.to_path_buf(),
        source,
    })?;
    parse_results(file, path)
}

/// As [`read_results`], from any reader; `source` names it in errors.
///
/// # Errors
/// As [`read_results`].
pub fn parse_results<R: std::io::Read>(reader: R, source: &Path) -> Result<ResultsTable> {
    let file: PathBuf = source.to_path_buf();
    let err = |line: u64, column: Option<&str>, message: String| StatsError::Table {
        file: file.clone(),
        line,
        column: column.map(str::to_string),
        message,
    };
    let mut rdr = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .from_reader(reader);
    let raw: Vec<String> = rdr
        .headers()
        .map_err(|e| err(1, None, e.to_string()))?
        .iter()
        .map(str::to_string)
        .collect();
    let find = |pred: &dyn Fn(&str, &str) -> bool| -> Vec<usize> {
        (0..raw.len())
            .filter(|&i| {
                let (n, u) = split_header(&raw[i]);
                pred(&n, &u)
            })
            .collect()
    };
    let one = |name: &str, idx: Vec<usize>, required: bool| -> Result<Option<usize>> {
        match idx.as_slice() {
            [] if required => Err(err(
                1,
                None,
                format!("missing column `{name}` (header: {})", raw.join(", ")),
            )),
            [] => Ok(None),
            [i] => Ok(Some(*i)),
            _ => Err(err(1, None, format!("more than one `{name}` column"))),
        }
    };
    let named = |want: &str| -> Vec<usize> {
        (0..raw.len())
            .filter(|&i| raw[i].trim().eq_ignore_ascii_case(want))
            .collect()
    };
    let group_col = one("group", named("group"), true)?.unwrap_or(0);
    let cell_col = match one("cell", named("cell"), false)? {
        Some(i) => Some(i),
        None => one("file", named("file"), false)?,
    };
    let status_col = one("status", named("status"), false)?;
    let reason_col = one("reason", named("reason"), false)?;

    let g0_cols = find(&|n, _| n == names::G0);
    if g0_cols.is_empty() && !find(&|n, _| n == names::C1).is_empty() {
        return Err(err(
            1,
            Some(names::C1),
            "G(t) of eq. 5.1 needs the shear modulus column `G0_<unit>`; `C1` is the \
             Mooney–Rivlin constant of eq. 4.1 (G0 = 2(C1 + C2), docs/theory/model.md)"
                .into(),
        ));
    }
    let g0_col = one("G0_<unit>", g0_cols, true)?.unwrap_or(0);
    let (_, g0_unit) = split_header(&raw[g0_col]);
    let g0_scale = modulus_unit(&g0_unit).ok_or_else(|| {
        err(
            1,
            Some(&raw[g0_col]),
            "G0 needs a modulus (pressure) unit such as Pa or kPa (e.g. `G0_kPa`)".into(),
        )
    })?;
    let mut term_cols: Vec<(usize, usize, f64)> = Vec::new();
    for k in 1.. {
        let gname = format!("g{k}");
        let tname = format!("tau{k}");
        let gi = one(&gname, find(&|n, u| n == gname && u.is_empty()), false)?;
        let ti = one(&tname, find(&|n, _| n == tname), false)?;
        match (gi, ti) {
            (None, None) => break,
            (Some(_), None) => {
                return Err(err(
                    1,
                    None,
                    format!("`{gname}` has no `{tname}_<unit>` column"),
                ));
            }
            (None, Some(_)) => {
                return Err(err(1, None, format!("`{tname}` has no `{gname}` column")));
            }
            (Some(gi), Some(ti)) => {
                let (_, u) = split_header(&raw[ti]);
                let scale = time_unit(&u).ok_or_else(|| {
                    err(
                        1,
                        Some(&raw[ti]),
                        format!("{tname} needs a time unit such as s or ms (e.g. `{tname}_s`)"),
                    )
                })?;
                term_cols.push((gi, ti, scale));
            }
        }
    }

    let mut cells = Vec::new();
    let mut excluded = Vec::new();
    for rec in rdr.records() {
        let rec = rec.map_err(|e| {
            err(
                e.position().map_or(0, |p| p.line()),
                None,
                format!("malformed CSV: {e}"),
            )
        })?;
        let line = rec.position().map_or(0, |p| p.line());
        let get = |i: usize| rec.get(i).unwrap_or("").to_string();
        let group = get(group_col);
        if group.is_empty() {
            return Err(err(line, Some(&raw[group_col]), "empty group name".into()));
        }
        let cell = cell_col.map_or_else(|| format!("line {line}"), get);
        let status = status_col.map(get).unwrap_or_default();
        if !(status.is_empty() || status.eq_ignore_ascii_case("ok")) {
            let reason = reason_col.map(get).unwrap_or_default();
            let reason = if reason.is_empty() {
                status
            } else {
                format!("{status}: {reason}")
            };
            excluded.push(Excluded {
                cell,
                group,
                line,
                reason,
            });
            continue;
        }
        let num = |i: usize, scale: f64| -> Result<f64> {
            let s = get(i);
            if s.is_empty() {
                return Err(err(
                    line,
                    Some(&raw[i]),
                    "empty cell (a used row needs every parameter; set `status` to exclude it)"
                        .into(),
                ));
            }
            let v: f64 = s
                .parse()
                .map_err(|_| err(line, Some(&raw[i]), format!("`{s}` is not a number")))?;
            if !v.is_finite() {
                return Err(err(line, Some(&raw[i]), format!("`{s}` is not finite")));
            }
            Ok(v * scale)
        };
        let g0 = num(g0_col, g0_scale)?;
        if !(g0 > 0.0) {
            return Err(err(
                line,
                Some(&raw[g0_col]),
                format!("G0 = {g0} Pa must be > 0 (the shear modulus G(0) of eq. 5.1)"),
            ));
        }
        let mut terms = Vec::with_capacity(term_cols.len());
        for &(gi, ti, scale) in &term_cols {
            terms.push((num(gi, 1.0)?, num(ti, scale)?));
        }
        let relaxation = Prony::new("G", &terms)
            .and_then(|p| Relaxation::new(names::G0, g0, p))
            .map_err(|e| err(line, None, format!("Prony parameters: {e}")))?;
        cells.push(CellRow {
            cell,
            group,
            line,
            relaxation,
        });
    }
    Ok(ResultsTable {
        cells,
        excluded,
        terms: term_cols.len(),
    })
}

fn write_err<E: std::fmt::Display>(e: E) -> StatsError {
    StatsError::Write(e.to_string())
}

/// Write group curves in long format, one row per group and time:
/// `group,n,time_s,G_mean_Pa,G_sd_Pa,G_norm_mean,G_norm_sd,E_mean_Pa,E_sd_Pa`.
///
/// # Errors
/// The writer fails.
pub fn write_group_curves<W: Write>(w: W, groups: &[GroupCurves]) -> Result<()> {
    let mut out = csv::Writer::from_writer(w);
    out.write_record([
        "group",
        "n",
        "time_s",
        "G_mean_Pa",
        "G_sd_Pa",
        "G_norm_mean",
        "G_norm_sd",
        "E_mean_Pa",
        "E_sd_Pa",
    ])
    .map_err(write_err)?;
    for g in groups {
        for (i, t) in g.times.iter().enumerate() {
            out.write_record([
                g.name.clone(),
                g.n.to_string(),
                t.to_string(),
                g.shear[i].mean.to_string(),
                g.shear[i].sd.to_string(),
                g.normalised[i].mean.to_string(),
                g.normalised[i].sd.to_string(),
                g.young[i].mean.to_string(),
                g.young[i].sd.to_string(),
            ])
            .map_err(write_err)?;
        }
    }
    out.flush().map_err(write_err)
}

/// Write the comparison of two groups over time:
/// `time_s,p_G,method_G,z_G,p_G_norm,method_G_norm,rank_biserial_G,hodges_lehmann_G_Pa`.
/// `p_G` also holds for E(t) = 3G(t); `p_G_norm` for the relaxation amount.
/// `z_G` is empty for the exact method.
///
/// # Errors
/// The writer fails.
pub fn write_time_comparisons<W: Write>(w: W, rows: &[TimeComparison]) -> Result<()> {
    let mut out = csv::Writer::from_writer(w);
    out.write_record([
        "time_s",
        "p_G",
        "method_G",
        "z_G",
        "p_G_norm",
        "method_G_norm",
        "rank_biserial_G",
        "hodges_lehmann_G_Pa",
    ])
    .map_err(write_err)?;
    for r in rows {
        out.write_record([
            r.t.to_string(),
            r.shear.p.to_string(),
            r.shear.used.to_string(),
            r.shear.z.map(|z| z.to_string()).unwrap_or_default(),
            r.normalised.p.to_string(),
            r.normalised.used.to_string(),
            r.shear_effect.rank_biserial.to_string(),
            r.shear_effect.hodges_lehmann.to_string(),
        ])
        .map_err(write_err)?;
    }
    out.flush().map_err(write_err)
}
