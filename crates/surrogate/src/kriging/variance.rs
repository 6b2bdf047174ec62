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

use faer::linalg::triangular_solve::solve_lower_triangular_in_place;
use faer::{Mat, Par};

use super::{KrigingModel, view};
use crate::error::Result;

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
        solve_lower_triangular_in_place(view(&self.c, n, n), rt.as_mut(), Par::Seq);
        let mut v = view(&self.ft, n, p).transpose() * &rt;
        for k in 0..p {
            v[(k, 0)] -= f[k];
        }
        solve_lower_triangular_in_place(view(&self.g, p, p).transpose(), v.as_mut(), Par::Seq);
        let rt: Vec<f64> = rt.col(0).iter().copied().collect();
        let v: Vec<f64> = v.col(0).iter().copied().collect();
        let phi =
            1.0 + v.iter().map(|a| a * a).sum::<f64>() - rt.iter().map(|a| a * a).sum::<f64>();
        Ok(VariancePoint {
            xn,
            rt,
            v,
            phi: phi.max(0.0),
        })
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
