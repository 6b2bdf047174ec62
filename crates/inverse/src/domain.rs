//! The bounded parameter domain of a fit (Table 5.3, Table A.2): named
//! parameters with SI units and bounds, linear or logarithmic scaling, and
//! linear inequality constraints such as g1 + g2 ≤ 1 − ε (§5.4.1).
//!
//! The optimiser works in *scaled* coordinates u ∈ [0, 1]ⁿ:
//! u = (x − lo)/(hi − lo) for linear parameters and
//! u = ln(x/lo)/ln(hi/lo) for log-scaled ones. Distances between optima,
//! bound flags and Latin-hypercube starts are all measured in u.

use serde::Serialize;

use crate::error::{InverseError, Result};

/// How a parameter is mapped to the optimiser's unit interval.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Scale {
    /// u = (x − lo)/(hi − lo).
    Linear,
    /// u = ln(x/lo)/ln(hi/lo); for parameters spanning decades (moduli,
    /// relaxation times). Needs lo > 0.
    Log,
}

/// One named, unit-carrying, bounded parameter (SI values).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Parameter {
    /// Name as printed ("G0", "tau1").
    pub name: String,
    /// SI unit as printed ("Pa", "s", "" for dimensionless).
    pub unit: String,
    /// Lower bound (SI).
    pub lower: f64,
    /// Upper bound (SI).
    pub upper: f64,
    /// Mapping to the unit interval.
    pub scale: Scale,
}

impl Parameter {
    /// A parameter; checked when the [`Domain`] is built.
    pub fn new(name: &str, unit: &str, lower: f64, upper: f64, scale: Scale) -> Self {
        Self {
            name: name.to_string(),
            unit: unit.to_string(),
            lower,
            upper,
            scale,
        }
    }

    /// Scaled coordinate u of a physical value x.
    pub fn to_unit(&self, x: f64) -> f64 {
        match self.scale {
            Scale::Linear => (x - self.lower) / (self.upper - self.lower),
            Scale::Log => (x / self.lower).ln() / (self.upper / self.lower).ln(),
        }
    }

    /// Physical value x of a scaled coordinate u.
    pub fn from_unit(&self, u: f64) -> f64 {
        match self.scale {
            Scale::Linear => self.lower + u * (self.upper - self.lower),
            Scale::Log => self.lower * ((self.upper / self.lower).ln() * u).exp(),
        }
    }

    /// dx/du at u (chain rule for gradients in scaled coordinates).
    pub fn dx_du(&self, u: f64) -> f64 {
        match self.scale {
            Scale::Linear => self.upper - self.lower,
            Scale::Log => self.from_unit(u) * (self.upper / self.lower).ln(),
        }
    }
}

/// Linear inequality constraint Σ aᵢ xᵢ ≤ b on the physical parameters.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LinearConstraint {
    /// Coefficients aᵢ, one per parameter.
    pub coefficients: Vec<f64>,
    /// Right-hand side b.
    pub rhs: f64,
    /// Human-readable form, e.g. "g1 + g2 <= 0.99".
    pub label: String,
}

impl LinearConstraint {
    /// Σ aᵢ xᵢ − b (≤ 0 when satisfied).
    pub fn value(&self, x: &[f64]) -> f64 {
        self.coefficients
            .iter()
            .zip(x)
            .map(|(a, xi)| a * xi)
            .sum::<f64>()
            - self.rhs
    }
}

/// A bounded parameter domain with linear constraints.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Domain {
    params: Vec<Parameter>,
    constraints: Vec<LinearConstraint>,
}

impl Domain {
    /// Builds a domain, rejecting empty, inverted or non-finite bounds and
    /// log scales with a non-positive lower bound.
    ///
    /// # Errors
    /// [`InverseError::InvalidSetting`] naming the offending parameter.
    pub fn new(params: Vec<Parameter>) -> Result<Self> {
        if params.is_empty() {
            return Err(InverseError::InvalidSetting(
                "a domain needs at least one parameter".into(),
            ));
        }
        for p in &params {
            if !(p.lower.is_finite() && p.upper.is_finite() && p.lower < p.upper) {
                return Err(InverseError::InvalidSetting(format!(
                    "parameter '{}': bounds [{}, {}] must be finite with lower < upper",
                    p.name, p.lower, p.upper
                )));
            }
            if p.scale == Scale::Log && p.lower <= 0.0 {
                return Err(InverseError::InvalidSetting(format!(
                    "parameter '{}': log scale needs a positive lower bound, got {}",
                    p.name, p.lower
                )));
            }
        }
        Ok(Self {
            params,
            constraints: Vec::new(),
        })
    }

