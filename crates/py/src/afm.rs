//! AFM instrument files and elastic / viscoelastic fits (`nlvid inspect`):
//! JPK force curves and maps read into numpy arrays with their metadata
//! (`nlvid_afm::read_force_map`), the quick Hertz (eq. 1.1) and Lee–Radok
//! Prony fits of a curve (`nlvid_afm::quick_fit`), and the same two fits
//! on arrays (`nlvid_afm::fit_hertz`, `nlvid_afm::fit_lee_radok`). The
//! curve fits also take afmformats' data objects ([`crate::columns`]).

use std::path::PathBuf;

use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::arrays::{quantity, same_length, vector};
use crate::errors::{IntoPy, input};
use nlvid_afm::QuickFitKind;
use nlvid_study::Dimension;

/// One force curve of an instrument file, SI units.
#[pyclass(module = "nlvid", frozen)]
pub(crate) struct ForceCurve {
    pub(crate) curve: nlvid_afm::ForceCurve,
    n_curves: usize,
}

#[pymethods]
impl ForceCurve {
    /// File (and curve index of a map) the curve came from.
    #[getter]
    fn source(&self) -> &str {
        &self.curve.source
    }
    /// Dict of the file's metadata: `format_version`, `instrument`,
    /// `position` ((x, y) m or None), `spring_constant_N_per_m`,
    /// `sensitivity_m_per_V` and where each came from (`file`/`override`).
    #[getter]
    fn metadata<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let c = &self.curve;
        let d = PyDict::new(py);
        let src = |s: nlvid_afm::CalibrationSource| match s {
            nlvid_afm::CalibrationSource::File => "file",
            nlvid_afm::CalibrationSource::Override => "override",
        };
        d.set_item("source", &c.source)?;
        d.set_item("format_version", &c.format_version)?;
        d.set_item("instrument", &c.instrument)?;
        d.set_item("position", c.position)?;
        d.set_item("spring_constant_N_per_m", c.calibration.spring_constant)?;
        d.set_item(
            "spring_constant_source",
            src(c.calibration.spring_constant_source),
        )?;
        d.set_item("sensitivity_m_per_V", c.calibration.sensitivity)?;
        d.set_item("sensitivity_source", src(c.calibration.sensitivity_source))?;
        d.set_item("curves_in_file", self.n_curves)?;
        Ok(d)
    }
    /// The segments, in recording order: list of dicts `index`, `kind`
    /// (extend, retract, hold, creep), `name`, `duration` (s), `time` (s,
    /// float64 array from the start of the first segment), `channels`
    /// (name → float64 array) and `units` (name → unit).
    #[getter]
    fn segments<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let out = PyList::empty(py);
        for s in &self.curve.segments {
            let d = PyDict::new(py);
            d.set_item("index", s.index)?;
            d.set_item("kind", s.kind.as_str())?;
            d.set_item("name", &s.name)?;
            d.set_item("duration", s.duration)?;
            d.set_item("time", PyArray1::from_slice(py, &s.time))?;
            let (ch, units) = (PyDict::new(py), PyDict::new(py));
            for c in &s.channels {
                ch.set_item(&c.name, PyArray1::from_slice(py, &c.values))?;
                units.set_item(&c.name, &c.unit)?;
            }
            d.set_item("channels", ch)?;
            d.set_item("units", units)?;
            out.append(d)?;
        }
        Ok(out)
    }
    /// The summary `nlvid --json inspect` prints (with every sample when
    /// `samples`).
    #[pyo3(signature = (samples = false))]
    fn summary<'py>(&self, py: Python<'py>, samples: bool) -> PyResult<Bound<'py, PyDict>> {
        crate::pyjson::dict(
            py,
            &nlvid_afm::summary_json(&self.curve, self.n_curves, samples),
        )
    }
    /// The curve as CSV text (`nlvid inspect --csv`).
    fn to_csv(&self) -> PyResult<String> {
        let mut buf = Vec::new();
        self.curve.write_csv(&mut buf).py()?;
        Ok(String::from_utf8_lossy(&buf).into_owned())
    }
    /// A curve given as columns: an afmformats data object
    /// (`afmformats.load_data(path)[i]`) or a dict of float64 arrays with
    /// afmformats' column names (`force` [N], `height (measured)` and/or
    /// `height (piezo)` [m], `time` [s], `segment`); `metadata` (default:
    /// `data.metadata`) must give `spring constant` [N/m]. Segment kinds
    /// are inferred from the piezo height (`crates/py/src/columns.rs`).
    #[staticmethod]
    #[pyo3(signature = (data, metadata = None, source = None))]
    fn from_columns(
        data: &Bound<'_, PyAny>,
        metadata: Option<Bound<'_, PyAny>>,
        source: Option<String>,
    ) -> PyResult<Self> {
        let meta = crate::columns::optional_mapping(metadata)?;
        let curve = crate::columns::force_curve(data, meta.as_ref(), source)?;
        Ok(Self { curve, n_curves: 1 })
    }
    fn __len__(&self) -> usize {
        self.curve.len()
    }
    fn __repr__(&self) -> String {
        let kinds: Vec<&str> = self
            .curve
            .segments
            .iter()
            .map(|s| s.kind.as_str())
            .collect();
        format!(
            "<nlvid.ForceCurve {} [{}], {} samples>",
            self.curve.source,
            kinds.join(", "),
            self.curve.len()
        )
    }
}

