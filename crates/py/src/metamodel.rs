//! Kriging meta-models (`nlvid surrogate predict | check`):
//! `nlvid_surrogate::NamedModel` with its input and output names; with the
//! `meta.json` of its build, the output time grid and parameter domain.

use std::path::PathBuf;

use numpy::{IntoPyArray, PyArray1};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::arrays::matrix;
use crate::errors::{IntoPy, input};
use nlvid_inverse::Model as _;

/// A fitted Kriging meta-model (file of `nlvid surrogate fit`).
#[pyclass(module = "nlvid", frozen)]
pub(crate) struct MetaModel {
    pub(crate) named: nlvid_surrogate::NamedModel,
    path: PathBuf,
    times: Option<Vec<f64>>,
}

impl MetaModel {
    /// ŷ (and the MSE) at every row of `x` (row-major, `n` × dim), as
    /// `predict_table` computes them; errors name the 0-based row.
    pub(crate) fn predict_rows(
        &self,
        x: &[f64],
        n: usize,
        mse: bool,
    ) -> Result<(Vec<f64>, Option<Vec<f64>>), String> {
        let (d, m) = (self.named.model.dim, self.named.model.n_outputs);
        let mut y = Vec::with_capacity(n * m);
        let mut s = if mse {
            Some(Vec::with_capacity(n * m))
        } else {
            None
        };
        for (i, xi) in x.chunks_exact(d.max(1)).take(n).enumerate() {
            let at = |e: nlvid_surrogate::SurrogateError| format!("row {i}: {e}");
            match &mut s {
                Some(s) => {
                    let p = self.named.model.predict_full(xi).map_err(at)?;
                    y.extend_from_slice(&p.y);
                    s.extend_from_slice(&p.mse);
                }
                None => y.extend(self.named.model.predict(xi).map_err(at)?),
            }
        }
        Ok((y, s))
    }

    fn check_dim(&self, cols: usize, what: &str) -> PyResult<()> {
        if cols != self.named.model.dim {
            return Err(input(format!(
                "{what}: {cols} input columns, the model has {} ({})",
                self.named.model.dim,
                self.named.input_names.join(", ")
            )));
        }
        Ok(())
    }
}

/// `v` (row-major, `n` × `m`) as a 2-d array, moved, not copied.
fn to_2d<'py>(py: Python<'py>, v: Vec<f64>, n: usize, m: usize) -> PyResult<Bound<'py, PyAny>> {
    let a = numpy::ndarray::Array2::from_shape_vec((n, m), v)
        .map_err(|e| crate::errors::NlvidError::new_err(e.to_string()))?;
    Ok(a.into_pyarray(py).into_any())
}

#[pymethods]
impl MetaModel {
    /// Loads a model file (JSON of `nlvid surrogate fit`); with `meta`, the
    /// `meta.json` of its build (output times, parameter domain), checked
    /// against the model.
    #[staticmethod]
    #[pyo3(signature = (path, meta = None))]
    fn load(path: PathBuf, meta: Option<PathBuf>) -> PyResult<Self> {
        let named = nlvid_surrogate::NamedModel::load(&path).py()?;
        let times = match &meta {
            Some(meta) => Some(
                nlvid_inverse::load_kriging_surrogate(
                    &path,
                    meta,
                    nlvid_inverse::Coordinates::Physical,
                )
                .py()?
                .times()
                .to_vec(),
            ),
            None => None,
        };
        Ok(MetaModel { named, path, times })
    }

