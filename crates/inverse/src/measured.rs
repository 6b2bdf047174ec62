//! Measured curves in: CSV files of an AFM run or a plate-compression run,
//! converted to SI, checked against the expected loading protocol and
//! resampled onto a model's time grid.
//!
//! Headers carry units: `name [unit]`, `name (unit)` or nlvid's own output
//! form `name_unit` (e.g. `time_s`), e.g. `time [s]`, `height (um)`,
//! `vDeflection [V]`; units are read by the study's unit table
//! (`nlvid_study::parse_unit`, one table for every input of nlvid).
//! Columns are chosen by `name` (case-sensitive, surrounding spaces
//! ignored).
//!
//! AFM (§5.2.2): the deflection column may be in volts (× deflection
//! sensitivity → metres), in metres, or already a force; then F = k·d and
//! the indentation is δ = Z − d (Z piezo travel towards the sample, d
//! deflection away from it, both positive in loading).

use std::path::{Path, PathBuf};

use nlvid_model::Curve;
use nlvid_study::{Dimension, parse_unit};
use serde::{Deserialize, Serialize};

use crate::error::{InverseError, Result};

/// The SI factor of `unit` and the first of `dims` it belongs to, by the
/// study's unit table (`nlvid_study::parse_unit`: any SI prefix, `um`/`µm`,
/// `m^2`, `nm/V`, …); `m2`-style areas (a trailing exponent without `^`)
/// are read as `m^2`.
fn unit_factor(unit: &str, dims: &[Dimension]) -> Option<(f64, Dimension)> {
    let unit = unit.trim();
    let parsed = parse_unit(unit).ok().or_else(|| {
        let base = unit.strip_suffix(['2', '3'])?;
        let exp = &unit[base.len()..];
        (!base.is_empty() && !base.contains('^'))
            .then(|| parse_unit(&format!("{base}^{exp}")).ok())
            .flatten()
    })?;
    dims.contains(&parsed.1).then_some(parsed)
}

/// The dimensions as a reader would name them, for messages.
fn dims_text(dims: &[Dimension]) -> String {
    dims.iter()
        .map(|d| format!("{d}"))
        .collect::<Vec<_>>()
        .join(" or ")
}

/// Splits `name [unit]` / `name (unit)` into (name, Some(unit)).
fn split_header(h: &str) -> (String, Option<String>) {
    let h = h.trim();
    for (open, close) in [('[', ']'), ('(', ')')] {
        if h.ends_with(close)
            && let Some(i) = h.rfind(open)
        {
            let unit = h[i + 1..h.len() - 1].trim().to_string();
            return (h[..i].trim().to_string(), Some(unit));
        }
    }
    (h.to_string(), None)
}

/// A CSV table with unit-carrying headers, kept with file line numbers.
struct Table {
    path: PathBuf,
    headers: Vec<(String, Option<String>)>,
    rows: Vec<(usize, Vec<String>)>,
}

impl Table {
    fn read(path: &Path) -> Result<Self> {
        let io = |message: String| InverseError::Io {
            path: path.to_path_buf(),
            message,
        };
        let mut reader = csv::ReaderBuilder::new()
            .trim(csv::Trim::All)
            .comment(Some(b'#'))
            .from_path(path)
            .map_err(|e| io(e.to_string()))?;
        let headers: Vec<(String, Option<String>)> = reader
            .headers()
            .map_err(|e| io(e.to_string()))?
            .iter()
            .map(split_header)
            .collect();
        if headers.iter().all(|(name, _)| name.is_empty()) {
            return Err(io(
                "row 1: the file is empty (expected a header line naming the columns, then data rows)"
                    .into(),
            ));
        }
        let mut rows = Vec::new();
        for rec in reader.records() {
            let rec = rec.map_err(|e| io(e.to_string()))?;
            let line = rec.position().map_or(0, |p| p.line() as usize);
            rows.push((line, rec.iter().map(str::to_string).collect()));
        }
        if rows.is_empty() {
            return Err(io("row 2: no data rows after the header".into()));
        }
        Ok(Self {
            path: path.to_path_buf(),
            headers,
            rows,
        })
    }