/// Reads a JPK file (`.jpk-force`, `.jpk-force-map`, QI data): a list of
/// `ForceCurve`, one per curve. `spring_constant` ("0.12 N/m") and
/// `sensitivity` ("110 nm/V") replace the file's calibration.
#[pyfunction]
#[pyo3(signature = (path, spring_constant = None, sensitivity = None))]
fn read_jpk(
    py: Python<'_>,
    path: PathBuf,
    spring_constant: Option<Bound<'_, PyAny>>,
    sensitivity: Option<Bound<'_, PyAny>>,
) -> PyResult<Vec<ForceCurve>> {
    let options = nlvid_afm::ReadOptions {
        spring_constant: spring_constant
            .map(|k| quantity(&k, "spring_constant", Dimension::STIFFNESS))
            .transpose()?,
        sensitivity: sensitivity
            .map(|s| quantity(&s, "sensitivity", Dimension::LENGTH_PER_VOLTAGE))
            .transpose()?,
    };
    let curves = py
        .detach(|| nlvid_afm::read_force_map(&path, &options))
        .py_ctx(|| format!("reading {}", path.display()))?;
    let n = curves.len();
    Ok(curves
        .into_iter()
        .map(|curve| ForceCurve { curve, n_curves: n })
        .collect())
}

fn contact_method(name: &str) -> PyResult<nlvid_afm::ContactMethod> {
    nlvid_afm::ContactMethod::from_name(name).map_err(|e| input(format!("contact: {e}")))
}

/// A `ForceCurve`, or anything [`ForceCurve::from_columns`] takes (an
/// afmformats data object, a dict of columns), converted.
fn with_curve<T>(
    curve: &Bound<'_, PyAny>,
    f: impl FnOnce(&nlvid_afm::ForceCurve) -> PyResult<T>,
) -> PyResult<T> {
    if let Ok(c) = curve.cast::<ForceCurve>() {
        return f(&c.get().curve);
    }
    f(&crate::columns::force_curve(curve, None, None)?)
}

/// `nlvid_afm::quick_fit` of `curve` (as [`with_curve`] takes it) as the
/// dict of `nlvid --json inspect` plus the `plot` arrays.
fn quick<'py>(
    py: Python<'py>,
    curve: &Bound<'py, PyAny>,
    kind: QuickFitKind,
    tip_radius: &Bound<'py, PyAny>,
    contact: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let r = quantity(tip_radius, "tip_radius", Dimension::LENGTH)?;
    let method = contact_method(contact)?;
    let f = with_curve(curve, |c| {
        py.detach(|| nlvid_afm::quick_fit(c, kind, r, method)).py()
    })?;
    let d = crate::pyjson::dict(py, &f.to_json())?;
    let plot = PyDict::new(py);
    plot.set_item("x", PyArray1::from_slice(py, &f.x))?;
    plot.set_item("x_label", f.x_label)?;
    plot.set_item("data_nN", PyArray1::from_slice(py, &f.data))?;
    plot.set_item("model_nN", PyArray1::from_slice(py, &f.model_force))?;
    d.set_item("plot", plot)?;
    d.set_item("text", f.text)?;
    Ok(d)
}

/// Paraboloidal Hertz fit (eq. 1.1) of a curve's approach, E and contact
/// point free (`nlvid inspect --fit hertz`). `curve`: a `ForceCurve`, an
/// afmformats data object or a dict of columns (`ForceCurve.from_columns`). `tip_radius` with a unit
/// ("5 um"); `contact`: "deviation" or "piecewise". Returns the values of
/// `nlvid --json inspect` (`youngs_modulus_Pa`, `contact_point_m`, …) and
/// `plot` arrays.
#[pyfunction]
#[pyo3(signature = (curve, tip_radius, poisson = 0.5, contact = "deviation"))]
fn hertz<'py>(
    py: Python<'py>,
    curve: &Bound<'py, PyAny>,
    tip_radius: Bound<'py, PyAny>,
    poisson: f64,
    contact: &str,
) -> PyResult<Bound<'py, PyDict>> {
    quick(
        py,
        curve,
        QuickFitKind::Hertz { poisson },
        &tip_radius,
        contact,
    )
}

