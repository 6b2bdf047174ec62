//! Numeric CSV tables (designs X, responses Y, predictions) and Kriging
//! model files that remember the names of their inputs and outputs.
//!
//! A model file is the JSON of [`KrigingModel`] with two more keys,
//! `input_names` and `output_names` (the X and Y headers it was fitted
//! on); readers that do not know them (e.g. the inverse stage) ignore them.

use std::path::Path;

use crate::error::{Result, SurrogateError, io_err};
use crate::kriging::KrigingModel;

/// A numeric table read from CSV.
#[derive(Debug, Clone, PartialEq)]
pub struct Table {
    /// Column names.
    pub header: Vec<String>,
    /// Rows.
    pub rows: Vec<Vec<f64>>,
}

impl Table {
    /// As a faer matrix.
    pub fn mat(&self) -> faer::Mat<f64> {
        faer::Mat::from_fn(self.rows.len(), self.header.len(), |i, j| self.rows[i][j])
    }

    /// A column by its full header (`G0 [Pa]`) or by its name without the
    /// unit suffix that `nlvid build --export` writes (`G0`).
    pub fn column(&self, name: &str) -> Option<usize> {
        let h = &self.header;
        h.iter().position(|c| c == name).or_else(|| {
            h.iter()
                .position(|c| c.split_once(" [").is_some_and(|(bare, _)| bare == name))
        })
    }
}

fn parse_err(path: &Path, message: String) -> SurrogateError {
    SurrogateError::Parse {
        path: path.to_path_buf(),
        message,
    }
}

/// Reads a numeric CSV with a header; a column named `index` is dropped.
///
/// # Errors
/// Unreadable file, a row of the wrong length, a value that is not a
/// number (naming the 1-based line and the column), no data rows.
pub fn read_table(path: &Path) -> Result<Table> {
    let mut rdr = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .from_path(path)
        .map_err(|e| parse_err(path, format!("cannot open: {e}")))?;
    let head: Vec<String> = rdr
        .headers()
        .map_err(|e| parse_err(path, format!("no header: {e}")))?
        .iter()
        .map(String::from)
        .collect();
    let keep: Vec<usize> = (0..head.len()).filter(|&j| head[j] != "index").collect();
    let mut rows = Vec::new();
    for (r, rec) in rdr.records().enumerate() {
        let line = r + 2;
        let rec = rec.map_err(|e| parse_err(path, format!("line {line}: bad CSV record: {e}")))?;
        if rec.len() != head.len() {
            return Err(parse_err(
                path,
                format!(
                    "line {line}: {} fields, header has {}",
                    rec.len(),
                    head.len()
                ),
            ));
        }
        let mut row = Vec::with_capacity(keep.len());
        for &j in &keep {
            let v: f64 = rec[j].parse().map_err(|_| {
                parse_err(
                    path,
                    format!(
                        "line {line}: column `{}`: `{}` is not a number",
                        head[j], &rec[j]
                    ),
                )
            })?;
            row.push(v);
        }
        rows.push(row);
    }
    if rows.is_empty() {
        return Err(parse_err(path, "no data rows".into()));
    }
    Ok(Table {
        header: keep.iter().map(|&j| head[j].clone()).collect(),
        rows,
    })
}

/// Writes rows as CSV with a header, values in exponent form.
///
/// # Errors
/// The writer fails.
pub fn write_table<W: std::io::Write>(w: W, header: &[String], rows: &[Vec<f64>]) -> Result<()> {
    let err = |e: csv::Error| SurrogateError::InvalidInput(format!("writing CSV: {e}"));
    let mut w = csv::Writer::from_writer(w);
    w.write_record(header).map_err(err)?;
    for r in rows {
        w.write_record(r.iter().map(|v| format!("{v:e}")))
            .map_err(err)?;
    }
    w.flush()
        .map_err(|e| SurrogateError::InvalidInput(format!("writing CSV: {e}")))
}

/// A Kriging model with the names of its inputs and outputs (empty when
/// the file does not record them).
#[derive(Debug, Clone)]
pub struct NamedModel {
    /// The model.
    pub model: KrigingModel,
    /// Input column names (the X header).
    pub input_names: Vec<String>,
    /// Output column names (the Y header).
    pub output_names: Vec<String>,
}

impl NamedModel {
    /// Output names, `y_0 …` where the file records none.
    pub fn outputs(&self) -> Vec<String> {
        if self.output_names.len() == self.model.n_outputs {
            self.output_names.clone()
        } else {
            (0..self.model.n_outputs)
                .map(|j| format!("y_{j}"))
                .collect()
        }
    }

    /// Writes the model file.
    ///
    /// # Errors
    /// The file cannot be written.
    pub fn save(&self, path: &Path) -> Result<()> {
        let mut v = serde_json::to_value(&self.model)
            .map_err(|e| SurrogateError::InvalidInput(format!("serialising the model: {e}")))?;
        v["input_names"] = serde_json::json!(self.input_names);
        v["output_names"] = serde_json::json!(self.output_names);
        let bytes = serde_json::to_vec(&v)
            .map_err(|e| SurrogateError::InvalidInput(format!("serialising the model: {e}")))?;
        nlvid_study::write_atomic(path, &bytes).map_err(io_err(path))
    }

    /// Reads a model file (with or without names).
    ///
    /// # Errors
    /// Unreadable file, not a Kriging model.
    pub fn load(path: &Path) -> Result<Self> {
        let bytes = std::fs::read(path).map_err(io_err(path))?;
        let v: serde_json::Value = serde_json::from_slice(&bytes)
            .map_err(|e| parse_err(path, format!("not a Kriging model file: {e}")))?;
        let names = |key: &str| -> Vec<String> {
            v.get(key)
                .and_then(|n| serde_json::from_value(n.clone()).ok())
                .unwrap_or_default()
        };
        let (input_names, output_names) = (names("input_names"), names("output_names"));
        let model = serde_json::from_value(v)
            .map_err(|e| parse_err(path, format!("not a Kriging model file: {e}")))?;
        Ok(Self {
            model,
            input_names,
            output_names,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn columns_are_found_with_or_without_their_unit_suffix() {
        let t = Table {
            header: ["G0 [Pa]", "g1 [1]", "tau1 [s]"].map(String::from).to_vec(),
            rows: vec![vec![1.0, 0.1, 0.2]],
        };
        assert_eq!(t.column("G0 [Pa]"), Some(0));
        assert_eq!(t.column("G0"), Some(0));
        assert_eq!(t.column("tau1"), Some(2));
        assert_eq!(t.column("tau"), None);
        assert_eq!(t.column("Pa"), None);
    }
}
