//! The Kriging variance without the predictor: the MSE factor φ(x) of
//! DACE report eq. 2.20, MSE_j(x) = σ_j²·φ(x), the posterior covariance of
//! two points and the predicted range-normalised error (thesis eq. 4.4
//! with the MSE in place of the squared error) that adaptive infill
//! ([`crate::infill`]) maximises.
//!
//! With rt = C⁻¹r(x) and v = G⁻ᵀ(F̃ᵀrt − f(x)) (R = CCᵀ, F̃ = C⁻¹F = QG):
//! φ(x) = 1 + |v|² − |rt|², and the universal-Kriging posterior covariance
//! of two points is σ²·k(a, b) with
//! k(a, b) = R(a, b) − rt_a·rt_b + v_a·v_b
//! (uᵀ(FᵀR⁻¹F)⁻¹u = |G⁻ᵀu|² since FᵀR⁻¹F = GᵀG). Conditioning on one more
//! noise-free site s at fixed θ updates k to k(a, b) − k(a, s)k(s, b)/k(s, s)
//! (the MSE does not depend on the outputs, so this is the exact MSE of
//! the model refitted with s added, same θ and normalisation).
//!
//! The predictor's error covariance across outputs, for likelihoods that
//! fold the surrogate's own uncertainty into the data variance (issue 17:
//! posteriors on the surrogate).
//!
//! Every kriged output shares one correlation model, so the MSE of DACE
//! report eq. 2.20 factors as `MSE_j(x) = v(x)·K_jj` with one scalar
//! `v(x) = s(x)²·φ(x)`, `φ(x) = 1 + uᵀ(FᵀR⁻¹F)⁻¹u − rᵀR⁻¹r` (s the
//! [`OutputScale`](super::OutputScale), 1 without) and K the process
//! covariance of the outputs. With a PCA the outputs are ŷ = μ + D V z
//! (D = diag(σ_y), V the kept components) and the scores' process
//! covariance is Σ = ρᵀρ/n (cross terms included), so the whole predictive
//! covariance is `Cov[ŷ(x)] = v(x)·U Uᵀ`, `U = D V L`, `L Lᵀ = Σ` — rank k
//! (k ≈ 8), which keeps a Gaussian likelihood with it O(k²) per evaluation
//! by the Woodbury identity. Without a PCA DACE krige each output on its
//! own and K is diagonal (σ²_j σ_y,j²).

use faer::linalg::triangular_solve::solve_lower_triangular_in_place;
use faer::{Mat, Par};

use super::calibration::{CalibrationData, VarianceCalibration};
use super::{KrigingModel, to_vec, view};
use crate::error::{Result, SurrogateError};
use crate::likelihood::Problem;

/// The factors of the MSE (DACE report eq. 2.20): R = CCᵀ (C lower, n × n),
/// F̃ = C⁻¹F (n × p) and G (upper, F̃ = QG, p × p), column-major. They do
/// not depend on the outputs, so a model file leaves them out and
/// [`KrigingModel::mse_factors`] rebuilds them once from the sites, θ and
/// the nugget — the same computation as the fit's (`Problem::factor`).
#[derive(Debug, Clone)]
pub(crate) struct MseFactors {
    c: Vec<f64>,
    ft: Vec<f64>,
    g: Vec<f64>,
}

impl MseFactors {
    pub(crate) fn new(c: Mat<f64>, ft: Mat<f64>, g: Mat<f64>) -> Self {
        Self {
            c: to_vec(c.as_ref()),
            ft: to_vec(ft.as_ref()),
            g: to_vec(g.as_ref()),
        }
    }

    pub(crate) fn c(&self, n: usize) -> faer::MatRef<'_, f64> {
        view(&self.c, n, n)
    }

    pub(crate) fn ft(&self, n: usize, p: usize) -> faer::MatRef<'_, f64> {
        view(&self.ft, n, p)
    }

    pub(crate) fn g(&self, p: usize) -> faer::MatRef<'_, f64> {
        view(&self.g, p, p)
    }
}

/// What [`KrigingModel::variance_point`] keeps of a point x for the
/// covariances k(x, ·).
#[derive(Debug, Clone)]
pub struct VariancePoint {
    /// Normalised internal coordinates of x.
    xn: Vec<f64>,
    /// C⁻¹r(x).
    rt: Vec<f64>,
    /// G⁻ᵀ(F̃ᵀrt − f(x)).
    v: Vec<f64>,
    /// φ(x) = k(x, x).
    pub phi: f64,
}

impl KrigingModel {
    /// The MSE factors: those of the fit, or (for a loaded model) R(θ)
    /// rebuilt at the stored sites, θ and nugget and factorised once
    /// (n³/3 flops; ≈ 0.1 s for n = 970).
    ///
    /// # Errors
    /// Stored sites of the wrong size, or a stored θ that no longer gives
    /// a positive definite R (a corrupted or hand-edited file).
    pub(crate) fn mse_factors(&self) -> Result<&MseFactors> {
        if let Some(f) = self.factors.get() {
            return Ok(f);
        }
        let (n, d) = (self.n_sites, self.dim);
        if self.sites.len() != n * d {
            return Err(SurrogateError::InvalidInput(format!(
                "model file: {} site coordinates for n_sites = {n}, dim = {d}",
                self.sites.len()
            )));
        }
        let sites = view(&self.sites, n, d);
        let none = Mat::<f64>::zeros(n, 0);
        let prob = Problem::new(
            sites,
            none.as_ref(),
            self.regression,
            self.correlation,
            self.report.nugget,
        );
        let Some((c, ft, g)) = prob.factor(&self.theta)? else {
            return Err(SurrogateError::NotPositiveDefinite {
                theta: self.theta.clone(),
                nugget: self.report.nugget,
            });
        };
        Ok(self.factors.get_or_init(|| MseFactors::new(c, ft, g)))
    }

    /// φ(x) at a caller's point: the MSE of every output is
    /// MSE_j(x) = σ_j²·φ(x) (DACE report eq. 2.20; σ_j² =
    /// [`KrigingModel::process_variance`]), times s(x)² with an output scale
    /// and times ŷ_j² with ln outputs (as [`KrigingModel::predict_full`]).
    ///
    /// # Errors
    /// `x` of the wrong length, not finite, or ≤ 0 on a log input.
    pub fn mse_factor(&self, x: &[f64]) -> Result<f64> {
        Ok(self.variance_point(x)?.phi)
    }

    /// The quantities of x needed for φ(x) and k(x, ·).
    ///
    /// # Errors
    /// As [`KrigingModel::mse_factor`].
    pub fn variance_point(&self, x: &[f64]) -> Result<VariancePoint> {
        let xi = self.internal_x(x)?;
        let (n, d, p) = (self.n_sites, self.dim, self.p());
        let xn: Vec<f64> = (0..d)
            .map(|k| (xi[k] - self.x_mean[k]) / self.x_std[k])
            .collect();
        let mut f = vec![0.0; p];
        self.regression.eval(&xn, &mut f);
        let mut dx = vec![0.0; d];
        let mut rt = Mat::<f64>::zeros(n, 1);
        for i in 0..n {
            for k in 0..d {
                dx[k] = xn[k] - self.sites[k * n + i];
            }
            rt[(i, 0)] = self.correlation.value(&self.theta, &dx);
        }
        let fm = Mat::<f64>::from_fn(p, 1, |k, _| f[k]);
        let v = self.solve_variance(rt.as_mut(), &fm)?;
        let phi = phi_of(rt.col(0).iter(), v.col(0).iter());
        let rt: Vec<f64> = rt.col(0).iter().copied().collect();
        let v: Vec<f64> = v.col(0).iter().copied().collect();
        Ok(VariancePoint { xn, rt, v, phi })
    }

    /// rt = C⁻¹r (in place, column by column of `r`, n × B) and
    /// v = G⁻ᵀ(F̃ᵀrt − f) (returned, p × B) for B points with regression
    /// values `f` (p × B): the two triangular solves of φ (module docs),
    /// all columns at once.
    fn solve_variance(&self, mut r: faer::MatMut<'_, f64>, f: &Mat<f64>) -> Result<Mat<f64>> {
        let (n, p) = (self.n_sites, self.p());
        let fac = self.mse_factors()?;
        solve_lower_triangular_in_place(fac.c(n), r.as_mut(), Par::Seq);
        let mut v = fac.ft(n, p).transpose() * r.as_ref() - f;
        solve_lower_triangular_in_place(fac.g(p).transpose(), v.as_mut(), Par::Seq);
        Ok(v)
    }

