//! Adapters between the Kriging surrogate (crate `nlvid-surrogate`) and the
//! fitter (thesis §4.4.1 steps 4–5, §5.4.1, App. A.2).
//!
//! - [`KrigingSurrogate`]: a fitted [`KrigingModel`] on a time grid, seen as
//!   a [`Model`] (the surrogate's own predictor and analytic gradient) and
//!   as a [`BasisModel`] (ŷ = μ + Bᵀφ(x) for the O(N²) eq. 5.3 misfit of
//!   [`crate::BasisMisfit`]). The surrogate's inputs are the [`Domain`]'s
//!   parameters in the domain's order (the one order of `nlvid_model`), as
//!   physical values or the domain's scaled coordinates u ∈ [0, 1]
//!   ([`Coordinates`]).
//! - [`ForwardFromModel`]: any [`Model`] (e.g. the analytic
//!   [`crate::LeeRadokHertz`]) as a surrogate-build [`ForwardModel`], so
//!   `nlvid_surrogate::build` can run it over a design drawn in the same
//!   [`Domain`].

use std::sync::OnceLock;

use nalgebra::{DMatrix, DVector};
use nlvid_model::{Domain, FailureKind, ForwardModel, RunFailure, Scale};
use nlvid_surrogate::{CalibrationData, KrigingModel, SurrogateError, VarianceCalibration};

use crate::basis::BasisModel;
use crate::error::{InverseError, Result};
use crate::model::{Model, check_len};
use crate::reduced::ReducedModel;

/// What the surrogate's inputs are.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Coordinates {
    /// Physical (SI) parameter values, as in the run store's design.
    Physical,
    /// The domain's scaled coordinates u ∈ [0, 1] (log axes in ln x).
    Unit,
}

/// A Kriging surrogate of a forward model on a fixed time grid.
#[derive(Debug, Clone)]
pub struct KrigingSurrogate {
    kriging: KrigingModel,
    domain: Domain,
    times: Vec<f64>,
    coordinates: Coordinates,
    b: DMatrix<f64>,
    mu: Vec<f64>,
    /// Output map A of the reduced form ŷ = A c(x) (m × (q + 1)), built
    /// on first use (without a PCA it is m × (m + 1) and rarely wanted).
    a: OnceLock<DMatrix<f64>>,
    /// The leave-one-out data of the Kriging variance calibration and its
    /// Gaussian and Student-t fits, each computed on first use.
    calibration_data: OnceLock<std::result::Result<CalibrationData, String>>,
    gaussian: OnceLock<std::result::Result<VarianceCalibration, String>>,
    student: OnceLock<std::result::Result<VarianceCalibration, String>>,
    /// The cross-validated output covariance, computed on first use.
    cv_cov: OnceLock<std::result::Result<nlvid_surrogate::OutputCovariance, String>>,
    /// The per-direction calibration and its output covariance, computed
    /// on first use.
    directions: OnceLock<std::result::Result<DirectionCalibration, String>>,
}

/// A per-direction calibration of the Kriging variance
/// ([`VarianceCalibration::fit_directions`]) with the output covariance
/// whose eigen-directions it scales
/// ([`KrigingModel::output_covariance_cv_scaled`]).
type DirectionCalibration = (VarianceCalibration, nlvid_surrogate::OutputCovariance);

fn model_err(x: &[f64], e: &SurrogateError) -> InverseError {
    InverseError::Model {
        x: x.to_vec(),
        message: format!("Kriging surrogate: {e}"),
    }
}

