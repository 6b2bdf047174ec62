//! Fitting with some model inputs held at known values (issue 17,
//! per-cell geometry; beyond the thesis, which fits every cell with one
//! mean shape, §5.4.2).
//!
//! A meta-model with the cell height H and base diameter D as inputs
//! beside the five material parameters of eq. 5.1 is fitted per cell with
//! H and D fixed at that cell's measured values: [`FixedInputs`] splits the
//! model's [`Domain`] into the free parameters (their own `Domain`, the
//! linear constraints restricted to them: Σ_free aᵢxᵢ ≤ b − Σ_fixed aᵢxᵢ)
//! and the fixed values; [`Fixed`] wraps any [`Objective`] or [`Model`] of
//! the full input vector as one of the free parameters only (value
//! unchanged, gradient and Jacobian = the free components / columns). The
//! multistart fit, the Gauss–Newton intervals and the posterior sampler
//! then see the free parameters and nothing else; with no input fixed the
//! wrapper is the identity.

use nalgebra::DMatrix;
use nlvid_model::{Domain, LinearConstraint};

use crate::error::{InverseError, Result};
use crate::misfit::Objective;
use crate::model::Model;

/// Relative slack with which a fixed value may sit outside its range
/// (rounding of values written with units).
const RANGE_SLACK: f64 = 1e-9;

/// The inputs of a model held fixed, and the domain of the others.
#[derive(Debug, Clone, PartialEq)]
pub struct FixedInputs {
    full: Domain,
    free: Domain,
    /// Position in the full vector of each free parameter, in order.
    free_index: Vec<usize>,
    /// A full-length vector holding the fixed values (free slots 0).
    template: Vec<f64>,
    fixed: Vec<(String, f64)>,
}

impl FixedInputs {
    /// Nothing fixed: every input of `full` is free.
    pub fn none(full: &Domain) -> Self {
        Self {
            full: full.clone(),
            free: full.clone(),
            free_index: (0..full.len()).collect(),
            template: vec![0.0; full.len()],
            fixed: Vec::new(),
        }
    }

    /// Holds each named input of `full` at its value (SI).
    ///
    /// # Errors
    /// [`InverseError::InvalidSetting`] for an unknown or repeated name, a
    /// non-finite value, a value outside the input's range (the model is not
    /// valid there), fixed values that violate a constraint on their own, or
    /// nothing left to fit.
    pub fn new(full: &Domain, fixed: &[(&str, f64)]) -> Result<Self> {
        let mut template = vec![0.0; full.len()];
        let mut is_fixed = vec![false; full.len()];
        for &(name, value) in fixed {
            let Some(i) = full.index_of(name) else {
                return Err(InverseError::InvalidSetting(format!(
                    "fixed input `{name}`: not an input of the model ({})",
                    full.names().join(", ")
                )));
            };
            if is_fixed[i] {
                return Err(InverseError::InvalidSetting(format!(
                    "fixed input `{name}` given twice"
                )));
            }
            let p = &full.params()[i];
            let slack = RANGE_SLACK * (p.upper - p.lower).abs().max(p.upper.abs());
            if !value.is_finite() || value < p.lower - slack || value > p.upper + slack {
                return Err(InverseError::InvalidSetting(format!(
                    "fixed input {name} = {value:e} {}: outside the model's range \
                     [{:e}, {:e}] {} (build the meta-model over a range that covers it)",
                    p.unit, p.lower, p.upper, p.unit
                )));
            }
            is_fixed[i] = true;
            template[i] = value.clamp(p.lower, p.upper);
        }
        let free_index: Vec<usize> = (0..full.len()).filter(|&i| !is_fixed[i]).collect();
        if free_index.is_empty() {
            return Err(InverseError::InvalidSetting(
                "every input of the model is fixed: nothing to fit".into(),
            ));
        }
        let params = free_index
            .iter()
            .map(|&i| full.params()[i].clone())
            .collect();
        let mut constraints = Vec::new();
        for c in full.constraints() {
            let rhs = c.rhs
                - (0..full.len())
                    .filter(|&i| is_fixed[i])
                    .map(|i| c.coefficients[i] * template[i])
                    .sum::<f64>();
            let coefficients: Vec<f64> = free_index.iter().map(|&i| c.coefficients[i]).collect();
            if coefficients.iter().all(|a| *a == 0.0) {
                if rhs < 0.0 {
                    return Err(InverseError::InvalidSetting(format!(
                        "the fixed inputs violate the constraint {}",
                        c.label
                    )));
                }
                continue;
            }
            constraints.push(LinearConstraint {
                coefficients,
                rhs,
                label: c.label.clone(),
            });
        }
        let free = Domain::new(params)?.with_constraints(constraints)?;
        Ok(Self {
            full: full.clone(),
            free,
            free_index,
            template,
            fixed: fixed.iter().map(|&(n, v)| (n.to_string(), v)).collect(),
        })
    }

