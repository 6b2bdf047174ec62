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

use super::{KrigingModel, view};
use crate::error::{Result, SurrogateError};

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
        let xi = self.internal_x(x)?;
        let (n, d, p) = (self.n_sites, self.dim, self.p());
        let xn: Vec<f64> = (0..d)
            .map(|k| (xi[k] - self.x_mean[k]) / self.x_std[k])
            .collect();
        let mut f = vec![0.0; p];
        self.regression.eval(&xn, &mut f);
        let mut r = Mat::<f64>::zeros(n, 1);
        let mut dx = vec![0.0; d];
        for i in 0..n {
            for k in 0..d {
                dx[k] = xn[k] - self.sites[k * n + i];
            }
            r[(i, 0)] = self.correlation.value(&self.theta, &dx);
        }
        let c = view(&self.c, n, n);
        let ft = view(&self.ft, n, p);
        let gmat = view(&self.g, p, p);
        solve_lower_triangular_in_place(c, r.as_mut(), Par::Seq);
        let mut v = ft.transpose() * &r;
        for k in 0..p {
            v[(k, 0)] -= f[k];
        }
        solve_lower_triangular_in_place(gmat.transpose(), v.as_mut(), Par::Seq);
        let phi = 1.0 + v.col(0).iter().map(|a| a * a).sum::<f64>()
            - r.col(0).iter().map(|a| a * a).sum::<f64>();
        // φ ≥ 0 in exact arithmetic; rounding at a design site can give −1e-16.
        let phi = phi.max(0.0);
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
        let m = self.n_outputs;
        let Some(pca) = &self.pca else {
            return Ok(OutputCovariance::Diagonal(self.process_variance()));
        };
        let k = pca.n_components;
        // Σ: the scores' residual covariance, or diag(σ²) for models saved
        // before it was stored.
        let sigma: Vec<f64> = if pca.residual_cov.len() == k * k {
            pca.residual_cov.clone()
        } else {
            let mut s = vec![0.0; k * k];
            for a in 0..k {
                s[a * k + a] = self.sigma2[a];
            }
            s
        };
        let l = psd_cholesky(&sigma, k)?;
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

    fn check_linear_for_variance(&self) -> Result<()> {
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

#[cfg(test)]
mod tests {
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

    #[test]
    fn log_output_models_are_refused() {
        let mut m = model(None, false);
        m.log_outputs = true;
        assert!(m.mse_scale(&[1.0, 0.5]).is_err());
        assert!(m.output_covariance().is_err());
    }
}
