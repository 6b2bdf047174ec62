//! The screen of the sampler's delayed acceptance (issue 17;
//! [`super::ensemble`] module docs, "Delayed acceptance"): ln L̃(u), the
//! likelihood with the calibrated Kriging variance v(x) replaced by a
//! quadratic model of ln v in the unit coordinates u, fitted to v at the
//! sampler's start positions and refitted after each burn-in with the
//! walkers' positions added.
//!
//! Why a model of v and not v itself: v(x) costs the O(N²) triangular
//! solve C⁻¹r(x), ≈ 74 % of a likelihood evaluation's instructions on the
//! demo meta-model (N = 970), while the mean c(x) costs O(N·(q + d))
//! (`likelihood_batch_cost screen`). Why not a constant: on the
//! demo's cells the Kriging error is comparable with the 2 % noise, so
//! ln L moves by several units across a posterior when v is held at its
//! value at the optimum; such a screen passes proposals that the full
//! likelihood then rejects (half of them evaluated for a third of them
//! accepted, docs/theory/inverse.md, "Session 15"). ln v is smooth over a
//! posterior's bulk, which a quadratic in u follows.
//!
//! The screen changes only at the end of a burn-in (once, twice with a
//! tempered restart): between those, every kernel keeps the posterior
//! invariant, and the kernel changes a finite number of times (finite
//! adaptation, as the independence proposal's refits; no kept draw is
//! taken before the first refit). One screen serves every ensemble, fitted
//! to all their positions: the ensembles run with the same kernel, as R̂
//! assumes. Delayed acceptance is exact for any screen; a poor one costs
//! only evaluations and acceptance.

use nalgebra::{DMatrix, DVector};

/// ln v(u) ≈ a + Σ b_i u_i + Σ_{i≤j} c_ij u_i u_j, clamped to the range
/// of ln v it was fitted to (a quadratic can run off outside the points
/// it was fitted on, e.g. on an axis refresh that redraws a coordinate
/// over the whole domain).
#[derive(Debug, Clone, PartialEq)]
pub struct VarianceModel {
    coefficients: DVector<f64>,
    /// Monomials of the model: 0 constant, 1 linear, 2 quadratic.
    degree: usize,
    lowest: f64,
    highest: f64,
}

impl VarianceModel {
    /// The least-squares fit of ln v at points `us` (unit coordinates)
    /// with calibrated variances `variances`: quadratic when there are at
    /// least twice as many points (with v > 0) as monomials, else linear
    /// under the same rule, else the mean of ln v. None without a single
    /// point with v > 0 or when the least-squares solve fails.
    pub fn fit(us: &[Vec<f64>], variances: &[f64]) -> Option<Self> {
        let points: Vec<(&Vec<f64>, f64)> = us
            .iter()
            .zip(variances)
            .filter(|(_, v)| **v > 0.0 && v.is_finite())
            .map(|(u, v)| (u, v.ln()))
            .collect();
        let d = points.first()?.0.len();
        let degree = [2, 1, 0]
            .into_iter()
            .find(|&k| points.len() >= 2 * monomials(d, k))
            .unwrap_or(0);
        let p = monomials(d, degree);
        let mut a = DMatrix::zeros(points.len(), p);
        let mut row = vec![0.0; p];
        for (i, (u, _)) in points.iter().enumerate() {
            features(u, degree, &mut row);
            for (j, f) in row.iter().enumerate() {
                a[(i, j)] = *f;
            }
        }
        let b = DVector::from_iterator(points.len(), points.iter().map(|(_, l)| *l));
        let coefficients = a.svd(true, true).solve(&b, 1e-12).ok()?;
        let (lowest, highest) = points
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), (_, l)| {
                (lo.min(*l), hi.max(*l))
            });
        coefficients.iter().all(|c| c.is_finite()).then_some(Self {
            coefficients,
            degree,
            lowest,
            highest,
        })
    }

    /// The modelled calibrated variance at unit coordinates `u`.
    pub fn variance(&self, u: &[f64]) -> f64 {
        let mut row = vec![0.0; self.coefficients.len()];
        features(u, self.degree, &mut row);
        let ln_v: f64 = row.iter().zip(&self.coefficients).map(|(f, c)| f * c).sum();
        ln_v.clamp(self.lowest, self.highest).exp()
    }
}

/// Number of monomials of degree ≤ `degree` (≤ 2) in `d` variables.
fn monomials(d: usize, degree: usize) -> usize {
    match degree {
        0 => 1,
        1 => 1 + d,
        _ => 1 + d + d * (d + 1) / 2,
    }
}

/// The monomials 1, u_i, u_i u_j (i ≤ j) up to `degree`, into `out`.
fn features(u: &[f64], degree: usize, out: &mut [f64]) {
    out[0] = 1.0;
    if degree == 0 {
        return;
    }
    let d = u.len();
    out[1..=d].copy_from_slice(u);
    if degree == 1 {
        return;
    }
    let mut k = d + 1;
    for i in 0..d {
        for j in i..d {
            out[k] = u[i] * u[j];
            k += 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A log-quadratic v is reproduced to rounding; with too few points
    /// for a quadratic the fit falls back to a plane, then to the mean;
    /// outside the fitted range ln v is clamped.
    #[test]
    fn a_log_quadratic_variance_is_recovered_and_clamped() {
        let truth = |u: &[f64]| {
            (-3.0 + 0.5 * u[0] - 1.5 * u[1] + 2.0 * u[0] * u[1] + 0.7 * u[2] * u[2]).exp()
        };
        // A deterministic scatter in [0.2, 0.8]³.
        let us: Vec<Vec<f64>> = (0..40)
            .map(|i| {
                let t = f64::from(i);
                vec![
                    0.2 + 0.6 * (0.37 * t).fract(),
                    0.2 + 0.6 * (0.61 * t + 0.1).fract(),
                    0.2 + 0.6 * (0.83 * t + 0.3).fract(),
                ]
            })
            .collect();
        let vs: Vec<f64> = us.iter().map(|u| truth(u)).collect();
        let m = VarianceModel::fit(&us, &vs).expect("fit");
        assert_eq!(m.degree, 2);
        for u in [[0.3, 0.4, 0.5], [0.7, 0.25, 0.6], [0.5, 0.5, 0.5]] {
            assert!((m.variance(&u) / truth(&u) - 1.0).abs() < 1e-10, "{u:?}");
        }
        let (lo, hi) = vs
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(a, b), v| (a.min(*v), b.max(*v)));
        for u in [[0.0, 1.0, 0.0], [1.0, 0.0, 1.0]] {
            let v = m.variance(&u);
            assert!(
                v >= lo * (1.0 - 1e-12) && v <= hi * (1.0 + 1e-12),
                "{u:?}: {v}"
            );
        }
        let plane = VarianceModel::fit(&us[..12], &vs[..12]).expect("plane");
        assert_eq!(plane.degree, 1);
        let mean = VarianceModel::fit(&us[..5], &vs[..5]).expect("mean");
        assert_eq!(mean.degree, 0);
        let want = (vs[..5].iter().map(|v| v.ln()).sum::<f64>() / 5.0).exp();
        assert!((mean.variance(&[0.5, 0.5, 0.5]) / want - 1.0).abs() < 1e-12);
        assert!(VarianceModel::fit(&us[..3], &[0.0, f64::NAN, -1.0]).is_none());
    }
}
