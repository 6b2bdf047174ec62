//! Ch. II's three-parameter solid (eq. 2.56) and its conversion to the
//! shared Prony relaxation modulus [`nlvid_model::Relaxation`].
//!
//! Two parametrisations appear in the thesis and must not be confused:
//!
//! - ch. IV–V and App. D (eqs. 4.2–4.3, 5.1, D.3–D.4): *Prony weights* `g_k`
//!   with `G(t) = G0 [g∞ + Σ g_k exp(−t/τ_k)]`, `g∞ = 1 − Σ g_k > 0`.
//!   This is [`nlvid_model::Prony`] inside [`nlvid_model::Relaxation`] (the
//!   one Prony type of the project, `crates/model`).
//! - ch. II (eq. 2.56): one exponential with the *long-term fraction*
//!   `g_α = G_α∞ / G_α0`, `G_α(t) = G_α0 [g_α + (1 − g_α) exp(−t/τ_α)]`.
//!   This is [`ThreeParameterSolid`]; it converts to a one-term
//!   [`nlvid_model::Prony`] with weight `1 − g_α`.

use nlvid_model::{Prony, Relaxation};

use crate::{MaterialError, Result};

/// Ch. II's three-parameter solid, eq. 2.56:
/// `G(t) = G_α0 [g + (1 − g) exp(−t/τ)]` with the *long-term fraction*
/// `g = G_α∞/G_α0` (not a Prony weight).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ThreeParameterSolid {
    /// Instantaneous modulus `G_α0` in Pa (ch. II's `G10` or `G20`).
    pub g0: f64,
    /// Long-term fraction `g_α = G_α∞ / G_α0`, in (0, 1].
    pub long_term_fraction: f64,
    /// Relaxation time `τ_α` in s.
    pub tau: f64,
}

impl ThreeParameterSolid {
    /// Converts to `G_α0 [g∞ + g_1 exp(−t/τ)]` with Prony weight
    /// `g_1 = 1 − g_α` and `g∞ = g_α`; `g_α = 1` gives an elastic series.
    /// `series` names the function in errors (`"G1"`, `"G2"`).
    ///
    /// # Errors
    /// [`MaterialError::Parameter`] unless `0 < g_α ≤ 1`, `τ > 0`;
    /// [`MaterialError::Model`] unless `G_α0` is finite and ≥ 0.
    pub fn to_relaxation(&self, series: &str) -> Result<Relaxation> {
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
        Ok(Relaxation::new(series, self.g0, prony)?)
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
    fn a_long_term_fraction_of_one_is_elastic_and_out_of_range_fractions_are_named() {
        let s = ThreeParameterSolid {
            g0: 2.0,
            long_term_fraction: 1.0,
            tau: 1.0,
        };
        assert!(s.to_relaxation("G2").expect("elastic").prony().is_empty());
        let e = ThreeParameterSolid {
            long_term_fraction: 0.0,
            ..s
        }
        .to_relaxation("G2")
        .expect_err("g = 0");
        assert!(e.to_string().contains("long_term_fraction"), "{e}");
    }
}
