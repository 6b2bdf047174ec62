//! The likelihood of one measured curve on a Kriging surrogate, with the
//! measurement noise estimated from the curve and the surrogate's own
//! error (its Kriging MSE, with the cross-time covariance) folded into the
//! variance (issue 17; docs/theory/inverse.md, "Posteriors").
//!
//! d = ŷ(x) + e_s + e_n with the surrogate error e_s ~ N(0, v(x)·K)
//! (DACE report eq. 2.20 across outputs, `nlvid_surrogate::OutputCovariance`,
//! with the kriged outputs' process covariance in K estimated by
//! leave-one-out cross-validation, `KrigingModel::output_covariance_cv`:
//! the ML estimate understates the demo meta-model's errors threefold,
//! docs/theory/inverse.md), v(x) replaced by its x-dependent calibration
//! α·v(x)^β fitted to the model's own leave-one-out residuals
//! (`KrigingSurrogate::variance_calibration`; below, v stands for the
//! calibrated value) and the measurement noise e_n ~ N(0, σ²I):
//! ln L(x) = −½ [ln det Σ + rᵀΣ⁻¹r] + const, Σ = σ²I + v(x)K, r = d − ŷ(x).
//! For a PCA-reduced surrogate K = U Uᵀ (rank k) and ŷ = A c(x) (rank r,
//! [`crate::ReducedModel`]), so by the Woodbury identity, with
//! M = I_k + (v/σ²) UᵀU and w = Uᵀr:
//! ln det Σ = m ln σ² + ln det M, rᵀΣ⁻¹r = (rᵀr − (v/σ²) wᵀM⁻¹w)/σ²,
//! rᵀr = dᵀd − 2 dᵀA c + cᵀ(AᵀA)c, w = Uᵀd − (UᵀA)c; with UᵀU = QΛQᵀ
//! diagonalised once per curve, ln det M and wᵀM⁻¹w are sums over its k
//! eigenvalues — O(k·r + r²) per evaluation after O(m·(k + r)²) once per
//! curve. Otherwise K is diagonal
//! and the sum runs over the m points. Both forms reduce to a spectrum
//! (λ_i, the residual's coordinates z_i, rᵀr; [`super::error_scale`]),
//! where a Student-t surrogate error (`heavy_tails`) integrates its scale
//! out.

use nalgebra::{DMatrix, DVector};
use nlvid_surrogate::{OutputCovariance, VarianceCalibration};

use super::error_scale::{ErrorScale, Spectrum};
use crate::error::{InverseError, Result};
use crate::model::{Model, check_len};
use crate::reduced::ReducedModel;
use crate::surrogate::KrigingSurrogate;

/// Φ⁻¹(0.75): the median of |N(0, 1)|.
const MAD_NORMAL: f64 = 0.674_489_750_196_081_7;

/// The measurement noise σ of a curve sampled at `times`, from the curve
/// alone: each interior point minus the straight line through its two
/// neighbours, e_j = d_j − (w₁ d_{j−1} + w₂ d_{j+1}), has variance
/// σ²(1 + w₁² + w₂²) where the signal is locally linear; σ̂ is the median
/// of |e_j|/√(1 + w₁² + w₂²) divided by Φ⁻¹(0.75) — robust to the few
/// points where the curve bends sharply (end of the ramp, fast relaxation).
///
/// # Errors
/// Fewer than 5 points, lengths that differ, times not increasing, or a
/// curve without noise (σ̂ = 0: e.g. interpolated between too few samples).
pub fn noise_sd(times: &[f64], values: &[f64]) -> Result<f64> {
    check_len("noise estimate: values vs times", times.len(), values.len())?;
    if times.len() < 5 || times.windows(2).any(|w| !(w[1] > w[0])) {
        return Err(InverseError::InvalidSetting(format!(
            "noise estimate: needs at least 5 points at increasing times ({} given)",
            times.len()
        )));
    }
    let mut e: Vec<f64> = (1..times.len() - 1)
        .map(|j| {
            let h = times[j + 1] - times[j - 1];
            let w1 = (times[j + 1] - times[j]) / h;
            let w2 = 1.0 - w1;
            (values[j] - w1 * values[j - 1] - w2 * values[j + 1]).abs()
                / (1.0 + w1 * w1 + w2 * w2).sqrt()
        })
        .collect();
    e.sort_by(f64::total_cmp);
    let n = e.len();
    let median = if n % 2 == 1 {
        e[n / 2]
    } else {
        0.5 * (e[n / 2 - 1] + e[n / 2])
    };
    let sd = median / MAD_NORMAL;
    if sd > 0.0 && sd.is_finite() {
        Ok(sd)
    } else {
        Err(InverseError::InvalidSetting(format!(
            "noise estimate: the curve shows no noise (sigma = {sd}); is it interpolated \
             between fewer samples than the model grid has points?"
        )))
    }
}