    /// The model file.
    #[getter]
    fn path(&self) -> PathBuf {
        self.path.clone()
    }
    /// Input column names (the X header it was fitted on).
    #[getter]
    fn input_names(&self) -> Vec<String> {
        self.named.input_names.clone()
    }
    /// Output names (`y_0`, … when the file records none).
    #[getter]
    fn output_names(&self) -> Vec<String> {
        self.named.outputs()
    }
    /// Number of inputs.
    #[getter]
    fn dim(&self) -> usize {
        self.named.model.dim
    }
    /// Number of outputs.
    #[getter]
    fn n_outputs(&self) -> usize {
        self.named.model.n_outputs
    }
    /// Output times (s) from `meta.json`, or None when loaded without it.
    #[getter]
    fn times<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray1<f64>>> {
        self.times.as_ref().map(|t| PyArray1::from_slice(py, t))
    }

    /// Predicts at the rows of `x` (float64, shape (n, dim), or (dim,) for
    /// one point; inputs in the order of `input_names`). Returns ŷ of shape
    /// (n, n_outputs), or (ŷ, MSE) with `mse=True`.
    #[pyo3(signature = (x, mse = false))]
    fn predict<'py>(
        &self,
        py: Python<'py>,
        x: &Bound<'py, PyAny>,
        mse: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        let x = matrix(x, "x")?;
        let (n, d) = x.shape();
        self.check_dim(d, "x")?;
        let rows = x.row_major();
        let (y, s) = if n * self.named.model.n_outputs > 256 {
            py.detach(|| self.predict_rows(&rows, n, mse))
        } else {
            self.predict_rows(&rows, n, mse)
        }
        .map_err(crate::errors::NlvidError::new_err)?;
        let m = self.named.model.n_outputs;
        match s {
            Some(s) => Ok((to_2d(py, y, n, m)?, to_2d(py, s, n, m)?)
                .into_pyobject(py)?
                .into_any()),
            None => to_2d(py, y, n, m),
        }
    }

    /// Range-normalised RMSE (thesis eq. 4.4) on a checking set: inputs `x`
    /// (n, dim), real outputs `y` (n, n_outputs). Returns the summary
    /// `nlvid surrogate check` saves: `rmse` (array, one per case), `min`,
    /// `median`, `max`, `worst`, `median_case`.
    fn check<'py>(
        &self,
        py: Python<'py>,
        x: &Bound<'py, PyAny>,
        y: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let (x, y) = (matrix(x, "x")?, matrix(y, "y")?);
        let ((n, d), (ny, my)) = (x.shape(), y.shape());
        self.check_dim(d, "x")?;
        if n != ny {
            return Err(input(format!(
                "{n} checking inputs but {ny} checking outputs"
            )));
        }
        if my != self.named.model.n_outputs {
            return Err(input(format!(
                "y: {my} output columns, the model has {}",
                self.named.model.n_outputs
            )));
        }
        let (xr, yr) = (x.row_major(), y.row_major());
        let summary = py
            .detach(|| -> nlvid_surrogate::Result<_> {
                let xm = nlvid_surrogate::faer::Mat::from_fn(n, d, |i, k| xr[i * d + k]);
                let pred = self.named.model.predict_many(xm.as_ref())?;
                let preds: Vec<Vec<f64>> = (0..pred.nrows())
                    .map(|i| (0..pred.ncols()).map(|j| pred[(i, j)]).collect())
                    .collect();
                let refs: Vec<Vec<f64>> = yr.chunks_exact(my.max(1)).map(<[f64]>::to_vec).collect();
                nlvid_surrogate::check::summarise(&refs, &preds)
            })
            .py()?;
        let v = serde_json::to_value(&summary)
            .map_err(|e| crate::errors::NlvidError::new_err(e.to_string()))?;
        let d = crate::pyjson::dict(py, &v)?;
        d.set_item("rmse", PyArray1::from_slice(py, &summary.rmse))?;
        Ok(d)
    }

    fn __repr__(&self) -> String {
        format!(
            "<nlvid.MetaModel {}: {} inputs ({}), {} outputs>",
            self.path.display(),
            self.named.model.dim,
            self.named.input_names.join(", "),
            self.named.model.n_outputs
        )
    }
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<MetaModel>()?;
    Ok(())
}