    /// φ(x) of each column of a batch of correlation columns `r` (n × B,
    /// overwritten by C⁻¹r) with regression values `f` (p × B).
    pub(crate) fn mse_factors_of(&self, mut r: Mat<f64>, f: &Mat<f64>) -> Result<Vec<f64>> {
        let v = self.solve_variance(r.as_mut(), f)?;
        Ok((0..r.ncols())
            .map(|j| phi_of(r.col(j).iter(), v.col(j).iter()))
            .collect())
    }

    /// k(a, b): the posterior covariance of the kriged outputs at a and b
    /// divided by σ² (k(a, a) = φ(a)).
    pub fn posterior_correlation(&self, a: &VariancePoint, b: &VariancePoint) -> f64 {
        let dx: Vec<f64> = a.xn.iter().zip(&b.xn).map(|(p, q)| p - q).collect();
        let r = self.correlation.value(&self.theta, &dx);
        let rr: f64 = a.rt.iter().zip(&b.rt).map(|(p, q)| p * q).sum();
        let vv: f64 = a.v.iter().zip(&b.v).map(|(p, q)| p * q).sum();
        r - rr + vv
    }

    /// The predicted range-normalised error at x,
    /// e(x) = sqrt(mean_j MSE_j(x)) / range_j ŷ_j(x) — thesis eq. 4.4 with
    /// the Kriging MSE in place of the squared error — written
    /// e² = φ(x)·a(x); returns a(x). `y` is the prediction ŷ(x)
    /// ([`KrigingModel::predict`]), `pv` [`KrigingModel::process_variance`]
    /// (both computed by the caller).
    ///
    /// # Errors
    /// A predicted curve of zero range.
    pub fn error_weight(&self, x: &[f64], y: &[f64], pv: &[f64]) -> Result<f64> {
        let s = match self.output_scale {
            Some(sc) => sc.eval(x).0,
            None => 1.0,
        };
        let mean_mse_over_phi = y
            .iter()
            .zip(pv)
            .map(|(yj, pj)| pj * if self.log_outputs { yj * yj } else { s * s })
            .sum::<f64>()
            / y.len() as f64;
        let hi = y.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let lo = y.iter().copied().fold(f64::INFINITY, f64::min);
        let range = hi - lo;
        if !(range > 0.0 && range.is_finite()) {
            return Err(crate::error::SurrogateError::InvalidInput(format!(
                "predicted curve of zero range at {x:?}"
            )));
        }
        Ok(mean_mse_over_phi / (range * range))
    }
}

/// φ = 1 + |v|² − |rt|² (module docs), clamped at 0 (rounding).
fn phi_of<'a>(rt: impl Iterator<Item = &'a f64>, v: impl Iterator<Item = &'a f64>) -> f64 {
    let phi = 1.0 + v.map(|a| a * a).sum::<f64>() - rt.map(|a| a * a).sum::<f64>();
    phi.max(0.0)
}

/// The process covariance K of the outputs (m × m), `Cov[ŷ(x)] = v(x)·K`
/// with v of [`KrigingModel::mse_scale`].
#[derive(Debug, Clone, PartialEq)]
pub enum OutputCovariance {
    /// K = U Uᵀ with U m × k, column-major (PCA-reduced models).
    LowRank {
        /// Rows m.
        m: usize,
        /// Columns k.
        k: usize,
        /// U, column-major m × k.
        factor: Vec<f64>,
    },
    /// K = diag(values) (outputs kriged one by one).
    Diagonal(Vec<f64>),
}

impl OutputCovariance {
    /// K_jj, the process variance of output j (equals
    /// [`KrigingModel::process_variance`]).
    pub fn diagonal(&self) -> Vec<f64> {
        match self {
            Self::Diagonal(v) => v.clone(),
            Self::LowRank { m, k, factor } => (0..*m)
                .map(|j| (0..*k).map(|a| factor[a * m + j].powi(2)).sum())
                .collect(),
        }
    }
}

impl KrigingModel {
    /// Score loadings l = Vᵀ D w of a linear functional wᵀy of the outputs
    /// (D = diag of the outputs' standard deviations, V the PCA basis): the
    /// functional's error is lᵀe for an error e in the kriged scores, so its
    /// variance under a score covariance Σ is lᵀ Σ l. None without a PCA;
    /// `w` must have one weight per output.
    pub fn score_loadings(&self, w: &[f64]) -> Option<Vec<f64>> {
        let pca = self.pca.as_ref()?;
        let m = self.n_outputs;
        debug_assert_eq!(w.len(), m);
        Some(
            (0..pca.n_components)
                .map(|a| {
                    (0..m)
                        .map(|j| pca.basis[a * m + j] * self.y_std[j] * w[j])
                        .sum()
                })
                .collect(),
        )
    }

    /// v(x) = s(x)²·φ(x): the factor with which every output's MSE
    /// (report eq. 2.20) scales the process covariance,
    /// `MSE_j(x) = v(x)·K_jj`. Value only, O(n²) (one triangular solve).
    ///
    /// # Errors
    /// `x` of the wrong length or not finite, s(x) ≤ 0, or a model with
    /// `log_outputs` (its MSE is a delta-method approximation, not of this
    /// form).
    pub fn mse_scale(&self, x: &[f64]) -> Result<f64> {
        self.check_linear_for_variance()?;
        // φ(x) of the one variance computation (`variance_point`).
        let phi = self.mse_factor(x)?;
        let s = match self.output_scale {
            Some(sc) => sc.check(x, "the prediction point")?,
            None => 1.0,
        };
        Ok(s * s * phi)
    }

    /// The process covariance K of the outputs (see [`OutputCovariance`]).
    ///
    /// # Errors
    /// A model with `log_outputs`; a score covariance that is not positive
    /// semi-definite.
    pub fn output_covariance(&self) -> Result<OutputCovariance> {
        self.check_linear_for_variance()?;
        self.output_covariance_with(&self.ml_process_covariance())
    }

    /// The process covariance K of the outputs with the kriged outputs'
    /// covariance Σ estimated by leave-one-out cross-validation instead of
    /// maximum likelihood ([`KrigingModel::cv_process_covariance`]).
    ///
    /// # Errors
    /// As [`KrigingModel::output_covariance`].
    pub fn output_covariance_cv(&self) -> Result<OutputCovariance> {
        self.check_linear_for_variance()?;
        self.output_covariance_with(&self.cv_process_covariance()?)
    }

    /// The process covariance K of [`KrigingModel::output_covariance_cv`]
    /// with each eigen-direction k of Σ_CV scaled by `directions[k]`
    /// (descending eigenvalues: Σ_CV = Σ_k λ_k q_k q_kᵀ replaced by
    /// Σ_k a_k λ_k q_k q_kᵀ), the K of a per-direction calibration
    /// ([`VarianceCalibration::fit_directions`]). Empty `directions`: the
    /// K of [`KrigingModel::output_covariance_cv`].
    ///
    /// # Errors
    /// As [`KrigingModel::output_covariance_cv`]; a model without a PCA;
    /// as many scales as Σ_CV has directions expected, each > 0 and finite.
    pub fn output_covariance_cv_scaled(&self, directions: &[f64]) -> Result<OutputCovariance> {
        if directions.is_empty() {
            return self.output_covariance_cv();
        }
        self.check_linear_for_variance()?;
        if self.pca.is_none() {
            // K is diagonal there and would drop Σ's cross terms.
            return Err(SurrogateError::InvalidSettings(
                "per-direction scales need a PCA-reduced model".into(),
            ));
        }
        let q = self.n_kriged();
        let eigen = EigenDirections::new(&self.cv_process_covariance()?, q)?;
        if directions.len() != eigen.lambda.len()
            || directions.iter().any(|a| !(*a > 0.0 && a.is_finite()))
        {
            return Err(SurrogateError::InvalidInput(format!(
                "{} direction scales for {} directions of the process covariance (each > 0)",
                directions.len(),
                eigen.lambda.len()
            )));
        }
        self.output_covariance_with(&eigen.scaled(directions))
    }

    /// Σ of the kriged outputs (q × q, column-major) as fitted: the PC
    /// scores' residual covariance, or diag(σ²) (outputs kriged one by one,
    /// or models saved before the covariance was stored).
    fn ml_process_covariance(&self) -> Vec<f64> {
        let q = self.n_kriged();
        match &self.pca {
            Some(pca) if pca.residual_cov.len() == q * q => pca.residual_cov.clone(),
            _ => {
                let mut s = vec![0.0; q * q];
                for j in 0..q {
                    s[j * q + j] = self.sigma2[j];
                }
                s
            }
        }
    }

