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
    if let Some(hint) = nlvid_study::delimiter_hint(&head) {
        return Err(parse_err(path, format!("line 1: {hint}")));
    }
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

/// Predictions of a [`NamedModel`] at the rows of a table.
#[derive(Debug, Clone, PartialEq)]
pub struct Predictions {
    /// Output names.
    pub names: Vec<String>,
    /// ŷ per point.
    pub y: Vec<Vec<f64>>,
    /// MSE per point, when asked for.
    pub mse: Option<Vec<Vec<f64>>>,
}

impl Predictions {
    /// CSV: header `<name>`…, then `mse_<name>`…, one row per point.
    ///
    /// # Errors
    /// The CSV writer fails (it writes to memory).
    pub fn to_csv(&self) -> Result<String> {
        let mut header = self.names.clone();
        let mut rows = self.y.clone();
        if let Some(m) = &self.mse {
            header.extend(self.names.iter().map(|n| format!("mse_{n}")));
            rows.iter_mut().zip(m).for_each(|(r, m)| r.extend(m));
        }
        let mut buf = Vec::new();
        write_table(&mut buf, &header, &rows)?;
        Ok(String::from_utf8_lossy(&buf).into_owned())
    }

    /// JSON: `outputs` and per point `x`, `y` (and `mse`) keyed by name.
    pub fn to_json(&self, x: &Table) -> serde_json::Value {
        let named = |names: &[String], v: &[f64]| -> serde_json::Value {
            names
                .iter()
                .zip(v)
                .map(|(n, v)| (n.clone(), serde_json::json!(v)))
                .collect::<serde_json::Map<_, _>>()
                .into()
        };
        let points: Vec<_> = (0..self.y.len())
            .map(|i| {
                let mut p = serde_json::json!({
                    "x": named(&x.header, &x.rows[i]),
                    "y": named(&self.names, &self.y[i]),
                });
                if let Some(m) = &self.mse {
                    p["mse"] = named(&self.names, &m[i]);
                }
                p
            })
            .collect();
        serde_json::json!({ "outputs": self.names, "points": points })
    }
}

impl NamedModel {
    /// Fits a model to the sites `x` and responses `y` with `options`,
    /// keeping the two headers as the input and output names.
    ///
    /// # Errors
    /// Tables of different lengths; as [`crate::FitOptions::settings`] and
    /// [`KrigingModel::fit`].
    pub fn fit(x: &Table, y: &Table, options: crate::FitOptions) -> Result<Self> {
        if x.rows.len() != y.rows.len() {
            return Err(SurrogateError::InvalidInput(format!(
                "{} input rows but {} output rows",
                x.rows.len(),
                y.rows.len()
            )));
        }
        let settings = options.settings(x)?;
        Ok(Self {
            model: KrigingModel::fit(x.mat().as_ref(), y.mat().as_ref(), &settings)?,
            input_names: x.header.clone(),
            output_names: y.header.clone(),
        })
    }

    /// Predicts at every row of `x` (and the MSE with `mse`).
    ///
    /// # Errors
    /// A column count that is not the model's; a point it cannot take,
    /// naming its 1-based line.
    pub fn predict_table(&self, x: &Table, mse: bool) -> Result<Predictions> {
        if x.header.len() != self.model.dim {
            return Err(SurrogateError::InvalidInput(format!(
                "{} input columns, the model has {}",
                x.header.len(),
                self.model.dim
            )));
        }
        let at = |i: usize, e: SurrogateError| {
            SurrogateError::InvalidInput(format!("line {}: {e}", i + 2))
        };
        let (mut y, mut m) = (Vec::new(), Vec::new());
        for (i, xi) in x.rows.iter().enumerate() {
            if mse {
                let p = self.model.predict_full(xi).map_err(|e| at(i, e))?;
                y.push(p.y);
                m.push(p.mse);
            } else {
                y.push(self.model.predict(xi).map_err(|e| at(i, e))?);
            }
        }
        Ok(Predictions {
            names: self.outputs(),
            y,
            mse: mse.then_some(m),
        })
    }

    /// What the trend and σ² are of, in words (their units).
    fn units(&self) -> &'static str {
        match (self.model.log_outputs, &self.model.output_scale) {
            (true, _) => "trend and σ² of ln y (log outputs)",
            (false, Some(_)) => "trend and σ² of y divided by its proportionality factor",
            (false, None) => "trend in output units, σ² in output units squared",
        }
    }

    /// `(term, coefficients per output)` of the trend, terms named by the
    /// inputs (`1`, `a`, `a*b`).
    fn beta(&self) -> Vec<(String, Vec<f64>)> {
        let t = self.model.trend();
        let name = |k: usize| {
            self.input_names
                .get(k)
                .cloned()
                .unwrap_or_else(|| format!("x_{k}"))
        };
        t.terms
            .iter()
            .zip(t.coefficients)
            .map(|(term, c)| {
                let f: Vec<String> = term.inputs.iter().map(|&k| name(k)).collect();
                (
                    if f.is_empty() {
                        "1".into()
                    } else {
                        f.join("*")
                    },
                    c,
                )
            })
            .collect()
    }

    /// The fit report as JSON: the fit's `report`, `outputs`, `units`,
    /// `beta` (per term `term`, `coefficients` per output) and `sigma2`
    /// (per output, [`KrigingModel::process_variance`]), both in the
    /// outputs' own units.
    pub fn report_json(&self) -> serde_json::Value {
        let beta: Vec<_> = self
            .beta()
            .into_iter()
            .map(|(term, c)| serde_json::json!({ "term": term, "coefficients": c }))
            .collect();
        serde_json::json!({
            "report": self.model.report, "outputs": self.outputs(), "units": self.units(),
            "beta": beta, "sigma2": self.model.process_variance(),
        })
    }

    /// The fit report for people: sizes, θ, ψ, and β, σ² of the first
    /// outputs in their own units.
    pub fn report_text(&self) -> String {
        let (m, r) = (&self.model, &self.model.report);
        let mut s = format!(
            "fitted {} sites × {} inputs → {} outputs ({} kriged, energy {:.8})\n\
             θ = {:?}\nψ = {:.6e} after {} evaluations ({}), nugget {:e}\n{} \
             (inputs in ln x for log inputs):\n",
            m.n_sites,
            m.dim,
            m.n_outputs,
            r.kriged_outputs,
            r.energy,
            r.theta,
            r.psi,
            r.evaluations,
            r.search,
            r.nugget,
            self.units()
        );
        let (beta, sigma2, outputs) = (self.beta(), m.process_variance(), self.outputs());
        let shown = outputs.len().min(3);
        for (j, name) in outputs.iter().enumerate().take(shown) {
            let terms: Vec<String> = beta
                .iter()
                .map(|(t, c)| format!("{:+.6e}·{t}", c[j]))
                .collect();
            s.push_str(&format!(
                "  {name}: β: {}; σ² = {:.6e}\n",
                terms.join(" "),
                sigma2[j]
            ));
        }
        if outputs.len() > shown {
            s.push_str(&format!(
                "  … {} more outputs (all with --json)\n",
                outputs.len() - shown
            ));
        }
        s
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
