//! Output helpers shared by all subcommands: atomic file writes, CSV tables
//! with unit-suffixed headers (also as JSON), and the `--json` convention.
//!
//! Convention: with `--json`, stdout carries exactly one JSON document and
//! nothing else; human-readable text goes to stdout otherwise; logs and
//! progress bars always go to stderr.

use std::io::Write;
use std::path::Path;

use anyhow::{Context, bail};
use serde_json::{Map, Value};

/// Writes `bytes` to `path` atomically: a temporary file in the same
/// directory, flushed to disk, then renamed over `path`. A reader (or a
/// resumed run) sees either the old file or the complete new one, never a
/// half-written file.
///
/// # Errors
/// The directory is not writable, the disk is full, or the rename fails; the
/// temporary file is removed on failure.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    nlvid_study::write_atomic(path, bytes)
        .with_context(|| format!("{}: cannot write", path.display()))
}

/// A column of a [`Table`]: a name and its SI unit symbol (`""` for none).
#[derive(Clone, Debug, PartialEq)]
pub struct Column {
    /// Quantity name, e.g. `time`, `stretch`, `sigma_1`.
    pub name: String,
    /// SI unit, e.g. `s`, `Pa`, `N/m`, `m/s`, or `""` if dimensionless.
    pub unit: String,
}

impl Column {
    /// A column with a unit.
    pub fn new(name: &str, unit: &str) -> Self {
        Self {
            name: name.to_string(),
            unit: unit.to_string(),
        }
    }

    /// The CSV header: `name_unit`, with `/` spelled `_per_` and spaces
    /// and `^` dropped, so `time_s`, `sigma_1_Pa`, `tension_N_per_m`,
    /// `speed_m_per_s`; dimensionless columns keep the bare name.
    pub fn header(&self) -> String {
        if self.unit.is_empty() {
            return self.name.clone();
        }
        let u = self
            .unit
            .replace('/', "_per_")
            .replace(['^', ' ', '*', '·'], "");
        format!("{}_{u}", self.name)
    }
}

/// A numeric table in SI, stored by column, written as CSV or JSON.
#[derive(Clone, Debug, Default)]
pub struct Table {
    columns: Vec<Column>,
    data: Vec<Vec<f64>>,
}

impl Table {
    /// An empty table with these columns.
    pub fn new(columns: Vec<Column>) -> Self {
        let data = vec![Vec::new(); columns.len()];
        Self { columns, data }
    }

    /// Number of rows.
    pub fn len(&self) -> usize {
        self.data.first().map_or(0, Vec::len)
    }

    /// Whether there are no rows.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Appends a row.
    ///
    /// # Errors
    /// Wrong number of values, or a NaN/infinite value (named by row and
    /// column header) — outputs never carry silent NaNs.
    pub fn push_row(&mut self, row: &[f64]) -> anyhow::Result<()> {
        if row.len() != self.columns.len() {
            bail!(
                "row {} has {} values for {} columns",
                self.len(),
                row.len(),
                self.columns.len()
            );
        }
        if let Some(j) = row.iter().position(|x| !x.is_finite()) {
            bail!(
                "row {}, column `{}`: value {} is not finite",
                self.len(),
                self.columns[j].header(),
                row[j]
            );
        }
        for (col, &x) in self.data.iter_mut().zip(row) {
            col.push(x);
        }
        Ok(())
    }

    /// The table as CSV text: header line of unit-suffixed names, then rows
    /// with every value in shortest exact (round-trip) form.
    ///
    /// # Errors
    /// Only if the CSV writer fails (it writes to memory).
    pub fn to_csv(&self) -> anyhow::Result<String> {
        let mut w = csv::Writer::from_writer(Vec::new());
        w.write_record(self.columns.iter().map(Column::header))?;
        for i in 0..self.len() {
            w.write_record(self.data.iter().map(|c| fmt_exact(c[i])))?;
        }
        let bytes = w.into_inner().context("flushing CSV")?;
        Ok(String::from_utf8(bytes)?)
    }

    /// Writes the CSV atomically to `path`.
    ///
    /// # Errors
    /// As [`write_atomic`].
    pub fn write_csv(&self, path: &Path) -> anyhow::Result<()> {
        write_atomic(path, self.to_csv()?.as_bytes())
    }

    /// The table as JSON: `{"<header>": [values...], ...}` in column order,
    /// the same names as the CSV headers.
    pub fn to_json(&self) -> Value {
        let mut m = Map::new();
        for (c, d) in self.columns.iter().zip(&self.data) {
            m.insert(
                c.header(),
                Value::Array(d.iter().map(|&x| Value::from(x)).collect()),
            );
        }
        Value::Object(m)
    }
}

