//! Prony series relaxation functions.
//!
//! Two parametrisations appear in the thesis and must not be confused
//! (DESIGN.md, "Traps"):
//!
//! - ch. IV–V and App. D (eqs. 4.2–4.3, 5.1, D.3–D.4): *Prony weights* `g_k`
//!   with `G(t) = G0 [g∞ + Σ g_k exp(−t/τ_k)]`, `g∞ = 1 − Σ g_k > 0`.
//!   This is [`Prony`] (weights) inside [`Relaxation`] (with `G0`).
//! - ch. II (eq. 2.56): one exponential with the *long-term fraction*
//!   `g_α = G_α∞ / G_α0`, `G_α(t) = G_α0 [g_α + (1 − g_α) exp(−t/τ_α)]`.
//!   This is [`ThreeParameterSolid`]; it converts to a one-term [`Prony`]
//!   with weight `1 − g_α`.

use crate::{MaterialError, Result};

/// One term `g_k exp(−t/τ_k)` of a normalised Prony series.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PronyTerm {
    /// Prony weight `g_k` (dimensionless, > 0).
    pub weight: f64,
    /// Relaxation time `τ_k` in s (> 0).
    pub tau: f64,
}

/// A normalised Prony series `g(t) = g∞ + Σ g_k exp(−t/τ_k)` with `g(0) = 1`
/// (eqs. 4.2–4.3, D.3–D.4).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Prony {
    terms: Vec<PronyTerm>,
}

impl Prony {
    /// A series with no relaxation (`g(t) ≡ 1`): a purely elastic material.
    pub fn elastic() -> Self {
        Self { terms: Vec::new() }
    }

    /// Builds a series from `(g_k, τ_k)` pairs, checking `g_k > 0`, `τ_k > 0`
    /// (finite) and `g∞ = 1 − Σ g_k > 0` (eq. 4.3).
    ///
    /// # Errors
    /// [`MaterialError::PronyTerm`] naming the series and the 1-based term.
    pub fn new(series: &'static str, terms: &[(f64, f64)]) -> Result<Self> {
        let mut sum = 0.0;
        let mut out = Vec::with_capacity(terms.len());
        for (i, &(weight, tau)) in terms.iter().enumerate() {
            let bad = |reason: String| MaterialError::PronyTerm {
                series,
                index: i + 1,
                reason,
            };
            if !(weight.is_finite() && weight > 0.0) {
                return Err(bad(format!("weight g = {weight} must be finite and > 0")));
            }
            if !(tau.is_finite() && tau > 0.0) {
                return Err(bad(format!(
                    "relaxation time tau = {tau} s must be finite and > 0"
                )));
            }
            sum += weight;
            if sum >= 1.0 {
                return Err(bad(format!(
                    "weights sum to {sum} ≥ 1 up to this term; the long-term weight \
                     g_inf = 1 − Σ g_k must stay > 0 (eq. 4.3)"
                )));
            }
            out.push(PronyTerm { weight, tau });
        }
        Ok(Self { terms: out })
    }

    /// The terms.
    pub fn terms(&self) -> &[PronyTerm] {
        &self.terms
    }

    /// Number of exponential terms.
    pub fn len(&self) -> usize {
        self.terms.len()
    }

    /// True when the series has no exponential term (elastic).
    pub fn is_empty(&self) -> bool {
        self.terms.is_empty()
    }

    /// Long-term weight `g∞ = 1 − Σ g_k` (eq. 4.3).
    pub fn long_term_weight(&self) -> f64 {
        1.0 - self.terms.iter().map(|t| t.weight).sum::<f64>()
    }

    /// `g(t) = g∞ + Σ g_k exp(−t/τ_k)`, so `g(0) = 1`.
    pub fn value(&self, t: f64) -> f64 {
        self.long_term_weight()
            + self
                .terms
                .iter()
                .map(|k| k.weight * (-t / k.tau).exp())
                .sum::<f64>()
    }

    /// `dg/dt = −Σ (g_k/τ_k) exp(−t/τ_k)`.
    pub fn derivative(&self, t: f64) -> f64 {
        -self
            .terms
            .iter()
            .map(|k| k.weight / k.tau * (-t / k.tau).exp())
            .sum::<f64>()
    }
}

/// A relaxation modulus `G(t) = G0 · g(t)` with a normalised Prony series
/// (eqs. 4.2, 5.1, D.3–D.4).
#[derive(Debug, Clone, PartialEq)]
pub struct Relaxation {
    g0: f64,
    prony: Prony,
}

