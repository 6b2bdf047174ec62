//! The fitted shear relaxation modulus (eq. 5.1)
//! G(t) = G0 [g∞ + Σ_k g_k e^{−t/τ_k}], g∞ = 1 − Σ g_k (eq. 4.3),
//! and E(t) = 3 G(t) (incompressible), plus a printable parameter table.
//!
//! Here g_k are *Prony weights* (ch. IV–V), not the long-term fractions
//! g_α of ch. II (eq. 2.56) — see DESIGN.md, Traps.

use std::fmt;

use nlvid_model::Domain;
use serde::Serialize;

use crate::error::{InverseError, Result};

/// One Prony term (weight g_k, time τ_k in s).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PronyTerm {
    /// Prony weight g_k (dimensionless).
    pub weight: f64,
    /// Relaxation time τ_k (s).
    pub tau: f64,
}

/// G(t) of eq. 5.1.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PronyShear {
    /// Instantaneous shear modulus G0 = G(0) (Pa); C1 of the neo-Hookean part.
    pub g0: f64,
    /// Prony terms.
    pub terms: Vec<PronyTerm>,
}

impl PronyShear {
    /// Reads G0 (or C1) and g1, tau1, g2, tau2, … from a fitted parameter
    /// vector by name.
    ///
    /// # Errors
    /// [`InverseError::InvalidSetting`] if G0/C1 is missing, a g_k has no
    /// tau_k, or the weights sum above 1.
    pub fn from_parameters(domain: &Domain, x: &[f64]) -> Result<Self> {
        domain.check_len(x)?;
        let g0 = domain
            .index_of("G0")
            .or_else(|| domain.index_of("C1"))
            .map(|i| x[i])
            .ok_or_else(|| {
                InverseError::InvalidSetting(
                    "no parameter named G0 (or C1) for G(t) of eq. 5.1".into(),
                )
            })?;
        let mut terms = Vec::new();
        for k in 1.. {
            match (
                domain.index_of(&format!("g{k}")),
                domain.index_of(&format!("tau{k}")),
            ) {
                (Some(i), Some(j)) => terms.push(PronyTerm {
                    weight: x[i],
                    tau: x[j],
                }),
                (None, None) => break,
                _ => {
                    return Err(InverseError::InvalidSetting(format!(
                        "Prony term {k} needs both g{k} and tau{k}"
                    )));
                }
            }
        }
        let s = Self { g0, terms };
        if s.g_inf() < -1e-12 {
            return Err(InverseError::InvalidSetting(format!(
                "Prony weights sum to {} > 1: G(t) would become negative",
                1.0 - s.g_inf()
            )));
        }
        Ok(s)
    }

    /// Long-term weight g∞ = 1 − Σ g_k (eq. 4.3).
    pub fn g_inf(&self) -> f64 {
        1.0 - self.terms.iter().map(|t| t.weight).sum::<f64>()
    }

    /// G(t) (Pa), eq. 5.1.
    pub fn shear(&self, t: f64) -> f64 {
        self.g0
            * (self.g_inf()
                + self
                    .terms
                    .iter()
                    .map(|p| p.weight * (-t / p.tau).exp())
                    .sum::<f64>())
    }

    /// E(t) = 3 G(t) (Pa), incompressible material.
    pub fn young(&self, t: f64) -> f64 {
        3.0 * self.shear(t)
    }

    /// (t, G(t), E(t)) on a grid.
    pub fn curve(&self, times: &[f64]) -> Vec<ModulusPoint> {
        times
            .iter()
            .map(|&t| ModulusPoint {
                time: t,
                shear: self.shear(t),
                young: self.young(t),
            })
            .collect()
    }
}

/// One point of the relaxation-modulus curve.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ModulusPoint {
    /// t (s).
    pub time: f64,
    /// G(t) (Pa).
    pub shear: f64,
    /// E(t) = 3G(t) (Pa).
    pub young: f64,
}

/// Parameter values with names and units, printable as a table.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ParameterTable {
    /// (name, value SI, unit).
    pub rows: Vec<(String, f64, String)>,
}

impl ParameterTable {
    /// Pairs values with the domain's names and units.
    ///
    /// # Errors
    /// [`InverseError::Vocabulary`] (wrong length).
    pub fn new(domain: &Domain, x: &[f64]) -> Result<Self> {
        domain.check_len(x)?;
        Ok(Self {
            rows: domain
                .params()
                .iter()
                .zip(x)
                .map(|(p, &v)| (p.name.clone(), v, p.unit.clone()))
                .collect(),
        })
    }
}

impl fmt::Display for ParameterTable {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (name, value, unit) in &self.rows {
            if unit.is_empty() || unit == "1" {
                writeln!(f, "{name:>8} = {value:.6e}")?;
            } else {
                writeln!(f, "{name:>8} = {value:.6e} {unit}")?;
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shear_modulus_follows_eq_5_1_and_young_is_three_times_it() {
        let d = Domain::table_5_3(0.01).expect("domain");
        let x = [2940.0, 0.5, 0.3, 0.1, 10.0];
        let g = PronyShear::from_parameters(&d, &x).expect("g");
        assert!((g.shear(0.0) - 2940.0).abs() < 1e-9);
        assert!((g.g_inf() - 0.2).abs() < 1e-15);
        let t = 52.0;
        let by_hand = 2940.0 * (0.2 + 0.5 * (-520.0f64).exp() + 0.3 * (-5.2f64).exp());
        assert!((g.shear(t) - by_hand).abs() < 1e-9 * by_hand);
        assert!((g.young(t) - 3.0 * by_hand).abs() < 1e-9 * by_hand);
        assert_eq!(g.curve(&[0.0, t]).len(), 2);
    }

    #[test]
    fn parameter_table_prints_names_and_units() {
        let d = Domain::table_5_3(0.01).expect("domain");
        let s = ParameterTable::new(&d, &[2940.0, 0.5, 0.3, 0.1, 10.0])
            .expect("t")
            .to_string();
        assert!(s.contains("G0 = 2.940000e3 Pa"), "{s}");
        assert!(s.contains("tau2 = 1.000000e1 s"), "{s}");
        assert!(s.contains("g1 = 5.000000e-1\n"), "{s}");
    }
}