/// UᵀU = QΛQᵀ diagonalised once, so that M = Q(I + (v/σ²)Λ)Qᵀ:
/// ln det M = Σ ln(1 + (v/σ²)λ_i) and wᵀM⁻¹w = Σ (Qᵀw)_i²/(1 + (v/σ²)λ_i),
/// O(k·r) per evaluation.
struct LowRank {
    ata: DMatrix<f64>,
    /// QᵀUᵀA.
    qta: DMatrix<f64>,
    /// λ, the eigenvalues of UᵀU (≥ 0).
    lambda: DVector<f64>,
    atd: DVector<f64>,
    /// QᵀUᵀd.
    qtd: DVector<f64>,
    dtd: f64,
}

impl LowRank {
    /// ln L (module docs, without −(m/2) ln 2π) at reduced coordinates
    /// `c` with calibrated Kriging variance `v`, noise variance `s2` and
    /// `m` data points, the error's scale as `scale` says.
    fn value(&self, c: &DVector<f64>, v: f64, s2: f64, m: f64, scale: &ErrorScale) -> f64 {
        let rtr = self.dtd - 2.0 * self.atd.dot(c) + c.dot(&(&self.ata * c));
        let w = &self.qtd - &self.qta * c;
        let spectrum = Spectrum {
            lambda: self.lambda.as_slice(),
            z: w.as_slice(),
            rtr,
            s2,
            m,
        };
        scale.ln_likelihood(&spectrum, v / s2)
    }
}

enum Form {
    LowRank(LowRank),
    Diagonal { k: Vec<f64> },
}

/// ln L(x) of one curve on a Kriging surrogate (module docs).
pub struct CurveLikelihood<'a> {
    surrogate: &'a KrigingSurrogate,
    data: Vec<f64>,
    noise_var: f64,
    /// v ↦ α v^β applied to the Kriging variance.
    calibration: VarianceCalibration,
    /// Gaussian or Student-t surrogate error (the calibration's ν).
    scale: ErrorScale,
    form: Form,
    /// Threads over which a batch's surrogate values are split (1:
    /// the calling thread only).
    threads: usize,
    /// Whether the surrogate's error enters Σ (else Σ = σ²I).
    surrogate_error: bool,
    /// A calibrated Kriging variance used at every point instead of
    /// α·v(x)^β ([`CurveLikelihood::with_variance_held`]).
    held_variance: Option<f64>,
}

