//! The forward-model contract: parameters (SI) → response on a fixed time
//! grid, or a typed failure. The membrane solver and the finite-element
//! models implement [`ForwardModel`]; [`HertzProny`] is a cheap analytic
//! model for tests, examples and benchmarks.

use serde::{Deserialize, Serialize};

/// Why a run produced no response.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum FailureKind {
    /// A nonlinear or time-step iteration did not converge.
    NotConverged,
    /// The parameters are outside what the model accepts.
    InvalidParameters,
    /// The model returned something unusable (NaN, wrong length, …).
    BadResponse,
    /// Anything else (I/O of an external solver, …).
    Other,
}

/// A failed run: what, when (model time, if known) and a message saying
/// what to change.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunFailure {
    /// Category.
    pub kind: FailureKind,
    /// Model time at failure [s], if the model knows it.
    pub time: Option<f64>,
    /// Human-readable reason.
    pub message: String,
}

impl std::fmt::Display for RunFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.time {
            Some(t) => write!(f, "{:?} at t = {t:e} s: {}", self.kind, self.message),
            None => write!(f, "{:?}: {}", self.kind, self.message),
        }
    }
}

impl std::error::Error for RunFailure {}

/// A forward model: one run maps parameters to the response on
/// [`ForwardModel::time_grid`].
pub trait ForwardModel: Sync {
    /// Parameter names, in the order of the parameter vector.
    fn parameter_names(&self) -> Vec<String>;
    /// SI units of the parameters (same order).
    fn parameter_units(&self) -> Vec<String>;
    /// The fixed time grid [s] of every response.
    fn time_grid(&self) -> &[f64];
    /// Index of the first time point after contact (filters look from here).
    fn contact_index(&self) -> usize {
        0
    }
    /// Identifier included in the study hash (model name and settings).
    fn identity(&self) -> String;
    /// Run at `params` (SI): the response at every time of the grid [N].
    fn run(&self, params: &[f64]) -> Result<Vec<f64>, RunFailure>;
}

/// Linear-viscoelastic Hertz indentation by a sphere, ramp then hold,
/// through the Lee–Radok integral
/// `F(t) = (16/3)√R ∫₀ᵗ G(t − s) d(δ^{3/2})/ds ds` (incompressible) with
/// a 2-term Prony shear relaxation modulus
/// `G(t) = G0 (1 − g1 − g2 + g1 e^{−t/τ1} + g2 e^{−t/τ2})`.
/// Parameters `[G0 (Pa), g1, g2, τ1 (s), τ2 (s)]` as thesis Table 5.3.
#[derive(Debug, Clone)]
pub struct HertzProny {
    /// Probe radius [m].
    pub radius: f64,
    /// Indentation rate during the ramp [m/s].
    pub rate: f64,
    /// Ramp duration [s].
    pub ramp_time: f64,
    times: Vec<f64>,
}

impl HertzProny {
    /// Probe of radius R, ramp at `rate` for `ramp_time`, then hold until
    /// `end_time`; `m` equally spaced times in (0, end_time].
    pub fn new(radius: f64, rate: f64, ramp_time: f64, end_time: f64, m: usize) -> Self {
        let times = (1..=m).map(|i| end_time * i as f64 / m as f64).collect();
        HertzProny {
            radius,
            rate,
            ramp_time,
            times,
        }
    }

    /// ∫₀^{min(t,tr)} e^{−(t−s)/τ} d(δ^{3/2})/ds ds (τ = ∞: no decay),
    /// with s = w² so that the s^{1/2} singularity disappears:
    /// = 3 v^{3/2} ∫₀^{√min(t,tr)} w² e^{−(t−w²)/τ} dw, composite
    /// 5-point Gauss–Legendre on 24 panels.
    fn hereditary(&self, t: f64, tau: f64) -> f64 {
        const X: [f64; 5] = [
            -0.906_179_845_938_664,
            -0.538_469_310_105_683,
            0.0,
            0.538_469_310_105_683,
            0.906_179_845_938_664,
        ];
        const W: [f64; 5] = [
            0.236_926_885_056_189,
            0.478_628_670_499_366,
            0.568_888_888_888_889,
            0.478_628_670_499_366,
            0.236_926_885_056_189,
        ];
        let top = t.min(self.ramp_time).sqrt();
        let panels = 24;
        let h = top / panels as f64;
        let mut sum = 0.0;
        for k in 0..panels {
            let mid = (k as f64 + 0.5) * h;
            for (x, w) in X.iter().zip(W) {
                let wv = mid + 0.5 * h * x;
                let decay = if tau.is_infinite() {
                    1.0
                } else {
                    (-(t - wv * wv) / tau).exp()
                };
                sum += w * 0.5 * h * wv * wv * decay;
            }
        }
        3.0 * self.rate.powf(1.5) * sum
    }
}

