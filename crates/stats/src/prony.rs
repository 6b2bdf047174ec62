//! Shear relaxation modulus from Prony parameters (eq. 5.1):
//! `G(t) = G0 [g∞ + Σ_k g_k e^{−t/τ_k}]`, `g∞ = 1 − Σ_k g_k`.
//!
//! Here `g_k` are Prony *weights* (ch. IV–V convention), not the long-term
//! fractions of ch. II. `E(t) = 3 G(t)` assumes incompressibility (§5.4.2).

use crate::{Result, StatsError};

/// One Prony term: weight `g` and relaxation time `tau` (s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PronyTerm {
    /// Weight g_k (dimensionless, ≥ 0).
    pub g: f64,
    /// Relaxation time τ_k, s (> 0).
    pub tau: f64,
}

/// A shear relaxation modulus, eq. 5.1.
#[derive(Debug, Clone, PartialEq)]
pub struct Prony {
    g0: f64,
    terms: Vec<PronyTerm>,
}

impl Prony {
    /// `G0` in Pa and the terms.
    ///
    /// # Errors
    /// `G0` not finite and > 0, a weight < 0 or not finite, a τ not finite
    /// and > 0, or Σ g_k > 1 (negative long-term modulus).
    pub fn new(g0: f64, terms: Vec<PronyTerm>) -> Result<Self> {
        if !(g0.is_finite() && g0 > 0.0) {
            return Err(StatsError::Prony(format!(
                "G0 = {g0} Pa must be finite and > 0"
            )));
        }
        for (k, t) in terms.iter().enumerate() {
            if !(t.g.is_finite() && t.g >= 0.0) {
                return Err(StatsError::Prony(format!(
                    "g{} = {} must be ≥ 0",
                    k + 1,
                    t.g
                )));
            }
            if !(t.tau.is_finite() && t.tau > 0.0) {
                return Err(StatsError::Prony(format!(
                    "tau{} = {} s must be > 0",
                    k + 1,
                    t.tau
                )));
            }
        }
        let sum: f64 = terms.iter().map(|t| t.g).sum();
        if sum > 1.0 {
            return Err(StatsError::Prony(format!(
                "weights sum to {sum} > 1, so g_inf = 1 − Σg < 0"
            )));
        }
        Ok(Self { g0, terms })
    }

    /// Instantaneous shear modulus G(0) = G0, Pa.
    pub fn g0(&self) -> f64 {
        self.g0
    }

    /// The terms.
    pub fn terms(&self) -> &[PronyTerm] {
        &self.terms
    }

    /// Long-term fraction g∞ = 1 − Σ g_k.
    pub fn g_inf(&self) -> f64 {
        1.0 - self.terms.iter().map(|t| t.g).sum::<f64>()
    }

    /// Normalised modulus G(t)/G(0) = g∞ + Σ g_k e^{−t/τ_k}.
    pub fn normalised(&self, t: f64) -> f64 {
        self.g_inf()
            + self
                .terms
                .iter()
                .map(|k| k.g * (-t / k.tau).exp())
                .sum::<f64>()
    }

    /// Shear relaxation modulus G(t), Pa (eq. 5.1).
    pub fn shear(&self, t: f64) -> f64 {
        self.g0 * self.normalised(t)
    }

    /// Young's relaxation modulus E(t) = 3 G(t), Pa (incompressible).
    pub fn young(&self, t: f64) -> f64 {
        3.0 * self.shear(t)
    }

    /// Amount of relaxation at `t`, 1 − G(t)/G(0) (Figs. 5.15, 5.17).
    pub fn relaxation(&self, t: f64) -> f64 {
        1.0 - self.normalised(t)
    }
}
