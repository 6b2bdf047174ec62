//! Fast eq. 5.3 misfit for models that are linear in a parameter-dependent
//! basis, y(x) = μ + Bᵀ φ(x) — the form of a Kriging (DACE) predictor:
//! φ(x) = [f(x); r(x)] (regression terms and correlations with the N
//! sites), B = [β; γ] with the output scaling folded in (N × m).
//!
//! With c = μ − d and weights W = diag(w):
//! Σ w_j (y_j − d_j)² = φᵀ G φ + 2 φᵀ h + k,
//! G = B W Bᵀ (N × N), h = B W c (N), k = cᵀ W c,
//! so a misfit costs O(N²) instead of O(N·m), and its gradient
//! 2 (G φ + h)ᵀ ∂φ/∂x costs O(N·n) more. G depends only on the model and
//! the weights (compute it once per surrogate, reuse it for every cell);
//! h and k once per data set (O(N·m)).
//!
//! Accuracy: the quadratic form cancels ‖c‖² down to the residual; the
//! relative error of Σ w r² is ≈ ε_mach ‖c‖²_W / Σ w r², negligible for
//! noisy data (≈ 1e-12 at a 2 % misfit) but a floor of ≈ 1e-8 on the eq. 5.3
//! value for a perfect fit. Negative round-off is clamped to 0.

use std::sync::Arc;

use nalgebra::{DMatrix, DVector};
use nlvid_model::Domain;

use crate::error::Result;
use crate::misfit::{MisfitTerm, SummedMisfit, rmse_of_sum};
use crate::model::{Model, check_len};

/// A model y(x) = μ + Bᵀ φ(x) on a fixed time grid.
pub trait BasisModel {
    /// The parameter domain.
    fn domain(&self) -> &Domain;

    /// The time grid t_j (s), length m.
    fn times(&self) -> &[f64];

    /// φ(x) (length N) and ∂φ/∂x (N × n).
    ///
    /// # Errors
    /// When the basis cannot be evaluated at x.
    fn basis(&self, x: &[f64]) -> Result<(DVector<f64>, DMatrix<f64>)>;

    /// B (N × m).
    fn coefficients(&self) -> &DMatrix<f64>;

    /// μ (length m).
    fn offset(&self) -> &[f64];
}

impl<B: BasisModel + ?Sized> BasisModel for &B {
    fn domain(&self) -> &Domain {
        (**self).domain()
    }
    fn times(&self) -> &[f64] {
        (**self).times()
    }
    fn basis(&self, x: &[f64]) -> Result<(DVector<f64>, DMatrix<f64>)> {
        (**self).basis(x)
    }
    fn coefficients(&self) -> &DMatrix<f64> {
        (**self).coefficients()
    }
    fn offset(&self) -> &[f64] {
        (**self).offset()
    }
}

/// A [`BasisModel`] seen as a plain [`Model`] (direct O(N·m) evaluation),
/// e.g. for [`crate::verify`], identifiability, or as a reference.
#[derive(Debug, Clone, Copy)]
pub struct AsModel<'a, B: ?Sized>(pub &'a B);

impl<B: BasisModel + ?Sized> Model for AsModel<'_, B> {
    fn domain(&self) -> &Domain {
        self.0.domain()
    }
    fn times(&self) -> &[f64] {
        self.0.times()
    }
    fn response(&self, x: &[f64]) -> Result<Vec<f64>> {
        Ok(self.response_and_jacobian(x)?.0)
    }
    fn jacobian(&self, x: &[f64]) -> Result<DMatrix<f64>> {
        Ok(self.response_and_jacobian(x)?.1)
    }
    fn response_and_jacobian(&self, x: &[f64]) -> Result<(Vec<f64>, DMatrix<f64>)> {
        let (phi, dphi) = self.0.basis(x)?;
        let b = self.0.coefficients();
        let y = b.tr_mul(&phi);
        let jac = b.tr_mul(&dphi);
        Ok((
            y.iter().zip(self.0.offset()).map(|(a, m)| a + m).collect(),
            jac,
        ))
    }
}

/// The Gram matrix G = B W Bᵀ of a basis model for given weights (None =
/// all ones). Cost O(N²·m); share it (it is in an [`Arc`]) between all data
/// sets fitted with the same model and weights.
///
/// # Errors
/// [`InverseError::LengthMismatch`] for weights of the wrong length.
pub fn gram<B: BasisModel + ?Sized>(
    model: &B,
    weights: Option<&[f64]>,
) -> Result<Arc<DMatrix<f64>>> {
    let b = model.coefficients();
    match weights {
        None => Ok(Arc::new(b * b.transpose())),
        Some(w) => {
            check_len("weights", b.ncols(), w.len())?;
            let mut bw = b.clone();
            for (j, wj) in w.iter().enumerate() {
                bw.column_mut(j).scale_mut(*wj);
            }
            Ok(Arc::new(bw * b.transpose()))
        }
    }
}

/// One experiment of a [`BasisMisfit`].
#[derive(Debug, Clone)]
pub struct BasisExperiment<B> {
    /// Label for reports.
    pub label: String,
    /// The model.
    pub model: B,
    gram: Arc<DMatrix<f64>>,
    h: DVector<f64>,
    k: f64,
    sum_w: f64,
    range: f64,
    /// Data and weights, for the direct evaluation when the Gram form
    /// cancels (see [`BasisExperiment::eval`]).
    data: Vec<f64>,
    weights: Option<Vec<f64>>,
}