/// Lee–Radok Prony fit of a curve's extend + hold segments
/// (`nlvid inspect --fit lee-radok`), `terms` 1 to 3; `curve` as for
/// [`hertz`].
#[pyfunction]
#[pyo3(signature = (curve, tip_radius, terms = 2, contact = "deviation"))]
fn lee_radok<'py>(
    py: Python<'py>,
    curve: &Bound<'py, PyAny>,
    tip_radius: Bound<'py, PyAny>,
    terms: usize,
    contact: &str,
) -> PyResult<Bound<'py, PyDict>> {
    quick(
        py,
        curve,
        QuickFitKind::LeeRadok { terms },
        &tip_radius,
        contact,
    )
}

/// Hertz fit (eq. 1.1, paraboloid of radius `tip_radius`) of `force` (N)
/// against tip–sample `separation` (m), both float64 arrays, with a force
/// offset and the contact point free (`nlvid_afm::fit_hertz`).
#[pyfunction]
#[pyo3(signature = (separation, force, tip_radius, poisson = 0.5))]
fn fit_hertz<'py>(
    py: Python<'py>,
    separation: &Bound<'py, PyAny>,
    force: &Bound<'py, PyAny>,
    tip_radius: &Bound<'py, PyAny>,
    poisson: f64,
) -> PyResult<Bound<'py, PyDict>> {
    let (s, f) = (vector(separation, "separation")?, vector(force, "force")?);
    same_length(&[("separation", s.len()), ("force", f.len())])?;
    let r = quantity(tip_radius, "tip_radius", Dimension::LENGTH)?;
    let settings = nlvid_afm::HertzSettings::new(r, poisson);
    let (sv, fv) = (s.values(), f.values());
    let h = py
        .detach(|| nlvid_afm::fit_hertz(&sv, &fv, &settings))
        .py()?;
    hertz_dict(py, &h)
}

pub(crate) fn hertz_dict<'py>(
    py: Python<'py>,
    h: &nlvid_afm::HertzFit,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("youngs_modulus_Pa", h.youngs_modulus)?;
    d.set_item("contact_point_m", h.contact_point)?;
    d.set_item("offset_N", h.offset)?;
    d.set_item("rmse_N", h.rmse)?;
    d.set_item("range_normalised_rmse", h.range_normalised_rmse)?;
    d.set_item("n_points", h.n_points)?;
    d.set_item("max_indentation_m", h.max_indentation)?;
    d.set_item("contact_at_edge", h.contact_at_edge())?;
    Ok(d)
}

/// Lee–Radok Prony fit of a ramp-hold: `force` (N) against `time` (s) and
/// `indentation` (m) from contact, probe radius `tip_radius`, `terms` 1 to
/// 3 (`nlvid_afm::fit_lee_radok`). Returns `g0_Pa`, `g_inf_Pa`, `terms`
/// (list of `{g_Pa, tau_s}`), `rmse_N`, `range_normalised_rmse`,
/// `iterations`, `force_fit` (array).
#[pyfunction]
#[pyo3(signature = (time, indentation, force, tip_radius, terms = 2))]
fn fit_lee_radok<'py>(
    py: Python<'py>,
    time: &Bound<'py, PyAny>,
    indentation: &Bound<'py, PyAny>,
    force: &Bound<'py, PyAny>,
    tip_radius: &Bound<'py, PyAny>,
    terms: usize,
) -> PyResult<Bound<'py, PyDict>> {
    let (t, x, f) = (
        vector(time, "time")?,
        vector(indentation, "indentation")?,
        vector(force, "force")?,
    );
    same_length(&[
        ("time", t.len()),
        ("indentation", x.len()),
        ("force", f.len()),
    ])?;
    let mut s =
        nlvid_afm::LeeRadokSettings::new(quantity(tip_radius, "tip_radius", Dimension::LENGTH)?);
    s.n_terms = terms;
    let (tv, xv, fv) = (t.values(), x.values(), f.values());
    let r = py
        .detach(|| nlvid_afm::fit_lee_radok(&tv, &xv, &fv, &s))
        .py()?;
    let g = &r.relaxation;
    let d = PyDict::new(py);
    d.set_item("g0_Pa", g.g0())?;
    d.set_item("g_inf_Pa", g.g_inf())?;
    let terms = PyList::empty(py);
    for t in g.prony().terms() {
        let e = PyDict::new(py);
        e.set_item("g_Pa", g.g0() * t.weight)?;
        e.set_item("tau_s", t.tau)?;
        terms.append(e)?;
    }
    d.set_item("terms", terms)?;
    d.set_item("rmse_N", r.rmse)?;
    d.set_item("range_normalised_rmse", r.range_normalised_rmse)?;
    d.set_item("iterations", r.iterations)?;
    d.set_item("force_fit", PyArray1::from_slice(py, &r.force_fit))?;
    Ok(d)
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<ForceCurve>()?;
    m.add_function(wrap_pyfunction!(read_jpk, m)?)?;
    m.add_function(wrap_pyfunction!(hertz, m)?)?;
    m.add_function(wrap_pyfunction!(lee_radok, m)?)?;
    m.add_function(wrap_pyfunction!(fit_hertz, m)?)?;
    m.add_function(wrap_pyfunction!(fit_lee_radok, m)?)?;
    Ok(())
}