impl<'a> CurveLikelihood<'a> {
    /// Prepares the likelihood of `data` (on the surrogate's grid) with
    /// measurement noise sd `noise` (e.g. [`noise_sd`]) and the surrogate
    /// error Student-t (`heavy_tails`) or Gaussian
    /// ([`KrigingSurrogate::variance_calibration`]); Gaussian with a scale
    /// per eigen-direction of the cross-validated Σ with `direction_scales`
    /// ([`KrigingSurrogate::direction_calibration`]).
    ///
    /// # Errors
    /// Data of the wrong length or not finite, σ ≤ 0, a surrogate without
    /// a linear predictor or Kriging variance, `heavy_tails` together with
    /// `direction_scales`.
    pub fn new(
        surrogate: &'a KrigingSurrogate,
        data: &[f64],
        noise: f64,
        heavy_tails: bool,
        direction_scales: bool,
    ) -> Result<Self> {
        let m = Model::times(surrogate).len();
        check_len("likelihood data", m, data.len())?;
        if data.iter().any(|v| !v.is_finite()) || !(noise > 0.0 && noise.is_finite()) {
            return Err(InverseError::InvalidSetting(format!(
                "likelihood: data must be finite and the noise sd > 0 (got {noise})"
            )));
        }
        let (cov, calibration) = if direction_scales {
            if heavy_tails {
                return Err(InverseError::InvalidSetting(
                    "likelihood: per-direction scales are Gaussian only (not with heavy_tails)"
                        .into(),
                ));
            }
            let (cal, cov) = surrogate.direction_calibration()?;
            (cov, cal)
        } else {
            (
                surrogate.output_covariance_cv()?,
                surrogate.variance_calibration(heavy_tails)?,
            )
        };
        let d = DVector::from_column_slice(data);
        let form = match cov {
            OutputCovariance::LowRank { m: mm, k, factor } if surrogate.is_reduced() => {
                let u = DMatrix::from_column_slice(mm, k, &factor);
                let a = surrogate.output_map();
                let eig = (u.transpose() * &u).symmetric_eigen();
                let qtu = eig.eigenvectors.transpose() * u.transpose();
                Form::LowRank(LowRank {
                    ata: a.transpose() * a,
                    qta: &qtu * a,
                    lambda: eig.eigenvalues.map(|l| l.max(0.0)),
                    atd: a.transpose() * &d,
                    qtd: qtu * &d,
                    dtd: d.dot(&d),
                })
            }
            other => Form::Diagonal {
                k: other.diagonal(),
            },
        };
        Ok(Self {
            surrogate,
            data: data.to_vec(),
            noise_var: noise * noise,
            scale: ErrorScale::new(calibration.nu),
            calibration,
            form,
            threads: 1,
            surrogate_error: true,
            held_variance: None,
        })
    }

    /// Splits each batch's surrogate values over up to `threads` threads
    /// ([`KrigingModel::coordinates_and_mse_scales`]; the same values for
    /// any count, so the same draws).
    ///
    /// [`KrigingModel::coordinates_and_mse_scales`]: nlvid_surrogate::KrigingModel::coordinates_and_mse_scales
    pub fn with_threads(mut self, threads: usize) -> Self {
        self.threads = threads.max(1);
        self
    }

    /// With `false`, Σ = σ²I: the surrogate's error left out (its
    /// calibrated variance taken as 0), the exact likelihood of data made
    /// by the surrogate itself plus white noise.
    pub fn with_surrogate_error(mut self, on: bool) -> Self {
        self.surrogate_error = on;
        self
    }

    /// With `Some(v)`, the calibrated Kriging variance is `v` at every
    /// point (e.g. α·v(x̂)^β at the fit) instead of α·v(x)^β: ln L then
    /// needs the surrogate's mean only (as [`CurveLikelihood::screen_values`]).
    pub fn with_variance_held(mut self, v: Option<f64>) -> Self {
        self.held_variance = v;
        self
    }

    /// Whether the calibrated variance is held ([`CurveLikelihood::with_variance_held`]).
    pub fn variance_held(&self) -> bool {
        self.held_variance.is_some()
    }

    /// The held calibrated variance (0 without the surrogate's error), if
    /// one is held.
    fn held(&self) -> Option<f64> {
        self.held_variance
            .map(|v| if self.surrogate_error { v } else { 0.0 })
    }

    /// The calibrated Kriging variance α·v^β of a raw v (0 without the
    /// surrogate's error).
    fn calibrated(&self, v: f64) -> f64 {
        if self.surrogate_error {
            self.calibration.apply(v)
        } else {
            0.0
        }
    }

    /// The measurement noise variance σ².
    pub fn noise_var(&self) -> f64 {
        self.noise_var
    }

    /// ln L(x) up to the constant −(m/2) ln 2π, at physical x.
    ///
    /// # Errors
    /// Surrogate failures at x; a non-positive-definite Σ (not expected:
    /// σ² > 0 and v(x)·K ⪰ 0).
    pub fn value(&self, x: &[f64]) -> Result<f64> {
        Ok(self.values(&[x.to_vec()])?[0])
    }

