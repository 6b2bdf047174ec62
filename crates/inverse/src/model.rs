//! The forward-model contract the fitter codes against: parameters (SI, in a
//! bounded [`Domain`]) → one response curve on a fixed time grid.
//!
//! The Kriging predictor (crate `surrogate`) and the real forward models
//! (membrane, FE) implement [`Model`] through small adapters, so the fitter
//! never knows which one it calls (argmin's problem-trait shape).

use nalgebra::DMatrix;
use nlvid_model::Domain;

use crate::error::{InverseError, Result};

/// Step in scaled coordinates u ∈ [0, 1] of the default central differences.
pub const FD_STEP_UNIT: f64 = 1e-5;

/// A forward model y(t_j; x), j = 1..m, on a fixed time grid.
///
/// Implementors provide [`Model::response`]; [`Model::jacobian`] defaults to
/// central finite differences ([`fd_jacobian`]), override it with the
/// analytic Jacobian where one exists (the Kriging predictor has one).
pub trait Model {
    /// The parameter domain (names, units, bounds, constraints).
    fn domain(&self) -> &Domain;

    /// The fixed time grid t_j (s), strictly increasing.
    fn times(&self) -> &[f64];

    /// Response y(t_j; x) (SI, e.g. N) at physical parameters x.
    ///
    /// # Errors
    /// [`InverseError::Model`] (or any other variant) when the model cannot
    /// be evaluated at x; never a NaN curve.
    fn response(&self, x: &[f64]) -> Result<Vec<f64>>;

    /// Jacobian J_jk = ∂y(t_j)/∂x_k (m × n, physical units).
    ///
    /// # Errors
    /// As [`Model::response`].
    fn jacobian(&self, x: &[f64]) -> Result<DMatrix<f64>> {
        fd_jacobian(self, x)
    }

    /// Response and Jacobian together (override when sharing work is cheaper).
    ///
    /// # Errors
    /// As [`Model::response`].
    fn response_and_jacobian(&self, x: &[f64]) -> Result<(Vec<f64>, DMatrix<f64>)> {
        Ok((self.response(x)?, self.jacobian(x)?))
    }
}

/// `&M` and `Box<M>` are models: every method forwards to `M`.
macro_rules! forward_model {
    ($($t:ty),*) => {$(
        impl<M: Model + ?Sized> Model for $t {
            fn domain(&self) -> &Domain {
                (**self).domain()
            }
            fn times(&self) -> &[f64] {
                (**self).times()
            }
            fn response(&self, x: &[f64]) -> Result<Vec<f64>> {
                (**self).response(x)
            }
            fn jacobian(&self, x: &[f64]) -> Result<DMatrix<f64>> {
                (**self).jacobian(x)
            }
            fn response_and_jacobian(&self, x: &[f64]) -> Result<(Vec<f64>, DMatrix<f64>)> {
                (**self).response_and_jacobian(x)
            }
        }
    )*};
}
forward_model!(&M, Box<M>);

/// Central finite-difference Jacobian of a model, stepping
/// [`FD_STEP_UNIT`] in each scaled coordinate (so log-scaled parameters get
/// relative steps); at a bound the stencil is clipped to the domain and
/// becomes one-sided.
///
/// # Errors
/// Any error of [`Model::response`]; [`InverseError::Vocabulary`] (wrong length).
pub fn fd_jacobian<M: Model + ?Sized>(model: &M, x: &[f64]) -> Result<DMatrix<f64>> {
    let domain = model.domain();
    domain.check_len(x)?;
    let m = model.times().len();
    let n = domain.len();
    let mut jac = DMatrix::zeros(m, n);
    for (k, p) in domain.params().iter().enumerate() {
        let u = p.to_unit(x[k]);
        let up = (u + FD_STEP_UNIT).min(1.0);
        let um = (u - FD_STEP_UNIT).max(0.0);
        let mut xp = x.to_vec();
        let mut xm = x.to_vec();
        xp[k] = p.from_unit(up);
        xm[k] = p.from_unit(um);
        let yp = model.response(&xp)?;
        let ym = model.response(&xm)?;
        check_len("model response", m, yp.len())?;
        check_len("model response", m, ym.len())?;
        let dx = xp[k] - xm[k];
        for j in 0..m {
            jac[(j, k)] = (yp[j] - ym[j]) / dx;
        }
    }
    Ok(jac)
}

/// Checks that a curve has the expected length.
///
/// # Errors
/// [`InverseError::LengthMismatch`].
pub fn check_len(what: &str, expected: usize, got: usize) -> Result<()> {
    if expected == got {
        Ok(())
    } else {
        Err(InverseError::LengthMismatch {
            what: what.to_string(),
            expected,
            got,
        })
    }
}

/// Checks that a Jacobian is m × n.
///
/// # Errors
/// [`InverseError::LengthMismatch`].
pub fn check_jacobian(jac: &DMatrix<f64>, m: usize, n: usize) -> Result<()> {
    check_len("Jacobian rows (time points)", m, jac.nrows())?;
    check_len("Jacobian columns (parameters)", n, jac.ncols())
}

/// Checks that every value of a model curve is finite.
///
/// # Errors
/// [`InverseError::NonFinite`] naming the first bad time index.
pub fn check_finite(y: &[f64], times: &[f64], x: &[f64]) -> Result<()> {
    match y.iter().position(|v| !v.is_finite()) {
        None => Ok(()),
        Some(index) => Err(InverseError::NonFinite {
            index,
            time: times.get(index).copied().unwrap_or(f64::NAN),
            x: x.to_vec(),
        }),
    }
}
