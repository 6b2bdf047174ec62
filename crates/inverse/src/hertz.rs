//! An analytic forward model: Lee–Radok linear-viscoelastic Hertz contact of
//! a rigid sphere on a half-space with a two-term Prony G(t) (eq. 5.1).
//!
//! F(t) = 8√R / (3(1 − ν)) · ∫₀ᵗ G(t − s) d[δ(s)^{3/2}]/ds ds,
//! which reduces to Hertz (eq. 1.1 with E = 2G(1 + ν)) for a constant G.
//! It is the baseline model nlvid compares the FE fits against, and the
//! cheap model the inverse machinery is tested and benchmarked on.
//!
//! The hereditary integral is evaluated exactly for the piecewise-linear
//! interpolant of ε = δ^{3/2} on the time grid (recursive exponential
//! update, as in the FE time integration); a step at t₀ loads
//! instantaneously. Cost: O(m) per response, O(m) for the analytic Jacobian.

use nalgebra::DMatrix;

use crate::domain::Domain;
use crate::error::{InverseError, Result};
use crate::model::Model;

/// Lee–Radok Hertz ramp-hold model with parameters x = (G0, g1, τ1, g2, τ2).
#[derive(Debug, Clone)]
pub struct LeeRadokHertz {
    domain: Domain,
    times: Vec<f64>,
    /// ε_j = δ(t_j)^{3/2} (m^{3/2}); negative indentation gives 0.
    eps: Vec<f64>,
    /// 8√R / (3(1 − ν)).
    prefactor: f64,
}

impl LeeRadokHertz {
    /// Model for a sphere of radius `radius` (m), Poisson ratio `poisson`,
    /// indentation history `indentation[j]` (m) at `times[j]` (s).
    ///
    /// # Errors
    /// [`InverseError::InvalidSetting`] if the domain does not have five
    /// parameters, the grid is not strictly increasing, lengths differ, or
    /// R ≤ 0, ν ∉ [0, 0.5].
    pub fn new(
        domain: Domain,
        times: Vec<f64>,
        indentation: &[f64],
        radius: f64,
        poisson: f64,
    ) -> Result<Self> {
        if domain.len() != 5 {
            return Err(InverseError::InvalidSetting(format!(
                "the Lee-Radok Prony model has 5 parameters (G0, g1, tau1, g2, tau2), the domain has {}",
                domain.len()
            )));
        }
        if times.len() != indentation.len() || times.len() < 2 {
            return Err(InverseError::InvalidSetting(format!(
                "time grid ({}) and indentation history ({}) must have the same length >= 2",
                times.len(),
                indentation.len()
            )));
        }
        if let Some(j) = times
            .windows(2)
            .position(|w| w[1].partial_cmp(&w[0]) != Some(std::cmp::Ordering::Greater))
        {
            return Err(InverseError::InvalidSetting(format!(
                "time grid must be strictly increasing (index {})",
                j + 1
            )));
        }
        if !(radius > 0.0 && (0.0..=0.5).contains(&poisson)) {
            return Err(InverseError::InvalidSetting(format!(
                "sphere radius must be > 0 and Poisson ratio in [0, 0.5], got R = {radius}, nu = {poisson}"
            )));
        }
        let eps = indentation.iter().map(|d| d.max(0.0).powf(1.5)).collect();
        Ok(Self {
            domain,
            times,
            eps,
            prefactor: 8.0 * radius.sqrt() / (3.0 * (1.0 - poisson)),
        })
    }

    /// Hereditary integrals h_k(t_j) = ∫ e^{−(t_j − s)/τ} dε(s) and their
    /// τ-derivatives (if `with_dtau`).
    fn hereditary(&self, tau: f64, with_dtau: bool) -> (Vec<f64>, Vec<f64>) {
        let m = self.times.len();
        let mut h = vec![0.0; m];
        let mut dh = vec![0.0; if with_dtau { m } else { 0 }];
        h[0] = self.eps[0];
        for j in 0..m - 1 {
            let dt = self.times[j + 1] - self.times[j];
            let rate = (self.eps[j + 1] - self.eps[j]) / dt;
            let a = (-dt / tau).exp();
            let b = tau * (1.0 - a);
            h[j + 1] = a * h[j] + rate * b;
            if with_dtau {
                let da = a * dt / (tau * tau);
                let db = (1.0 - a) - a * dt / tau;
                dh[j + 1] = da * h[j] + a * dh[j] + rate * db;
            }
        }
        (h, dh)
    }

