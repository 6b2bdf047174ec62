//! The regression part of a Kriging model in physical units: the trend
//! μ_j(x) = Σ_i β_ij f_i(x) of the predictor (report eq. 2.16) written as a
//! polynomial in the kriged input coordinates (x, or ln x for log inputs)
//! with coefficients in output units, rather than in the standardised
//! inputs and outputs (and PC scores) the fit works in.

use crate::kriging::KrigingModel;
use crate::regression::Regression;

/// One term of the trend polynomial: the product of the listed inputs
/// (empty: the constant; `[k]`: x_k; `[k, l]`: x_k x_l).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TrendTerm {
    /// Input indices (0-based), each factor once per power.
    pub inputs: Vec<usize>,
}

/// μ_j(x) = Σ_terms c_tj Π x_k over the kriged coordinates; with
/// `log_outputs` in ln y, with an output scale in the kriged y/s.
#[derive(Debug, Clone, PartialEq)]
pub struct Trend {
    /// The polynomial terms.
    pub terms: Vec<TrendTerm>,
    /// Coefficients, `coefficients[t][j]` for term t and output j.
    pub coefficients: Vec<Vec<f64>>,
}

impl KrigingModel {
    /// The trend in physical units (see the module doc): the standardised
    /// β, unscaled through the PCA basis and the output deviations, with
    /// the input standardisation x̃ = (x − μ)/s expanded.
    pub fn trend(&self) -> Trend {
        let (d, m) = (self.dim, self.n_outputs);
        let p = self.regression.n_terms(d);
        let (b, mu) = self.basis_coefficients();
        let nb = self.n_basis();
        let mean = |j: usize| {
            if self.output_scale.is_some() {
                b[j * nb + nb - 1]
            } else {
                mu[j]
            }
        };
        let beta = |a: usize, j: usize| b[j * nb + a];
        let (xm, xs) = (&self.x_mean, &self.x_std);
        let mut terms = vec![TrendTerm { inputs: vec![] }];
        let mut coefficients = vec![(0..m).map(mean).collect::<Vec<_>>()];
        let linear = self.regression != Regression::Poly0;
        if linear {
            for k in 0..d {
                terms.push(TrendTerm { inputs: vec![k] });
                coefficients.push(vec![0.0; m]);
            }
        }
        // Add c·Π x̃ over `idx` (normalised) to the physical polynomial.
        let add = |idx: &[usize], c: &[f64], coefficients: &mut Vec<Vec<f64>>| match *idx {
            [] => (0..m).for_each(|j| coefficients[0][j] += c[j]),
            [k] => {
                for j in 0..m {
                    coefficients[1 + k][j] += c[j] / xs[k];
                    coefficients[0][j] -= c[j] * xm[k] / xs[k];
                }
            }
            [k, l] => {
                let s = xs[k] * xs[l];
                for j in 0..m {
                    let q = c[j] / s;
                    coefficients[1 + k][j] -= q * xm[l];
                    coefficients[1 + l][j] -= q * xm[k];
                    coefficients[0][j] += q * xm[k] * xm[l];
                }
            }
            _ => {}
        };
        let col = |a: usize| (0..m).map(|j| beta(a, j)).collect::<Vec<_>>();
        add(&[], &col(0), &mut coefficients);
        if linear {
            for k in 0..d {
                add(&[k], &col(1 + k), &mut coefficients);
            }
        }
        if self.regression == Regression::Poly2 {
            let mut a = 1 + d;
            for k in 0..d {
                for l in k..d {
                    let c = col(a);
                    add(&[k, l], &c, &mut coefficients);
                    terms.push(TrendTerm { inputs: vec![k, l] });
                    coefficients.push(c.iter().map(|v| v / (xs[k] * xs[l])).collect());
                    a += 1;
                }
            }
        }
        debug_assert_eq!(terms.len(), p);
        Trend {
            terms,
            coefficients,
        }
    }
}

impl Trend {
    /// μ_j(x) at a point in the kriged coordinates.
    pub fn value(&self, x: &[f64], j: usize) -> f64 {
        self.terms
            .iter()
            .zip(&self.coefficients)
            .map(|(t, c)| c[j] * t.inputs.iter().map(|&k| x[k]).product::<f64>())
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Correlation, KrigingSettings, ThetaSearch};
    use faer::Mat;

    /// The trend in physical units equals the trend evaluated the way the
    /// predictor does (standardised x, f(x̃), unscaled β), for every
    /// regression, with and without PCA.
    #[test]
    fn physical_trend_equals_the_standardised_trend_at_any_point() {
        let n = 30;
        let x = Mat::from_fn(n, 2, |i, k| {
            let t = i as f64 / n as f64;
            if k == 0 {
                3.0 + 5.0 * t
            } else {
                200.0 * (7.0 * t).sin() + 500.0
            }
        });
        let y = Mat::from_fn(n, 3, |i, j| {
            let (a, b) = (x[(i, 0)], x[(i, 1)]);
            (j as f64 + 1.0) * (a * a + 0.01 * b) + (a * b * 1e-3).sin()
        });
        for reg in [Regression::Poly0, Regression::Poly1, Regression::Poly2] {
            for pca in [None, Some(0.999_999)] {
                let mut s = KrigingSettings::new(reg, Correlation::Gauss, 2);
                s.theta = ThetaSearch::Fixed(vec![1.0, 1.0]);
                s.pca_energy = pca;
                let model = KrigingModel::fit(x.as_ref(), y.as_ref(), &s).expect("fit");
                let trend = model.trend();
                let (b, mu) = model.basis_coefficients();
                let nb = model.n_basis();
                let p = reg.n_terms(2);
                for pt in [[4.0, 450.0], [7.5, 690.0], [3.1, 330.0]] {
                    let xn: Vec<f64> = (0..2)
                        .map(|k| (pt[k] - model.x_mean[k]) / model.x_std[k])
                        .collect();
                    let mut f = vec![0.0; p];
                    reg.eval(&xn, &mut f);
                    for j in 0..3 {
                        let direct: f64 = mu[j] + (0..p).map(|a| b[j * nb + a] * f[a]).sum::<f64>();
                        let got = trend.value(&pt, j);
                        assert!(
                            (got - direct).abs() <= 1e-9 * direct.abs().max(1.0),
                            "{reg:?} pca {pca:?} at {pt:?}, output {j}: {got} vs {direct}"
                        );
                    }
                }
            }
        }
    }
}
