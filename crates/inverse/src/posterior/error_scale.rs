//! The surrogate error's scale in the likelihood (issue 17;
//! docs/theory/inverse.md, "Session 17").
//!
//! A curve's likelihood under Σ(ρ) = σ²(I + ρK̃) depends on the data only
//! through a spectrum: eigenvalues λ_i of the surrogate covariance in
//! units of its scale (UᵀU, or K's diagonal), the residual's coordinates
//! z_i along them and its squared norm rᵀr, so that
//!
//!   ln f(ρ) = −½ [m ln σ² + Σ ln(1 + ρλ_i) + (rᵀr − ρ Σ z_i²/(1 + ρλ_i))/σ²].
//!
//! With a Gaussian surrogate error ρ = v/σ² (v the calibrated Kriging
//! variance) and ln L = ln f(v/σ²). With the Student-t calibration
//! (`VarianceCalibration::nu` finite) the error's variance is w·v with
//! 1/w ~ Gamma(ν/2, rate ν/2), and w is integrated out:
//!
//!   L = ∫ f(w v/σ²) p(w) dw = ∫ exp h(u) du,  u = ln w,
//!   h(u) = ln f(e^u v/σ²) + (ν/2) ln(ν/2) − ln Γ(ν/2) − (ν/2)(u + e^{−u}),
//!
//! by Gauss–Hermite quadrature centred on the mode of h (safeguarded
//! Newton on h′, analytic h″) and scaled by its curvature (Laplace's
//! approximation with its Gaussian replaced by a 32-node rule).

use nalgebra::DMatrix;

/// Nodes of the Gauss–Hermite rule for the mixture integral: 32 keep
/// ln L within 4e-6 of a fine trapezoid rule for ν ≥ 1 (20: 1.2e-4).
const NODES: usize = 32;

/// The residual's spectrum (module docs): everything ln f(ρ) needs.
pub(crate) struct Spectrum<'a> {
    /// λ_i ≥ 0.
    pub lambda: &'a [f64],
    /// z_i, the residual's coordinate along λ_i's direction.
    pub z: &'a [f64],
    /// rᵀr.
    pub rtr: f64,
    /// σ².
    pub s2: f64,
    /// Number of data points m.
    pub m: f64,
}

impl Spectrum<'_> {
    /// ln f(ρ) (module docs), without −(m/2) ln 2π.
    pub fn ln_f(&self, rho: f64) -> f64 {
        self.ln_f_with(rho, false)
    }

    /// ln f(ρ) with ln det as a sum of lns, or (`one_ln`, the mixture's
    /// 32 nodes) as the ln of one product — 1.8× → 1.5× the Gaussian
    /// screen's cost — falling back to the sum where the product would
    /// leave f64's range. The Gaussian keeps the sum: the same bits as
    /// before the mixture existed.
    fn ln_f_with(&self, rho: f64, one_ln: bool) -> f64 {
        let (mut logdet, mut det, mut zez) = (0.0, 1.0, 0.0);
        for (zi, li) in self.z.iter().zip(self.lambda) {
            let e = 1.0 + rho * li;
            if one_ln {
                det *= e;
            } else {
                logdet += e.ln();
            }
            zez += zi * zi / e;
        }
        if one_ln {
            logdet = if det.is_finite() && det > 1e-300 {
                det.ln()
            } else {
                self.lambda.iter().map(|li| (1.0 + rho * li).ln()).sum()
            };
        }
        let quad = (self.rtr.max(0.0) - rho * zez) / self.s2;
        -0.5 * (self.m * self.s2.ln() + logdet + quad)
    }

    /// ρ·d ln f/dρ and ρ²·d² ln f/dρ² (the derivatives in ln ρ, less the
    /// first-order term of the second).
    fn ln_f_slopes(&self, rho: f64) -> (f64, f64) {
        let (mut a, mut b, mut c, mut d) = (0.0, 0.0, 0.0, 0.0);
        for (zi, li) in self.z.iter().zip(self.lambda) {
            let inv = 1.0 / (1.0 + rho * li);
            let z2 = zi * zi * inv * inv;
            a += li * inv;
            b += z2;
            c += li * li * inv * inv;
            d += z2 * li * inv;
        }
        let d1 = -0.5 * (a - b / self.s2);
        let d2 = -0.5 * (-c + 2.0 * d / self.s2);
        (rho * d1, rho * rho * d2)
    }
}

