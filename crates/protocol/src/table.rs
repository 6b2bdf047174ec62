//! Measured histories read from CSV (e.g. the actual piezo Z(t) of an
//! experiment, which the thesis uses as FE input in §4.3).
//!
//! Format: a header row, then one row per sample. The time column is the
//! one named `time` or `t` with a time unit (`time_s`, `t [ms]`); the value
//! column is the one whose unit has the program's dimension (length for
//! [`Quantity::Displacement`], force for [`Quantity::Force`]), or the one
//! named explicitly. Every row becomes a breakpoint; between rows the value
//! is interpolated linearly. Time must increase strictly; empty cells, NaN
//! and infinities are errors naming the file, line and column.

use std::path::{Path, PathBuf};

use crate::units::{Dim, Header, parse_header};
use crate::{Label, Program, ProgramBuilder, ProtocolError, Quantity, Result};

fn wanted_dim(q: Quantity) -> Dim {
    match q {
        Quantity::Displacement => Dim::Length,
        Quantity::Force => Dim::Force,
        Quantity::Dimensionless => Dim::None,
    }
}

/// Read a tabulated history from a CSV file.
///
/// `value_column`: the header name (without unit, case-insensitive) of the
/// value column; `None` picks the only non-time column of the right
/// dimension.
///
/// # Errors
/// File unreadable, malformed CSV, missing / ambiguous columns, a cell that
/// is not a finite number, time not strictly increasing, fewer than 2 rows.
pub fn read_table(path: &Path, quantity: Quantity, value_column: Option<&str>) -> Result<Program> {
    let file = std::fs::File::open(path).map_err(|source| ProtocolError::Io {
        file: path.to_path_buf(),
        source,
    })?;
    parse_table(file, path, quantity, value_column)
}

/// As [`read_table`], from any reader; `source` names it in errors.
///
/// # Errors
/// As [`read_table`].
pub fn parse_table<R: std::io::Read>(
    reader: R,
    source: &Path,
    quantity: Quantity,
    value_column: Option<&str>,
) -> Result<Program> {
    let file: PathBuf = source.to_path_buf();
    let mut rdr = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .from_reader(reader);
    let csv_err = |e: csv::Error, file: &PathBuf| ProtocolError::Csv {
        file: file.clone(),
        line: e.position().map_or(0, |p| p.line()),
        message: e.to_string(),
    };
    let raw: Vec<String> = rdr
        .headers()
        .map_err(|e| csv_err(e, &file))?
        .iter()
        .map(str::to_string)
        .collect();
    let headers: Vec<Header> = raw.iter().map(|h| parse_header(h)).collect();
    let found = raw.join(", ");
    let col_err = |message: String| ProtocolError::Column {
        file: file.clone(),
        message,
        found: found.clone(),
    };

    let time_cols: Vec<usize> = (0..headers.len())
        .filter(|&i| matches!(headers[i].name.as_str(), "time" | "t"))
        .collect();
    let ti = match time_cols.as_slice() {
        [i] => *i,
        [] => return Err(col_err("no time column (`time_s`, `t [ms]`, ...)".into())),
        _ => return Err(col_err("more than one time column".into())),
    };
    if headers[ti].dim != Dim::Time {
        return Err(col_err(format!(
            "time column `{}` needs a time unit (s, ms, us, min), e.g. `time_s`",
            raw[ti]
        )));
    }
    let want = wanted_dim(quantity);
    let vi = match value_column {
        Some(name) => {
            let name = name.to_lowercase();
            let i = (0..headers.len())
                .find(|&i| i != ti && headers[i].name == name)
                .ok_or_else(|| col_err(format!("no column named `{name}`")))?;
            if headers[i].dim != want {
                return Err(col_err(format!(
                    "column `{}` has the wrong unit for a {quantity:?} (expected SI unit `{}`)",
                    raw[i],
                    quantity.si_unit()
                )));
            }
            i
        }
        None => {
            let cands: Vec<usize> = (0..headers.len())
                .filter(|&i| i != ti && headers[i].dim == want)
                .collect();
            match cands.as_slice() {
                [i] => *i,
                [] => {
                    return Err(col_err(format!(
                        "no {quantity:?} column (a header with a unit like `{}`)",
                        match want {
                            Dim::Length => "piezo_um",
                            Dim::Force => "force_nN",
                            _ => "value",
                        }
                    )));
                }
                _ => {
                    return Err(col_err(format!(
                        "several {quantity:?} columns; name the one to use"
                    )));
                }
            }
        }
    };

    let mut rows: Vec<(f64, f64)> = Vec::new();
    for rec in rdr.records() {
        let rec = rec.map_err(|e| csv_err(e, &file))?;
        let line = rec.position().map_or(0, |p| p.line());
        let cell = |i: usize| -> Result<f64> {
            let s = rec.get(i).unwrap_or("");
            let bad = |message: String| ProtocolError::Value {
                file: file.clone(),
                line,
                column: raw[i].clone(),
                message,
            };
            if s.is_empty() {
                return Err(bad("empty cell".into()));
            }
            let v: f64 = s
                .parse()
                .map_err(|_| bad(format!("`{s}` is not a number")))?;
            if !v.is_finite() {
                return Err(bad(format!("`{s}` is not finite")));
            }
            Ok(v * headers[i].to_si)
        };
        let (t, v) = (cell(ti)?, cell(vi)?);
        if let Some(&(previous, _)) = rows.last()
            && t <= previous
        {
            return Err(ProtocolError::NonMonotonicTime {
                file: file.clone(),
                line,
                time: t,
                previous,
            });
        }
        rows.push((t, v));
    }
    if rows.len() < 2 {
        return Err(col_err(format!(
            "needs at least 2 data rows, found {}",
            rows.len()
        )));
    }
    let (t0, v0) = rows[0];
    let mut b = ProgramBuilder::starting_at(quantity, t0, v0);
    for &(t, v) in &rows[1..] {
        b = b.line_to(t, v, Label::Tabulated)?;
    }
    b.build()
}
