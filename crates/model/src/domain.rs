//! The parameter domain (Tables 4.1, 5.3, A.2): named parameters with SI
//! units and bounds, linear or logarithmic scaling, and linear inequality
//! constraints such as g1 + g2 ≤ 1 − ε (§4.4.1, §5.4.1).
//!
//! Designs, Kriging inputs and fits all work in *scaled* coordinates
//! u ∈ [0, 1]ⁿ: u = (x − lo)/(hi − lo) for linear parameters and
//! u = ln(x/lo)/ln(hi/lo) for log-scaled ones. Every meta-model stores its
//! domain, so a fit reads back exactly the box its surrogate was built on.

use serde::{Deserialize, Serialize};

use crate::error::{ModelError, Result};
use crate::names;

/// How a parameter is mapped to the unit interval.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Scale {
    /// u = (x − lo)/(hi − lo).
    Linear,
    /// u = ln(x/lo)/ln(hi/lo), for parameters spanning decades (moduli,
    /// relaxation times). Needs lo > 0.
    Log,
}

/// One named, unit-carrying, bounded parameter (SI values).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Parameter {
    /// Name ([`names`]: "G0", "tau1", …).
    pub name: String,
    /// SI unit as printed ("Pa", "s", "1" for dimensionless).
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

    /// Physical value x of a scaled coordinate u. On a log axis
    /// x = exp(ln lo + u (ln hi − ln lo)): the expression every stored
    /// design was drawn with, so designs — and the study hashes of run
    /// stores built from them — are reproduced bit for bit.
    pub fn from_unit(&self, u: f64) -> f64 {
        match self.scale {
            Scale::Linear => self.lower + u * (self.upper - self.lower),
            Scale::Log => (self.lower.ln() + u * (self.upper.ln() - self.lower.ln())).exp(),
        }
    }

    /// dx/du at u (chain rule for gradients in scaled coordinates).
    pub fn dx_du(&self, u: f64) -> f64 {
        match self.scale {
            Scale::Linear => self.upper - self.lower,
            Scale::Log => self.from_unit(u) * (self.upper / self.lower).ln(),
        }
    }

    /// True for a logarithmic axis.
    pub fn is_log(&self) -> bool {
        self.scale == Scale::Log
    }
}

/// Linear inequality constraint Σ aᵢ xᵢ ≤ b on the physical parameters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
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

/// A bounded parameter domain with linear constraints, in one parameter
/// order (the forward model's).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "DomainFile", into = "DomainFile")]
pub struct Domain {
    params: Vec<Parameter>,
    constraints: Vec<LinearConstraint>,
}

/// The stored form of a [`Domain`]; read back through [`Domain::new`]'s
/// checks.
#[derive(Serialize, Deserialize)]
struct DomainFile {
    parameters: Vec<Parameter>,
    #[serde(default)]
    constraints: Vec<LinearConstraint>,
}

impl TryFrom<DomainFile> for Domain {
    type Error = ModelError;
    fn try_from(f: DomainFile) -> Result<Self> {
        Domain::new(f.parameters)?.with_constraints(f.constraints)
    }
}

impl From<Domain> for DomainFile {
    fn from(d: Domain) -> Self {
        Self {
            parameters: d.params,
            constraints: d.constraints,
        }
    }
}

impl Domain {
    /// A domain without constraints, rejecting empty, repeated, inverted or
    /// non-finite bounds and log scales with a non-positive lower bound.
    ///
    /// # Errors
    /// [`ModelError::Domain`] naming the offending parameter.
    pub fn new(params: Vec<Parameter>) -> Result<Self> {
        if params.is_empty() {
            return Err(ModelError::Domain(
                "a domain needs at least one parameter".into(),
            ));
        }
        for (i, p) in params.iter().enumerate() {
            if !(p.lower.is_finite() && p.upper.is_finite() && p.lower < p.upper) {
                return Err(ModelError::Domain(format!(
                    "parameter '{}': bounds [{}, {}] must be finite with lower < upper",
                    p.name, p.lower, p.upper
                )));
            }
            if p.scale == Scale::Log && p.lower <= 0.0 {
                return Err(ModelError::Domain(format!(
                    "parameter '{}': log scale needs a positive lower bound, got {}",
                    p.name, p.lower
                )));
            }
            if params[..i].iter().any(|q| q.name == p.name) {
                return Err(ModelError::Domain(format!(
                    "parameter '{}' is listed twice",
                    p.name
                )));
            }
        }
        Ok(Self {
            params,
            constraints: Vec::new(),
        })
    }