/// How the surrogate error's scale enters ln L: fixed (Gaussian) or
/// integrated over a Student-t mixture (module docs).
#[derive(Debug, Clone)]
pub(crate) enum ErrorScale {
    Gaussian,
    Student {
        /// ν/2.
        half_nu: f64,
        /// (ν/2) ln(ν/2) − ln Γ(ν/2).
        ln_prior_norm: f64,
        /// Gauss–Hermite nodes t_j and ln ω_j + t_j² (for ∫ e^{−t²} g).
        nodes: Vec<(f64, f64)>,
    },
}

impl ErrorScale {
    /// Gaussian for ν = ∞, the Student-t mixture for finite ν > 0.
    pub fn new(nu: f64) -> Self {
        if !nu.is_finite() {
            return Self::Gaussian;
        }
        let half_nu = 0.5 * nu;
        Self::Student {
            half_nu,
            ln_prior_norm: half_nu * half_nu.ln() - libm::lgamma(half_nu),
            nodes: gauss_hermite(NODES),
        }
    }

    /// ln L of the spectrum at the error variance `rho0` = v/σ² (module
    /// docs).
    pub fn ln_likelihood(&self, spectrum: &Spectrum<'_>, rho0: f64) -> f64 {
        let Self::Student {
            half_nu,
            ln_prior_norm,
            nodes,
        } = self
        else {
            return spectrum.ln_f(rho0);
        };
        if !(rho0 > 0.0) {
            return spectrum.ln_f(0.0);
        }
        let h = |u: f64| {
            spectrum.ln_f_with(rho0 * u.exp(), true) + ln_prior_norm - half_nu * (u + (-u).exp())
        };
        // h′ and h″ in u.
        let slopes = |u: f64| {
            let (d1, d2) = spectrum.ln_f_slopes(rho0 * u.exp());
            let e = half_nu * (-u).exp();
            (d1 - half_nu + e, d1 + d2 - e)
        };
        let mode = newton_root(slopes);
        let curvature = slopes(mode).1;
        // Not concave at the root found (not expected: h″ < 0 wherever the
        // prior's term dominates): fall back to unit width.
        let width = if curvature < 0.0 {
            (-2.0 / curvature).sqrt()
        } else {
            1.0
        };
        let h0 = h(mode);
        let sum: f64 = nodes
            .iter()
            .map(|&(t, ln_w)| (h(mode + width * t) - h0 + ln_w).exp())
            .sum();
        h0 + (width * sum).ln()
    }
}

/// A root of h′ (decreasing through it: h′ → +∞ as u → −∞ by the prior's
/// e^{−u}, h′ < 0 for large u) by Newton's method on h′ with h″, kept
/// inside a bracket and bisected when a step leaves it.
fn newton_root(slopes: impl Fn(f64) -> (f64, f64)) -> f64 {
    let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
    let mut u = 0.0;
    for _ in 0..100 {
        let (g, gp) = slopes(u);
        if g > 0.0 {
            lo = u;
        } else {
            hi = u;
        }
        let mut next = if gp < 0.0 { u - g / gp } else { f64::NAN };
        if !(next > lo && next < hi) {
            next = match (lo.is_finite(), hi.is_finite()) {
                (true, true) => 0.5 * (lo + hi),
                (true, false) => lo + 2.0,
                (false, true) => hi - 2.0,
                (false, false) => u,
            };
        }
        if (next - u).abs() < 1e-10 {
            return next;
        }
        u = next;
    }
    u
}

