//! The Prony relaxation modulus (eqs. 4.2–4.3, 5.1):
//! `G(t) = G0 [g∞ + Σ_k g_k e^{−t/τ_k}]`, `g∞ = 1 − Σ_k g_k`.
//!
//! The `g_k` here are Prony *weights* (ch. IV–V). Ch. II's *long-term
//! fraction* g_α = G_α∞/G_α0 of eq. 2.56 is another quantity; a one-term
//! series with weight `1 − g_α` expresses it (`nlvid_material`'s
//! `ThreeParameterSolid`).

use serde::{Deserialize, Serialize};

use crate::error::{ModelError, Result};
use crate::names;

/// One term `g_k e^{−t/τ_k}` of a normalised Prony series.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PronyTerm {
    /// Prony weight g_k (dimensionless, ≥ 0).
    pub weight: f64,
    /// Relaxation time τ_k (s, > 0).
    pub tau: f64,
}

/// A normalised Prony series `g(t) = g∞ + Σ g_k e^{−t/τ_k}`, `g(0) = 1`
/// (eqs. 4.2–4.3). Weights are ≥ 0 and sum to less than 1, so the
/// long-term weight g∞ is positive (a solid).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(try_from = "Vec<PronyTerm>", into = "Vec<PronyTerm>")]
pub struct Prony {
    terms: Vec<PronyTerm>,
}

impl TryFrom<Vec<PronyTerm>> for Prony {
    type Error = ModelError;
    fn try_from(terms: Vec<PronyTerm>) -> Result<Self> {
        let pairs: Vec<(f64, f64)> = terms.iter().map(|t| (t.weight, t.tau)).collect();
        Self::new("G", &pairs)
    }
}

impl From<Prony> for Vec<PronyTerm> {
    fn from(p: Prony) -> Self {
        p.terms
    }
}

impl Prony {
    /// No relaxation (`g(t) ≡ 1`): an elastic material.
    pub fn elastic() -> Self {
        Self { terms: Vec::new() }
    }