    fn err(&self, row: usize, column: &str, message: String) -> InverseError {
        InverseError::Data {
            path: self.path.clone(),
            row,
            column: column.to_string(),
            message,
        }
    }

    /// Column `name` converted to SI; returns the values and the matched
    /// dimension (first of `dims` the header's unit belongs to).
    fn column(&self, name: &str, dims: &[Dimension]) -> Result<(Vec<f64>, Dimension)> {
        let suffixed = |h: &(String, Option<String>)| {
            h.1.is_none()
                && h.0
                    .strip_prefix(name)
                    .and_then(|r| r.strip_prefix('_'))
                    .is_some_and(|u| unit_factor(&u.replace("_per_", "/"), dims).is_some())
        };
        let i = self
            .headers
            .iter()
            .position(|h| h.0 == name || suffixed(h))
            .ok_or_else(|| {
                let available: Vec<String> = self.headers.iter().map(|(n, _)| n.clone()).collect();
                let message = match nlvid_study::delimiter_hint(&available) {
                    Some(hint) => format!("column not found; {hint}"),
                    None => format!("column not found; the header has {available:?}"),
                };
                self.err(1, name, message)
            })?;
        let from_suffix = self.headers[i]
            .0
            .strip_prefix(name)
            .and_then(|r| r.strip_prefix('_'))
            .map(|u| u.replace("_per_", "/"));
        let unit = self.headers[i].1.clone().or(from_suffix).ok_or_else(|| {
            self.err(
                1,
                name,
                format!(
                    "header has no unit; write it as '{name} [unit]' (expected a {})",
                    dims_text(dims)
                ),
            )
        })?;
        let (factor, dim) = unit_factor(&unit, dims).ok_or_else(|| {
            self.err(
                1,
                name,
                format!("unit '{unit}' is not a unit of a {}", dims_text(dims)),
            )
        })?;
        let mut values = Vec::with_capacity(self.rows.len());
        for (line, rec) in &self.rows {
            let cell = rec
                .get(i)
                .ok_or_else(|| self.err(*line, name, "row is shorter than the header".into()))?;
            let v: f64 = cell
                .parse()
                .map_err(|_| self.err(*line, name, format!("'{cell}' is not a number")))?;
            if !v.is_finite() {
                return Err(self.err(*line, name, format!("value '{cell}' is not finite")));
            }
            values.push(v * factor);
        }
        Ok((values, dim))
    }

    fn check_time(&self, name: &str, t: &[f64]) -> Result<()> {
        for j in 1..t.len() {
            if t[j] <= t[j - 1] {
                return Err(self.err(
                    self.rows[j].0,
                    name,
                    format!(
                        "time must increase strictly: {} s follows {} s",
                        t[j],
                        t[j - 1]
                    ),
                ));
            }
        }
        Ok(())
    }
}

/// AFM calibration (§5.2.2).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Calibration {
    /// Deflection sensitivity (m/V); needed only for a deflection in volts.
    pub deflection_sensitivity: Option<f64>,
    /// Cantilever spring constant k (N/m).
    pub spring_constant: f64,
}

/// Column names of an AFM CSV.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct AfmColumns {
    /// Time column.
    pub time: String,
    /// Piezo travel Z column (length).
    pub piezo: String,
    /// Deflection column (volts, length, or force).
    pub deflection: String,
}

/// Column names of a plate-compression CSV.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CompressionColumns {
    /// Time column.
    pub time: String,
    /// Plate displacement column (length).
    pub displacement: String,
    /// Force column.
    pub force: String,
    /// Optional contact-area column.
    pub contact_area: Option<String>,
}