impl KrigingSurrogate {
    /// Wraps a fitted model whose inputs are the parameters of `domain`, in
    /// its order, and whose outputs are the response at `times` (s).
    ///
    /// Cost: O(N · q · m) once, to fold the output scaling into B.
    ///
    /// # Errors
    /// [`InverseError::InvalidSetting`] when the input or output counts do
    /// not match.
    pub fn new(
        kriging: KrigingModel,
        domain: Domain,
        times: Vec<f64>,
        coordinates: Coordinates,
    ) -> Result<Self> {
        if kriging.dim != domain.len() {
            return Err(InverseError::InvalidSetting(format!(
                "the surrogate has {} inputs, the parameter domain {} ({})",
                kriging.dim,
                domain.len(),
                domain.names().join(", ")
            )));
        }
        if kriging.n_outputs != times.len() {
            return Err(InverseError::InvalidSetting(format!(
                "the surrogate predicts {} values, the time grid has {}",
                kriging.n_outputs,
                times.len()
            )));
        }
        let (b, mu) = kriging.basis_coefficients();
        let b = DMatrix::from_column_slice(kriging.n_basis(), kriging.n_outputs, &b);
        let s = Self {
            kriging,
            domain,
            times,
            coordinates,
            b,
            mu,
            a: OnceLock::new(),
            calibration_data: OnceLock::new(),
            gaussian: OnceLock::new(),
            student: OnceLock::new(),
            cv_cov: OnceLock::new(),
            directions: OnceLock::new(),
        };
        s.check_basis_form()?;
        Ok(s)
    }

    /// The fast misfit (`BasisMisfit`) relies on ŷ(x) = μ + Bᵀφ(x) exactly;
    /// a predictor that is not linear in its basis (e.g. one kriging ln y)
    /// would make it silently wrong. Compared once, at u = 0.4 in every
    /// scaled coordinate (inside the domain, off any symmetry), to 1e-8 of
    /// the curve's magnitude plus the rounding of the two sums: both are
    /// sums of the same N = n_basis terms in another order, so they may
    /// differ by about ε·Σ_a|B_aj φ_a| (allowed: 64 ε Σ_a|B_aj φ_a|). That
    /// term matters for a closely correlated design (small θ, large γ):
    /// the N = 970 FE meta-model of the demo sums terms 2·10⁸ times the
    /// curve, and its two forms differ by 1.4e-8 of the curve — rounding,
    /// while a ln y predictor differs by 1e-3 or more.
    fn check_basis_form(&self) -> Result<()> {
        let x = self.domain.from_unit(&vec![0.4; self.domain.len()]);
        let direct = Model::response(self, &x)?;
        let (phi, _) = BasisModel::basis(self, &x)?;
        let via_basis = self.b.transpose() * &phi;
        let scale = direct.iter().fold(f64::MIN_POSITIVE, |a, v| a.max(v.abs()));
        // Σ_a |B_aj φ_a| per output j.
        let magnitude = self.b.abs().transpose() * phi.abs();
        let mut worst = (0.0, 0.0);
        for (j, y) in direct.iter().enumerate() {
            let diff = (y - (self.mu[j] + via_basis[j])).abs();
            let allowed = 1e-8 * scale + 64.0 * f64::EPSILON * magnitude[j];
            if diff / allowed > worst.0 {
                worst = (diff / allowed, diff);
            }
        }
        if worst.0 <= 1.0 {
            Ok(())
        } else {
            Err(InverseError::InvalidSetting(format!(
                "the surrogate's predictor is not of the form mu + B^T phi(x) (differs by {:.2e} \
                 of the curve at x = {x:?}, beyond rounding), which the fast eq. 5.3 misfit \
                 needs: refit the surrogate without output transforms such as --log-outputs",
                worst.1 / scale
            )))
        }
    }

    /// The parameter domain (the surrogate's inputs, in order).
    pub fn domain(&self) -> &Domain {
        &self.domain
    }

    /// The wrapped Kriging model.
    pub fn kriging(&self) -> &KrigingModel {
        &self.kriging
    }

    /// True when the outputs are PCA-reduced (q + 1 < m coordinates): the
    /// reduced misfit ([`crate::ReducedMisfit`]) then costs O(N·q·n) per
    /// evaluation instead of O(N·m).
    pub fn is_reduced(&self) -> bool {
        self.kriging.pca.is_some() && self.kriging.n_output_coordinates() < self.kriging.n_outputs
    }

    /// v(x) of the Kriging MSE at physical x: the predictive covariance of
    /// the curve is v(x)·K with K of [`KrigingModel::output_covariance`]
    /// (DACE report eq. 2.20; see `nlvid_surrogate::OutputCovariance`).
    ///
    /// # Errors
    /// As [`KrigingModel::mse_scale`], naming x.
    pub fn mse_scale(&self, x: &[f64]) -> Result<f64> {
        let (xs, _) = self.inputs(x)?;
        self.kriging.mse_scale(&xs).map_err(|e| model_err(x, &e))
    }