    /// A series from `(g_k, τ_k)` pairs, checking `g_k ≥ 0`, `τ_k > 0` (both
    /// finite) and `g∞ = 1 − Σ g_k > 0` (eq. 4.3). A zero weight is kept (an
    /// inert term) so that term k stays term k.
    ///
    /// # Errors
    /// [`ModelError::PronyTerm`] naming the series and the 1-based term.
    pub fn new(series: &str, terms: &[(f64, f64)]) -> Result<Self> {
        let mut sum = 0.0;
        let mut out = Vec::with_capacity(terms.len());
        for (i, &(weight, tau)) in terms.iter().enumerate() {
            let bad = |reason: String| ModelError::PronyTerm {
                series: series.to_string(),
                index: i + 1,
                reason,
            };
            if !(weight.is_finite() && weight >= 0.0) {
                return Err(bad(format!("weight g = {weight} must be finite and ≥ 0")));
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

    /// The terms, in order.
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

    /// `g(t) = g∞ + Σ g_k e^{−t/τ_k}`; `g(0) = 1`.
    pub fn value(&self, t: f64) -> f64 {
        self.long_term_weight()
            + self
                .terms
                .iter()
                .map(|k| k.weight * (-t / k.tau).exp())
                .sum::<f64>()
    }

    /// `dg/dt = −Σ (g_k/τ_k) e^{−t/τ_k}` (1/s).
    pub fn derivative(&self, t: f64) -> f64 {
        -self
            .terms
            .iter()
            .map(|k| k.weight / k.tau * (-t / k.tau).exp())
            .sum::<f64>()
    }
}

/// A relaxation modulus `G(t) = G0 · g(t)` (eqs. 4.2, 5.1). With
/// `g0` = [`names::G0`] it is the shear relaxation modulus of a cell; the
/// material crate also uses it for ch. II's G1(t), G2(t).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Relaxation {
    g0: f64,
    prony: Prony,
}

impl Relaxation {
    /// `G(t) = g0 · prony(t)`; `name` is used in errors (e.g. `"G0"`).
    ///
    /// # Errors
    /// [`ModelError::Parameter`] unless `g0` is finite and ≥ 0.
    pub fn new(name: &str, g0: f64, prony: Prony) -> Result<Self> {
        if !(g0.is_finite() && g0 >= 0.0) {
            return Err(ModelError::Parameter {
                name: name.to_string(),
                value: g0,
                reason: "an instantaneous modulus must be finite and ≥ 0 (Pa)".into(),
            });
        }
        Ok(Self { g0, prony })
    }

    /// The shear relaxation modulus of eq. 5.1 from a named parameter
    /// vector: `G0` and the pairs `g1, tau1`, `g2, tau2`, … (any order).
    /// Other names (geometry, α, …) are ignored.
    ///
    /// # Errors
    /// No `G0` (naming `C1` when it is there: G0 = 2(C1 + C2) is a
    /// different quantity), a `gk` without its `tauk`, names and values of
    /// different lengths, or values out of range.
    pub fn from_named(names: &[impl AsRef<str>], x: &[f64]) -> Result<Self> {
        if names.len() != x.len() {
            return Err(ModelError::ParameterCount {
                expected: names.len(),
                names: names
                    .iter()
                    .map(AsRef::as_ref)
                    .collect::<Vec<_>>()
                    .join(", "),
                got: x.len(),
            });
        }
        let find = |wanted: &str| names.iter().position(|n| n.as_ref() == wanted);
        let Some(i0) = find(names::G0) else {
            let hint = if find(names::C1).is_some() {
                "; C1 is the Mooney–Rivlin constant of eq. 4.1, and the shear modulus is G0 = 2(C1 + C2)"
            } else {
                ""
            };
            return Err(ModelError::Parameter {
                name: names::G0.into(),
                value: f64::NAN,
                reason: format!("missing: G(t) of eq. 5.1 needs the shear modulus G0{hint}"),
            });
        };
        let mut pairs = Vec::new();
        for k in 1.. {
            match (find(&names::weight(k)), find(&names::time(k))) {
                (Some(i), Some(j)) => pairs.push((x[i], x[j])),
                (None, None) => break,
                _ => {
                    return Err(ModelError::Parameter {
                        name: names::weight(k),
                        value: f64::NAN,
                        reason: format!("Prony term {k} needs both g{k} and tau{k}"),
                    });
                }
            }
        }
        Self::new(names::G0, x[i0], Prony::new("G", &pairs)?)
    }

    /// Instantaneous value `G(0)` (Pa).
    pub fn g0(&self) -> f64 {
        self.g0
    }

    /// Long-term value `G(∞) = G0 g∞` (Pa).
    pub fn g_inf(&self) -> f64 {
        self.g0 * self.prony.long_term_weight()
    }

    /// The normalised series.
    pub fn prony(&self) -> &Prony {
        &self.prony
    }

    /// `G(t)` (Pa), eq. 5.1.
    pub fn value(&self, t: f64) -> f64 {
        self.g0 * self.prony.value(t)
    }

    /// `dG/dt` (Pa/s).
    pub fn derivative(&self, t: f64) -> f64 {
        self.g0 * self.prony.derivative(t)
    }

    /// Young's relaxation modulus `E(t) = 3 G(t)` of an incompressible
    /// material (Pa).
    pub fn young(&self, t: f64) -> f64 {
        3.0 * self.value(t)
    }

    /// The same series scaled by `factor` (`G → factor·G`).
    pub fn scaled(&self, factor: f64) -> Self {
        Self {
            g0: self.g0 * factor,
            prony: self.prony.clone(),
        }
    }

    /// `(t, G(t), E(t))` at each time.
    pub fn curve(&self, times: &[f64]) -> Vec<ModulusPoint> {
        times
            .iter()
            .map(|&t| ModulusPoint {
                time: t,
                shear: self.value(t),
                young: self.young(t),
            })
            .collect()
    }
}

/// One point of a relaxation-modulus curve.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ModulusPoint {
    /// t (s).
    pub time: f64,
    /// G(t) (Pa).
    pub shear: f64,
    /// E(t) = 3 G(t) (Pa).
    pub young: f64,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eq_5_1_by_hand() {
        let g =
            Relaxation::from_named(&names::PRONY2, &[1000.0, 0.3, 0.2, 0.5, 10.0]).expect("valid");
        for t in [0.0, 0.1, 1.0, 52.0] {
            let by_hand = 1000.0 * (0.5 + 0.3 * (-t / 0.5f64).exp() + 0.2 * (-t / 10.0f64).exp());
            assert!((g.value(t) - by_hand).abs() <= 1e-12 * by_hand, "t = {t}");
            assert_eq!(g.young(t), 3.0 * g.value(t));
        }
        assert_eq!(g.value(0.0), 1000.0);
        assert!((g.g_inf() - 500.0).abs() < 1e-12);
    }

    #[test]
    fn derivative_matches_central_differences() {
        let g = Relaxation::new(
            "G0",
            700.0,
            Prony::new("G", &[(0.4, 0.3), (0.1, 4.0)]).unwrap(),
        )
        .unwrap();
        for t in [0.01, 0.5, 3.0] {
            let h = 1e-6;
            let fd = (g.value(t + h) - g.value(t - h)) / (2.0 * h);
            assert!((fd - g.derivative(t)).abs() <= 1e-6 * fd.abs(), "t = {t}");
        }
    }

    #[test]
    fn named_parameters_in_any_order_and_c1_is_not_g0() {
        let a = Relaxation::from_named(&["tau1", "g1", "G0", "H"], &[0.5, 0.3, 900.0, 1e-5])
            .expect("order does not matter");
        assert_eq!(a.g0(), 900.0);
        assert_eq!(
            a.prony().terms(),
            &[PronyTerm {
                weight: 0.3,
                tau: 0.5
            }]
        );
        let e = Relaxation::from_named(&["C1", "g1", "tau1"], &[450.0, 0.3, 0.5])
            .expect_err("C1 is not G0");
        assert!(e.to_string().contains("G0 = 2(C1 + C2)"), "{e}");
        let e = Relaxation::from_named(&["G0", "g1"], &[450.0, 0.3]).expect_err("no tau1");
        assert!(e.to_string().contains("tau1"), "{e}");
    }

    #[test]
    fn weights_summing_to_one_are_rejected_with_the_term() {
        let e = Prony::new("G", &[(0.5, 1.0), (0.5, 2.0)]).expect_err("g_inf = 0");
        assert!(e.to_string().contains("term 2"), "{e}");
        let e = Prony::new("G2", &[(0.2, -1.0)]).expect_err("negative tau");
        assert!(e.to_string().contains("tau = -1"), "{e}");
        assert!(
            Prony::new("G", &[(0.0, 1.0)]).is_ok(),
            "a zero weight is an inert term"
        );
    }

    #[test]
    fn serde_round_trip_validates() {
        let p = Prony::new("G", &[(0.3, 0.5)]).unwrap();
        let text = serde_json::to_string(&p).unwrap();
        assert_eq!(serde_json::from_str::<Prony>(&text).unwrap(), p);
        assert!(
            serde_json::from_str::<Prony>(r#"[{"weight":0.7,"tau":1},{"weight":0.4,"tau":2}]"#)
                .is_err()
        );
    }
}