    /// Adds the constraint Σ_{names} x ≤ rhs (e.g. g1 + g2 ≤ 1 − ε).
    ///
    /// # Errors
    /// [`InverseError::InvalidSetting`] if a name is unknown.
    pub fn with_sum_constraint(mut self, names: &[&str], rhs: f64) -> Result<Self> {
        let mut coefficients = vec![0.0; self.params.len()];
        for name in names {
            let i = self.index_of(name).ok_or_else(|| {
                InverseError::InvalidSetting(format!(
                    "constraint refers to unknown parameter '{name}'"
                ))
            })?;
            coefficients[i] = 1.0;
        }
        let label = format!("{} <= {}", names.join(" + "), rhs);
        self.constraints.push(LinearConstraint {
            coefficients,
            rhs,
            label,
        });
        Ok(self)
    }

    /// The five-parameter Prony domain of Table 5.3 (breast-cancer cells):
    /// G0 ∈ [80, 4000] Pa (log), g1 ∈ [0.01, 1], τ1 ∈ [0.01, 2] s (log),
    /// g2 ∈ [0.01, 1], τ2 ∈ [2, 40] s (log), with g1 + g2 ≤ 1 − ε.
    ///
    /// # Errors
    /// [`InverseError::InvalidSetting`] if ε is not in [0, 0.98).
    pub fn prony2_table_5_3(eps: f64) -> Result<Self> {
        if !(0.0..0.98).contains(&eps) {
            return Err(InverseError::InvalidSetting(format!(
                "epsilon of g1 + g2 <= 1 - epsilon must be in [0, 0.98), got {eps}"
            )));
        }
        Self::new(vec![
            Parameter::new("G0", "Pa", 80.0, 4000.0, Scale::Log),
            Parameter::new("g1", "", 0.01, 1.0, Scale::Linear),
            Parameter::new("tau1", "s", 0.01, 2.0, Scale::Log),
            Parameter::new("g2", "", 0.01, 1.0, Scale::Linear),
            Parameter::new("tau2", "s", 2.0, 40.0, Scale::Log),
        ])?
        .with_sum_constraint(&["g1", "g2"], 1.0 - eps)
    }

    /// Number of parameters.
    pub fn len(&self) -> usize {
        self.params.len()
    }

    /// Always false (a domain has ≥ 1 parameter); for clippy's `len` rule.
    pub fn is_empty(&self) -> bool {
        self.params.is_empty()
    }

    /// The parameters.
    pub fn params(&self) -> &[Parameter] {
        &self.params
    }

    /// The linear constraints.
    pub fn constraints(&self) -> &[LinearConstraint] {
        &self.constraints
    }

    /// Index of a parameter by name.
    pub fn index_of(&self, name: &str) -> Option<usize> {
        self.params.iter().position(|p| p.name == name)
    }

    /// Checks the length of a parameter vector.
    ///
    /// # Errors
    /// [`InverseError::ParameterCount`].
    pub fn check_len(&self, x: &[f64]) -> Result<()> {
        if x.len() == self.params.len() {
            Ok(())
        } else {
            Err(InverseError::ParameterCount {
                expected: self.params.len(),
                got: x.len(),
            })
        }
    }

    /// Physical → scaled coordinates.
    pub fn to_unit(&self, x: &[f64]) -> Vec<f64> {
        self.params
            .iter()
            .zip(x)
            .map(|(p, &v)| p.to_unit(v))
            .collect()
    }

    /// Scaled → physical coordinates.
    pub fn from_unit(&self, u: &[f64]) -> Vec<f64> {
        self.params
            .iter()
            .zip(u)
            .map(|(p, &v)| p.from_unit(v))
            .collect()
    }