    /// The reduced coordinates c(x) ([`crate::ReducedModel`]) and v(x)
    /// ([`KrigingSurrogate::mse_scale`]) at many physical points at once
    /// ([`KrigingModel::coordinates_and_mse_scales`]: one multi-column
    /// triangular solve for the batch, split over up to `threads` threads
    /// with the same values for any count).
    ///
    /// # Errors
    /// As [`KrigingSurrogate::mse_scale`] for any point (naming the first).
    pub fn coordinates_and_mse_scales(
        &self,
        xs: &[Vec<f64>],
        threads: usize,
    ) -> Result<(Vec<DVector<f64>>, Vec<f64>)> {
        let inputs = xs
            .iter()
            .map(|x| Ok(self.inputs(x)?.0))
            .collect::<Result<Vec<_>>>()?;
        let (c, v) = self
            .kriging
            .coordinates_and_mse_scales(&inputs, threads)
            .map_err(|e| model_err(xs.first().map_or(&[][..], Vec::as_slice), &e))?;
        Ok((c.into_iter().map(DVector::from_vec).collect(), v))
    }

    /// The reduced coordinates c(x) alone at many physical points
    /// ([`KrigingModel::output_coordinate_batch`]: no variance, so no
    /// O(N²) solve), bit for bit those of
    /// [`KrigingSurrogate::coordinates_and_mse_scales`], split over
    /// `threads` as there.
    ///
    /// # Errors
    /// As [`KrigingSurrogate::coordinates_and_mse_scales`].
    pub fn coordinate_batch(&self, xs: &[Vec<f64>], threads: usize) -> Result<Vec<DVector<f64>>> {
        let inputs = xs
            .iter()
            .map(|x| Ok(self.inputs(x)?.0))
            .collect::<Result<Vec<_>>>()?;
        let c = self
            .kriging
            .output_coordinate_batch(&inputs, threads)
            .map_err(|e| model_err(xs.first().map_or(&[][..], Vec::as_slice), &e))?;
        Ok(c.into_iter().map(DVector::from_vec).collect())
    }

    /// The x-dependent calibration of the Kriging variance, v(x) ↦
    /// α·v(x)^β, fitted by maximum likelihood to the model's own
    /// leave-one-out residuals under the K of
    /// [`KrigingSurrogate::output_covariance_cv`]
    /// (docs/theory/inverse.md, "Fifth round"): with `heavy_tails` the
    /// Student-t scale mixture with its ν
    /// ([`VarianceCalibration::fit_student`]), else Gaussian
    /// ([`VarianceCalibration::fit`]). The leave-one-out data are computed
    /// once per surrogate (O(N³/3)), each fit once.
    ///
    /// # Errors
    /// A process covariance that is not positive semi-definite; LOO data
    /// the fit refuses (e.g. all v equal).
    pub fn variance_calibration(&self, heavy_tails: bool) -> Result<VarianceCalibration> {
        let data = || {
            self.calibration_data
                .get_or_init(|| {
                    self.kriging
                        .loo_calibration_data()
                        .map_err(|e| e.to_string())
                })
                .clone()
        };
        let fit =
            |cell: &OnceLock<std::result::Result<VarianceCalibration, String>>,
             f: fn(&CalibrationData) -> nlvid_surrogate::Result<VarianceCalibration>| {
                cell.get_or_init(|| f(&data()?).map_err(|e| e.to_string()))
                    .clone()
            };
        if heavy_tails {
            fit(&self.student, VarianceCalibration::fit_student)
        } else {
            fit(&self.gaussian, VarianceCalibration::fit)
        }
        .map_err(|e| InverseError::InvalidSetting(format!("Kriging variance calibration: {e}")))
    }