    /// ln L at each of many physical points: with a PCA the surrogate's
    /// c(x) and v(x) for the whole batch at once
    /// ([`KrigingSurrogate::coordinates_and_mse_scales`]), then the
    /// Woodbury form (module docs) point by point.
    ///
    /// # Errors
    /// As [`CurveLikelihood::value`] for any point of the batch.
    pub fn values(&self, xs: &[Vec<f64>]) -> Result<Vec<f64>> {
        let s2 = self.noise_var;
        match &self.form {
            Form::LowRank(form) => {
                let m = self.data.len() as f64;
                if let Some(v) = self.held() {
                    // The surrogate's mean only, as in `screen_values`.
                    let cs = self.surrogate.coordinate_batch(xs, self.threads)?;
                    return Ok(cs
                        .iter()
                        .map(|c| form.value(c, v, s2, m, &self.scale))
                        .collect());
                }
                let (cs, vs) = self
                    .surrogate
                    .coordinates_and_mse_scales(xs, self.threads)?;
                Ok(cs
                    .iter()
                    .zip(vs)
                    .map(|(c, v)| form.value(c, self.calibrated(v), s2, m, &self.scale))
                    .collect())
            }
            Form::Diagonal { k } => xs
                .iter()
                .map(|x| {
                    let v = match self.held() {
                        Some(v) => v,
                        None => self.calibrated(self.surrogate.mse_scale(x)?),
                    };
                    let y = Model::response(self.surrogate, x)?;
                    // The spectrum of a diagonal K: λ_j = K_jj, z_j = r_j √K_jj.
                    let r: Vec<f64> = self.data.iter().zip(&y).map(|(d, y)| d - y).collect();
                    let z: Vec<f64> = r.iter().zip(k).map(|(r, kj)| r * kj.sqrt()).collect();
                    let spectrum = Spectrum {
                        lambda: k,
                        z: &z,
                        rtr: r.iter().map(|r| r * r).sum(),
                        s2,
                        m: self.data.len() as f64,
                    };
                    Ok(self.scale.ln_likelihood(&spectrum, v / s2))
                })
                .collect(),
        }
    }

    /// The calibrated Kriging variance α·v(x)^β (the v of the module
    /// docs) at each of many physical points, computed as by
    /// [`CurveLikelihood::values`].
    ///
    /// # Errors
    /// As [`KrigingSurrogate::coordinates_and_mse_scales`].
    pub fn calibrated_variances(&self, xs: &[Vec<f64>]) -> Result<Vec<f64>> {
        let (_, vs) = self
            .surrogate
            .coordinates_and_mse_scales(xs, self.threads)?;
        Ok(vs.into_iter().map(|v| self.calibrated(v)).collect())
    }

