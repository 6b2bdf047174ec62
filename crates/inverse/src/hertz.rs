//! The analytic forward model of the fits: Lee–Radok linear-viscoelastic
//! Hertz contact of a rigid sphere on a half-space with a two-term Prony
//! G(t) (eq. 5.1), driven by an indentation history δ(t_j) (measured, or
//! [`ramp_hold_indentation`]).
//!
//! F(t) = 8√R / (3(1 − ν)) · ∫₀ᵗ G(t − s) d[δ(s)^{3/2}]/ds ds,
//! which reduces to Hertz (eq. 1.1 with E = 2G(1 + ν)) for a constant G.
//! It is the baseline model nlvid compares the FE fits against, and the
//! cheap model the inverse machinery is tested and benchmarked on.
//!
//! The integral and its Jacobian are the pipeline's one Lee–Radok kernel,
//! `nlvid_forward::LeeRadok::sampled` (exact for δ^{3/2} piecewise linear
//! between samples). Cost: O(m) per response and per analytic Jacobian.

use nalgebra::DMatrix;
use nlvid_forward::LeeRadok;
use nlvid_model::{Domain, Relaxation, names};

use crate::error::{InverseError, Result};
use crate::model::Model;

/// Lee–Radok Hertz model with parameters x = (G0, g1, g2, τ1, τ2)
/// ([`names::PRONY2`]).
#[derive(Debug, Clone)]
pub struct LeeRadokHertz {
    domain: Domain,
    kernel: LeeRadok,
}

impl LeeRadokHertz {
    /// Model for a sphere of radius `radius` (m), Poisson ratio `poisson`,
    /// indentation history `indentation[j]` (m) at `times[j]` (s).
    ///
    /// # Errors
    /// [`InverseError::InvalidSetting`] if the domain's parameters are not
    /// G0, g1, g2, tau1, tau2 in this order, the grid has fewer than 2
    /// points or is not strictly increasing, lengths differ, or R ≤ 0,
    /// ν ∉ [0, 0.5].
    pub fn new(
        domain: Domain,
        times: Vec<f64>,
        indentation: &[f64],
        radius: f64,
        poisson: f64,
    ) -> Result<Self> {
        domain
            .check_names(&names::PRONY2)
            .map_err(|e| InverseError::InvalidSetting(format!("the Lee-Radok Prony model: {e}")))?;
        if times.len() < 2 {
            return Err(InverseError::InvalidSetting(format!(
                "the Lee-Radok model needs a time grid of >= 2 points, got {}",
                times.len()
            )));
        }
        let kernel = LeeRadok::sampled(radius, poisson, times, indentation)
            .map_err(|e| InverseError::InvalidSetting(e.to_string()))?;
        Ok(Self { domain, kernel })
    }

    /// G(t) of x, or [`InverseError::Model`] naming what is out of range
    /// (G0 ≤ 0, τ ≤ 0, g < 0, g1 + g2 ≥ 1, non-finite).
    fn relaxation(&self, x: &[f64]) -> Result<Relaxation> {
        self.domain.check_len(x)?;
        let bad = |message: String| InverseError::Model {
            x: x.to_vec(),
            message,
        };
        if !(x[0] > 0.0) {
            return Err(bad(format!("G0 must be positive, got {} Pa", x[0])));
        }
        Relaxation::from_named(&names::PRONY2, x).map_err(|e| bad(e.to_string()))
    }
}

impl Model for LeeRadokHertz {
    fn domain(&self) -> &Domain {
        &self.domain
    }

    fn times(&self) -> &[f64] {
        self.kernel.times()
    }

    fn response(&self, x: &[f64]) -> Result<Vec<f64>> {
        Ok(self.kernel.force(&self.relaxation(x)?))
    }

    fn jacobian(&self, x: &[f64]) -> Result<DMatrix<f64>> {
        Ok(self.response_and_jacobian(x)?.1)
    }

    /// Columns ∂F/∂(G0, g1, g2, τ1, τ2): the kernel's parameter order.
    fn response_and_jacobian(&self, x: &[f64]) -> Result<(Vec<f64>, DMatrix<f64>)> {
        let (y, columns) = self.kernel.force_and_jacobian(&self.relaxation(x)?);
        let jac = DMatrix::from_fn(y.len(), columns.len(), |j, k| columns[k][j]);
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
        let d = Domain::table_5_3(0.01).expect("domain");
        let t = ramp_hold_grid(0.2, 100, 52.0, 300, 1e-3).expect("grid");
        let delta = ramp_hold_indentation(&t, 10e-6, 2e-6);
        LeeRadokHertz::new(d, t, &delta, 2.5e-6, 0.5).expect("model")
    }

    #[test]
    fn elastic_limit_is_hertz() {
        // g1 = g2 -> 0 is outside the domain's bounds but fine for the model:
        // F = 16/3 G0 sqrt(R) delta^{3/2} for nu = 1/2 (eq. 1.1 with E = 3 G0).
        let m = model();
        let y = m.response(&[1000.0, 0.0, 0.0, 0.1, 10.0]).expect("y");
        let hertz = 16.0 / 3.0 * 1000.0 * (2.5e-6f64).sqrt() * (2e-6f64).powf(1.5);
        let last = *y.last().expect("nonempty");
        assert!((last - hertz).abs() < 1e-12 * hertz);
    }

    #[test]
    fn matches_closed_form_when_delta_to_three_halves_is_linear_in_time() {
        // eps = c t on [0, tr], then hold: exact Lee-Radok integral is
        // F = A G0 [ginf eps + sum g_k tau_k c (e^{-(t - min(t,tr))/tau_k} - e^{-t/tau_k})].
        let d = Domain::table_5_3(0.01).expect("domain");
        let t = ramp_hold_grid(0.5, 37, 30.0, 80, 1e-3).expect("grid");
        let (tr, c) = (0.5, 4e-9);
        let delta: Vec<f64> = t.iter().map(|&s| (c * s.min(tr)).powf(2.0 / 3.0)).collect();
        let m = LeeRadokHertz::new(d, t.clone(), &delta, 2.5e-6, 0.3).expect("model");
        let x = [700.0, 0.5, 0.3, 0.07, 8.0];
        let y = m.response(&x).expect("y");
        let a = 8.0 * (2.5e-6f64).sqrt() / (3.0 * 0.7);
        for (j, &tj) in t.iter().enumerate() {
            let tm = tj.min(tr);
            let term =
                |g: f64, tau: f64| g * tau * c * ((-(tj - tm) / tau).exp() - (-tj / tau).exp());
            let exact = a * x[0] * (0.2 * c * tm + term(x[1], x[3]) + term(x[2], x[4]));
            assert!(
                (y[j] - exact).abs() <= 1e-9 * exact.abs() + 1e-24,
                "t = {tj}"
            );
        }
    }

    #[test]
    fn analytic_jacobian_matches_central_differences() {
        let m = model();
        let x = [650.0, 0.45, 0.35, 0.08, 9.0];
        let j = m.jacobian(&x).expect("jac");
        let jfd = fd_jacobian(&m, &x).expect("fd");
        for k in 0..5 {
            let col_norm = jfd.column(k).norm();
            let diff = (j.column(k) - jfd.column(k)).norm();
            assert!(diff <= 1e-6 * col_norm, "column {k}: {diff} vs {col_norm}");
        }
    }
}