    /// The model's full input domain.
    pub fn full_domain(&self) -> &Domain {
        &self.full
    }

    /// The domain of the free parameters (what the fit sees).
    pub fn free_domain(&self) -> &Domain {
        &self.free
    }

    /// The fixed inputs, (name, SI value), as given.
    pub fn fixed(&self) -> &[(String, f64)] {
        &self.fixed
    }

    /// The full input vector of free parameters `x`.
    pub fn expand(&self, x: &[f64]) -> Vec<f64> {
        let mut full = self.template.clone();
        for (&i, &v) in self.free_index.iter().zip(x) {
            full[i] = v;
        }
        full
    }

    /// The free components of a full-length vector (e.g. a gradient).
    pub fn restrict(&self, full: &[f64]) -> Vec<f64> {
        self.free_index.iter().map(|&i| full[i]).collect()
    }

    /// The free columns of a Jacobian with one column per full input.
    pub fn columns(&self, jac: &DMatrix<f64>) -> DMatrix<f64> {
        jac.select_columns(&self.free_index)
    }
}

/// An [`Objective`] or [`Model`] of the full input vector, seen as one of
/// the free parameters of a [`FixedInputs`].
#[derive(Debug, Clone)]
pub struct Fixed<T> {
    inner: T,
    inputs: FixedInputs,
}

impl<T> Fixed<T> {
    /// Wraps `inner`, whose domain must be `inputs.full_domain()`.
    ///
    /// # Errors
    /// [`InverseError::InvalidSetting`] when the domains differ.
    pub fn new(inner: T, inputs: FixedInputs, inner_domain: &Domain) -> Result<Self> {
        if inner_domain != inputs.full_domain() {
            return Err(InverseError::InvalidSetting(format!(
                "fixed inputs of a model on ({}) applied to a model on ({})",
                inputs.full_domain().names().join(", "),
                inner_domain.names().join(", ")
            )));
        }
        Ok(Self { inner, inputs })
    }

    /// The wrapped objective or model.
    pub fn inner(&self) -> &T {
        &self.inner
    }

    /// The split into fixed and free inputs.
    pub fn inputs(&self) -> &FixedInputs {
        &self.inputs
    }
}

impl<O: Objective> Fixed<O> {
    /// An objective with some inputs fixed.
    ///
    /// # Errors
    /// As [`Fixed::new`].
    pub fn objective(inner: O, inputs: FixedInputs) -> Result<Self> {
        let d = inner.domain().clone();
        Self::new(inner, inputs, &d)
    }
}

impl<M: Model> Fixed<M> {
    /// A model with some inputs fixed.
    ///
    /// # Errors
    /// As [`Fixed::new`].
    pub fn model(inner: M, inputs: FixedInputs) -> Result<Self> {
        let d = inner.domain().clone();
        Self::new(inner, inputs, &d)
    }
}

impl<O: Objective> Objective for Fixed<O> {
    fn domain(&self) -> &Domain {
        self.inputs.free_domain()
    }
    fn value(&self, x: &[f64]) -> Result<f64> {
        self.inner.value(&self.inputs.expand(x))
    }
    fn value_and_gradient(&self, x: &[f64]) -> Result<(f64, Vec<f64>)> {
        let (v, g) = self.inner.value_and_gradient(&self.inputs.expand(x))?;
        Ok((v, self.inputs.restrict(&g)))
    }
    fn per_experiment(&self, x: &[f64]) -> Result<Vec<f64>> {
        self.inner.per_experiment(&self.inputs.expand(x))
    }
    fn final_value(&self, x: &[f64]) -> Result<f64> {
        self.inner.final_value(&self.inputs.expand(x))
    }
}

impl<M: Model> Model for Fixed<M> {
    fn domain(&self) -> &Domain {
        self.inputs.free_domain()
    }
    fn times(&self) -> &[f64] {
        self.inner.times()
    }
    fn response(&self, x: &[f64]) -> Result<Vec<f64>> {
        self.inner.response(&self.inputs.expand(x))
    }
    fn jacobian(&self, x: &[f64]) -> Result<DMatrix<f64>> {
        Ok(self
            .inputs
            .columns(&self.inner.jacobian(&self.inputs.expand(x))?))
    }
    fn response_and_jacobian(&self, x: &[f64]) -> Result<(Vec<f64>, DMatrix<f64>)> {
        let (y, j) = self.inner.response_and_jacobian(&self.inputs.expand(x))?;
        Ok((y, self.inputs.columns(&j)))
    }
}