/// Below this fraction of M = (Σ_a |φ_a| √G_aa + √k)² the Gram sum has
/// lost too many digits to cancellation: the misfit is then computed
/// directly, O(N·m). M bounds Σ_ab |φ_a| |B_a|·|B_b| |φ_b| + 2 Σ_a |φ_a|
/// |B_a|·|μ − d| + k (Cauchy–Schwarz, |B_a| the weighted row norm, √G_aa),
/// the size of the terms whose rounding (≈ (N + m)·ε·M) ends up in the sum,
/// including the rounding of G and h themselves.
const CANCELLATION: f64 = 1e-6;

impl<B: BasisModel> BasisExperiment<B> {
    /// Precomputes h and k for `data` (on the model grid); `gram` must be
    /// [`gram`]`(&model, weights)`.
    ///
    /// # Errors
    /// Length mismatches, non-finite data, zero data range, bad weights.
    pub fn new(
        label: &str,
        model: B,
        gram: Arc<DMatrix<f64>>,
        data: &[f64],
        weights: Option<&[f64]>,
    ) -> Result<Self> {
        let b = model.coefficients();
        let (n_basis, m) = (b.nrows(), b.ncols());
        check_len(&format!("data of experiment '{label}'"), m, data.len())?;
        check_len("basis offset", m, model.offset().len())?;
        check_len("Gram matrix rows", n_basis, gram.nrows())?;
        check_len("Gram matrix columns", n_basis, gram.ncols())?;
        // Reuse Experiment's checks of data and weights (finite, range > 0).
        let checked = crate::misfit::Experiment::new(
            label,
            AsModel(&model),
            data.to_vec(),
            weights.map(<[f64]>::to_vec),
        )?;
        let range = checked.data_range();
        let w = |j: usize| weights.map_or(1.0, |w| w[j]);
        let wc = DVector::from_iterator(m, (0..m).map(|j| w(j) * (model.offset()[j] - data[j])));
        let k = (0..m)
            .map(|j| w(j) * (model.offset()[j] - data[j]).powi(2))
            .sum();
        let h = b * wc;
        let sum_w = weights.map_or(m as f64, |w| w.iter().sum());
        Ok(Self {
            label: label.to_string(),
            model,
            gram,
            h,
            k,
            sum_w,
            range,
            data: data.to_vec(),
            weights: weights.map(<[f64]>::to_vec),
        })
    }

    /// Σ w_j r_j² and B W r with r = μ + Bᵀφ − d, computed directly.
    fn direct(&self, phi: &DVector<f64>) -> (f64, DVector<f64>) {
        let b = self.model.coefficients();
        let mut r = b.tr_mul(phi);
        let mu = self.model.offset();
        let mut swr2 = 0.0;
        for j in 0..r.len() {
            let w = self.weights.as_ref().map_or(1.0, |w| w[j]);
            r[j] += mu[j] - self.data[j];
            swr2 += w * r[j] * r[j];
            r[j] *= w;
        }
        (swr2, b * r)
    }

    /// (e, ∂e/∂x) if `with_gradient`, else (e, []).
    ///
    /// Σ w r² = φᵀGφ + 2φᵀh + k in O(N²); when that sum is below
    /// [`CANCELLATION`] of its terms' magnitude (a good fit of data far from
    /// the mean curve μ: the terms cancel and round-off dominates — it can
    /// even turn negative) the residual is formed directly instead.
    pub(crate) fn eval(&self, x: &[f64], with_gradient: bool) -> Result<(f64, Vec<f64>)> {
        let (phi, dphi) = self.model.basis(x)?;
        check_len("basis phi", self.h.len(), phi.len())?;
        // The direct residual costs ≈ 2·N·m, the Gram form N²: take the
        // direct one outright when it is not dearer (it is always exact).
        let (swr2, v) = if 2 * self.data.len() <= phi.len() {
            self.direct(&phi)
        } else {
            let g_phi = &*self.gram * &phi;
            let gram_sum = phi.dot(&g_phi) + 2.0 * phi.dot(&self.h) + self.k;
            let row_norms: f64 = phi
                .iter()
                .enumerate()
                .map(|(a, p)| p.abs() * self.gram[(a, a)].max(0.0).sqrt())
                .sum();
            let magnitude = (row_norms + self.k.max(0.0).sqrt()).powi(2);
            if gram_sum < CANCELLATION * magnitude {
                self.direct(&phi)
            } else {
                (gram_sum, g_phi + &self.h)
            }
        };
        let time0 = self.model.times().first().copied().unwrap_or(f64::NAN);
        let gradient = with_gradient.then_some((&dphi, phi.len(), move || v));
        rmse_of_sum(swr2.max(0.0), (self.sum_w, self.range), x, time0, gradient)
    }
}

/// Sum of eq. 5.3 misfits over [`BasisExperiment`]s, evaluated through the
/// precomputed Gram matrices. Same value and gradient as
/// [`crate::Misfit`] over [`AsModel`] (to round-off).
pub type BasisMisfit<B> = SummedMisfit<BasisExperiment<B>>;

impl<B: BasisModel> MisfitTerm for BasisExperiment<B> {
    fn label(&self) -> &str {
        &self.label
    }
    fn domain(&self) -> &Domain {
        self.model.domain()
    }
    fn eval(&self, x: &[f64], with_gradient: bool) -> Result<(f64, Vec<f64>)> {
        BasisExperiment::eval(self, x, with_gradient)
    }
}
