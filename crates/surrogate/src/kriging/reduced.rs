//! The predictor in its reduced (output-space) form, for fitters whose cost
//! must not grow with n·m (thesis §5.4.1: one fit per cell on a surrogate
//! with N ≈ 970 runs and m ≈ 5000 output times).
//!
//! Every linear-output model (no `log_outputs`) predicts
//! `ŷ(x) = s(x)·(μ + σ ⊙ V z(x)) = A c(x)` with
//! `A = [μ, diag(σ)·V]` (m × (q + 1), fixed) and `c(x) = s(x)·[1; z(x)]`
//! (q + 1 values), where `z = βᵀf(x) + γᵀr(x)` are the q kriged outputs
//! (PC scores with a PCA, V = I without), μ, σ the output means and
//! deviations and s(x) the [`OutputScale`](super::OutputScale) (1 without).
//! c(x) and ∂c/∂x cost O(n·q·d); A is shared by every evaluation.

use super::KrigingModel;
use crate::error::{Result, SurrogateError};

impl KrigingModel {
    /// Number of reduced coordinates q + 1 of [`KrigingModel::output_coordinates`].
    pub fn n_output_coordinates(&self) -> usize {
        self.n_kriged() + 1
    }

    /// The fixed output map A = [μ, diag(σ)·V] (m × (q + 1), column-major)
    /// with ŷ(x) = A c(x) (DACE report eq. 2.16 with the output
    /// normalisation, PCA rotation V and output scaling written out).
    /// Without a PCA, V = I (q = m: then A has m + 1 columns and no
    /// reduction is gained).
    ///
    /// # Errors
    /// [`SurrogateError::InvalidSettings`] for a model with `log_outputs`
    /// (its predictor exp(·) is not linear in c).
    pub fn output_map(&self) -> Result<Vec<f64>> {
        self.check_linear_outputs()?;
        let (m, q) = (self.n_outputs, self.n_kriged());
        let mut a = vec![0.0; m * (q + 1)];
        a[..m].copy_from_slice(&self.y_mean);
        match &self.pca {
            Some(pca) => {
                for k in 0..q {
                    let v = &pca.basis[k * m..(k + 1) * m];
                    let col = &mut a[(k + 1) * m..(k + 2) * m];
                    for j in 0..m {
                        col[j] = self.y_std[j] * v[j];
                    }
                }
            }
            None => {
                for j in 0..m {
                    a[(j + 1) * m + j] = self.y_std[j];
                }
            }
        }
        Ok(a)
    }

    /// Reduced coordinates c(x) = s(x)·[1; z(x)] of the prediction
    /// (ŷ = A c, see [`KrigingModel::output_map`]) and ∂c/∂x with respect
    /// to the caller's x (log inputs and normalisation included),
    /// row-major (q + 1) × d. Cost O(n·q·d) — independent of m.
    ///
    /// # Errors
    /// `x` of the wrong length or not finite, a log input ≤ 0, s(x) ≤ 0,
    /// or a model with `log_outputs`.
    pub fn output_coordinates(&self, x: &[f64]) -> Result<(Vec<f64>, Vec<f64>)> {
        self.check_linear_outputs()?;
        let xi = self.internal_x(x)?;
        let (n, d, p, q) = (self.n_sites, self.dim, self.p(), self.n_kriged());
        let xn: Vec<f64> = (0..d)
            .map(|k| (xi[k] - self.x_mean[k]) / self.x_std[k])
            .collect();
        let mut f = vec![0.0; p];
        self.regression.eval(&xn, &mut f);
        let mut df = vec![0.0; d * p];
        self.regression.jacobian(&xn, &mut df);
        // r_i and ∂r_i/∂xn_k, the latter column-major n × d.
        let mut r = vec![0.0; n];
        let mut dr = vec![0.0; n * d];
        let mut dx = vec![0.0; d];
        let mut g = vec![0.0; d];
        for i in 0..n {
            for k in 0..d {
                dx[k] = xn[k] - self.sites[k * n + i];
            }
            r[i] = self.correlation.value_and_grad_d(&self.theta, &dx, &mut g);
            for k in 0..d {
                dr[k * n + i] = g[k];
            }
        }
        // ∂xn_k/∂x_k.
        let scale: Vec<f64> = (0..d)
            .map(|k| self.dinternal(x, k) / self.x_std[k])
            .collect();
        let mut c = vec![0.0; q + 1];
        let mut dc = vec![0.0; (q + 1) * d];
        c[0] = 1.0;
        for j in 0..q {
            let b = &self.beta[j * p..(j + 1) * p];
            let gm = &self.gamma[j * n..(j + 1) * n];
            c[j + 1] = dot(b, &f) + dot(gm, &r);
            for k in 0..d {
                let dz = dot(&df[k * p..(k + 1) * p], b) + dot(&dr[k * n..(k + 1) * n], gm);
                dc[(j + 1) * d + k] = dz * scale[k];
            }
        }
        if let Some(sc) = self.output_scale {
            let s = sc.check(x, "the prediction point")?;
            let (_, ds) = sc.eval(x);
            let kk = sc.input();
            for j in 0..=q {
                for k in 0..d {
                    dc[j * d + k] *= s;
                }
                dc[j * d + kk] += ds * c[j];
                c[j] *= s;
            }
        }
        Ok((c, dc))
    }

    fn check_linear_outputs(&self) -> Result<()> {
        if self.log_outputs {
            Err(SurrogateError::InvalidSettings(
                "the model predicts exp(kriged ln y): it has no linear output map (refit \
                 without --log-outputs to use the reduced form)"
                    .into(),
            ))
        } else {
            Ok(())
        }
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}