    /// K from the kriged outputs' covariance Σ (q × q, column-major).
    fn output_covariance_with(&self, sigma: &[f64]) -> Result<OutputCovariance> {
        let m = self.n_outputs;
        let Some(pca) = &self.pca else {
            let q = self.n_kriged();
            return Ok(OutputCovariance::Diagonal(
                (0..q)
                    .map(|j| sigma[j * q + j] * self.y_std[j] * self.y_std[j])
                    .collect(),
            ));
        };
        let k = pca.n_components;
        let l = psd_cholesky(sigma, k)?;
        let mut factor = vec![0.0; m * k];
        for b in 0..k {
            for a in b..k {
                let lab = l[b * k + a];
                if lab == 0.0 {
                    continue;
                }
                let va = &pca.basis[a * m..(a + 1) * m];
                let col = &mut factor[b * m..(b + 1) * m];
                for j in 0..m {
                    col[j] += va[j] * lab;
                }
            }
        }
        for b in 0..k {
            for j in 0..m {
                factor[b * m + j] *= self.y_std[j];
            }
        }
        Ok(OutputCovariance::LowRank { m, k, factor })
    }

    /// The leave-one-out estimate of the kriged outputs' process
    /// covariance, Σ_CV = (1/n) Σ_i γ_i γ_iᵀ / Q_ii (q × q, column-major;
    /// γ_i = (QY)_i, the LOO residual of site i is γ_i/Q_ii with
    /// covariance Σ/Q_ii, Dubrule 1983): Bachoc's (2013) cross-validation
    /// estimate of the variance, eq. 7, for several outputs sharing one
    /// correlation, in place of the ML Σ = (1/n) Σ_i ρ_i ρ_iᵀ. It is what
    /// the model's errors at left-out sites say its error covariance is.
    /// Cost O(n³/3).
    ///
    /// # Errors
    /// None expected (the Result is for symmetry with the other
    /// covariances).
    pub fn cv_process_covariance(&self) -> Result<Vec<f64>> {
        Ok(self.cv_covariance_from(&self.loo_precision_diagonal()?))
    }

    /// The process covariance K of [`KrigingModel::output_covariance_cv`]
    /// estimated near `x` instead of over the whole design: the training
    /// sites' leave-one-out residuals r_i, each standardised by its
    /// calibrated variance (`cal`, α v_i^β), weighted by w_i = c(x, x_i)^p
    /// (c the model's correlation, p = `power`; p < 1 widens the
    /// neighbourhood), and pooled with Σ_CV as `prior_sites` pseudo-sites:
    /// Σ_x = (n₀ Σ_CV + Σ_i w_i z_i z_iᵀ · n_eff/Σ_i w_i)/(n₀ + n_eff),
    /// n_eff = (Σ w)²/Σ w². Returns K and n_eff.
    ///
    /// # Errors
    /// As [`KrigingModel::output_covariance_cv`]; as
    /// [`KrigingModel::variance_point`].
    pub fn output_covariance_local(
        &self,
        x: &[f64],
        cal: &VarianceCalibration,
        power: f64,
        prior_sites: f64,
    ) -> Result<(OutputCovariance, f64)> {
        self.check_linear_for_variance()?;
        let d = self.dim;
        let qii = self.loo_precision_diagonal()?;
        let z = self.standardised_loo_residuals(&qii, cal)?;
        let global = self.cv_covariance_from(&qii);
        let xi = self.internal_x(x)?;
        let xn: Vec<f64> = (0..d)
            .map(|k| (xi[k] - self.x_mean[k]) / self.x_std[k])
            .collect();
        let (sigma, n_eff) = self.local_sigma(&xn, None, &z, &global, power, prior_sites);
        Ok((self.output_covariance_with(&sigma)?, n_eff))
    }

    /// Mean log density (per site, additive constants included) of each
    /// training site's standardised LOO residual z_j under N(0, Σ_x) with
    /// Σ_x of [`KrigingModel::output_covariance_local`] at x_j built from
    /// the *other* sites — the local covariance's own predictive score;
    /// `power` = 0 with `prior_sites` = 0 scores the global Σ_CV.
    ///
    /// # Errors
    /// As [`KrigingModel::output_covariance_local`]; a Σ_x that is not
    /// positive definite.
    pub fn local_covariance_score(
        &self,
        cal: &VarianceCalibration,
        power: f64,
        prior_sites: f64,
    ) -> Result<f64> {
        let (n, q, d) = (self.n_sites, self.n_kriged(), self.dim);
        let qii = self.loo_precision_diagonal()?;
        let z = self.standardised_loo_residuals(&qii, cal)?;
        let global = self.cv_covariance_from(&qii);
        let mut total = 0.0;
        for j in 0..n {
            let xn: Vec<f64> = (0..d).map(|k| self.sites[k * n + j]).collect();
            let (sigma, _) = self.local_sigma(&xn, Some(j), &z, &global, power, prior_sites);
            let white = Whitener::new(&sigma, q)?;
            let zj: Vec<f64> = (0..q).map(|a| z[a * n + j]).collect();
            total += -0.5
                * (white.energy(&zj)
                    + white.log_det()
                    + white.rank as f64 * (2.0 * std::f64::consts::PI).ln());
        }
        Ok(total / n as f64)
    }

    /// z_i = s_i r_i/√(α v_i^β) of every site (q × n, column-major by
    /// output): the LOO residuals r_i = γ_i/Q_ii standardised by their
    /// calibrated variance, ~ N(0, Σ_CV) under the calibrated model.
    fn standardised_loo_residuals(
        &self,
        qii: &[f64],
        cal: &VarianceCalibration,
    ) -> Result<Vec<f64>> {
        let (n, q) = (self.n_sites, self.n_kriged());
        let mut z = vec![0.0; q * n];
        for i in 0..n {
            let s2 = match self.output_scale {
                Some(sc) => sc.check(&self.site_physical(i), "a training site")?.powi(2),
                None => 1.0,
            };
            let f = s2.sqrt() / (qii[i] * cal.apply(s2 / qii[i]).sqrt());
            for a in 0..q {
                z[a * n + i] = self.gamma[a * n + i] * f;
            }
        }
        Ok(z)
    }

    /// Σ_x at the normalised point `xn` (docs of
    /// [`KrigingModel::output_covariance_local`]), leaving out site
    /// `exclude`; and n_eff.
    fn local_sigma(
        &self,
        xn: &[f64],
        exclude: Option<usize>,
        z: &[f64],
        global: &[f64],
        power: f64,
        prior_sites: f64,
    ) -> (Vec<f64>, f64) {
        let (n, q, d) = (self.n_sites, self.n_kriged(), self.dim);
        let mut dx = vec![0.0; d];
        let mut local = vec![0.0; q * q];
        let (mut sw, mut sw2) = (0.0, 0.0);
        for i in 0..n {
            if exclude == Some(i) {
                continue;
            }
            for k in 0..d {
                dx[k] = xn[k] - self.sites[k * n + i];
            }
            let w = self.correlation.value(&self.theta, &dx).powf(power);
            if !(w > 0.0) {
                continue;
            }
            for a in 0..q {
                let za = w * z[a * n + i];
                for b in 0..q {
                    local[b * q + a] += za * z[b * n + i];
                }
            }
            sw += w;
            sw2 += w * w;
        }
        let n_eff = if sw2 > 0.0 { sw * sw / sw2 } else { 0.0 };
        let sigma = global
            .iter()
            .zip(&local)
            .map(|(g, l)| {
                let l = if sw > 0.0 { l / sw } else { 0.0 };
                (prior_sites * g + n_eff * l) / (prior_sites + n_eff)
            })
            .collect();
        (sigma, n_eff)
    }

    /// Σ_CV of [`KrigingModel::cv_process_covariance`] from the Q_ii.
    fn cv_covariance_from(&self, qii: &[f64]) -> Vec<f64> {
        let (n, q) = (self.n_sites, self.n_kriged());
        let mut s = vec![0.0; q * q];
        for i in 0..n {
            for a in 0..q {
                let ga = self.gamma[a * n + i];
                for b in 0..q {
                    s[b * q + a] += ga * self.gamma[b * n + i] / qii[i];
                }
            }
        }
        for v in &mut s {
            *v /= n as f64;
        }
        s
    }

