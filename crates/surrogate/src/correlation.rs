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
        let mut small = [[0.0; 4]; 16];
        let mut big = Vec::new();
        let ks: &mut [[f64; 4]] = if dim <= 16 {
            &mut small[..dim]
        } else {
            big.resize(dim, [0.0; 4]);
            &mut big
        };
        for k in 0..dim {
            ks[k] = self.kernel(theta[k], p, d[k]);
        }
        let r: f64 = ks.iter().map(|k| k[0]).product();
        let mut dp = 0.0;
        for k in 0..dim {
            let others: f64 = ks
                .iter()
                .enumerate()
                .filter(|(l, _)| *l != k)
                .map(|(_, kl)| kl[0])
                .product();
            grad[k] = others * ks[k][2];
            dp += others * ks[k][3];
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

/// exp(−a) of one a ≥ 0: the Gaussian correlation exp(−Σ_k θ_k d_k²)
/// from its exponent. Cody–Waite: n = round(−a·log₂e) (by adding and
/// subtracting 1.5·2⁵²), r = −a − n·ln 2 in two parts (|r| ≤ ln 2 / 2),
/// exp(r) by its Taylor polynomial to r¹³ (remainder below 4e-18), times
/// 2ⁿ built from n's bits; within 1 ulp of libm's `exp` (test below), 0 for
/// a ≥ 708.39 (where exp(−a) < 2.3e-308), NaN for NaN.
///
/// Written here rather than called from libm or `wide`: it is
/// straight-line code that LLVM vectorises inside
/// `KrigingModel::correlation_column`'s loop, at the CPU's widest SIMD
/// width once that loop is dispatched at run time (libm's scalar `exp` was
/// half the instructions of a prediction's mean; `wide`'s four-lane exp
/// compiles for the baseline's two lanes only; issue 17,
/// docs/theory/inverse.md "Session 16"). Rust never fuses `a * b + c`, so
/// every instruction set gives the same bits.
#[inline(always)]
pub(crate) fn exp_neg(a: f64) -> f64 {
    const LN2_HI: f64 = 0.693_145_751_953_125;
    const LN2_LO: f64 = 1.428_606_820_309_417_3e-6;
    const SHIFT: f64 = 6_755_399_441_055_744.0;
    // 1/k! for k = 13 down to 2.
    const INV_FACTORIAL: [f64; 12] = [
        1.0 / 6_227_020_800.0,
        1.0 / 479_001_600.0,
        1.0 / 39_916_800.0,
        1.0 / 3_628_800.0,
        1.0 / 362_880.0,
        1.0 / 40_320.0,
        1.0 / 5_040.0,
        1.0 / 720.0,
        1.0 / 120.0,
        1.0 / 24.0,
        1.0 / 6.0,
        0.5,
    ];
    let x = -a;
    let t = x * std::f64::consts::LOG2_E + SHIFT;
    let n = t - SHIFT;
    let r = (x - n * LN2_HI) - n * LN2_LO;
    let mut p = INV_FACTORIAL[0];
    for c in &INV_FACTORIAL[1..] {
        p = p * r + c;
    }
    let p = (p * r + 1.0) * r + 1.0;
    // n + 1023 in the exponent field: 2ⁿ, normal for n ≥ −1022.
    let biased = t.to_bits().wrapping_sub(SHIFT.to_bits()).wrapping_add(1023);
    let scaled = p * f64::from_bits(biased << 52);
    if a >= 708.39 { 0.0 } else { scaled }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// exp(−a) against libm's exp over the exponents a Gaussian
    /// correlation takes (0 to past underflow): within 1 ulp (of the
    /// value's binade) below 708.39, 0 from there, NaN for NaN.
    #[test]
    fn exp_neg_is_libm_exp_within_one_ulp() {
        let mut a: Vec<f64> = (0..200_000)
            .map(|i| 750.0 * (f64::from(i) / 200_000.0).powi(3))
            .collect();
        a.extend([
            0.0,
            1e-300,
            1e-17,
            0.5 * std::f64::consts::LN_2,
            708.0,
            708.39,
            745.2,
        ]);
        a.extend([f64::INFINITY]);
        let mut worst = 0.0f64;
        for &ai in &a {
            let e = exp_neg(ai);
            let want = (-ai).exp();
            if ai < 708.39 {
                let ulp = f64::EPSILON * 2f64.powi(want.log2().floor() as i32);
                worst = worst.max((e - want).abs() / ulp);
            } else {
                assert!(e == 0.0 && want < 3e-308, "exp(-{ai}) = {e}, libm {want}");
            }
        }
        assert!(worst <= 1.0, "worst error {worst} ulp");
        assert_eq!(exp_neg(0.0), 1.0);
        assert!(exp_neg(f64::NAN).is_nan());
    }

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
