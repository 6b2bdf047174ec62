//! DACE correlation models (Lophaven et al. 2002, §2.4, Table 2.1).
//!
//! Every model is a product over input dimensions of a one-dimensional
//! kernel `s(θ_k, d_k)` of the (normalised) distance `d_k = x_k − s_k`:
//! `R(θ, d) = Π_k s(θ_k, d_k)`. `expg` carries one extra parameter, the
//! common power `p ∈ (0, 2]`, as the last entry of θ (as DACE's `correxpg`).

use serde::{Deserialize, Serialize};

/// A correlation family of the DACE toolbox.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Correlation {
    /// `exp(−θ d²)` (`corrgauss`).
    Gauss,
    /// `exp(−θ |d|)` (`correxp`).
    Exp,
    /// `exp(−θ |d|^p)`, p shared by all dimensions (`correxpg`).
    Expg,
    /// `max(0, 1 − θ|d|)` (`corrlin`).
    Lin,
    /// `1 − 1.5ξ + 0.5ξ³`, ξ = min(1, θ|d|) (`corrspherical`).
    Spherical,
    /// `1 − 3ξ² + 2ξ³`, ξ = min(1, θ|d|) (`corrcubic`).
    Cubic,
    /// Cubic spline in ξ = θ|d| (`corrspline`).
    Spline,
}

impl Correlation {
    /// All families, for parsing and tests.
    pub const ALL: [Correlation; 7] = [
        Correlation::Gauss,
        Correlation::Exp,
        Correlation::Expg,
        Correlation::Lin,
        Correlation::Spherical,
        Correlation::Cubic,
        Correlation::Spline,
    ];