/// A measured curve: the one curve type, [`Curve`], with the channels
/// `displacement` (m: piezo Z (AFM) or plate displacement), `force` (N),
/// optionally `indentation` (δ = Z − d, m, AFM) and `contact_area` (m²),
/// plus where each sample stands in its file.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MeasuredCurve {
    /// Source file.
    pub path: PathBuf,
    /// 1-based file line of each sample.
    pub lines: Vec<usize>,
    /// The samples (SI).
    pub curve: Curve,
}

impl MeasuredCurve {
    /// A measured curve of `path` from its samples and their file lines.
    ///
    /// # Errors
    /// [`InverseError::InvalidSetting`] when `curve` lacks a `displacement`
    /// or `force` channel or `lines` has not one entry per sample.
    pub fn new(path: &Path, lines: Vec<usize>, curve: Curve) -> Result<Self> {
        let missing = ["displacement", "force"]
            .into_iter()
            .find(|c| curve.values(c).is_none());
        if let Some(c) = missing {
            return Err(InverseError::InvalidSetting(format!(
                "{}: a measured curve needs a `{c}` channel",
                path.display()
            )));
        }
        crate::model::check_len("file lines of the samples", curve.len(), lines.len())?;
        Ok(Self {
            path: path.to_path_buf(),
            lines,
            curve,
        })
    }

    /// Builds the [`Curve`] of a measured run (time, displacement, force,
    /// optional indentation and contact area) and the curve of `path`.
    ///
    /// # Errors
    /// As [`Curve::new`] and [`Curve::with`] (non-increasing time, a value
    /// that is not finite, lengths that differ), and as [`MeasuredCurve::new`].
    pub fn from_columns(
        path: &Path,
        lines: Vec<usize>,
        (time, displacement, force): (Vec<f64>, Vec<f64>, Vec<f64>),
        indentation: Option<Vec<f64>>,
        contact_area: Option<Vec<f64>>,
    ) -> Result<Self> {
        let bad = |e: nlvid_model::ModelError| {
            InverseError::InvalidSetting(format!("{}: {e}", path.display()))
        };
        let mut c = Curve::new(time)
            .and_then(|c| c.with("displacement", "m", displacement))
            .and_then(|c| c.with("force", "N", force))
            .map_err(bad)?;
        if let Some(d) = indentation {
            c = c.with("indentation", "m", d).map_err(bad)?;
        }
        if let Some(a) = contact_area {
            c = c.with("contact_area", "m^2", a).map_err(bad)?;
        }
        Self::new(path, lines, c)
    }

    /// t (s).
    pub fn time(&self) -> &[f64] {
        self.curve.time()
    }

    /// Controlled displacement (m): piezo Z (AFM) or plate displacement.
    pub fn displacement(&self) -> &[f64] {
        self.curve.values("displacement").unwrap_or_default()
    }

    /// Force (N).
    pub fn force(&self) -> &[f64] {
        self.curve.values("force").unwrap_or_default()
    }

    /// Indentation δ = Z − d (m), AFM only.
    pub fn indentation(&self) -> Option<&[f64]> {
        self.curve.values("indentation")
    }

    /// Contact area (m²), if measured.
    pub fn contact_area(&self) -> Option<&[f64]> {
        self.curve.values("contact_area")
    }
}