    /// Q_ii of Q = R⁻¹ − R⁻¹F(FᵀR⁻¹F)⁻¹FᵀR⁻¹ for every site:
    /// |C⁻¹e_i|² − |G⁻ᵀF̃ᵀC⁻¹e_i|².
    fn loo_precision_diagonal(&self) -> Result<Vec<f64>> {
        let (n, p) = (self.n_sites, self.p());
        let fac = self.mse_factors()?;
        let mut w = Mat::<f64>::identity(n, n);
        solve_lower_triangular_in_place(fac.c(n), w.as_mut(), Par::Seq);
        let mut a = fac.ft(n, p).transpose() * &w;
        solve_lower_triangular_in_place(fac.g(p).transpose(), a.as_mut(), Par::Seq);
        Ok((0..n)
            .map(|i| {
                (0..n).map(|r| w[(r, i)].powi(2)).sum::<f64>()
                    - (0..p).map(|k| a[(k, i)].powi(2)).sum::<f64>()
            })
            .collect())
    }

    /// The leave-one-out (cross-validation) estimate of the process
    /// variance over the maximum-likelihood one, σ²_CV/σ²_ML (Bachoc 2013,
    /// "Cross validation and maximum likelihood estimations of
    /// hyper-parameters of Gaussian processes with model misspecification",
    /// Comput. Stat. Data Anal. 66:55, eq. 7): with Q = R⁻¹ −
    /// R⁻¹F(FᵀR⁻¹F)⁻¹FᵀR⁻¹, the universal-Kriging LOO residual of site i
    /// is e_i = (QY)_i/Q_ii with variance σ²/Q_ii (Dubrule 1983), so the
    /// ratio is the mean over sites of (QY)_iᵀ Σ⁻¹ (QY)_i /(q·Q_ii), Σ the
    /// kriged outputs' process covariance (the PC scores' with a PCA), q
    /// their number. QY = γ is stored. 1 in expectation when the model's
    /// own error bars are right; larger when they are too narrow. Cost
    /// O(n³/3) (C⁻¹).
    ///
    /// # Errors
    /// A process covariance that is not positive definite.
    pub fn cv_variance_ratio(&self) -> Result<f64> {
        let (n, q) = (self.n_sites, self.n_kriged());
        let qii = self.loo_precision_diagonal()?;
        let white = Whitener::new(&self.ml_process_covariance(), q)
            .map_err(|e| SurrogateError::InvalidSettings(format!("cv_variance_ratio: {e}")))?;
        let mut g = vec![0.0; q];
        let mut total = 0.0;
        for i in 0..n {
            for (a, ga) in g.iter_mut().enumerate() {
                *ga = self.gamma[a * n + i];
            }
            total += white.energy(&g) / qii[i];
        }
        Ok(total / (n * white.rank) as f64)
    }

    /// The leave-one-out residuals of the training sites as calibration
    /// data (Dubrule 1983; docs/theory/surrogate.md, "Calibration of the
    /// Kriging variance"): per site i, the Kriging variance the model gives
    /// its own left-out prediction, v_i = s(x_i)²/Q_ii — the φ of the design
    /// without site i at x_i, the same quantity as
    /// [`KrigingModel::mse_scale`] at a new point — and the energy
    /// E_i = s_i² r_iᵀ Σ_CV⁻¹ r_i of its LOO residual r_i = γ_i/Q_ii in the
    /// kriged outputs, Σ_CV of [`KrigingModel::cv_process_covariance`].
    /// Under the model E_i ~ v_i·χ²_k, k = rank Σ_CV. Cost O(n³/3).
    ///
    /// # Errors
    /// A zero or indefinite Σ_CV; an output scale that is not positive at
    /// a site.
    pub fn loo_calibration_data(&self) -> Result<CalibrationData> {
        let (n, q) = (self.n_sites, self.n_kriged());
        let qii = self.loo_precision_diagonal()?;
        let sigma = self.cv_covariance_from(&qii);
        let white = Whitener::new(&sigma, q)?;
        let eigen = EigenDirections::new(&sigma, q)?;
        let per_direction = eigen.lambda.len() == white.rank;
        let mut v = Vec::with_capacity(n);
        let mut energy = Vec::with_capacity(n);
        let mut directions = Vec::with_capacity(if per_direction { n * white.rank } else { 0 });
        let mut r = vec![0.0; q];
        for i in 0..n {
            let s2 = match self.output_scale {
                Some(sc) => {
                    let x = self.site_physical(i);
                    sc.check(&x, "a training site")?.powi(2)
                }
                None => 1.0,
            };
            for (a, ra) in r.iter_mut().enumerate() {
                *ra = self.gamma[a * n + i] / qii[i];
            }
            v.push(s2 / qii[i]);
            energy.push(s2 * white.energy(&r));
            if per_direction {
                directions.extend(eigen.squared_coordinates(&r).map(|z| s2 * z));
            }
        }
        Ok(CalibrationData {
            v,
            energy,
            dof: white.rank,
            directions,
        })
    }

    /// The same data for runs the model was not fitted to (a checking set
    /// of physical inputs `x` and curves `y`): per run v(x)
    /// ([`KrigingModel::mse_scale`]) and the energy eᵀΣ_CV⁻¹e of the
    /// error's coordinates in the kriged outputs, e = Vᵀ D⁻¹ (y − ŷ(x))
    /// with a PCA (V the kept components, D = diag(σ_y)), e = D⁻¹(y − ŷ)
    /// without (the error outside V's span is not part of the Kriging
    /// variance and is left out).
    ///
    /// # Errors
    /// Lengths that differ; as [`KrigingModel::mse_scale`] and
    /// [`KrigingModel::predict`].
    pub fn calibration_data(&self, x: &[Vec<f64>], y: &[Vec<f64>]) -> Result<CalibrationData> {
        if x.len() != y.len() || y.iter().any(|c| c.len() != self.n_outputs) {
            return Err(SurrogateError::InvalidInput(format!(
                "{} inputs, {} curves (of {} values each expected)",
                x.len(),
                y.len(),
                self.n_outputs
            )));
        }
        let (m, q) = (self.n_outputs, self.n_kriged());
        let sigma = self.cv_process_covariance()?;
        let white = Whitener::new(&sigma, q)?;
        let eigen = EigenDirections::new(&sigma, q)?;
        let per_direction = eigen.lambda.len() == white.rank;
        let (mut v, mut energy, mut directions) = (Vec::new(), Vec::new(), Vec::new());
        let mut e = vec![0.0; q];
        for (xi, yi) in x.iter().zip(y) {
            let yh = self.predict(xi)?;
            let d: Vec<f64> = (0..m).map(|j| (yi[j] - yh[j]) / self.y_std[j]).collect();
            match &self.pca {
                Some(pca) => {
                    for (a, ea) in e.iter_mut().enumerate() {
                        let va = &pca.basis[a * m..(a + 1) * m];
                        *ea = va.iter().zip(&d).map(|(p, r)| p * r).sum();
                    }
                }
                None => e.copy_from_slice(&d),
            }
            v.push(self.mse_scale(xi)?);
            energy.push(white.energy(&e));
            if per_direction {
                directions.extend(eigen.squared_coordinates(&e));
            }
        }
        Ok(CalibrationData {
            v,
            energy,
            dof: white.rank,
            directions,
        })
    }

    /// The x-dependent calibration of the Kriging variance fitted to the
    /// model's own leave-one-out residuals
    /// ([`KrigingModel::loo_calibration_data`],
    /// [`VarianceCalibration::fit`]).
    ///
    /// # Errors
    /// As those two.
    pub fn variance_calibration(&self) -> Result<VarianceCalibration> {
        VarianceCalibration::fit(&self.loo_calibration_data()?)
    }

    /// Physical coordinates of training site i (the inverse of the input
    /// normalisation and of ln on log inputs).
    fn site_physical(&self, i: usize) -> Vec<f64> {
        let n = self.n_sites;
        (0..self.dim)
            .map(|k| {
                let xi = self.x_mean[k] + self.x_std[k] * self.sites[k * n + i];
                if self.log_inputs.get(k).copied().unwrap_or(false) {
                    xi.exp()
                } else {
                    xi
                }
            })
            .collect()
    }

    pub(super) fn check_linear_for_variance(&self) -> Result<()> {
        if self.log_outputs {
            Err(SurrogateError::InvalidSettings(
                "the model predicts exp(kriged ln y): its MSE is not v(x)·K (refit without \
                 --log-outputs for a likelihood with the Kriging variance)"
                    .into(),
            ))
        } else {
            Ok(())
        }
    }
}

/// The eigen-directions of a psd covariance Σ (q × q, column-major):
/// Σ = Σ_k λ_k q_k q_kᵀ over the eigenvalues above 1e-14 of the largest,
/// in descending order — the directions of a per-direction calibration
/// ([`VarianceCalibration::fit_directions`]).
struct EigenDirections {
    /// λ_k, descending.
    lambda: Vec<f64>,
    /// q_k, column-major q × lambda.len().
    vectors: Vec<f64>,
    q: usize,
}