    /// Name as used on the command line and in model files.
    pub fn name(self) -> &'static str {
        match self {
            Correlation::Gauss => "gauss",
            Correlation::Exp => "exp",
            Correlation::Expg => "expg",
            Correlation::Lin => "lin",
            Correlation::Spherical => "spherical",
            Correlation::Cubic => "cubic",
            Correlation::Spline => "spline",
        }
    }

    /// Parse a name (`gauss`, `corrgauss`, …).
    pub fn parse(s: &str) -> Option<Self> {
        let s = s.trim().to_ascii_lowercase();
        let s = s.strip_prefix("corr").unwrap_or(&s);
        Self::ALL.into_iter().find(|c| c.name() == s)
    }

    /// Number of θ entries for `dim` inputs.
    pub fn n_theta(self, dim: usize) -> usize {
        if self == Correlation::Expg {
            dim + 1
        } else {
            dim
        }
    }

    /// One-dimensional kernel: (s, ∂s/∂d, ∂s/∂θ, ∂s/∂p) for scale θ, power p
    /// (only `expg` uses p), distance d.
    #[inline]
    pub(crate) fn kernel(self, theta: f64, p: f64, d: f64) -> [f64; 4] {
        let a = d.abs();
        let sg = if d > 0.0 {
            1.0
        } else if d < 0.0 {
            -1.0
        } else {
            0.0
        };
        match self {
            Correlation::Gauss => {
                let s = (-theta * d * d).exp();
                [s, -2.0 * theta * d * s, -d * d * s, 0.0]
            }
            Correlation::Exp => {
                let s = (-theta * a).exp();
                [s, -theta * sg * s, -a * s, 0.0]
            }
            Correlation::Expg => {
                if a == 0.0 {
                    return [1.0, 0.0, 0.0, 0.0];
                }
                let ap = a.powf(p);
                let s = (-theta * ap).exp();
                [
                    s,
                    -theta * p * sg * a.powf(p - 1.0) * s,
                    -ap * s,
                    -theta * ap * a.ln() * s,
                ]
            }
            Correlation::Lin => {
                let xi = theta * a;
                if xi < 1.0 {
                    [1.0 - xi, -theta * sg, -a, 0.0]
                } else {
                    [0.0; 4]
                }
            }
            Correlation::Spherical => {
                let xi = theta * a;
                if xi < 1.0 {
                    let ds = 1.5 * (xi * xi - 1.0);
                    [
                        1.0 - xi * (1.5 - 0.5 * xi * xi),
                        ds * theta * sg,
                        ds * a,
                        0.0,
                    ]
                } else {
                    [0.0; 4]
                }
            }
            Correlation::Cubic => {
                let xi = theta * a;
                if xi < 1.0 {
                    let ds = 6.0 * xi * (xi - 1.0);
                    [
                        1.0 - xi * xi * (3.0 - 2.0 * xi),
                        ds * theta * sg,
                        ds * a,
                        0.0,
                    ]
                } else {
                    [0.0; 4]
                }
            }
            Correlation::Spline => {
                let xi = theta * a;
                let (s, ds) = if xi <= 0.2 {
                    (1.0 - xi * xi * (15.0 - 30.0 * xi), xi * (-30.0 + 90.0 * xi))
                } else if xi < 1.0 {
                    let u = 1.0 - xi;
                    (1.25 * u * u * u, -3.75 * u * u)
                } else {
                    (0.0, 0.0)
                };
                [s, ds * theta * sg, ds * a, 0.0]
            }
        }
    }

    /// Correlation `R(θ, d)` (Lophaven et al. eq. 2.18 with Table 2.1).
    pub fn value(self, theta: &[f64], d: &[f64]) -> f64 {
        let p = self.power(theta);
        d.iter()
            .zip(theta)
            .map(|(&dk, &tk)| self.kernel(tk, p, dk)[0])
            .product()
    }

    /// Correlation and its gradient with respect to d (written into `grad`).
    pub fn value_and_grad_d(self, theta: &[f64], d: &[f64], grad: &mut [f64]) -> f64 {
        let p = self.power(theta);
        let dim = d.len();
        let mut ks = [[0.0; 4]; 16];
        let mut big = Vec::new();
        let ks: &mut [[f64; 4]] = if dim <= 16 {
            &mut ks[..dim]
        } else {
            big.resize(dim, [0.0; 4]);
            &mut big
        };
        for k in 0..dim {
            ks[k] = self.kernel(theta[k], p, d[k]);
        }
        let mut r = 1.0;
        for k in 0..dim {
            r *= ks[k][0];
            let mut others = 1.0;
            for (l, kl) in ks.iter().enumerate() {
                if l != k {
                    others *= kl[0];
                }
            }
            grad[k] = others * ks[k][1];
        }
        r
    }

    /// Correlation and its gradient with respect to θ (length `n_theta`).
    pub fn value_and_grad_theta(self, theta: &[f64], d: &[f64], grad: &mut [f64]) -> f64 {
        let p = self.power(theta);
        let dim = d.len();
        let mut r = 1.0;
        let mut dp = 0.0;
        for k in 0..dim {
            let kk = self.kernel(theta[k], p, d[k]);
            r *= kk[0];
            let mut others = 1.0;
            for l in 0..dim {
                if l != k {
                    others *= self.kernel(theta[l], p, d[l])[0];
                }
            }
            grad[k] = others * kk[2];
            dp += others * kk[3];
        }
        if self == Correlation::Expg {
            grad[dim] = dp;
        }
        r
    }

    fn power(self, theta: &[f64]) -> f64 {
        if self == Correlation::Expg {
            theta.last().copied().unwrap_or(2.0)
        } else {
            1.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gradients_match_central_differences_for_every_family() {
        let d = [0.13, -0.27, 0.05];
        for c in Correlation::ALL {
            let mut theta = vec![1.3, 0.7, 2.1];
            if c == Correlation::Expg {
                theta.push(1.6);
            }
            let mut gd = vec![0.0; 3];
            c.value_and_grad_d(&theta, &d, &mut gd);
            for k in 0..3 {
                let h = 1e-6;
                let (mut dp, mut dm) = (d, d);
                dp[k] += h;
                dm[k] -= h;
                let fd = (c.value(&theta, &dp) - c.value(&theta, &dm)) / (2.0 * h);
                assert!((fd - gd[k]).abs() < 1e-7, "{c:?} d{k}: {fd} vs {}", gd[k]);
            }
            let mut gt = vec![0.0; theta.len()];
            c.value_and_grad_theta(&theta, &d, &mut gt);
            for k in 0..theta.len() {
                let h = 1e-6;
                let (mut tp, mut tm) = (theta.clone(), theta.clone());
                tp[k] += h;
                tm[k] -= h;
                let fd = (c.value(&tp, &d) - c.value(&tm, &d)) / (2.0 * h);
                assert!((fd - gt[k]).abs() < 1e-7, "{c:?} θ{k}: {fd} vs {}", gt[k]);
            }
        }
    }

    #[test]
    fn every_family_is_one_at_zero_distance() {
        for c in Correlation::ALL {
            let theta = vec![2.0; c.n_theta(2)];
            assert_eq!(c.value(&theta, &[0.0, 0.0]), 1.0);
        }
    }
}