/// Names of the five cell parameters of thesis Table 5.3 in the order the
/// forward models take them: `G0, g1, g2, tau1, tau2` (eq. 5.1).
pub const PRONY2_NAMES: [&str; 5] = ["G0", "g1", "g2", "tau1", "tau2"];

/// SI units of [`PRONY2_NAMES`].
pub const PRONY2_UNITS: [&str; 5] = ["Pa", "1", "1", "s", "s"];

impl ForwardModel for HertzProny {
    fn parameter_names(&self) -> Vec<String> {
        PRONY2_NAMES.map(String::from).to_vec()
    }
    fn parameter_units(&self) -> Vec<String> {
        PRONY2_UNITS.map(String::from).to_vec()
    }
    fn time_grid(&self) -> &[f64] {
        &self.times
    }
    fn identity(&self) -> String {
        format!(
            "HertzProny(R={:e},v={:e},tr={:e},m={},tend={:e})",
            self.radius,
            self.rate,
            self.ramp_time,
            self.times.len(),
            self.times.last().copied().unwrap_or(0.0)
        )
    }
    fn run(&self, p: &[f64]) -> Result<Vec<f64>, RunFailure> {
        let bad = |message: String| RunFailure {
            kind: FailureKind::InvalidParameters,
            time: None,
            message,
        };
        let [g0, g1, g2, tau1, tau2] = p else {
            return Err(bad(format!("expected 5 parameters, got {}", p.len())));
        };
        if !(*g0 > 0.0 && *tau1 > 0.0 && *tau2 > 0.0) {
            return Err(bad(format!(
                "G0, tau1, tau2 must be > 0 (got {g0}, {tau1}, {tau2})"
            )));
        }
        let ginf = 1.0 - g1 - g2;
        if ginf < 0.0 || *g1 < 0.0 || *g2 < 0.0 {
            return Err(bad(format!(
                "need g1, g2 ≥ 0 and g1 + g2 ≤ 1 (got {g1}, {g2})"
            )));
        }
        let c = 16.0 / 3.0 * self.radius.sqrt() * g0;
        Ok(self
            .times
            .iter()
            .map(|&t| {
                c * (ginf * self.hereditary(t, f64::INFINITY)
                    + g1 * self.hereditary(t, *tau1)
                    + g2 * self.hereditary(t, *tau2))
            })
            .collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn elastic_limit_is_the_hertz_force() {
        // g1 = g2 = 0: F = (16/3) G0 √R δ^{3/2}.
        let m = HertzProny::new(5e-6, 1e-6, 1.0, 3.0, 30);
        let f = m.run(&[1000.0, 0.0, 0.0, 1.0, 1.0]).unwrap();
        for (t, fi) in m.time_grid().iter().zip(&f) {
            let delta = 1e-6 * t.min(1.0);
            let hertz = 16.0 / 3.0 * 1000.0 * (5e-6f64).sqrt() * delta.powf(1.5);
            assert!(
                (fi - hertz).abs() < 1e-12 * hertz.max(1e-30),
                "{fi} vs {hertz}"
            );
        }
    }

    #[test]
    fn single_term_hold_matches_closed_form_at_ramp_end_and_relaxes() {
        // Independent check by direct quadrature in s (midpoint, fine grid).
        let m = HertzProny::new(5e-6, 1e-6, 1.0, 4.0, 8);
        let (g0, g1, tau) = (800.0, 0.6, 0.3);
        let f = m.run(&[g0, g1, 0.0, tau, 1.0]).unwrap();
        for (t, fi) in m.time_grid().iter().zip(&f) {
            let n = 400_000;
            let top = t.min(1.0);
            let h = top / n as f64;
            let mut s = 0.0;
            for k in 0..n {
                let sv = (k as f64 + 0.5) * h;
                let g = 1.0 - g1 + g1 * (-(t - sv) / tau).exp();
                s += g * 1.5 * (1e-6f64).powf(1.5) * sv.sqrt() * h;
            }
            let reference = 16.0 / 3.0 * (5e-6f64).sqrt() * g0 * s;
            assert!(
                (fi - reference).abs() < 1e-6 * reference,
                "t={t}: {fi} vs {reference}"
            );
        }
        assert!(f[7] < f[1]);
    }

    #[test]
    fn bad_parameters_are_a_typed_failure() {
        let m = HertzProny::new(5e-6, 1e-6, 1.0, 4.0, 8);
        let e = m.run(&[800.0, 0.7, 0.6, 1.0, 2.0]).unwrap_err();
        assert_eq!(e.kind, FailureKind::InvalidParameters);
    }
}
