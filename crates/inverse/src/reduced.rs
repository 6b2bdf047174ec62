//! Eq. 5.3 misfit evaluated in the reduced (PCA) output space, for models
//! ŷ(x) = A c(x) with a fixed m × r map A and r ≪ m coordinates c(x) — a
//! PCA-reduced Kriging surrogate with output scaling F/G0:
//! A = [μ, diag(σ)Φ], c = G0·[1; z(x)] (z the kriged PC scores).
//!
//! With √W = diag(√w) and the thin QR factorisation √W A = Q R (once per
//! model and weights, O(m·r²)):
//! Σ w_j (ŷ_j − d_j)² = ‖R c − b‖² + ρ², b = Qᵀ√W d, ρ² = ‖√W d − Q b‖²
//! (b, ρ² once per data set, O(m·r)). Both terms are sums of squares of
//! vectors whose entries are formed without cancelling squares — unlike
//! the Gram form φᵀGφ + 2φᵀh + k of [`crate::BasisMisfit`] — so the
//! rounding error of √(Σ w r²) is ≈ ε·‖√W d‖ (absolute), the same as for
//! the directly formed residual ŷ − d: there is no loss of digits at a
//! good fit. Per evaluation: c(x) and ∂c/∂x (O(N·q·n) for Kriging), then
//! O(r²): nothing grows with m or with N·m.
//!
//! Reported values ([`Objective::per_experiment`], [`Objective::final_value`])
//! are computed directly from ŷ = A c (O(m·r)), so the misfits a fit prints
//! are eq. 5.3 of the predicted curve, not of the reduced sum.

use std::sync::Arc;

use nalgebra::{DMatrix, DVector};
use nlvid_model::Domain;

use crate::error::{InverseError, Result};
use crate::misfit::{MisfitTerm, SummedMisfit, rmse_of_sum};
use crate::model::check_len;

/// A model ŷ(x) = A c(x) on a fixed time grid with a fixed output map A
/// (m × r) and r reduced coordinates c(x).
pub trait ReducedModel {
    /// The parameter domain.
    fn domain(&self) -> &Domain;

    /// The time grid t_j (s), length m.
    fn times(&self) -> &[f64];

    /// A (m × r).
    fn output_map(&self) -> &DMatrix<f64>;

    /// c(x) (length r) and ∂c/∂x (r × n, physical x in the domain's order).
    ///
    /// # Errors
    /// When the model cannot be evaluated at x.
    fn coordinates(&self, x: &[f64]) -> Result<(DVector<f64>, DMatrix<f64>)>;

    /// c(x) alone, for value-only evaluations; override when it is cheaper
    /// than [`ReducedModel::coordinates`].
    ///
    /// # Errors
    /// When the model cannot be evaluated at x.
    fn coordinate_values(&self, x: &[f64]) -> Result<DVector<f64>> {
        Ok(self.coordinates(x)?.0)
    }
}

impl<R: ReducedModel + ?Sized> ReducedModel for &R {
    fn domain(&self) -> &Domain {
        (**self).domain()
    }
    fn times(&self) -> &[f64] {
        (**self).times()
    }
    fn output_map(&self) -> &DMatrix<f64> {
        (**self).output_map()
    }
    fn coordinates(&self, x: &[f64]) -> Result<(DVector<f64>, DMatrix<f64>)> {
        (**self).coordinates(x)
    }
    fn coordinate_values(&self, x: &[f64]) -> Result<DVector<f64>> {
        (**self).coordinate_values(x)
    }
}

/// √W A = Q R of a reduced model for given weights: what every data set
/// fitted with that model and those weights shares.
#[derive(Debug, Clone)]
pub struct Projection {
    q: DMatrix<f64>,
    r: DMatrix<f64>,
    weights: Option<Vec<f64>>,
}

impl Projection {
    /// Number of reduced coordinates r.
    pub fn n_coordinates(&self) -> usize {
        self.r.ncols()
    }
}

/// Factorises √W A = Q R (Householder, thin) for a reduced model and
/// optional weights (None = all 1). Cost O(m·r²); share the result (it is
/// in an [`Arc`]) between all data sets fitted with the same model and
/// weights.
///
/// # Errors
/// [`InverseError::LengthMismatch`] for weights of the wrong length,
/// [`InverseError::InvalidSetting`] for negative or non-finite weights or a
/// non-finite output map.
pub fn projection<R: ReducedModel + ?Sized>(
    model: &R,
    weights: Option<&[f64]>,
) -> Result<Arc<Projection>> {
    let a = model.output_map();
    let m = a.nrows();
    check_len("output map rows (time points)", model.times().len(), m)?;
    if let Some(w) = weights {
        check_len("weights", m, w.len())?;
        if let Some(j) = w.iter().position(|v| !(v.is_finite() && *v >= 0.0)) {
            return Err(InverseError::InvalidSetting(format!(
                "weight {j} is {} (weights must be finite and >= 0)",
                w[j]
            )));
        }
    }
    if a.iter().any(|v| !v.is_finite()) {
        return Err(InverseError::InvalidSetting(
            "the reduced model's output map has non-finite entries".into(),
        ));
    }
    let mut wa = a.clone();
    if let Some(w) = weights {
        for (j, wj) in w.iter().enumerate() {
            wa.row_mut(j).scale_mut(wj.sqrt());
        }
    }
    let qr = wa.qr();
    Ok(Arc::new(Projection {
        q: qr.q(),
        r: qr.r(),
        weights: weights.map(<[f64]>::to_vec),
    }))
}