    /// Adds constraints, checking that each has one coefficient per
    /// parameter and a finite right-hand side.
    ///
    /// # Errors
    /// [`ModelError::Domain`] naming the constraint.
    pub fn with_constraints(mut self, constraints: Vec<LinearConstraint>) -> Result<Self> {
        for c in &constraints {
            if c.coefficients.len() != self.params.len()
                || !c.rhs.is_finite()
                || c.coefficients.iter().any(|a| !a.is_finite())
            {
                return Err(ModelError::Domain(format!(
                    "constraint '{}' needs {} finite coefficients and a finite bound (got {} and {})",
                    c.label,
                    self.params.len(),
                    c.coefficients.len(),
                    c.rhs
                )));
            }
        }
        self.constraints.extend(constraints);
        Ok(self)
    }

    /// Adds the constraint Σ_{names} x ≤ rhs (e.g. g1 + g2 ≤ 1 − ε).
    ///
    /// # Errors
    /// [`ModelError::Domain`] if a name is unknown.
    pub fn with_sum_constraint(mut self, names: &[&str], rhs: f64) -> Result<Self> {
        let mut coefficients = vec![0.0; self.params.len()];
        for name in names {
            let i = self.index_of(name).ok_or_else(|| {
                ModelError::Domain(format!("constraint refers to unknown parameter '{name}'"))
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

    /// The five-parameter cell domain of Table 5.3 in nlvid's order
    /// ([`names::PRONY2`]): G0 ∈ [80, 4000] Pa (log), g1, g2 ∈ [0.01, 1],
    /// τ1 ∈ [0.01, 2] s (log), τ2 ∈ [2, 40] s (log), g1 + g2 ≤ 1 − ε.
    /// Table 5.3's first column is G0, the shear modulus
    /// (`docs/theory/model.md`).
    ///
    /// # Errors
    /// [`ModelError::Domain`] if ε is not in [0, 0.98).
    pub fn table_5_3(eps: f64) -> Result<Self> {
        if !(0.0..0.98).contains(&eps) {
            return Err(ModelError::Domain(format!(
                "epsilon of g1 + g2 <= 1 - epsilon must be in [0, 0.98), got {eps}"
            )));
        }
        Self::prony2([
            (80.0, 4000.0, Scale::Log),
            (0.01, 1.0, Scale::Linear),
            (0.01, 1.0, Scale::Linear),
            (0.01, 2.0, Scale::Log),
            (2.0, 40.0, Scale::Log),
        ])?
        .with_sum_constraint(&["g1", "g2"], 1.0 - eps)
    }

    /// The six-parameter capsule domain of Table 4.1 in nlvid's order
    /// ([`names::CAPSULE`]): C1 ∈ [5, 50] MPa (log), α ∈ [0, 0.5],
    /// g1 ∈ [0.5, 1], g2 ∈ [0, 0.5], τ1 ∈ [0.03, 0.3] s (log),
    /// τ2 ∈ [1, 5] s (log), g1 + g2 ≤ 1 − ε (§4.4.1: "satisfies the
    /// constraint g1 + g2 < 1"). The bounds are the thesis's; the log axes
    /// for the modulus and the times are nlvid's choice, as in
    /// [`Domain::table_5_3`] (the thesis's `lhsdesign` drew every axis
    /// linearly).
    ///
    /// # Errors
    /// [`ModelError::Domain`] if ε is not in [0, 0.5) (g1 ≥ 0.5 needs room).
    pub fn table_4_1(eps: f64) -> Result<Self> {
        if !(0.0..0.5).contains(&eps) {
            return Err(ModelError::Domain(format!(
                "epsilon of g1 + g2 <= 1 - epsilon must be in [0, 0.5), got {eps}"
            )));
        }
        let bounds = [
            (5e6, 50e6, Scale::Log),
            (0.0, 0.5, Scale::Linear),
            (0.5, 1.0, Scale::Linear),
            (0.0, 0.5, Scale::Linear),
            (0.03, 0.3, Scale::Log),
            (1.0, 5.0, Scale::Log),
        ];
        Self::new(
            names::CAPSULE
                .iter()
                .zip(names::CAPSULE_UNITS)
                .zip(bounds)
                .map(|((n, u), (lo, hi, s))| Parameter::new(n, u, lo, hi, s))
                .collect(),
        )?
        .with_sum_constraint(&["g1", "g2"], 1.0 - eps)
    }

    /// The wider cell domain of the surrogate accuracy and timing studies
    /// (`docs/theory/surrogate.md`): G0 ∈ [100, 5000] Pa (log), g1, g2 ∈
    /// [0, 0.9], τ1 ∈ [0.01, 1] s (log), τ2 ∈ [1, 100] s (log),
    /// g1 + g2 ≤ 0.99.
    pub fn cell_study() -> Self {
        Self::prony2([
            (100.0, 5000.0, Scale::Log),
            (0.0, 0.9, Scale::Linear),
            (0.0, 0.9, Scale::Linear),
            (0.01, 1.0, Scale::Log),
            (1.0, 100.0, Scale::Log),
        ])
        .and_then(|d| d.with_sum_constraint(&["g1", "g2"], 0.99))
        .expect("the bounds above are valid")
    }

    /// A [`names::PRONY2`] domain from (lower, upper, scale) per parameter.
    fn prony2(bounds: [(f64, f64, Scale); 5]) -> Result<Self> {
        Self::new(
            names::PRONY2
                .iter()
                .zip(names::PRONY2_UNITS)
                .zip(bounds)
                .map(|((n, u), (lo, hi, s))| Parameter::new(n, u, lo, hi, s))
                .collect(),
        )
    }

    /// Number of parameters.
    pub fn len(&self) -> usize {
        self.params.len()
    }

    /// Always false (a domain has ≥ 1 parameter); for clippy's `len` rule.
    pub fn is_empty(&self) -> bool {
        self.params.is_empty()
    }

    /// The parameters, in order.
    pub fn params(&self) -> &[Parameter] {
        &self.params
    }

    /// The parameter names, in order.
    pub fn names(&self) -> Vec<String> {
        self.params.iter().map(|p| p.name.clone()).collect()
    }

    /// The SI units, in order.
    pub fn units(&self) -> Vec<String> {
        self.params.iter().map(|p| p.unit.clone()).collect()
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
    /// [`ModelError::ParameterCount`].
    pub fn check_len(&self, x: &[f64]) -> Result<()> {
        if x.len() == self.params.len() {
            Ok(())
        } else {
            Err(ModelError::ParameterCount {
                expected: self.params.len(),
                names: self.names().join(", "),
                got: x.len(),
            })
        }
    }

    /// Checks that `names` are this domain's parameter names in this order
    /// (a forward model, a surrogate and a domain must agree).
    ///
    /// # Errors
    /// [`ModelError::Domain`] listing both orders.
    pub fn check_names(&self, names: &[impl AsRef<str>]) -> Result<()> {
        let ours = self.names();
        if ours.len() == names.len() && ours.iter().zip(names).all(|(a, b)| a == b.as_ref()) {
            Ok(())
        } else {
            Err(ModelError::Domain(format!(
                "parameters [{}] do not match the domain's [{}]",
                names
                    .iter()
                    .map(AsRef::as_ref)
                    .collect::<Vec<_>>()
                    .join(", "),
                ours.join(", ")
            )))
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

    /// True when every constraint holds at x within `tol` (absolute).
    pub fn feasible(&self, x: &[f64], tol: f64) -> bool {
        self.constraints.iter().all(|c| c.value(x) <= tol)
    }

    /// True when x is inside the bounds (with relative slack `tol` of each
    /// range) and satisfies every constraint within `tol`.
    pub fn contains(&self, x: &[f64], tol: f64) -> bool {
        x.len() == self.params.len()
            && self.params.iter().zip(x).all(|(p, &v)| {
                let slack = tol * (p.upper - p.lower);
                v >= p.lower - slack && v <= p.upper + slack
            })
            && self.feasible(x, tol)
    }

    /// The parameters whose scaled coordinate lies within `tol` of 0 or 1.
    pub fn on_bounds(&self, x: &[f64], tol: f64) -> Vec<BoundHit> {
        let mut hits = Vec::new();
        for (p, &v) in self.params.iter().zip(x) {
            let u = p.to_unit(v);
            let side = if u <= tol {
                BoundSide::Lower
            } else if u >= 1.0 - tol {
                BoundSide::Upper
            } else {
                continue;
            };
            hits.push(BoundHit {
                name: p.name.clone(),
                side,
            });
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

    /// Reads a domain for a model with these parameter names and SI units
    /// (`"1"` for dimensionless) from a study section:
    ///
    /// ```toml
    /// [design.parameters]
    /// G0 = { range = ["80 Pa", "4 kPa"], log = true }
    /// g1 = { range = [0.01, 1.0] }
    /// [[design.constraint]]      # Σ coefficients·x ≤ at_most
    /// coefficients = { g1 = 1, g2 = 1 }
    /// at_most = 0.99
    /// ```
    ///
    /// Every parameter must be given, in any order; the domain takes the
    /// model's order.
    ///
    /// # Errors
    /// Missing or unknown parameters, wrong units, empty ranges, log axes
    /// with lower ≤ 0, constraints naming unknown parameters — each naming
    /// file, line and key.
    pub fn from_section(
        s: &mut nlvid_study::Section,
        names: &[String],
        units: &[String],
    ) -> nlvid_study::Result<Self> {
        use nlvid_study::{Bounds, Dimension};
        let mut ps = s.subsection("parameters")?;
        let mut params = Vec::with_capacity(names.len());
        for (name, unit) in names.iter().zip(units) {
            let dim = if unit == "1" {
                Dimension::NONE
            } else {
                nlvid_study::parse_unit(unit)
                    .map_err(|e| ps.invalid(name, format!("model unit `{unit}`: {e}")))?
                    .1
            };
            if !ps.has(name) {
                return Err(ps.invalid(
                    name,
                    format!(
                        "missing parameter `{name}` (the model's parameters: {}); \
                         write {name} = {{ range = [lower, upper] }}",
                        names.join(", ")
                    ),
                ));
            }
            let mut p = ps.subsection(name)?;
            let (lower, upper) = p.req_range("range", dim, Bounds::ANY)?;
            let log = p.opt_bool("log")?.unwrap_or(false);
            if log && lower <= 0.0 {
                return Err(p.invalid("log", "a logarithmic axis needs a positive lower bound"));
            }
            p.finish()?;
            let scale = if log { Scale::Log } else { Scale::Linear };
            params.push(Parameter::new(name, unit, lower, upper, scale));
        }
        ps.finish()?;
        let mut constraints = Vec::new();
        for mut c in s.tables("constraint")? {
            let mut co = c.subsection("coefficients")?;
            let mut coefficients = vec![0.0; names.len()];
            let mut terms = Vec::new();
            for key in co.keys().iter().map(|k| k.to_string()).collect::<Vec<_>>() {
                match names.iter().position(|n| *n == key) {
                    Some(i) => {
                        coefficients[i] = co.req_f64(&key, Bounds::ANY)?;
                        terms.push(if coefficients[i] == 1.0 {
                            key.clone()
                        } else {
                            format!("{} {key}", coefficients[i])
                        });
                    }
                    None => {
                        return Err(co.invalid(
                            &key,
                            format!("not a parameter of the model ({})", names.join(", ")),
                        ));
                    }
                }
            }
            co.finish()?;
            let rhs = c.req_f64("at_most", Bounds::ANY)?;
            c.finish()?;
            constraints.push(LinearConstraint {
                coefficients,
                rhs,
                label: format!("{} <= {rhs}", terms.join(" + ")),
            });
        }
        Domain::new(params)
            .and_then(|d| d.with_constraints(constraints))
            .map_err(|e| s.invalid("parameters", e.to_string()))
    }
}

/// Which side of a parameter range.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum BoundSide {
    /// At the lower bound.
    Lower,
    /// At the upper bound.
    Upper,
}

/// A parameter found on a bound of the domain (the domain should be widened).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
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
        let d = Domain::table_5_3(0.01).expect("domain");
        let x = [300.0, 0.4, 0.3, 0.05, 10.0];
        let back = d.from_unit(&d.to_unit(&x));
        for (a, b) in x.iter().zip(&back) {
            assert!((a - b).abs() <= 1e-12 * a.abs());
        }
        let g0 = &d.params()[0];
        assert!((g0.to_unit((80.0f64 * 4000.0).sqrt()) - 0.5).abs() < 1e-14);
    }

    #[test]
    fn table_4_1_holds_the_thesis_bounds_and_the_weight_constraint() {
        let d = Domain::table_4_1(0.01).expect("domain");
        assert_eq!(d.names(), names::CAPSULE);
        let bounds: Vec<(f64, f64)> = d.params().iter().map(|p| (p.lower, p.upper)).collect();
        // Table 4.1, in nlvid's order C1 (MPa → Pa), α, g1, g2, τ1, τ2.
        assert_eq!(
            bounds,
            [
                (5e6, 50e6),
                (0.0, 0.5),
                (0.5, 1.0),
                (0.0, 0.5),
                (0.03, 0.3),
                (1.0, 5.0)
            ]
        );
        // Material Set 1 of §4.4.2 (g1 + g2 = 0.9835) is inside, and so is
        // Set 2; g1 + g2 = 0.995 is not.
        assert!(d.contains(&[28.8179e6, 0.0, 0.7652, 0.2183, 0.1608, 5.0], 1e-12));
        assert!(d.contains(&[21.9096e6, 0.0, 0.5036, 0.3464, 0.2018, 1.1285], 1e-12));
        assert!(!d.contains(&[20e6, 0.1, 0.8, 0.195, 0.1, 2.0], 1e-12));
        assert!(Domain::table_4_1(0.5).is_err());
    }

    #[test]
    fn dx_du_matches_finite_differences() {
        let d = Domain::table_5_3(0.01).expect("domain");
        for p in d.params() {
            let (u, h) = (0.37, 1e-6);
            let fd = (p.from_unit(u + h) - p.from_unit(u - h)) / (2.0 * h);
            assert!((fd - p.dx_du(u)).abs() <= 1e-7 * fd.abs(), "{}", p.name);
        }
    }

    #[test]
    fn sum_constraint_and_bound_flags_are_reported() {
        let d = Domain::table_5_3(0.01).expect("domain");
        assert_eq!(d.names(), names::PRONY2);
        assert!(d.contains(&[300.0, 0.5, 0.49, 0.1, 10.0], 1e-12));
        assert!(!d.contains(&[300.0, 0.5, 0.5, 0.1, 10.0], 1e-12));
        let hits = d.on_bounds(&[4000.0, 0.5, 0.2, 0.01, 10.0], 1e-6);
        assert_eq!(hits.len(), 2);
        assert_eq!(
            (hits[0].name.as_str(), hits[0].side),
            ("G0", BoundSide::Upper)
        );
        assert_eq!(
            (hits[1].name.as_str(), hits[1].side),
            ("tau1", BoundSide::Lower)
        );
        assert_eq!(
            d.active_constraints(&[300.0, 0.5, 0.49, 0.1, 10.0], 1e-9),
            vec!["g1 + g2 <= 0.99".to_string()]
        );
    }

    #[test]
    fn invalid_domains_are_rejected_with_the_parameter_name() {
        let e = Domain::new(vec![Parameter::new("tau", "s", 0.0, 1.0, Scale::Log)])
            .expect_err("log with zero lower bound");
        assert!(e.to_string().contains("tau"));
        let e = Domain::new(vec![Parameter::new("a", "1", 2.0, 1.0, Scale::Linear)])
            .expect_err("inverted");
        assert!(e.to_string().contains("'a'"));
        let p = Parameter::new("a", "1", 0.0, 1.0, Scale::Linear);
        assert!(Domain::new(vec![p.clone(), p]).is_err(), "repeated name");
        assert!(
            Domain::table_5_3(0.01)
                .and_then(|d| d.with_sum_constraint(&["g3"], 1.0))
                .is_err()
        );
    }

    #[test]
    fn stored_domain_reads_back_equal_and_is_checked() {
        let d = Domain::table_5_3(0.01).expect("domain");
        let text = serde_json::to_string(&d).expect("json");
        assert!(text.contains(r#""scale":"log""#), "{text}");
        assert_eq!(serde_json::from_str::<Domain>(&text).expect("read back"), d);
        let broken = text.replace("4000.0", "-1.0");
        assert!(
            serde_json::from_str::<Domain>(&broken).is_err(),
            "inverted bounds"
        );
    }

    #[test]
    fn domain_from_a_study_section_names_the_bad_key() {
        let text = r#"
[design.parameters]
G0 = { range = ["80 Pa", "4 kPa"], log = true }
g1 = { range = [0.01, 1.0] }
[[design.constraint]]
coefficients = { g1 = 1, g7 = 1 }
at_most = 0.99
"#;
        let mut study = nlvid_study::Study::parse("d.toml", text).expect("parse");
        let mut s = study.section("design").expect("section");
        let names = vec!["G0".to_string(), "g1".to_string()];
        let units = vec!["Pa".to_string(), "1".to_string()];
        let e = Domain::from_section(&mut s, &names, &units).expect_err("g7");
        assert!(e.to_string().contains("g7"), "{e}");
        let good = text.replace("g7", "G0").replace("0.99", "1000");
        let mut study = nlvid_study::Study::parse("d.toml", &good).expect("parse");
        let mut s = study.section("design").expect("section");
        let d = Domain::from_section(&mut s, &names, &units).expect("domain");
        assert_eq!(d.params()[0].upper, 4000.0);
        assert_eq!(d.constraints()[0].label, "g1 + G0 <= 1000");
    }
}