    /// ln L̃(x): ln L with the calibrated Kriging variance given
    /// (`variances`, one per point) instead of v(x), at each of many
    /// physical points — the surrogate's mean c(x) only
    /// ([`KrigingSurrogate::coordinate_batch`], O(N·(q + d)) per point, no
    /// O(N²) solve). The cheap first stage of the sampler's delayed
    /// acceptance ([`super::screen`]); equal to ln L where the variance
    /// given is v(x). None without a PCA (the diagonal form needs the full
    /// m-point prediction).
    ///
    /// # Errors
    /// As [`CurveLikelihood::value`] for any point of the batch.
    pub fn screen_values(&self, xs: &[Vec<f64>], variances: &[f64]) -> Result<Option<Vec<f64>>> {
        let Form::LowRank(form) = &self.form else {
            return Ok(None);
        };
        check_len("screen variances", xs.len(), variances.len())?;
        let (s2, m) = (self.noise_var, self.data.len() as f64);
        let cs = self.surrogate.coordinate_batch(xs, self.threads)?;
        Ok(Some(
            cs.iter()
                .zip(variances)
                .map(|(c, &v)| form.value(c, v, s2, m, &self.scale))
                .collect(),
        ))
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::surrogate::Coordinates;
    use crate::surrogate_file::load_kriging_surrogate;
    use std::path::Path;

    pub(crate) fn demo_surrogate() -> KrigingSurrogate {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/demo/metamodel");
        load_kriging_surrogate(
            &dir.join("model.json"),
            &dir.join("meta.json"),
            Coordinates::Physical,
        )
        .expect("demo meta-model")
    }

    /// The surrogate's curve at `x` plus a deterministic sawtooth of
    /// amplitude 2 % of its peak (the tests' data), and that amplitude.
    pub(crate) fn pseudo_noisy_curve(s: &KrigingSurrogate, x: &[f64]) -> (Vec<f64>, f64) {
        let y = s.response(x).expect("y");
        let noise = 0.02 * y.iter().fold(0.0f64, |a, &b| a.max(b));
        let data = y
            .iter()
            .enumerate()
            .map(|(j, v)| v + noise * ((j * 7919 % 101) as f64 / 50.0 - 1.0))
            .collect();
        (data, noise)
    }

    /// ln N(data; s(x), Σ + σ² I) up to the constant, with Σ + σ² I built
    /// and factorised as an m × m matrix (the tests' second method).
    fn dense_gaussian_ln_l(
        mut sigma: DMatrix<f64>,
        noise: f64,
        data: &[f64],
        s: &KrigingSurrogate,
        x: &[f64],
    ) -> f64 {
        let m = data.len();
        for j in 0..m {
            sigma[(j, j)] += noise * noise;
        }
        let y = s.response(x).unwrap();
        let r = DVector::from_iterator(m, data.iter().zip(&y).map(|(d, y)| d - y));
        let chol = sigma.cholesky().expect("spd");
        let logdet: f64 = 2.0 * chol.l().diagonal().iter().map(|l| l.ln()).sum::<f64>();
        -0.5 * (logdet + r.dot(&chol.solve(&r)))
    }

    /// `lik` equals [`dense_gaussian_ln_l`] with the surrogate-error
    /// covariance `sigma(x)` to 1e-7 (relative) at the curve's point
    /// (1500 Pa, 0.3, 0.25, 0.5 s, 10 s) and two others.
    fn assert_equals_dense_gaussian(
        lik: &CurveLikelihood,
        s: &KrigingSurrogate,
        data: &[f64],
        noise: f64,
        sigma: impl Fn(&[f64]) -> DMatrix<f64>,
    ) {
        for x in [
            [1500.0, 0.3, 0.25, 0.5, 10.0],
            [1400.0, 0.35, 0.2, 0.3, 14.0],
            [3000.0, 0.1, 0.6, 1.5, 5.0],
        ] {
            let dense = dense_gaussian_ln_l(sigma(&x), noise, data, s, &x);
            let ours = lik.value(&x).unwrap();
            assert!(
                (ours - dense).abs() < 1e-7 * dense.abs().max(1.0),
                "x {x:?}: {ours} vs {dense}"
            );
        }
    }

    /// The Woodbury form equals the dense Gaussian log-density with
    /// Σ = σ²I + α v(x)^β·diag(σ_y) V Σ_z Vᵀ diag(σ_y) (the calibrated
    /// Kriging variance) built and factorised as an m × m matrix (second
    /// method), at the truth and off it.
    #[test]
    fn woodbury_likelihood_equals_the_dense_gaussian() {
        let s = demo_surrogate();
        assert!(s.is_reduced());
        let x0 = [1500.0, 0.3, 0.25, 0.5, 10.0];
        let (data, noise) = pseudo_noisy_curve(&s, &x0);
        let lik = CurveLikelihood::new(&s, &data, noise, false, false).expect("lik");
        let OutputCovariance::LowRank { m, k, factor } =
            s.kriging().output_covariance_cv().unwrap()
        else {
            panic!("PCA model");
        };
        let u = DMatrix::from_column_slice(m, k, &factor);
        let cal = s.variance_calibration(false).unwrap();
        // A calibration that differs from v ↦ v, or the test would not
        // see it applied.
        assert!((cal.beta - 1.0).abs() > 0.05, "{cal:?}");
        let k = &u * u.transpose();
        assert_equals_dense_gaussian(&lik, &s, &data, noise, |x| {
            &k * (cal.alpha * s.mse_scale(x).unwrap().powf(cal.beta))
        });
    }

    /// With the calibrated variance held (`with_variance_held`), the
    /// likelihood is the dense Gaussian with Σ = σ²I + v_held·K at every
    /// point (second method), not with v(x): at x0 (where v_held is
    /// v(x0)) it equals the ordinary likelihood, at the other points it
    /// does not.
    #[test]
    fn held_variance_likelihood_is_the_dense_gaussian_with_that_variance() {
        let s = demo_surrogate();
        let x0 = [1500.0, 0.3, 0.25, 0.5, 10.0];
        let (data, noise) = pseudo_noisy_curve(&s, &x0);
        let plain = CurveLikelihood::new(&s, &data, noise, false, false).expect("lik");
        let v0 = plain.calibrated_variances(&[x0.to_vec()]).unwrap()[0];
        let held = CurveLikelihood::new(&s, &data, noise, false, false)
            .expect("lik")
            .with_variance_held(Some(v0));
        assert!(held.variance_held() && !plain.variance_held());
        let OutputCovariance::LowRank { m, k, factor } =
            s.kriging().output_covariance_cv().unwrap()
        else {
            panic!("PCA model");
        };
        let u = DMatrix::from_column_slice(m, k, &factor);
        let k = &u * u.transpose();
        assert_equals_dense_gaussian(&held, &s, &data, noise, |_| &k * v0);
        let at_x0 = (held.value(&x0).unwrap(), plain.value(&x0).unwrap());
        assert!(
            (at_x0.0 - at_x0.1).abs() < 1e-9 * at_x0.1.abs(),
            "{at_x0:?}"
        );
        let x1 = [3000.0, 0.1, 0.6, 1.5, 5.0];
        let v1 = plain.calibrated_variances(&[x1.to_vec()]).unwrap()[0];
        assert!((v1 / v0 - 1.0).abs() > 0.1, "v(x1) {v1} v(x0) {v0}");
        assert!((held.value(&x1).unwrap() - plain.value(&x1).unwrap()).abs() > 1e-6);
        // A batch gives each point's value.
        let batch = held.values(&[x0.to_vec(), x1.to_vec()]).unwrap();
        assert_eq!(
            batch,
            vec![held.value(&x0).unwrap(), held.value(&x1).unwrap()]
        );
    }

    /// Without the surrogate's error the likelihood is the white-noise
    /// Gaussian −½[m ln σ² + rᵀr/σ²] (closed form), for the Gaussian and
    /// the Student-t error alike, and the calibrated variances are 0.
    #[test]
    fn likelihood_without_the_surrogate_error_is_white_noise() {
        let s = demo_surrogate();
        let x0 = [1500.0, 0.3, 0.25, 0.5, 10.0];
        let (data, noise) = pseudo_noisy_curve(&s, &x0);
        let xs = [x0, [3000.0, 0.1, 0.6, 1.5, 5.0]];
        for heavy_tails in [false, true] {
            let with = CurveLikelihood::new(&s, &data, noise, heavy_tails, false).expect("lik");
            let without = CurveLikelihood::new(&s, &data, noise, heavy_tails, false)
                .expect("lik")
                .with_surrogate_error(false);
            for x in xs {
                let y = s.response(&x).unwrap();
                let rtr: f64 = data.iter().zip(&y).map(|(d, y)| (d - y).powi(2)).sum();
                let m = data.len() as f64;
                let white = -0.5 * (m * (noise * noise).ln() + rtr / (noise * noise));
                let ours = without.value(&x).unwrap();
                assert!(
                    (ours - white).abs() < 1e-9 * white.abs(),
                    "{x:?}: {ours} vs {white}"
                );
                // The error term matters here, or the test would not see it.
                assert!((with.value(&x).unwrap() - white).abs() > 1e-3);
            }
            let xs: Vec<Vec<f64>> = xs.iter().map(|x| x.to_vec()).collect();
            assert_eq!(without.calibrated_variances(&xs).unwrap(), vec![0.0; 2]);
        }
    }

    /// With `direction_scales` the likelihood is the dense Gaussian with
    /// Σ = σ²I + α v(x)^β·diag(σ_y) V Σ' Vᵀ diag(σ_y), Σ' = Σ_k a_k λ_k q_k q_kᵀ
    /// over the eigenpairs of Σ_CV taken here by nalgebra (second method;
    /// the scales in descending order of λ), at three points. Not with
    /// `heavy_tails`.
    #[test]
    fn per_direction_likelihood_equals_the_dense_gaussian() {
        let s = demo_surrogate();
        let km = s.kriging();
        let pca = km.pca.as_ref().expect("PCA model");
        let (m, q) = (km.n_outputs, km.n_kriged());
        let x0 = [1500.0, 0.3, 0.25, 0.5, 10.0];
        let (data, noise) = pseudo_noisy_curve(&s, &x0);
        let lik = CurveLikelihood::new(&s, &data, noise, false, true).expect("lik");
        assert!(CurveLikelihood::new(&s, &data, noise, true, true).is_err());
        let (cal, _) = s.direction_calibration().unwrap();
        assert!(
            cal.directions.iter().any(|a| (a - 1.0).abs() > 0.1),
            "{cal:?}"
        );
        let eig = DMatrix::from_column_slice(q, q, &km.cv_process_covariance().unwrap())
            .symmetric_eigen();
        let mut order: Vec<usize> = (0..q).collect();
        order.sort_by(|&i, &j| eig.eigenvalues[j].total_cmp(&eig.eigenvalues[i]));
        let mut scaled = DMatrix::<f64>::zeros(q, q);
        for (c, &e) in order.iter().enumerate() {
            let qe = eig.eigenvectors.column(e);
            scaled += qe * qe.transpose() * (cal.directions[c] * eig.eigenvalues[e]);
        }
        let dv = DMatrix::from_fn(m, q, |j, a| km.y_std[j] * pca.basis[a * m + j]);
        let k = &dv * scaled * dv.transpose();
        assert_equals_dense_gaussian(&lik, &s, &data, noise, |x| {
            &k * cal.apply(s.mse_scale(x).unwrap())
        });
    }

    /// ln L of a batch on the demo meta-model (n = 970 sites) is bitwise
    /// the same on 1 and 2 threads, for the batch sizes the sampler makes
    /// (up to 64; fewer when proposals fall outside the prior).
    #[test]
    fn batch_values_are_the_same_on_one_and_two_threads() {
        let s = demo_surrogate();
        let x0 = [1500.0, 0.3, 0.25, 0.5, 10.0];
        let data = s.response(&x0).expect("y");
        let one = CurveLikelihood::new(&s, &data, 1e-10, true, false).expect("lik");
        let two = CurveLikelihood::new(&s, &data, 1e-10, true, false)
            .expect("lik")
            .with_threads(2);
        let xs: Vec<Vec<f64>> = (0..64)
            .map(|i| {
                let t = f64::from(i) / 64.0;
                vec![
                    900.0 + 2500.0 * t,
                    0.1 + 0.5 * (7.0 * t).fract(),
                    0.35 - 0.3 * (3.0 * t).fract(),
                    0.02 + 1.5 * (5.0 * t).fract(),
                    2.0 + 37.0 * (11.0 * t).fract(),
                ]
            })
            .collect();
        for b in [1, 2, 3, 5, 31, 32, 33, 64] {
            let a: Vec<u64> = one
                .values(&xs[..b])
                .unwrap()
                .iter()
                .map(|v| v.to_bits())
                .collect();
            let c: Vec<u64> = two
                .values(&xs[..b])
                .unwrap()
                .iter()
                .map(|v| v.to_bits())
                .collect();
            assert_eq!(a, c, "batch of {b}");
        }
    }

    /// σ̂ of a smooth curve plus N(0, σ²) noise on an uneven grid is σ
    /// within the estimator's sampling error (MAD: ≈ 1.65σ/√(2n)).
    #[test]
    fn noise_estimate_recovers_the_added_noise() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(4);
        let n = 3000;
        let times: Vec<f64> = (0..n)
            .map(|i| {
                let t = i as f64 / n as f64;
                52.0 * t * t + 0.01 * t
            })
            .collect();
        for sigma in [1e-11, 3e-10] {
            let values: Vec<f64> = times
                .iter()
                .map(|&t| {
                    let u1: f64 = 1.0 - rng.random::<f64>();
                    let u2: f64 = rng.random();
                    let e = (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos();
                    1e-8 * (0.4 + 0.6 * (-t / 0.5).exp()) * t.min(1.0) + sigma * e
                })
                .collect();
            let est = noise_sd(&times, &values).unwrap();
            assert!((est / sigma - 1.0).abs() < 0.08, "sigma {sigma}: {est}");
        }
        assert!(noise_sd(&times[..3], &[0.0; 3]).is_err());
        let flat = vec![1.0; 10];
        let t: Vec<f64> = (0..10).map(f64::from).collect();
        assert!(noise_sd(&t, &flat).is_err());
    }
}