/// One experiment of a [`ReducedMisfit`].
#[derive(Debug, Clone)]
pub struct ReducedExperiment<R> {
    /// Label for reports.
    pub label: String,
    /// The model.
    pub model: R,
    projection: Arc<Projection>,
    b: DVector<f64>,
    rho2: f64,
    sum_w: f64,
    range: f64,
    data: Vec<f64>,
}

impl<R: ReducedModel> ReducedExperiment<R> {
    /// Precomputes b = Qᵀ√W d and ρ² = ‖√W d − Q b‖² for `data` (on the
    /// model grid); `projection` must be [`projection`]`(&model, weights)`
    /// and carries the weights. Cost O(m·r).
    ///
    /// # Errors
    /// Length mismatches, non-finite data, zero data range, bad weights.
    pub fn new(label: &str, model: R, projection: Arc<Projection>, data: &[f64]) -> Result<Self> {
        let m = model.output_map().nrows();
        check_len(&format!("data of experiment '{label}'"), m, data.len())?;
        check_len("projection Q rows", m, projection.q.nrows())?;
        check_len(
            "projection R columns",
            model.output_map().ncols(),
            projection.r.ncols(),
        )?;
        if let Some(j) = data.iter().position(|v| !v.is_finite()) {
            return Err(InverseError::InvalidSetting(format!(
                "data of experiment '{label}' is not finite at index {j}"
            )));
        }
        let weights = projection.weights.as_deref();
        if let Some(w) = weights {
            crate::misfit::check_weights(w, m)?;
        }
        let range = crate::misfit::curve_range(data, &format!("data of experiment '{label}'"))?;
        let wd = DVector::from_iterator(
            m,
            (0..m).map(|j| weights.map_or(1.0, |w| w[j].sqrt()) * data[j]),
        );
        let b = projection.q.tr_mul(&wd);
        let rho2 = (wd - &projection.q * &b).norm_squared();
        let sum_w = weights.map_or(m as f64, |w| w.iter().sum());
        Ok(Self {
            label: label.to_string(),
            model,
            projection,
            b,
            rho2,
            sum_w,
            range,
            data: data.to_vec(),
        })
    }

    /// ρ² / Σw: the weighted mean square of the data outside the span of
    /// √W A — the smallest Σ w r² / Σ w any parameter set can reach.
    pub fn floor_mean_square(&self) -> f64 {
        self.rho2 / self.sum_w
    }

    /// (e, ∂e/∂x) from the reduced form; ∂e/∂x only if `with_gradient`.
    pub(crate) fn eval(&self, x: &[f64], with_gradient: bool) -> Result<(f64, Vec<f64>)> {
        let (c, dc) = if with_gradient {
            self.model.coordinates(x)?
        } else {
            (self.model.coordinate_values(x)?, DMatrix::zeros(0, 0))
        };
        check_len("reduced coordinates", self.b.len(), c.len())?;
        let res = &self.projection.r * &c - &self.b;
        let swr2 = res.norm_squared() + self.rho2;
        let time0 = self.model.times().first().copied().unwrap_or(f64::NAN);
        // ∂Σwr²/∂x = 2 (Rc − b)ᵀ R ∂c/∂x.
        let v = || self.projection.r.tr_mul(&res);
        let gradient = with_gradient.then_some((&dc, c.len(), v));
        rmse_of_sum(swr2, (self.sum_w, self.range), x, time0, gradient)
    }

    /// Eq. 5.3 from the predicted curve ŷ = A c(x), formed directly (O(m·r)).
    ///
    /// # Errors
    /// Model errors; a non-finite prediction.
    pub fn direct(&self, x: &[f64]) -> Result<f64> {
        let c = self.model.coordinate_values(x)?;
        let y = self.model.output_map() * c;
        crate::model::check_finite(y.as_slice(), self.model.times(), x)?;
        crate::misfit::range_normalised_rmse(
            y.as_slice(),
            &self.data,
            self.projection.weights.as_deref(),
        )
    }
}

/// Sum of eq. 5.3 misfits over [`ReducedExperiment`]s: values and
/// gradients from the reduced form during the search, reported values
/// ([`crate::Objective::per_experiment`], [`crate::Objective::final_value`])
/// from the directly formed predicted curve ([`ReducedExperiment::direct`]).
pub type ReducedMisfit<R> = SummedMisfit<ReducedExperiment<R>>;

impl<R: ReducedModel> MisfitTerm for ReducedExperiment<R> {
    fn label(&self) -> &str {
        &self.label
    }
    fn domain(&self) -> &Domain {
        self.model.domain()
    }
    fn eval(&self, x: &[f64], with_gradient: bool) -> Result<(f64, Vec<f64>)> {
        ReducedExperiment::eval(self, x, with_gradient)
    }
    fn reported(&self, x: &[f64]) -> Result<f64> {
        self.direct(x)
    }
}