    /// True when x is inside the bounds (with relative slack `tol` of each
    /// range) and satisfies every constraint within `tol`.
    pub fn contains(&self, x: &[f64], tol: f64) -> bool {
        x.len() == self.params.len()
            && self.params.iter().zip(x).all(|(p, &v)| {
                let slack = tol * (p.upper - p.lower);
                v >= p.lower - slack && v <= p.upper + slack
            })
            && self.constraints.iter().all(|c| c.value(x) <= tol)
    }

    /// Names of the parameters whose scaled coordinate lies within `tol` of
    /// 0 or 1, with which side ("lower"/"upper").
    pub fn on_bounds(&self, x: &[f64], tol: f64) -> Vec<BoundHit> {
        let mut hits = Vec::new();
        for (p, &v) in self.params.iter().zip(x) {
            let u = p.to_unit(v);
            if u <= tol {
                hits.push(BoundHit {
                    name: p.name.clone(),
                    side: BoundSide::Lower,
                });
            } else if u >= 1.0 - tol {
                hits.push(BoundHit {
                    name: p.name.clone(),
                    side: BoundSide::Upper,
                });
            }
        }
        hits
    }

    /// Labels of the constraints active at x (|value| ≤ tol).
    pub fn active_constraints(&self, x: &[f64], tol: f64) -> Vec<String> {
        self.constraints
            .iter()
            .filter(|c| c.value(x).abs() <= tol)
            .map(|c| c.label.clone())
            .collect()
    }
}

/// Which side of a parameter range.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum BoundSide {
    /// At the lower bound.
    Lower,
    /// At the upper bound.
    Upper,
}

/// A parameter found on a bound of the domain (the domain should be widened).
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct BoundHit {
    /// Parameter name.
    pub name: String,
    /// Side.
    pub side: BoundSide,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unit_mapping_round_trips_for_linear_and_log_parameters() {
        let d = Domain::prony2_table_5_3(0.01).expect("domain");
        let x = [300.0, 0.4, 0.05, 0.3, 10.0];
        let back = d.from_unit(&d.to_unit(&x));
        for (a, b) in x.iter().zip(&back) {
            assert!((a - b).abs() <= 1e-12 * a.abs());
        }
        // log scale: geometric midpoint maps to 0.5
        let g0 = &d.params()[0];
        assert!((g0.to_unit((80.0f64 * 4000.0).sqrt()) - 0.5).abs() < 1e-14);
    }

    #[test]
    fn dx_du_matches_finite_differences() {
        let d = Domain::prony2_table_5_3(0.01).expect("domain");
        for p in d.params() {
            let u = 0.37;
            let h = 1e-6;
            let fd = (p.from_unit(u + h) - p.from_unit(u - h)) / (2.0 * h);
            assert!((fd - p.dx_du(u)).abs() <= 1e-7 * fd.abs(), "{}", p.name);
        }
    }

    #[test]
    fn sum_constraint_and_bound_flags_are_reported() {
        let d = Domain::prony2_table_5_3(0.01).expect("domain");
        assert!(d.contains(&[300.0, 0.5, 0.1, 0.49, 10.0], 1e-12));
        assert!(!d.contains(&[300.0, 0.5, 0.1, 0.5, 10.0], 1e-12));
        let hits = d.on_bounds(&[4000.0, 0.5, 0.01, 0.2, 10.0], 1e-6);
        assert_eq!(hits.len(), 2);
        assert_eq!(hits[0].name, "G0");
        assert_eq!(hits[0].side, BoundSide::Upper);
        assert_eq!(hits[1].name, "tau1");
        assert_eq!(hits[1].side, BoundSide::Lower);
        assert_eq!(
            d.active_constraints(&[300.0, 0.5, 0.1, 0.49, 10.0], 1e-9),
            vec!["g1 + g2 <= 0.99".to_string()]
        );
    }

    #[test]
    fn invalid_domains_are_rejected_with_the_parameter_name() {
        let e = Domain::new(vec![Parameter::new("tau", "s", 0.0, 1.0, Scale::Log)])
            .expect_err("log with zero lower bound");
        assert!(e.to_string().contains("tau"));
        let e = Domain::new(vec![Parameter::new("a", "", 2.0, 1.0, Scale::Linear)])
            .expect_err("inverted");
        assert!(e.to_string().contains("'a'"));
        assert!(
            Domain::prony2_table_5_3(0.01)
                .and_then(|d| d.with_sum_constraint(&["g3"], 1.0))
                .is_err()
        );
    }
}