impl EigenDirections {
    fn new(sigma: &[f64], q: usize) -> Result<Self> {
        let evd = Mat::from_fn(q, q, |i, j| sigma[j * q + i])
            .self_adjoint_eigen(faer::Side::Lower)
            .map_err(|e| {
                SurrogateError::InvalidSettings(format!(
                    "eigen-decomposition of the process covariance failed: {e:?}"
                ))
            })?;
        let (s, u) = (evd.S(), evd.U());
        // faer sorts ascending.
        let top = (0..q).map(|i| s[i]).fold(0.0, f64::max);
        let keep: Vec<usize> = (0..q).rev().filter(|&i| s[i] > 1e-14 * top).collect();
        Ok(Self {
            lambda: keep.iter().map(|&i| s[i]).collect(),
            vectors: keep
                .iter()
                .flat_map(|&i| (0..q).map(move |r| u[(r, i)]))
                .collect(),
            q,
        })
    }

    /// (q_kᵀ g)²/λ_k per direction: the squared whitened coordinates of g
    /// (they sum to gᵀΣ⁻¹g on Σ's span).
    fn squared_coordinates<'a>(&'a self, g: &'a [f64]) -> impl Iterator<Item = f64> + 'a {
        self.lambda.iter().enumerate().map(move |(k, l)| {
            let qk = &self.vectors[k * self.q..(k + 1) * self.q];
            qk.iter().zip(g).map(|(a, b)| a * b).sum::<f64>().powi(2) / l
        })
    }

    /// Σ_k a_k λ_k q_k q_kᵀ (q × q, column-major).
    fn scaled(&self, a: &[f64]) -> Vec<f64> {
        let q = self.q;
        let mut s = vec![0.0; q * q];
        for (k, (l, ak)) in self.lambda.iter().zip(a).enumerate() {
            let qk = &self.vectors[k * q..(k + 1) * q];
            for c in 0..q {
                for r in 0..q {
                    s[c * q + r] += ak * l * qk[r] * qk[c];
                }
            }
        }
        s
    }
}

/// Lower Cholesky factor (column-major k × k) of a symmetric positive
/// semi-definite matrix; pivots below 1e-14 of the largest diagonal entry
/// are set to zero (a rank-deficient Σ, e.g. fewer sites than components).
fn psd_cholesky(a: &[f64], k: usize) -> Result<Vec<f64>> {
    let scale = (0..k).map(|i| a[i * k + i]).fold(0.0, f64::max);
    let mut l = vec![0.0; k * k];
    for j in 0..k {
        let mut d = a[j * k + j];
        for p in 0..j {
            d -= l[p * k + j] * l[p * k + j];
        }
        if d < -1e-10 * scale.max(f64::MIN_POSITIVE) {
            return Err(SurrogateError::InvalidSettings(format!(
                "the score covariance is not positive semi-definite (pivot {j} = {d:e})"
            )));
        }
        if d <= 1e-14 * scale {
            continue;
        }
        let djj = d.sqrt();
        l[j * k + j] = djj;
        for i in j + 1..k {
            let mut s = a[j * k + i];
            for p in 0..j {
                s -= l[p * k + i] * l[p * k + j];
            }
            l[j * k + i] = s / djj;
        }
    }
    Ok(l)
}

/// Whitening by a psd covariance Σ (q × q): |L⁻¹g|² with L Lᵀ = Σ, zero
/// pivots (directions without variance) left out of the sum and the rank.
struct Whitener {
    l: Vec<f64>,
    q: usize,
    rank: usize,
}

impl Whitener {
    fn new(sigma: &[f64], q: usize) -> Result<Self> {
        let l = psd_cholesky(sigma, q)?;
        let rank = (0..q).filter(|&j| l[j * q + j] > 0.0).count();
        if rank == 0 {
            return Err(SurrogateError::InvalidSettings(
                "the process covariance is zero".into(),
            ));
        }
        Ok(Self { l, q, rank })
    }

    /// ln det Σ on Σ's span (the zero pivots left out).
    fn log_det(&self) -> f64 {
        (0..self.q)
            .map(|j| self.l[j * self.q + j])
            .filter(|&d| d > 0.0)
            .map(|d| 2.0 * d.ln())
            .sum()
    }