/// Reads an AFM run: F = k·d, δ = Z − d (§5.2.2).
///
/// # Errors
/// [`InverseError::Data`] naming file, row and column for a missing column,
/// a missing or wrong unit, a non-number or NaN, non-increasing time, or a
/// deflection in volts without a deflection sensitivity;
/// [`InverseError::InvalidSetting`] for a non-positive calibration.
pub fn read_afm_csv(path: &Path, cols: &AfmColumns, cal: &Calibration) -> Result<MeasuredCurve> {
    if !(cal.spring_constant > 0.0 && cal.spring_constant.is_finite()) {
        return Err(InverseError::InvalidSetting(format!(
            "spring constant must be > 0 N/m, got {}",
            cal.spring_constant
        )));
    }
    let table = Table::read(path)?;
    let (time, _) = table.column(&cols.time, &[Dimension::TIME])?;
    table.check_time(&cols.time, &time)?;
    let (z, _) = table.column(&cols.piezo, &[Dimension::LENGTH])?;
    let (raw, dim) = table.column(
        &cols.deflection,
        &[Dimension::VOLTAGE, Dimension::LENGTH, Dimension::FORCE],
    )?;
    let k = cal.spring_constant;
    let d: Vec<f64> = match dim {
        Dimension::VOLTAGE => {
            let s = cal
                .deflection_sensitivity
                .filter(|s| *s > 0.0 && s.is_finite())
                .ok_or_else(|| {
                    table.err(
                        1,
                        &cols.deflection,
                        "deflection is in volts: give a positive deflection sensitivity (nm/V)"
                            .into(),
                    )
                })?;
            raw.iter().map(|v| v * s).collect()
        }
        Dimension::LENGTH => raw,
        _ => raw.iter().map(|f| f / k).collect(),
    };
    let force = d.iter().map(|d| k * d).collect();
    let indentation = z.iter().zip(&d).map(|(z, d)| z - d).collect();
    MeasuredCurve::from_columns(
        path,
        table.rows.iter().map(|(l, _)| *l).collect(),
        (time, z, force),
        Some(indentation),
        None,
    )
}

/// Reads a plate-compression run.
///
/// # Errors
/// As [`read_afm_csv`].
pub fn read_compression_csv(path: &Path, cols: &CompressionColumns) -> Result<MeasuredCurve> {
    let table = Table::read(path)?;
    let (time, _) = table.column(&cols.time, &[Dimension::TIME])?;
    table.check_time(&cols.time, &time)?;
    let (displacement, _) = table.column(&cols.displacement, &[Dimension::LENGTH])?;
    let (force, _) = table.column(&cols.force, &[Dimension::FORCE])?;
    let contact_area = match &cols.contact_area {
        Some(name) => Some(table.column(name, &[Dimension::AREA])?.0),
        None => None,
    };
    MeasuredCurve::from_columns(
        path,
        table.rows.iter().map(|(l, _)| *l).collect(),
        (time, displacement, force),
        None,
        contact_area,
    )
}

/// Tolerances of [`MeasuredCurve::check_protocol`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ProtocolTolerance {
    /// Allowed duration difference, as a fraction of the expected duration.
    pub duration: f64,
    /// Allowed displacement deviation at any sample, as a fraction of the
    /// expected amplitude (max |displacement|); catches wrong rates and
    /// amplitudes.
    pub displacement: f64,
}

impl Default for ProtocolTolerance {
    fn default() -> Self {
        Self {
            duration: 0.02,
            displacement: 0.05,
        }
    }
}

/// Linear interpolation of (ts, ys) at t; ts strictly increasing, t inside.
fn interp(ts: &[f64], ys: &[f64], t: f64) -> f64 {
    let i = ts.partition_point(|&s| s <= t).clamp(1, ts.len() - 1);
    let (t0, t1) = (ts[i - 1], ts[i]);
    let w = (t - t0) / (t1 - t0);
    ys[i - 1] * (1.0 - w) + ys[i] * w
}