/// Shortest text that reads back to exactly `x`; exponent form for very
/// small or large magnitudes so columns stay readable.
pub fn fmt_exact(x: f64) -> String {
    let a = x.abs();
    if x == 0.0 || (1e-4..1e15).contains(&a) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// Provenance to embed in every JSON result: the study file, its SHA-256
/// hash (see `nlvid_study::StudyHash`) and the program version.
pub fn provenance(study: &nlvid_study::Study) -> Value {
    serde_json::json!({
        "study": study.name(),
        "study_sha256": study.hash().to_string(),
        "nlvid_version": env!("CARGO_PKG_VERSION"),
    })
}

/// `<stem>.<suffix>` next to `study` (`cell.toml` → `cell.simulate.csv`):
/// where commands write their outputs by default.
pub fn next_to(study: &Path, suffix: &str) -> std::path::PathBuf {
    let stem = study
        .file_stem()
        .map_or_else(|| "study".into(), |s| s.to_string_lossy().into_owned());
    study.with_file_name(format!("{stem}.{suffix}"))
}

/// A curve as JSON: `{"time_s": [...], "<header>": [...], ...}`, the
/// headers of its CSV (unit-suffixed, as [`Table::to_json`]).
pub fn curve_json(curve: &nlvid_model::Curve) -> Value {
    let mut m = Map::new();
    m.insert("time_s".into(), Value::from(curve.time().to_vec()));
    for c in curve.channels() {
        m.insert(c.header(), Value::from(c.values.clone()));
    }
    Value::Object(m)
}

/// Named parameters as JSON with unit-suffixed keys: `{"G0_Pa": 1000,
/// "g1": 0.3, "tau1_s": 0.5}`.
pub fn parameters_json(params: &[(String, f64, String)]) -> Value {
    params
        .iter()
        .map(|(n, v, u)| {
            let key = if u.is_empty() || u == "1" {
                n.clone()
            } else {
                Column::new(n, u).header()
            };
            (key, Value::from(*v))
        })
        .collect::<Map<_, _>>()
        .into()
}

/// Prints one JSON document on stdout (the `--json` convention).
///
/// # Errors
/// Writing to stdout fails (e.g. a closed pipe).
pub fn print_json(value: &Value) -> anyhow::Result<()> {
    let mut text = serde_json::to_string_pretty(value)?;
    text.push('\n');
    print_text(&text)
}

/// Writes `text` to stdout. A closed pipe (`nlvid … | head`) is an
/// `io::Error` that [`crate::report`] turns into a quiet exit, never a
/// panic as `print!` would.
///
/// # Errors
/// Writing to stdout fails.
pub fn print_text(text: &str) -> anyhow::Result<()> {
    let mut out = std::io::stdout().lock();
    out.write_all(text.as_bytes())?;
    out.flush()?;
    Ok(())
}

/// `println!` that returns the write error instead of panicking on a
/// closed stdout: `say!("{x} N")?;`.
#[macro_export]
macro_rules! say {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        writeln!(std::io::stdout(), $($arg)*)
    }};
}

#[cfg(test)]
mod tests {
    use std::fs;

    use super::*;

    #[test]
    fn headers_carry_units() {
        assert_eq!(Column::new("time", "s").header(), "time_s");
        assert_eq!(Column::new("sigma_1", "Pa").header(), "sigma_1_Pa");
        assert_eq!(Column::new("tension", "N/m").header(), "tension_N_per_m");
        assert_eq!(Column::new("stretch", "").header(), "stretch");
    }

    #[test]
    fn csv_round_trips_values_exactly() {
        let mut t = Table::new(vec![Column::new("time", "s"), Column::new("force", "N")]);
        let rows = [[0.0, 1.234_567_890_123_456_7e-9], [0.1, -2.0 / 3.0]];
        for r in &rows {
            t.push_row(r).unwrap();
        }
        let csv = t.to_csv().unwrap();
        let mut lines = csv.lines();
        assert_eq!(lines.next(), Some("time_s,force_N"));
        for (line, r) in lines.zip(&rows) {
            let back: Vec<f64> = line.split(',').map(|s| s.parse().unwrap()).collect();
            assert_eq!(back, r.to_vec());
        }
    }

    #[test]
    fn nan_rows_are_rejected_with_the_column_name() {
        let mut t = Table::new(vec![Column::new("time", "s"), Column::new("force", "N")]);
        let e = t.push_row(&[0.0, f64::NAN]).unwrap_err().to_string();
        assert_eq!(e, "row 0, column `force_N`: value NaN is not finite");
        assert!(t.push_row(&[1.0]).is_err());
        assert!(t.is_empty());
    }

    #[test]
    fn atomic_write_replaces_the_file_and_leaves_no_temporary() {
        let dir = std::env::temp_dir().join(format!("nlvid-cli-atomic-{}", std::process::id()));
        fs::create_dir_all(&dir).unwrap();
        let p = dir.join("out.csv");
        write_atomic(&p, b"old").unwrap();
        write_atomic(&p, b"new").unwrap();
        assert_eq!(fs::read(&p).unwrap(), b"new");
        let names: Vec<_> = fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names, vec![std::ffi::OsString::from("out.csv")]);
        assert!(write_atomic(&dir.join("no/such/dir/x"), b"x").is_err());
        fs::remove_dir_all(&dir).unwrap();
    }
}