impl Relaxation {
    /// `G(t) = g0 · prony(t)`; `name` is used in errors (e.g. `"G10"`).
    ///
    /// # Errors
    /// [`MaterialError::Parameter`] unless `g0` is finite and ≥ 0.
    pub fn new(name: &'static str, g0: f64, prony: Prony) -> Result<Self> {
        if !(g0.is_finite() && g0 >= 0.0) {
            return Err(MaterialError::Parameter {
                name,
                value: g0,
                reason: "an instantaneous modulus must be finite and ≥ 0 (Pa)",
            });
        }
        Ok(Self { g0, prony })
    }

    /// Instantaneous value `G(0)` in Pa.
    pub fn g0(&self) -> f64 {
        self.g0
    }

    /// Long-term value `G(∞) = G0 g∞` in Pa.
    pub fn g_inf(&self) -> f64 {
        self.g0 * self.prony.long_term_weight()
    }

    /// The normalised series.
    pub fn prony(&self) -> &Prony {
        &self.prony
    }

    /// `G(t)` in Pa.
    pub fn value(&self, t: f64) -> f64 {
        self.g0 * self.prony.value(t)
    }

    /// `dG/dt` in Pa/s.
    pub fn derivative(&self, t: f64) -> f64 {
        self.g0 * self.prony.derivative(t)
    }

    /// The same series scaled by `factor` (`G → factor·G`).
    pub fn scaled(&self, factor: f64) -> Self {
        Self {
            g0: self.g0 * factor,
            prony: self.prony.clone(),
        }
    }
}

/// Ch. II's three-parameter solid, eq. 2.56:
/// `G(t) = G0 [g + (1 − g) exp(−t/τ)]` with the *long-term fraction*
/// `g = G∞/G0` (not a Prony weight).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ThreeParameterSolid {
    /// Instantaneous modulus `G_α0` in Pa.
    pub g0: f64,
    /// Long-term fraction `g_α = G_α∞ / G_α0`, in (0, 1].
    pub long_term_fraction: f64,
    /// Relaxation time `τ_α` in s.
    pub tau: f64,
}

impl ThreeParameterSolid {
    /// Converts to `G0 [g∞ + g_1 exp(−t/τ)]` with Prony weight
    /// `g_1 = 1 − g_α` and `g∞ = g_α`; `g_α = 1` gives an elastic series.
    ///
    /// # Errors
    /// [`MaterialError::Parameter`] unless `0 < g_α ≤ 1`, `τ > 0`, `G0 ≥ 0`.
    pub fn to_relaxation(&self, series: &'static str) -> Result<Relaxation> {
        let g = self.long_term_fraction;
        if !(g.is_finite() && g > 0.0 && g <= 1.0) {
            return Err(MaterialError::Parameter {
                name: "long_term_fraction",
                value: g,
                reason: "g_alpha = G_inf/G_0 of eq. 2.56 must lie in (0, 1]",
            });
        }
        if !(self.tau.is_finite() && self.tau > 0.0) {
            return Err(MaterialError::Parameter {
                name: "tau",
                value: self.tau,
                reason: "a relaxation time must be finite and > 0 (s)",
            });
        }
        let prony = if g == 1.0 {
            Prony::elastic()
        } else {
            Prony::new(series, &[(1.0 - g, self.tau)])?
        };
        Relaxation::new(series, self.g0, prony)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eq_2_56_form_equals_prony_form_at_all_times() {
        let s = ThreeParameterSolid {
            g0: 3.0,
            long_term_fraction: 0.3,
            tau: 2.0,
        };
        let r = s.to_relaxation("G1").expect("valid");
        for &t in &[0.0, 0.1, 1.0, 5.0, 100.0] {
            let direct = 3.0 * (0.3 + 0.7 * (-t / 2.0f64).exp());
            assert!((r.value(t) - direct).abs() < 1e-14 * direct);
        }
        assert!((r.g_inf() - 0.9).abs() < 1e-15);
    }

    #[test]
    fn weights_summing_to_one_are_rejected_with_term_index() {
        let e = Prony::new("G", &[(0.5, 1.0), (0.5, 2.0)]).expect_err("g_inf = 0");
        let msg = e.to_string();
        assert!(msg.contains("`G`") && msg.contains("term 2"), "{msg}");
        let e = Prony::new("G2", &[(0.2, -1.0)]).expect_err("negative tau");
        assert!(e.to_string().contains("tau = -1"), "{e}");
    }
}