    fn check(&self, x: &[f64]) -> Result<()> {
        self.domain.check_len(x)?;
        if !(x[0] > 0.0 && x[2] > 0.0 && x[4] > 0.0) || x.iter().any(|v| !v.is_finite()) {
            return Err(InverseError::Model {
                x: x.to_vec(),
                message: "G0, tau1, tau2 must be positive and finite".into(),
            });
        }
        Ok(())
    }
}

impl Model for LeeRadokHertz {
    fn domain(&self) -> &Domain {
        &self.domain
    }

    fn times(&self) -> &[f64] {
        &self.times
    }

    fn response(&self, x: &[f64]) -> Result<Vec<f64>> {
        self.check(x)?;
        let (g0, g1, t1, g2, t2) = (x[0], x[1], x[2], x[3], x[4]);
        let ginf = 1.0 - g1 - g2;
        let (h1, _) = self.hereditary(t1, false);
        let (h2, _) = self.hereditary(t2, false);
        Ok((0..self.times.len())
            .map(|j| self.prefactor * g0 * (ginf * self.eps[j] + g1 * h1[j] + g2 * h2[j]))
            .collect())
    }

    fn jacobian(&self, x: &[f64]) -> Result<DMatrix<f64>> {
        Ok(self.response_and_jacobian(x)?.1)
    }

    fn response_and_jacobian(&self, x: &[f64]) -> Result<(Vec<f64>, DMatrix<f64>)> {
        self.check(x)?;
        let (g0, g1, t1, g2, t2) = (x[0], x[1], x[2], x[3], x[4]);
        let ginf = 1.0 - g1 - g2;
        let (h1, dh1) = self.hereditary(t1, true);
        let (h2, dh2) = self.hereditary(t2, true);
        let m = self.times.len();
        let a = self.prefactor;
        let mut y = vec![0.0; m];
        let mut jac = DMatrix::zeros(m, 5);
        for j in 0..m {
            let e = self.eps[j];
            let bracket = ginf * e + g1 * h1[j] + g2 * h2[j];
            y[j] = a * g0 * bracket;
            jac[(j, 0)] = a * bracket;
            jac[(j, 1)] = a * g0 * (h1[j] - e);
            jac[(j, 2)] = a * g0 * g1 * dh1[j];
            jac[(j, 3)] = a * g0 * (h2[j] - e);
            jac[(j, 4)] = a * g0 * g2 * dh2[j];
        }
        Ok((y, jac))
    }
}

/// Time grid of a ramp-hold test: `n_ramp` uniform intervals on
/// [0, t_ramp], then `n_hold` points log-spaced in (t − t_ramp) from
/// `first_hold_step` to t_end − t_ramp (dense where fast relaxation shows).
///
/// # Errors
/// [`InverseError::InvalidSetting`] for non-positive durations or counts.
pub fn ramp_hold_grid(
    t_ramp: f64,
    n_ramp: usize,
    t_end: f64,
    n_hold: usize,
    first_hold_step: f64,
) -> Result<Vec<f64>> {
    if !(t_ramp > 0.0
        && t_end > t_ramp + first_hold_step
        && first_hold_step > 0.0
        && n_ramp >= 1
        && n_hold >= 2)
    {
        return Err(InverseError::InvalidSetting(format!(
            "ramp-hold grid needs 0 < t_ramp < t_end, first_hold_step > 0, n_ramp >= 1, n_hold >= 2 \
             (got t_ramp = {t_ramp}, t_end = {t_end}, first step = {first_hold_step}, {n_ramp}, {n_hold})"
        )));
    }
    let mut t: Vec<f64> = (0..=n_ramp)
        .map(|i| t_ramp * i as f64 / n_ramp as f64)
        .collect();
    let (l0, l1) = (first_hold_step.ln(), (t_end - t_ramp).ln());
    for i in 0..n_hold {
        let s = (l0 + (l1 - l0) * i as f64 / (n_hold - 1) as f64).exp();
        t.push(t_ramp + s);
    }
    Ok(t)
}