    /// gᵀΣ⁻¹g on Σ's span (forward substitution).
    fn energy(&self, g: &[f64]) -> f64 {
        let (l, q) = (&self.l, self.q);
        let mut z = vec![0.0; q];
        let mut quad = 0.0;
        for j in 0..q {
            let ljj = l[j * q + j];
            if ljj <= 0.0 {
                continue;
            }
            let mut v = g[j];
            for t in 0..j {
                v -= l[t * q + j] * z[t];
            }
            z[j] = v / ljj;
            quad += z[j] * z[j];
        }
        quad
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;
    use crate::kriging::{KrigingSettings, OutputScale, ThetaSearch};
    use crate::{Correlation, Regression};
    use faer::Mat;

    /// n sites of a seeded 2-D Latin hypercube on [0.5, 2] × [-1, 1] and
    /// three smooth outputs.
    fn model(scale: bool) -> KrigingModel {
        let mut rng = <rand_chacha::ChaCha8Rng as rand::SeedableRng>::seed_from_u64(4);
        let u = crate::doe::latin_hypercube_unit(11, 2, &mut rng);
        let x = Mat::from_fn(11, 2, |i, k| {
            if k == 0 {
                0.5 + 1.5 * u[i][0]
            } else {
                2.0 * u[i][1] - 1.0
            }
        });
        let y = Mat::from_fn(11, 3, |i, j| {
            let (a, b) = (x[(i, 0)], x[(i, 1)]);
            a * (1.0 + j as f64) + (b * (j as f64 + 1.0)).sin() + a * b
        });
        let mut s = KrigingSettings::new(Regression::Poly1, Correlation::Gauss, 2);
        s.theta = ThetaSearch::Fixed(vec![0.7, 1.3]);
        if scale {
            s.output_scale = Some(OutputScale::Linear { input: 0 });
            s.log_inputs = vec![true, false];
        }
        KrigingModel::fit(x.as_ref(), y.as_ref(), &s).unwrap()
    }

    /// σ²_CV/σ²_ML from the stored factors equals the brute-force
    /// leave-one-out computation (second method): for every site i the
    /// GLS Kriging predictor and its MSE factor are rebuilt densely from
    /// the correlation matrix of the other n − 1 sites (same θ), and
    /// (y_i − ŷ₋ᵢ(x_i))²/(σ_j² φ₋ᵢ(x_i)) is averaged over sites and outputs.
    #[test]
    fn cv_variance_ratio_equals_brute_force_leave_one_out() {
        use nalgebra::{DMatrix, DVector};
        let m = model(false);
        let (n, d, p, q) = (m.n_sites, m.dim, m.p(), m.n_kriged());
        let site = |i: usize| (0..d).map(|k| m.sites[k * n + i]).collect::<Vec<f64>>();
        let corr = |a: &[f64], b: &[f64]| {
            let dx: Vec<f64> = a.iter().zip(b).map(|(x, y)| x - y).collect();
            m.correlation.value(&m.theta, &dx)
        };
        let freg = |x: &[f64]| {
            let mut f = vec![0.0; p];
            m.regression.eval(x, &mut f);
            f
        };
        // Normalised outputs of the fixture's formula at its sites.
        let y = |i: usize, j: usize| {
            let xi = site(i);
            let (a, b) = (
                xi[0] * m.x_std[0] + m.x_mean[0],
                xi[1] * m.x_std[1] + m.x_mean[1],
            );
            let v = a * (1.0 + j as f64) + (b * (j as f64 + 1.0)).sin() + a * b;
            (v - m.y_mean[j]) / m.y_std[j]
        };
        let mut total = 0.0;
        let mut per_output = vec![0.0; q];
        let mut loo = Vec::new();
        for i in 0..n {
            let others: Vec<usize> = (0..n).filter(|&t| t != i).collect();
            let r = DMatrix::from_fn(n - 1, n - 1, |a, b| {
                corr(&site(others[a]), &site(others[b]))
            });
            let f = DMatrix::from_fn(n - 1, p, |a, k| freg(&site(others[a]))[k]);
            let rinv = r.try_inverse().unwrap();
            let ftrf = (f.transpose() * &rinv * &f).try_inverse().unwrap();
            let rx = DVector::from_fn(n - 1, |a, _| corr(&site(others[a]), &site(i)));
            let fx = DVector::from_vec(freg(&site(i)));
            let u = f.transpose() * &rinv * &rx - &fx;
            let phi = 1.0 - rx.dot(&(&rinv * &rx)) + u.dot(&(&ftrf * &u));
            let mut res = DVector::zeros(q);
            for j in 0..q {
                let yv = DVector::from_fn(n - 1, |a, _| y(others[a], j));
                let beta = &ftrf * (f.transpose() * &rinv * &yv);
                let pred = fx.dot(&beta) + rx.dot(&(&rinv * (&yv - &f * &beta)));
                total += (y(i, j) - pred).powi(2) / (m.sigma2[j] * phi);
                per_output[j] += (y(i, j) - pred).powi(2) / phi / n as f64;
                res[j] = y(i, j) - pred;
            }
            loo.push((phi, res));
        }
        let brute = total / (n * q) as f64;
        // The calibration data: v_i is the brute-force φ₋ᵢ(x_i), E_i the
        // LOO residual's energy under Σ_CV (dense solve).
        let cv = m.cv_process_covariance().unwrap();
        let sig = DMatrix::from_column_slice(q, q, &cv);
        let data = m.loo_calibration_data().unwrap();
        assert_eq!(data.dof, q);
        for i in 0..n {
            let (want_v, res) = &loo[i];
            let want_e = res.dot(&sig.clone().lu().solve(res).unwrap());
            assert!((data.v[i] / want_v - 1.0).abs() < 1e-6, "site {i}: v");
            assert!((data.energy[i] / want_e - 1.0).abs() < 1e-6, "site {i}: E");
        }
        let ours = m.cv_variance_ratio().unwrap();
        assert!((ours / brute - 1.0).abs() < 1e-6, "{ours} vs {brute}");
        // Σ_CV's diagonal: the mean of the squared LOO residuals over their
        // MSE factors, output by output.
        for j in 0..q {
            let v = cv[j * q + j];
            assert!(
                (v / per_output[j] - 1.0).abs() < 1e-6,
                "output {j}: {v} vs {}",
                per_output[j]
            );
        }
    }

    #[test]
    fn mse_factor_times_process_variance_is_the_predictors_mse() {
        for scale in [false, true] {
            let m = model(scale);
            let pv = m.process_variance();
            for x in [[0.7, 0.2], [1.9, -0.95], [1.234, 0.5]] {
                let full = m.predict_full(&x).unwrap();
                let phi = m.mse_factor(&x).unwrap();
                let s2 = if scale { x[0] * x[0] } else { 1.0 };
                for j in 0..3 {
                    let want = full.mse[j];
                    assert!(
                        (phi * pv[j] * s2 - want).abs() <= 1e-10 * want.abs() + 1e-300,
                        "{x:?} output {j}: {} vs {want}",
                        phi * pv[j] * s2
                    );
                }
            }
        }
    }

    /// Gaussian elimination with partial pivoting (independent of faer).
    fn solve(mut a: Vec<Vec<f64>>, mut b: Vec<f64>) -> Vec<f64> {
        let n = b.len();
        for c in 0..n {
            let p = (c..n)
                .max_by(|&i, &j| a[i][c].abs().total_cmp(&a[j][c].abs()))
                .unwrap();
            a.swap(c, p);
            b.swap(c, p);
            for r in c + 1..n {
                let f = a[r][c] / a[c][c];
                for k in c..n {
                    a[r][k] -= f * a[c][k];
                }
                b[r] -= f * b[c];
            }
        }
        let mut x = vec![0.0; n];
        for r in (0..n).rev() {
            let s: f64 = (r + 1..n).map(|k| a[r][k] * x[k]).sum();
            x[r] = (b[r] - s) / a[r][r];
        }
        x
    }

    /// φ(x) of universal Kriging on the normalised `sites` by dense
    /// solves: 1 + uᵀ(FᵀR⁻¹F)⁻¹u − rᵀR⁻¹r, u = FᵀR⁻¹r − f (report eq. 2.20).
    fn dense_phi(m: &KrigingModel, sites: &[Vec<f64>], xn: &[f64]) -> f64 {
        let n = sites.len();
        let p = m.p();
        let corr = |a: &[f64], b: &[f64]| {
            let d: Vec<f64> = a.iter().zip(b).map(|(u, v)| u - v).collect();
            m.correlation.value(&m.theta, &d)
        };
        let nugget = (10.0 + m.n_sites as f64) * f64::EPSILON;
        let r_mat: Vec<Vec<f64>> = (0..n)
            .map(|i| {
                (0..n)
                    .map(|j| corr(&sites[i], &sites[j]) + if i == j { nugget } else { 0.0 })
                    .collect()
            })
            .collect();
        let f_of = |x: &[f64]| {
            let mut f = vec![0.0; p];
            m.regression.eval(x, &mut f);
            f
        };
        let fmat: Vec<Vec<f64>> = sites.iter().map(|s| f_of(s)).collect();
        let r: Vec<f64> = sites.iter().map(|s| corr(s, xn)).collect();
        let rinv_r = solve(r_mat.clone(), r.clone());
        let rinv_f: Vec<Vec<f64>> = (0..p)
            .map(|l| solve(r_mat.clone(), fmat.iter().map(|row| row[l]).collect()))
            .collect();
        let ftrf: Vec<Vec<f64>> = (0..p)
            .map(|a| {
                (0..p)
                    .map(|b| (0..n).map(|i| fmat[i][a] * rinv_f[b][i]).sum())
                    .collect()
            })
            .collect();
        let f = f_of(xn);
        let u: Vec<f64> = (0..p)
            .map(|a| (0..n).map(|i| fmat[i][a] * rinv_r[i]).sum::<f64>() - f[a])
            .collect();
        let w = solve(ftrf, u.clone());
        1.0 + u.iter().zip(&w).map(|(a, b)| a * b).sum::<f64>()
            - r.iter().zip(&rinv_r).map(|(a, b)| a * b).sum::<f64>()
    }

    #[test]
    fn rank_one_update_equals_a_dense_refit_with_the_new_site() {
        let m = model(false);
        let (n, d) = (m.n_sites, m.dim);
        let sites: Vec<Vec<f64>> = (0..n)
            .map(|i| (0..d).map(|k| m.sites[k * n + i]).collect())
            .collect();
        let new_site = [1.1, 0.35];
        let s = m.variance_point(&new_site).unwrap();
        let mut grown = sites.clone();
        grown.push(s.xn.clone());
        // The dense formula reproduces φ of the fitted model …
        for x in [[0.6, -0.8], [1.2, 0.3], [1.8, 0.9]] {
            let a = m.variance_point(&x).unwrap();
            let direct = dense_phi(&m, &sites, &a.xn);
            assert!((a.phi - direct).abs() < 1e-9, "{} vs {direct}", a.phi);
            // … and the rank-one update its value with the new site.
            let k = m.posterior_correlation(&a, &s);
            let updated = a.phi - k * k / s.phi;
            let want = dense_phi(&m, &grown, &a.xn);
            assert!(
                (updated - want).abs() < 1e-9 * (1.0 + want.abs()),
                "{x:?}: {updated} vs {want}"
            );
            assert!(updated < a.phi, "a new site lowers the MSE");
        }
        // At the new site itself the updated MSE vanishes.
        assert!((s.phi - s.phi * s.phi / m.posterior_correlation(&s, &s)).abs() < 1e-12);
    }
}

#[cfg(test)]
mod covariance_tests {
    use super::*;
    use crate::correlation::Correlation;
    use crate::kriging::KrigingSettings;
    use crate::regression::Regression;
    use faer::Mat;

    /// 30 sites in 2-D, 40 smooth outputs (a family of curves).
    fn model(pca: Option<f64>, scaled: bool) -> KrigingModel {
        let n = 30;
        let x = Mat::from_fn(n, 2, |i, k| {
            let t = (i as f64 + 0.5) / n as f64;
            if k == 0 {
                0.5 + t
            } else {
                ((i * 7) % n) as f64 / n as f64
            }
        });
        let y = Mat::from_fn(n, 40, |i, j| {
            let (a, b) = (x[(i, 0)], x[(i, 1)]);
            let t = j as f64 / 40.0;
            a * (1.0 + b * (-3.0 * t).exp() + 0.3 * (a * t * 5.0).sin())
        });
        let mut s = KrigingSettings::new(Regression::Poly1, Correlation::Gauss, 2);
        s.pca_energy = pca;
        if scaled {
            s.output_scale = Some(crate::kriging::OutputScale::Linear { input: 0 });
        }
        KrigingModel::fit(x.as_ref(), y.as_ref(), &s).expect("fit")
    }

