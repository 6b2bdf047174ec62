//! A printable table of fitted parameters, and G(t) of eq. 5.1 from a
//! fitted parameter vector as the shared [`nlvid_model::Relaxation`] (the
//! one Prony type; names matched as in `docs/theory/model.md`, so `G0` is
//! the shear modulus and a vector named `C1` is refused).

use std::fmt;

use nlvid_model::{Domain, Relaxation, names};
use serde::Serialize;

use crate::error::{InverseError, Result};

/// G(t) of eq. 5.1 from `x` over `domain`, matched by name (`G0`, `g1`,
/// `tau1`, … in any order; `nlvid_model::Relaxation::from_named`).
///
/// # Errors
/// [`InverseError::ParameterCount`] for a wrong length;
/// [`InverseError::InvalidSetting`] when the domain has no `G0` (a `C1` is
/// named as a different quantity, G0 = 2(C1 + C2)), a `g_k` without its
/// `tau_k`, or weights that leave no long-term modulus.
///
/// A capsule vector (eq. 4.1–4.3: `C1`, `alpha`, no `G0`) gives the wall's
/// shear relaxation with G0 = 2(C1 + C2) = 2 C1 (1 + α), the project's
/// vocabulary; its Prony weights are those of eq. 4.2.
pub fn relaxation(domain: &Domain, x: &[f64]) -> Result<Relaxation> {
    domain.check_len(x)?;
    let mut names: Vec<&str> = domain.params().iter().map(|p| p.name.as_str()).collect();
    let mut x = x.to_vec();
    let find = |names: &[&str], n: &str| names.iter().position(|m| *m == n);
    if let (None, Some(i), Some(j)) = (
        find(&names, names::G0),
        find(&names, names::C1),
        find(&names, names::ALPHA),
    ) {
        x[i] = 2.0 * x[i] * (1.0 + x[j]);
        names[i] = names::G0;
    }
    Relaxation::from_named(&names, &x)
        .map_err(|e| InverseError::InvalidSetting(format!("G(t) of eq. 5.1: {e}")))
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
    fn a_capsule_vector_relaxes_from_g0_equal_to_twice_c1_plus_c2() {
        let domain = Domain::table_4_1(0.01).expect("Table 4.1");
        // C1, alpha, g1, g2, tau1, tau2 (§4.4.3's RH set)
        let x = [21.2546e6, 0.372, 0.7674, 0.1546, 0.0623, 1.3936];
        let g = relaxation(&domain, &x).expect("capsule");
        let g0 = 2.0 * (21.2546e6 + 0.372 * 21.2546e6);
        assert!((g.value(0.0) / g0 - 1.0).abs() < 1e-14);
        let g_inf = g0 * (1.0 - 0.7674 - 0.1546);
        assert!((g.value(1e6) / g_inf - 1.0).abs() < 1e-12);
    }

    #[test]
    fn relaxation_follows_eq_5_1_by_name_and_young_is_three_times_it() {
        let d = Domain::table_5_3(0.01).expect("domain");
        let x = [2940.0, 0.5, 0.3, 0.1, 10.0];
        let g = relaxation(&d, &x).expect("g");
        assert!((g.value(0.0) - 2940.0).abs() < 1e-9);
        assert!((g.prony().long_term_weight() - 0.2).abs() < 1e-15);
        let t = 52.0;
        let by_hand = 2940.0 * (0.2 + 0.5 * (-520.0f64).exp() + 0.3 * (-5.2f64).exp());
        assert!((g.value(t) - by_hand).abs() < 1e-9 * by_hand);
        assert!((g.young(t) - 3.0 * by_hand).abs() < 1e-9 * by_hand);
        assert_eq!(g.curve(&[0.0, t]).len(), 2);
    }

    /// The factor-2 class of error: a domain whose modulus is named `C1`
    /// (eq. 4.1's constant, G0 = 2(C1 + C2)) is not read as G0.
    #[test]
    fn a_c1_named_vector_is_refused_as_g0() {
        use nlvid_model::{Parameter, Scale};
        let d = Domain::new(vec![
            Parameter::new("C1", "Pa", 80.0, 4000.0, Scale::Log),
            Parameter::new("g1", "", 0.0, 0.9, Scale::Linear),
            Parameter::new("tau1", "s", 0.01, 1.0, Scale::Log),
        ])
        .expect("domain");
        let e = relaxation(&d, &[500.0, 0.3, 0.5]).expect_err("C1 is not G0");
        assert!(e.to_string().contains("G0 = 2(C1 + C2)"), "{e}");
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