/// Indentation of a ramp at constant `rate` (m/s) up to `depth` (m), then hold.
pub fn ramp_hold_indentation(times: &[f64], rate: f64, depth: f64) -> Vec<f64> {
    times.iter().map(|&t| (rate * t).min(depth)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::fd_jacobian;

    fn model() -> LeeRadokHertz {
        let d = Domain::prony2_table_5_3(0.01).expect("domain");
        let t = ramp_hold_grid(0.2, 100, 52.0, 300, 1e-3).expect("grid");
        let delta = ramp_hold_indentation(&t, 10e-6, 2e-6);
        LeeRadokHertz::new(d, t, &delta, 2.5e-6, 0.5).expect("model")
    }

    #[test]
    fn elastic_limit_is_hertz() {
        // g1 = g2 -> 0 is outside the domain's bounds but fine for the model:
        // F = 16/3 G0 sqrt(R) delta^{3/2} for nu = 1/2 (eq. 1.1 with E = 3 G0).
        let m = model();
        let y = m.response(&[1000.0, 0.0, 0.1, 0.0, 10.0]).expect("y");
        let hertz = 16.0 / 3.0 * 1000.0 * (2.5e-6f64).sqrt() * (2e-6f64).powf(1.5);
        let last = *y.last().expect("nonempty");
        assert!((last - hertz).abs() < 1e-12 * hertz);
    }

    #[test]
    fn matches_closed_form_when_delta_to_three_halves_is_linear_in_time() {
        // eps = c t on [0, tr], then hold: exact Lee-Radok integral is
        // F = A G0 [ginf eps + sum g_k tau_k c (e^{-(t - min(t,tr))/tau_k} - e^{-t/tau_k})].
        let d = Domain::prony2_table_5_3(0.01).expect("domain");
        let t = ramp_hold_grid(0.5, 37, 30.0, 80, 1e-3).expect("grid");
        let (tr, c) = (0.5, 4e-9);
        let delta: Vec<f64> = t.iter().map(|&s| (c * s.min(tr)).powf(2.0 / 3.0)).collect();
        let m = LeeRadokHertz::new(d, t.clone(), &delta, 2.5e-6, 0.3).expect("model");
        let x = [700.0, 0.5, 0.07, 0.3, 8.0];
        let y = m.response(&x).expect("y");
        let a = 8.0 * (2.5e-6f64).sqrt() / (3.0 * 0.7);
        for (j, &tj) in t.iter().enumerate() {
            let tm = tj.min(tr);
            let term =
                |g: f64, tau: f64| g * tau * c * ((-(tj - tm) / tau).exp() - (-tj / tau).exp());
            let exact = a * x[0] * (0.2 * c * tm + term(x[1], x[2]) + term(x[3], x[4]));
            assert!(
                (y[j] - exact).abs() <= 1e-9 * exact.abs() + 1e-24,
                "t = {tj}"
            );
        }
    }

    #[test]
    fn analytic_jacobian_matches_central_differences() {
        let m = model();
        let x = [650.0, 0.45, 0.08, 0.35, 9.0];
        let j = m.jacobian(&x).expect("jac");
        let jfd = fd_jacobian(&m, &x).expect("fd");
        for k in 0..5 {
            let col_norm = jfd.column(k).norm();
            let diff = (j.column(k) - jfd.column(k)).norm();
            assert!(diff <= 1e-6 * col_norm, "column {k}: {diff} vs {col_norm}");
        }
    }
}