    /// The per-direction calibration of the Kriging variance, a scale per
    /// eigen-direction of the cross-validated Σ with one exponent β
    /// ([`VarianceCalibration::fit_directions`] on the same leave-one-out
    /// data as [`KrigingSurrogate::variance_calibration`]), with the output
    /// covariance K it scales
    /// ([`KrigingModel::output_covariance_cv_scaled`]): the surrogate
    /// error is N(0, α v(x)^β K). Computed once per surrogate.
    ///
    /// # Errors
    /// As [`KrigingSurrogate::variance_calibration`] and
    /// [`KrigingSurrogate::output_covariance_cv`].
    pub fn direction_calibration(
        &self,
    ) -> Result<(VarianceCalibration, nlvid_surrogate::OutputCovariance)> {
        self.directions
            .get_or_init(|| {
                let data = self
                    .calibration_data
                    .get_or_init(|| {
                        self.kriging
                            .loo_calibration_data()
                            .map_err(|e| e.to_string())
                    })
                    .clone()?;
                let cal = VarianceCalibration::fit_directions(&data).map_err(|e| e.to_string())?;
                let cov = self
                    .kriging
                    .output_covariance_cv_scaled(&cal.directions)
                    .map_err(|e| e.to_string())?;
                Ok((cal, cov))
            })
            .clone()
            .map_err(|e| InverseError::InvalidSetting(format!("Kriging variance calibration: {e}")))
    }

    /// The process covariance K of the outputs with the kriged outputs'
    /// covariance estimated by leave-one-out cross-validation
    /// ([`KrigingModel::output_covariance_cv`]), computed once per
    /// surrogate (O(N³/3)): the K of the posteriors' likelihood.
    ///
    /// # Errors
    /// A model with ln outputs; a covariance that is not positive
    /// semi-definite.
    pub fn output_covariance_cv(&self) -> Result<nlvid_surrogate::OutputCovariance> {
        self.cv_cov
            .get_or_init(|| {
                self.kriging
                    .output_covariance_cv()
                    .map_err(|e| e.to_string())
            })
            .clone()
            .map_err(|e| InverseError::InvalidSetting(format!("Kriging variance: {e}")))
    }

    /// Surrogate inputs at physical x and d(input_i)/d(x_i).
    fn inputs(&self, x: &[f64]) -> Result<(Vec<f64>, Vec<f64>)> {
        self.domain.check_len(x)?;
        let params = self.domain.params();
        let mut xs = Vec::with_capacity(x.len());
        let mut ds = Vec::with_capacity(x.len());
        for (i, p) in params.iter().enumerate() {
            match self.coordinates {
                Coordinates::Physical => {
                    xs.push(x[i]);
                    ds.push(1.0);
                }
                Coordinates::Unit => {
                    if p.scale == Scale::Log && x[i] <= 0.0 {
                        return Err(InverseError::Model {
                            x: x.to_vec(),
                            message: format!(
                                "log-scaled parameter '{}' must be > 0 for the surrogate",
                                p.name
                            ),
                        });
                    }
                    let u = p.to_unit(x[i]);
                    xs.push(u);
                    ds.push(1.0 / p.dx_du(u));
                }
            }
        }
        Ok((xs, ds))
    }
}

impl BasisModel for KrigingSurrogate {
    fn domain(&self) -> &Domain {
        &self.domain
    }
    fn times(&self) -> &[f64] {
        &self.times
    }
    fn basis(&self, x: &[f64]) -> Result<(DVector<f64>, DMatrix<f64>)> {
        let (xs, ds) = self.inputs(x)?;
        let (phi, dphi_s) = self.kriging.basis(&xs).map_err(|e| model_err(x, &e))?;
        let (nb, d) = (phi.len(), xs.len());
        let mut dphi = DMatrix::zeros(nb, d);
        for a in 0..nb {
            for i in 0..d {
                dphi[(a, i)] = dphi_s[a * d + i] * ds[i];
            }
        }
        Ok((DVector::from_vec(phi), dphi))
    }
    fn coefficients(&self) -> &DMatrix<f64> {
        &self.b
    }
    fn offset(&self) -> &[f64] {
        &self.mu
    }
}

