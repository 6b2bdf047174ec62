//! Local identifiability at a fitted point: which parameters can the data
//! pin down? (§4.4.2 found C1/C2 and the long-term relaxation poorly
//! determined by RR tests.)
//!
//! Residuals and Jacobians of all experiments are stacked after dividing
//! each experiment by the range of its data (and multiplying by √w_j), so
//! they share the units of eq. 5.3. Then
//! - the *scaled sensitivity* S_jk = J̃_jk · s_k, with s_k the parameter
//!   value or its range, and its singular values σ_1 ≥ … ≥ σ_n and
//!   condition number σ_1/σ_n: a tiny σ_n means some direction (the
//!   matching right singular vector) barely changes the curve;
//! - the Gauss–Newton covariance C = σ̂² (J̃ᵀJ̃)⁻¹ with
//!   σ̂² = Σ r̃² / (M − n), computed through the SVD of S (singular values
//!   below M·ε·σ_1 count as zero, giving infinite variances), and
//!   approximate 95 % intervals x_k ± 1.96 √C_kk (normal approximation,
//!   linearised, bounds and constraints ignored).

use nalgebra::{DMatrix, DVector};
use serde::Serialize;

use crate::error::{InverseError, Result};
use crate::misfit::Misfit;
use crate::model::{Model, check_finite, check_jacobian, check_len};

/// z of a two-sided 95 % normal interval.
pub const Z95: f64 = 1.959_963_984_540_054;

/// How the Jacobian columns are scaled before the SVD.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum SensitivityScaling {
    /// s_k = |x_k| (relative sensitivity, d y / d ln x).
    Value,
    /// s_k = upper_k − lower_k (sensitivity over the domain).
    Range,
}

/// Local identifiability analysis at a parameter set.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Identifiability {
    /// Parameter names.
    pub names: Vec<String>,
    /// Parameter values (SI).
    pub x: Vec<f64>,
    /// Scaling used for the sensitivity matrix.
    pub scaling: SensitivityScaling,
    /// Singular values of the scaled sensitivity matrix, descending.
    pub singular_values: Vec<f64>,
    /// Right singular vectors (columns, in the order of `singular_values`),
    /// in scaled coordinates: column i tells which parameter combination
    /// singular value i belongs to.
    pub directions: Vec<Vec<f64>>,
    /// σ_1 / σ_n (infinite if σ_n = 0).
    pub condition_number: f64,
    /// σ̂² = Σ r̃² / (M − n) (range-normalised residual variance).
    pub residual_variance: f64,
    /// Number of stacked residuals M.
    pub residuals: usize,
    /// Standard errors √C_kk (SI; infinite if unidentifiable).
    pub std_errors: Vec<f64>,
    /// Approximate 95 % intervals (lower, upper) (SI).
    pub intervals: Vec<(f64, f64)>,
}

impl Identifiability {
    /// Half-width of the 95 % interval relative to |x_k|.
    pub fn relative_half_widths(&self) -> Vec<f64> {
        self.std_errors
            .iter()
            .zip(&self.x)
            .map(|(s, x)| Z95 * s / x.abs())
            .collect()
    }
}

/// Identifiability of the misfit's experiments at x.
///
/// # Errors
/// Model errors; [`InverseError::InvalidSetting`] if there are no more
/// residuals than parameters; [`InverseError::LinearAlgebra`] if the SVD
/// fails.
pub fn identifiability<M: Model>(
    misfit: &Misfit<M>,
    x: &[f64],
    scaling: SensitivityScaling,
) -> Result<Identifiability> {
    let domain = misfit.domain();
    domain.check_len(x)?;
    let n = domain.len();
    let total: usize = misfit.experiments().iter().map(|e| e.data.len()).sum();
    if total <= n {
        return Err(InverseError::InvalidSetting(format!(
            "identifiability needs more data points ({total}) than parameters ({n})"
        )));
    }
    let mut jt = DMatrix::zeros(total, n);
    let mut r = DVector::zeros(total);
    let mut row = 0;
    for e in misfit.experiments() {
        let (y, jac) = e.model.response_and_jacobian(x)?;
        check_finite(&y, e.model.times(), x)?;
        check_len(
            &format!("model curve of '{}'", e.label),
            e.data.len(),
            y.len(),
        )?;
        check_jacobian(&jac, y.len(), n)?;
        let range = e.data_range();
        for j in 0..y.len() {
            let sw = e.weights.as_ref().map_or(1.0, |w| w[j]).sqrt();
            r[row] = sw * (y[j] - e.data[j]) / range;
            for k in 0..n {
                jt[(row, k)] = sw * jac[(j, k)] / range;
            }
            row += 1;
        }
    }
    let scale: Vec<f64> = domain
        .params()
        .iter()
        .zip(x)
        .map(|(p, &v)| match scaling {
            SensitivityScaling::Value => v.abs(),
            SensitivityScaling::Range => p.upper - p.lower,
        })
        .collect();
    let mut s = jt.clone();
    for (k, &sk) in scale.iter().enumerate() {
        s.column_mut(k).scale_mut(sk);
    }
    let svd = s
        .try_svd(false, true, f64::EPSILON, 10_000)
        .ok_or_else(|| InverseError::LinearAlgebra("SVD of the scaled sensitivity".into()))?;
    let v_t = svd
        .v_t
        .ok_or_else(|| InverseError::LinearAlgebra("SVD without right vectors".into()))?;
    // nalgebra does not guarantee ordering: sort descending.
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| svd.singular_values[b].total_cmp(&svd.singular_values[a]));
    let singular_values: Vec<f64> = order.iter().map(|&i| svd.singular_values[i]).collect();
    let directions: Vec<Vec<f64>> = order
        .iter()
        .map(|&i| v_t.row(i).iter().copied().collect())
        .collect();
    let s_max = singular_values[0];
    let s_min = singular_values[n - 1];
    let condition_number = if s_min > 0.0 {
        s_max / s_min
    } else {
        f64::INFINITY
    };
    let residual_variance = r.norm_squared() / (total - n) as f64;
    let cutoff = total as f64 * f64::EPSILON * s_max;
    // C_x = σ̂² D V Σ⁻² Vᵀ D, diagonal only.
    let std_errors: Vec<f64> = (0..n)
        .map(|k| {
            let mut var = 0.0;
            for (i, dir) in directions.iter().enumerate() {
                let vk = dir[k];
                if vk == 0.0 {
                    continue;
                }
                if singular_values[i] <= cutoff {
                    return f64::INFINITY;
                }
                var += (vk / singular_values[i]).powi(2);
            }
            scale[k] * (residual_variance * var).sqrt()
        })
        .collect();
    let intervals = x
        .iter()
        .zip(&std_errors)
        .map(|(&v, &s)| (v - Z95 * s, v + Z95 * s))
        .collect();
    Ok(Identifiability {
        names: domain.params().iter().map(|p| p.name.clone()).collect(),
        x: x.to_vec(),
        scaling,
        singular_values,
        directions,
        condition_number,
        residual_variance,
        residuals: total,
        std_errors,
        intervals,
    })
}