impl MeasuredCurve {
    /// Checks the controlled displacement against the expected history
    /// (`expected_times`, `expected_displacement`, piecewise linear), both
    /// measured from their first sample (time and displacement offsets
    /// removed).
    ///
    /// # Errors
    /// [`InverseError::ProtocolMismatch`] naming the file, row and time of
    /// the duration, amplitude or first displacement mismatch;
    /// [`InverseError::InvalidSetting`] for a malformed expected history.
    pub fn check_protocol(
        &self,
        expected_times: &[f64],
        expected_displacement: &[f64],
        tol: ProtocolTolerance,
    ) -> Result<()> {
        let n = expected_times.len();
        if n < 2
            || n != expected_displacement.len()
            || expected_times.windows(2).any(|w| w[1] <= w[0])
        {
            return Err(InverseError::InvalidSetting(
                "expected protocol needs >= 2 strictly increasing times with one displacement each"
                    .into(),
            ));
        }
        let te: Vec<f64> = expected_times
            .iter()
            .map(|t| t - expected_times[0])
            .collect();
        let ze: Vec<f64> = expected_displacement
            .iter()
            .map(|z| z - expected_displacement[0])
            .collect();
        let (time, displacement) = (self.time(), self.displacement());
        let tm: Vec<f64> = time.iter().map(|t| t - time[0]).collect();
        let zm: Vec<f64> = displacement.iter().map(|z| z - displacement[0]).collect();
        let last = tm.len() - 1;
        let mismatch = |j: usize, message: String| InverseError::ProtocolMismatch {
            path: self.path.clone(),
            row: self.lines[j],
            time: time[j],
            message,
        };
        let (dur_e, dur_m) = (te[n - 1], tm[last]);
        if (dur_m - dur_e).abs() > tol.duration * dur_e {
            return Err(mismatch(
                last,
                format!(
                    "duration {dur_m:.4} s, expected {dur_e:.4} s (tolerance {:.1} %)",
                    100.0 * tol.duration
                ),
            ));
        }
        let amp_e = ze.iter().fold(0.0f64, |a, z| a.max(z.abs()));
        let (j_max, amp_m) = zm.iter().enumerate().fold((0, 0.0f64), |(jm, a), (j, z)| {
            if z.abs() > a { (j, z.abs()) } else { (jm, a) }
        });
        if amp_e <= 0.0 {
            return Err(InverseError::InvalidSetting(
                "expected protocol has zero amplitude".into(),
            ));
        }
        if (amp_m - amp_e).abs() > tol.displacement * amp_e {
            return Err(mismatch(
                j_max,
                format!(
                    "amplitude {:.4e} m, expected {amp_e:.4e} m (tolerance {:.1} %)",
                    amp_m,
                    100.0 * tol.displacement
                ),
            ));
        }
        for j in 0..=last {
            if tm[j] > te[n - 1] {
                break;
            }
            let z_exp = interp(&te, &ze, tm[j]);
            if (zm[j] - z_exp).abs() > tol.displacement * amp_e {
                return Err(mismatch(
                    j,
                    format!(
                        "displacement {:.4e} m, expected {z_exp:.4e} m: deviation {:.1} % of the \
                         amplitude (tolerance {:.1} %); different rate or amplitude?",
                        zm[j],
                        100.0 * (zm[j] - z_exp).abs() / amp_e,
                        100.0 * tol.displacement
                    ),
                ));
            }
        }
        Ok(())
    }

    /// Linear resampling of `values` (one per sample, e.g. `self.force()`)
    /// onto a model time grid given relative to the first sample.
    ///
    /// # Errors
    /// [`InverseError::ProtocolMismatch`] if the grid runs beyond the data
    /// (by more than 1e-9 of the duration); [`InverseError::LengthMismatch`].
    pub fn resample(&self, values: &[f64], grid: &[f64]) -> Result<Vec<f64>> {
        let time = self.time();
        crate::model::check_len("values to resample", time.len(), values.len())?;
        let tm: Vec<f64> = time.iter().map(|t| t - time[0]).collect();
        let end = tm[tm.len() - 1];
        let slack = 1e-9 * end.max(f64::MIN_POSITIVE);
        if let Some(&bad) = grid.iter().find(|&&t| t < -slack || t > end + slack) {
            let last = time.len() - 1;
            return Err(InverseError::ProtocolMismatch {
                path: self.path.clone(),
                row: self.lines[last],
                time: time[last],
                message: format!(
                    "the model grid needs t = {bad} s but the data cover 0 ... {end} s"
                ),
            });
        }
        if tm.len() == 1 {
            return Ok(vec![values[0]; grid.len()]);
        }
        Ok(grid
            .iter()
            .map(|&t| interp(&tm, values, t.clamp(0.0, end)))
            .collect())
    }
}