impl ReducedModel for KrigingSurrogate {
    fn domain(&self) -> &Domain {
        &self.domain
    }
    fn times(&self) -> &[f64] {
        &self.times
    }
    fn output_map(&self) -> &DMatrix<f64> {
        self.a.get_or_init(|| {
            let (m, r) = (self.kriging.n_outputs, self.kriging.n_output_coordinates());
            match self.kriging.output_map() {
                Ok(a) => DMatrix::from_column_slice(m, r, &a),
                // Unreachable: `new` refuses models whose predictor is not
                // linear (ln outputs); a NaN map makes `projection` fail
                // with a typed error rather than fit silently.
                Err(_) => DMatrix::from_element(m, r, f64::NAN),
            }
        })
    }
    /// c(x) = s(x)·[1; z(x)] with z the kriged outputs (PC scores),
    /// O(N·q·n) (`KrigingModel::output_coordinates`).
    fn coordinates(&self, x: &[f64]) -> Result<(DVector<f64>, DMatrix<f64>)> {
        let (xs, ds) = self.inputs(x)?;
        let (c, dc_s) = self
            .kriging
            .output_coordinates(&xs)
            .map_err(|e| model_err(x, &e))?;
        let (r, d) = (c.len(), xs.len());
        let mut dc = DMatrix::zeros(r, d);
        for l in 0..r {
            for i in 0..d {
                dc[(l, i)] = dc_s[l * d + i] * ds[i];
            }
        }
        Ok((DVector::from_vec(c), dc))
    }
    fn coordinate_values(&self, x: &[f64]) -> Result<DVector<f64>> {
        let (xs, _) = self.inputs(x)?;
        let c = self
            .kriging
            .output_coordinate_values(&xs)
            .map_err(|e| model_err(x, &e))?;
        Ok(DVector::from_vec(c))
    }
}

impl Model for KrigingSurrogate {
    fn domain(&self) -> &Domain {
        &self.domain
    }
    fn times(&self) -> &[f64] {
        &self.times
    }
    /// The Kriging predictor ŷ(x) (DACE report eq. 2.16).
    fn response(&self, x: &[f64]) -> Result<Vec<f64>> {
        let (xs, _) = self.inputs(x)?;
        self.kriging.predict(&xs).map_err(|e| model_err(x, &e))
    }
    fn jacobian(&self, x: &[f64]) -> Result<DMatrix<f64>> {
        Ok(self.response_and_jacobian(x)?.1)
    }
    /// Predictor and its analytic gradient (DACE `predictor`, report eq. 2.18).
    fn response_and_jacobian(&self, x: &[f64]) -> Result<(Vec<f64>, DMatrix<f64>)> {
        let (xs, ds) = self.inputs(x)?;
        let pp = self
            .kriging
            .predict_full(&xs)
            .map_err(|e| model_err(x, &e))?;
        let (m, d) = (pp.y.len(), xs.len());
        let mut jac = DMatrix::zeros(m, d);
        for j in 0..m {
            for i in 0..d {
                jac[(j, i)] = pp.dy[j * d + i] * ds[i];
            }
        }
        Ok((pp.y, jac))
    }
}

/// A [`Model`] run as a surrogate-build [`ForwardModel`]: parameters in the
/// domain's order and units, response on the model's grid; a failed run is
/// [`FailureKind::Other`] with the model's message.
#[derive(Debug, Clone)]
pub struct ForwardFromModel<M> {
    /// The model.
    pub model: M,
    /// Identity recorded in the run store (model name and settings).
    pub identity: String,
}

impl<M: Model + Sync> ForwardModel for ForwardFromModel<M> {
    fn parameter_names(&self) -> Vec<String> {
        self.model
            .domain()
            .params()
            .iter()
            .map(|p| p.name.clone())
            .collect()
    }
    fn parameter_units(&self) -> Vec<String> {
        self.model
            .domain()
            .params()
            .iter()
            .map(|p| p.unit.clone())
            .collect()
    }
    fn time_grid(&self) -> &[f64] {
        self.model.times()
    }
    fn identity(&self) -> String {
        self.identity.clone()
    }
    fn run(&self, params: &[f64]) -> std::result::Result<Vec<f64>, RunFailure> {
        let fail = |e: InverseError| RunFailure::new(FailureKind::Other, e.to_string());
        let y = self.model.response(params).map_err(fail)?;
        check_len("model response", self.model.times().len(), y.len()).map_err(fail)?;
        Ok(y)
    }
}