    /// v(x)·K_jj must equal the MSE of `predict_full` (the DACE formula,
    /// computed there by a separate code path) at points off the sites,
    /// with and without a PCA and an output scale.
    #[test]
    fn mse_scale_times_process_variance_is_the_predictor_mse() {
        for (pca, scaled) in [(None, false), (Some(0.99999), false), (Some(0.99999), true)] {
            let m = model(pca, scaled);
            let cov = m.output_covariance().expect("cov");
            let diag = cov.diagonal();
            let pv = m.process_variance();
            for (a, b) in diag.iter().zip(&pv) {
                assert!((a - b).abs() <= 1e-10 * b.abs().max(1e-300), "{a} vs {b}");
            }
            for x in [[0.73, 0.41], [1.21, 0.05], [0.9, 0.9]] {
                let v = m.mse_scale(&x).expect("v");
                let full = m.predict_full(&x).expect("full");
                for (j, mse) in full.mse.iter().enumerate() {
                    let ours = v * diag[j];
                    assert!(
                        (ours - mse).abs() <= 1e-9 * mse.abs() + 1e-300,
                        "pca {pca:?} scaled {scaled} x {x:?} j {j}: {ours} vs {mse}"
                    );
                }
            }
        }
    }

    /// The batch of [`KrigingModel::coordinates_and_mse_scales`] equals
    /// the one-point functions (`output_coordinate_values`, `mse_scale`,
    /// separate code paths) point by point, with and without a PCA and an
    /// output scale, for a batch of one and of seven points.
    #[test]
    fn batched_coordinates_and_mse_scales_equal_the_one_point_values() {
        let pts: Vec<Vec<f64>> = (0..7)
            .map(|i| vec![0.55 + 0.13 * i as f64, (0.31 * i as f64).sin().abs()])
            .collect();
        for (pca, scaled) in [(None, false), (Some(0.99999), false), (Some(0.99999), true)] {
            let m = model(pca, scaled);
            for batch in [&pts[..1], &pts[..]] {
                let (cs, vs) = m.coordinates_and_mse_scales(batch, 1).expect("batch");
                assert_eq!((cs.len(), vs.len()), (batch.len(), batch.len()));
                for (x, (c, v)) in batch.iter().zip(cs.iter().zip(&vs)) {
                    let c1 = m.output_coordinate_values(x).expect("c");
                    let v1 = m.mse_scale(x).expect("v");
                    // φ = 1 + |v|² − |rt|² is a difference of O(1) terms:
                    // near a site (φ ≈ 1e-11 at (0.55, 0)) the two roundings
                    // agree to ≈ nε absolutely, not relatively.
                    assert!(
                        (v - v1).abs() <= 1e-10 * v1.abs() + 1e-12,
                        "x {x:?}: {v} vs {v1}"
                    );
                    // z_k = Σ_i γ_ik r_i + Σ_j β_jk f_j sums terms far larger
                    // than z_k (γ of an ill-conditioned R), in another order
                    // in the batch: rounding ≈ nε·Σ|terms| (r ≤ 1, |f| ≲ 2).
                    let (n, p) = (m.n_sites, m.p());
                    for (k, (a, b)) in c.iter().zip(&c1).enumerate().skip(1) {
                        let terms: f64 =
                            (0..n).map(|i| m.gamma[(k - 1) * n + i].abs()).sum::<f64>()
                                + 2.0 * (0..p).map(|j| m.beta[(k - 1) * p + j].abs()).sum::<f64>();
                        assert!(
                            (a - b).abs() <= 1e-12 * c[0] * terms,
                            "x {x:?}, c_{k}: {a} vs {b} (terms {terms:e})"
                        );
                    }
                    assert_eq!(c[0], c1[0]);
                }
            }
        }
    }

    /// The batch split over threads gives every point bitwise the values
    /// of the whole batch on one thread, for 2 and 3 threads and for every
    /// cut of the batch into two parts, parts of one point included (what
    /// the split relies on: faer's kernels give a column the same
    /// arithmetic in any batch of ≥ 2 columns, and a part of one point is
    /// solved as two copies). The coordinates without the variance
    /// (`output_coordinate_batch`) are the batch's bit for bit, a point
    /// alone included.
    #[test]
    fn batch_values_do_not_depend_on_the_thread_count() {
        let pts: Vec<Vec<f64>> = (0..17)
            .map(|i| vec![0.52 + 0.057 * i as f64, (0.73 * i as f64).cos().abs()])
            .collect();
        let bits = |(c, v): (Vec<Vec<f64>>, Vec<f64>)| -> Vec<Vec<u64>> {
            c.iter()
                .zip(&v)
                .map(|(c, v)| c.iter().chain([v]).map(|x| x.to_bits()).collect())
                .collect()
        };
        for (pca, scaled) in [(None, false), (Some(0.99999), true)] {
            let m = model(pca, scaled);
            let one = bits(m.coordinates_and_mse_scales(&pts, 1).expect("batch"));
            for threads in [2, 3] {
                let par = bits(m.coordinates_and_mse_scales(&pts, threads).expect("batch"));
                assert_eq!(par, one, "{threads} threads");
            }
            let without_v: Vec<Vec<u64>> = one.iter().map(|p| p[..p.len() - 1].to_vec()).collect();
            for threads in [1, 2, 3] {
                let coordinates: Vec<Vec<u64>> = m
                    .output_coordinate_batch(&pts, threads)
                    .expect("coordinates")
                    .iter()
                    .map(|c| c.iter().map(|x| x.to_bits()).collect())
                    .collect();
                assert_eq!(coordinates, without_v, "coordinates on {threads} threads");
            }
            for (p, want) in pts.iter().zip(&without_v) {
                let alone = m
                    .output_coordinate_batch(std::slice::from_ref(p), 1)
                    .expect("one point");
                let alone: Vec<u64> = alone[0].iter().map(|x| x.to_bits()).collect();
                assert_eq!(&alone, want, "{p:?} alone");
            }
            for cut in 1..pts.len() {
                let mut parts = bits(m.coordinates_and_mse_scales(&pts[..cut], 1).expect("a"));
                parts.extend(bits(
                    m.coordinates_and_mse_scales(&pts[cut..], 1).expect("b"),
                ));
                assert_eq!(parts, one, "cut at {cut}");
            }
        }
    }

    /// The correlation column of the batch path equals the per-site
    /// formula bit for bit, for `gauss` (accumulated by dimension) and for
    /// another family (per site), whatever `out` held before (NaN here: no
    /// entry may be added to instead of written).
    #[test]
    fn correlation_column_equals_the_per_site_formula_bitwise() {
        for corr in [Correlation::Gauss, Correlation::Exp] {
            let mut m = model(Some(0.99999), false);
            m.correlation = corr;
            let (n, d) = (m.n_sites, m.dim);
            let xn = [0.37, -1.21];
            let mut col = vec![f64::NAN; n];
            m.correlation_column(&xn, &mut col, &mut [0.0; 2]);
            for (i, r) in col.iter().enumerate() {
                let dx: Vec<f64> = (0..d).map(|k| xn[k] - m.sites[k * n + i]).collect();
                assert_eq!(
                    r.to_bits(),
                    m.correlation_value(&dx).to_bits(),
                    "{corr:?} site {i}"
                );
            }
        }
    }

    /// With a PCA, U Uᵀ has the off-diagonal terms D V Σ Vᵀ D: checked
    /// entry by entry against that product written out.
    #[test]
    fn low_rank_factor_reproduces_the_score_covariance() {
        let m = model(Some(0.99999), false);
        let pca = m.pca.clone().expect("pca");
        let (mo, k) = (m.n_outputs, pca.n_components);
        let OutputCovariance::LowRank { factor, .. } = m.output_covariance().expect("cov") else {
            panic!("a PCA model has a low-rank covariance");
        };
        for (i, j) in [(0, 0), (3, 17), (39, 2), (20, 21)] {
            let uu: f64 = (0..k)
                .map(|a| factor[a * mo + i] * factor[a * mo + j])
                .sum();
            let mut dvsvd = 0.0;
            for a in 0..k {
                for b in 0..k {
                    dvsvd +=
                        pca.basis[a * mo + i] * pca.residual_cov[b * k + a] * pca.basis[b * mo + j];
                }
            }
            dvsvd *= m.y_std[i] * m.y_std[j];
            assert!(
                (uu - dvsvd).abs() <= 1e-10 * dvsvd.abs().max(1e-12),
                "{i},{j}: {uu} vs {dvsvd}"
            );
        }
    }