/// Gauss–Hermite rule of `n` nodes for ∫ e^{−t²} g(t) dt, by the
/// Golub–Welsch eigenvalue method: nodes t_j and ln ω_j + t_j².
fn gauss_hermite(n: usize) -> Vec<(f64, f64)> {
    let jacobi = DMatrix::from_fn(n, n, |i, j| {
        if i + 1 == j || j + 1 == i {
            (0.5 * i.max(j) as f64).sqrt()
        } else {
            0.0
        }
    });
    let eig = jacobi.symmetric_eigen();
    let mut nodes: Vec<(f64, f64)> = (0..n)
        .map(|j| {
            let t = eig.eigenvalues[j];
            let v0 = eig.eigenvectors[(0, j)];
            // ω_j = √π v_0j².
            (
                t,
                0.5 * std::f64::consts::PI.ln() + 2.0 * v0.abs().ln() + t * t,
            )
        })
        .collect();
    nodes.sort_by(|a, b| a.0.total_cmp(&b.0));
    nodes
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The rule integrates e^{−t²}·t^{2p} exactly for 2p < 2n (here up
    /// to t^{38}) — checked for p = 0, 1, 2, 5: √π (2p − 1)!!/2^p.
    #[test]
    fn gauss_hermite_rule_integrates_even_moments() {
        let rule = gauss_hermite(NODES);
        for p in [0, 1, 2, 5] {
            let ours: f64 = rule
                .iter()
                .map(|&(t, lw)| (lw - t * t).exp() * t.powi(2 * p))
                .sum();
            let double_factorial: f64 = (1..=p).map(|i| (2 * i - 1) as f64).product();
            let want = std::f64::consts::PI.sqrt() * double_factorial / 2f64.powi(p);
            assert!((ours / want - 1.0).abs() < 1e-12, "p {p}: {ours} vs {want}");
        }
    }

    /// The mixture's ln L equals a brute-force trapezoid integral over
    /// u = ln w on a fine grid (second method) for spectra where the data
    /// pull w below, near and above 1, for ν from 1 to 50; and a Gaussian
    /// scale is ln f(ρ₀) itself.
    #[test]
    fn student_mixture_equals_a_fine_trapezoid_integral() {
        let lambda: [f64; 8] = [40.0, 12.0, 5.0, 2.0, 0.7, 0.3, 0.05, 0.0];
        for (scale, rho0) in [
            (0.1, 1.0f64),
            (1.0, 1.0),
            (8.0, 1.0),
            (1.0, 1e-3),
            (3.0, 50.0),
        ] {
            // z = QᵀUᵀr, so z_i = 0 where λ_i = 0 and rᵀr ≥ Σ z_i²/λ_i.
            let z: Vec<f64> = lambda
                .iter()
                .enumerate()
                .map(|(i, l)| {
                    let sign = if i % 2 == 0 { 1.0 } else { -0.7 };
                    scale * (l * (1.0 + l * rho0)).sqrt() * sign
                })
                .collect();
            let outside: f64 = z
                .iter()
                .zip(&lambda)
                .filter(|(_, l)| **l > 0.0)
                .map(|(z, l)| z * z / l)
                .sum();
            let spectrum = Spectrum {
                lambda: &lambda,
                z: &z,
                rtr: outside + 300.0,
                s2: 1.0,
                m: 300.0,
            };
            assert_eq!(
                ErrorScale::Gaussian.ln_likelihood(&spectrum, rho0),
                spectrum.ln_f(rho0)
            );
            for nu in [1.0, 2.0, 3.0, 5.2, 50.0] {
                let ours = ErrorScale::new(nu).ln_likelihood(&spectrum, rho0);
                let half = 0.5 * nu;
                let h = |u: f64| {
                    spectrum.ln_f(rho0 * u.exp()) + half * half.ln()
                        - libm::lgamma(half)
                        - half * (u + (-u).exp())
                };
                let (a, b, n) = (-30.0, 30.0, 60_000);
                let du = (b - a) / n as f64;
                let top = (0..=n)
                    .map(|i| h(a + du * i as f64))
                    .fold(f64::MIN, f64::max);
                let sum: f64 = (0..=n)
                    .map(|i| {
                        let w = if i == 0 || i == n { 0.5 } else { 1.0 };
                        w * (h(a + du * i as f64) - top).exp()
                    })
                    .sum();
                let brute = top + (sum * du).ln();
                assert!(
                    (ours - brute).abs() < 1e-5,
                    "scale {scale}, rho0 {rho0}, nu {nu}: {ours} vs {brute}"
                );
            }
        }
    }
}