    /// The per-direction K: with all scales 1 it is the cross-validated
    /// K (U Uᵀ entry by entry), it is linear in the scales
    /// (K(a) + K(b) = K(a + b)), and the LOO data's coordinates per
    /// direction sum to their energies; without a PCA it is refused.
    /// A functional's variance from its score loadings, lᵀ Σ_CV l, equals
    /// wᵀ K w with the output covariance K built by
    /// [`KrigingModel::output_covariance_cv`] (a second path); no PCA: None.
    #[test]
    fn score_loadings_give_the_functionals_variance() {
        let m = model(Some(0.99999), false);
        let OutputCovariance::LowRank { m: mo, k, factor } = m.output_covariance_cv().expect("cv")
        else {
            panic!("a PCA model has a low-rank covariance");
        };
        let sigma = m.cv_process_covariance().expect("Σ_CV");
        let q = m.n_kriged();
        for w in [
            (0..mo)
                .map(|j| f64::from(u8::from(j == mo - 1)))
                .collect::<Vec<_>>(),
            (0..mo).map(|j| (0.3 * j as f64).sin()).collect(),
        ] {
            let l = m.score_loadings(&w).expect("PCA");
            assert_eq!(l.len(), q);
            let via_scores: f64 = (0..q)
                .flat_map(|a| (0..q).map(move |b| (a, b)))
                .map(|(a, b)| l[a] * sigma[a * q + b] * l[b])
                .sum();
            let via_outputs: f64 = (0..k)
                .map(|a| {
                    (0..mo)
                        .map(|i| factor[a * mo + i] * w[i])
                        .sum::<f64>()
                        .powi(2)
                })
                .sum();
            assert!(
                (via_scores - via_outputs).abs() <= 1e-10 * via_outputs.abs(),
                "{via_scores} vs {via_outputs}"
            );
        }
        assert!(model(None, false).score_loadings(&[1.0; 40]).is_none());
    }

    /// The local covariance reduces to the cross-validated one when it is
    /// not local: every site weighted 1 (power 0) with v ↦ v (α = β = 1)
    /// gives the mean of γ_iγ_iᵀ/Q_ii, which is Σ_CV; far from every site
    /// (all weights underflow) the prior sites give Σ_CV alone. Its score
    /// with every other site weighted 1 is the mean Gaussian log density of
    /// each z_j under the mean of the others' z zᵀ, computed here densely.
    #[test]
    fn local_covariance_without_locality_is_the_cross_validated_one() {
        let m = model(Some(0.99999), false);
        let unit = VarianceCalibration {
            alpha: 1.0,
            beta: 1.0,
            beta_se: 0.0,
            nu: f64::INFINITY,
            directions: Vec::new(),
        };
        let entries = |cov: OutputCovariance| {
            let OutputCovariance::LowRank { m: mo, k, factor } = cov else {
                panic!("a PCA model has a low-rank covariance");
            };
            (0..mo * mo)
                .map(|ij| {
                    let (i, j) = (ij / mo, ij % mo);
                    (0..k)
                        .map(|a| factor[a * mo + i] * factor[a * mo + j])
                        .sum::<f64>()
                })
                .collect::<Vec<f64>>()
        };
        let cv = entries(m.output_covariance_cv().expect("cv"));
        let big = cv.iter().fold(0.0f64, |a, b| a.max(b.abs()));
        let (all, n_eff) = m
            .output_covariance_local(&[0.8, 0.3], &unit, 0.0, 0.0)
            .expect("local");
        assert!((n_eff - m.n_sites as f64).abs() < 1e-9, "n_eff {n_eff}");
        for (a, b) in entries(all).iter().zip(&cv) {
            assert!((a - b).abs() <= 1e-9 * big, "{a} vs {b}");
        }
        let (far, n_far) = m
            .output_covariance_local(&[1e3, 1e3], &unit, 1.0, 2.0)
            .expect("far");
        assert_eq!(n_far, 0.0);
        for (a, b) in entries(far).iter().zip(&cv) {
            assert!((a - b).abs() <= 1e-9 * big, "{a} vs {b}");
        }
        // A local neighbourhood changes K (the test would pass vacuously
        // if the weights were ignored).
        let (near, n_near) = m
            .output_covariance_local(&[0.8, 0.3], &unit, 30.0, 0.0)
            .expect("near");
        assert!(n_near < 0.5 * m.n_sites as f64, "n_eff {n_near}");
        let moved = entries(near)
            .iter()
            .zip(&cv)
            .fold(0.0f64, |a, (x, y)| a.max((x - y).abs()));
        assert!(moved > 1e-3 * big, "{moved}");

        // The score, densely: z_j = γ_j/√Q_jj (α = β = 1, no output scale).
        let (n, q) = (m.n_sites, m.n_kriged());
        let qii = m.loo_precision_diagonal().expect("qii");
        let z =
            |j: usize| -> Vec<f64> { (0..q).map(|a| m.gamma[a * n + j] / qii[j].sqrt()).collect() };
        let mut direct = 0.0;
        for j in 0..n {
            let sigma = Mat::<f64>::from_fn(q, q, |a, b| {
                (0..n)
                    .filter(|&i| i != j)
                    .map(|i| z(i)[a] * z(i)[b])
                    .sum::<f64>()
                    / (n - 1) as f64
            });
            use faer::prelude::Solve;
            let llt = sigma.llt(faer::Side::Lower).expect("spd");
            let zj = Mat::<f64>::from_fn(q, 1, |a, _| z(j)[a]);
            let quad = (zj.transpose() * llt.solve(&zj))[(0, 0)];
            let log_det: f64 = (0..q).map(|a| 2.0 * llt.L()[(a, a)].ln()).sum();
            direct -= 0.5 * (quad + log_det + q as f64 * std::f64::consts::TAU.ln());
        }
        direct /= n as f64;
        let score = m.local_covariance_score(&unit, 0.0, 0.0).expect("score");
        assert!(
            (score - direct).abs() <= 1e-9 * direct.abs(),
            "{score} vs {direct}"
        );
    }

    #[test]
    fn scaled_output_covariance_is_linear_in_the_direction_scales() {
        let m = model(Some(0.99999), false);
        let kk = |cov: OutputCovariance| {
            let OutputCovariance::LowRank { m: mo, k, factor } = cov else {
                panic!("a PCA model has a low-rank covariance");
            };
            move |i: usize, j: usize| -> f64 {
                (0..k)
                    .map(|a| factor[a * mo + i] * factor[a * mo + j])
                    .sum()
            }
        };
        let data = m.loo_calibration_data().expect("loo");
        let k = data.dof;
        assert_eq!(data.directions.len(), k * data.v.len());
        for (i, e) in data.energy.iter().enumerate() {
            let sum: f64 = data.directions[i * k..(i + 1) * k].iter().sum();
            assert!((sum - e).abs() <= 1e-8 * e.max(1e-300), "{i}: {sum} vs {e}");
        }
        let a: Vec<f64> = (0..k).map(|c| 0.5 + c as f64).collect();
        let b: Vec<f64> = (0..k).map(|c| 2.0 / (1.0 + c as f64)).collect();
        let ab: Vec<f64> = a.iter().zip(&b).map(|(x, y)| x + y).collect();
        let cv = kk(m.output_covariance_cv().expect("cv"));
        let ones = kk(m.output_covariance_cv_scaled(&vec![1.0; k]).expect("ones"));
        let (ka, kb, kab) = (
            kk(m.output_covariance_cv_scaled(&a).expect("a")),
            kk(m.output_covariance_cv_scaled(&b).expect("b")),
            kk(m.output_covariance_cv_scaled(&ab).expect("a + b")),
        );
        for (i, j) in [(0, 0), (3, 17), (39, 2), (20, 21), (39, 39)] {
            let scale = (cv(i, i) * cv(j, j)).sqrt();
            assert!((ones(i, j) - cv(i, j)).abs() <= 1e-9 * scale, "{i},{j}");
            assert!(
                (ka(i, j) + kb(i, j) - kab(i, j)).abs() <= 1e-9 * scale * 10.0,
                "{i},{j}: {} + {} vs {}",
                ka(i, j),
                kb(i, j),
                kab(i, j)
            );
        }
        assert!(m.output_covariance_cv_scaled(&[1.0]).is_err());
        assert!(
            model(None, false)
                .output_covariance_cv_scaled(&[1.0; 40])
                .is_err()
        );
    }

    #[test]
    fn log_output_models_are_refused() {
        let mut m = model(None, false);
        m.log_outputs = true;
        assert!(m.mse_scale(&[1.0, 0.5]).is_err());
        assert!(m.output_covariance().is_err());
    }
}
