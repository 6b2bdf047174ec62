//! Small reference materials written inside the fem crate, used to verify
//! the engine independently of the `material` crate and to drive the AFM
//! model until the thesis's Prony model (eq. 5.1, §4.3) is wired in.
//!
//! - [`NeoHookean`]: decoupled compressible neo-Hookean,
//!   Ψ = μ/2 (J^{-2/3} I₁ − 3) + κ/2 (J − 1)².
//! - [`PronyNeoHookean`]: the same with Simo's (1987) finite-strain Prony
//!   relaxation of the isochoric second Piola–Kirchhoff stress,
//!   G(t) = μ (g_∞ + Σ g_k e^{−t/τ_k}), g_∞ = 1 − Σ g_k (eq. 5.1), held as
//!   the shared `nlvid_model::Relaxation`. In the
//!   small-strain limit it is exactly linear viscoelasticity with G(t) and a
//!   constant bulk modulus κ, which is what the Lee–Radok check needs.

use nlvid_material::{Mat3, Material3, MaterialError, PointResponse3, PointState, Tangent3};
use nlvid_model::Relaxation;

/// Decoupled compressible neo-Hookean solid.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NeoHookean {
    /// Shear modulus μ (Pa).
    pub mu: f64,
    /// Bulk modulus κ (Pa).
    pub kappa: f64,
}

/// Isochoric (μ = 1) and volumetric (κ = 1) parts of P and ∂P/∂F.
struct Split {
    p_iso: Mat3,
    a_iso: Tangent3,
    p_vol: Mat3,
    a_vol: Tangent3,
}

fn split(f: &Mat3) -> Result<Split, MaterialError> {
    let j = f.determinant();
    if !(j > 0.0) {
        return Err(MaterialError::Deformation(format!("det F = {j:.3e} ≤ 0")));
    }
    let fi = f
        .try_inverse()
        .ok_or_else(|| MaterialError::Deformation("singular F".into()))?;
    let i1 = f.norm_squared();
    let c = j.powf(-2.0 / 3.0);
    let fit = fi.transpose();
    let p_iso = c * (f - (i1 / 3.0) * fit);
    let p_vol = (j * j - j) * fit;
    let mut a_iso = Tangent3::zeros();
    let mut a_vol = Tangent3::zeros();
    for i in 0..3 {
        for jj in 0..3 {
            for k in 0..3 {
                for l in 0..3 {
                    let d = if i == k && jj == l { 1.0 } else { 0.0 };
                    // ∂F⁻¹_Ji/∂F_kL = −F⁻¹_Jk F⁻¹_Li
                    let a = c
                        * (d - 2.0 / 3.0 * f[(i, jj)] * fi[(l, k)]
                            - 2.0 / 3.0 * fi[(jj, i)] * f[(k, l)]
                            + 2.0 / 9.0 * i1 * fi[(jj, i)] * fi[(l, k)]
                            + i1 / 3.0 * fi[(jj, k)] * fi[(l, i)]);
                    let v = (2.0 * j * j - j) * fi[(jj, i)] * fi[(l, k)]
                        - (j * j - j) * fi[(jj, k)] * fi[(l, i)];
                    a_iso[(3 * i + jj, 3 * k + l)] = a;
                    a_vol[(3 * i + jj, 3 * k + l)] = v;
                }
            }
        }
    }
    Ok(Split {
        p_iso,
        a_iso,
        p_vol,
        a_vol,
    })
}

fn response(f: &Mat3, p: Mat3, tangent: Tangent3) -> PointResponse3 {
    let j = f.determinant();
    PointResponse3 {
        cauchy: p * f.transpose() / j,
        first_piola: p,
        tangent,
    }
}

impl PointState for NeoHookean {
    type State = ();

    fn initial_state(&self) {}
}

impl Material3 for NeoHookean {
    fn update(
        &self,
        _: &(),
        f: &Mat3,
        _dt: f64,
        _: &mut (),
    ) -> nlvid_material::Result<PointResponse3> {
        let s = split(f)?;
        Ok(response(
            f,
            self.mu * s.p_iso + self.kappa * s.p_vol,
            self.mu * s.a_iso + self.kappa * s.a_vol,
        ))
    }
}

/// Most Prony terms [`PronyNeoHookean`] supports.
pub const MAX_TERMS: usize = 4;

/// Neo-Hookean solid with Prony-series relaxation of its isochoric part
/// (Simo 1987): S = S_vol + g_∞ S_iso + Σ g_k h_k with
/// h_k(t) = ∫ e^{−(t−s)/τ_k} dS_iso/ds ds, updated exactly for S_iso linear
/// in time over a step. The shear modulus relaxes as the shared
/// [`Relaxation`] G(t) = G0 [g∞ + Σ g_k e^{−t/τ_k}] (eq. 5.1).
#[derive(Debug, Clone, PartialEq)]
pub struct PronyNeoHookean {
    /// Shear relaxation modulus; G0 = μ (Pa).
    pub shear: Relaxation,
    /// Bulk modulus κ (Pa), not relaxing.
    pub kappa: f64,
}

/// History of one [`PronyNeoHookean`] point.
#[derive(Debug, Clone, PartialEq)]
pub struct PronyState {
    h: [Mat3; MAX_TERMS],
    s_iso: Mat3,
}

impl PronyNeoHookean {
    /// Checks the parameters (the series itself is checked by
    /// [`Relaxation`]).
    ///
    /// # Errors
    /// [`MaterialError::Parameter`] for non-positive G0 or κ, or more than
    /// [`MAX_TERMS`] terms.
    pub fn new(shear: Relaxation, kappa: f64) -> nlvid_material::Result<Self> {
        let bad = |name, value, reason| {
            Err(MaterialError::Parameter {
                name,
                value,
                reason,
            })
        };
        if !(shear.g0() > 0.0) {
            return bad("G0", shear.g0(), "must be positive");
        }
        if !(kappa > 0.0) {
            return bad("bulk modulus", kappa, "must be positive");
        }
        if shear.prony().len() > MAX_TERMS {
            return bad("Prony terms", shear.prony().len() as f64, "at most 4");
        }
        Ok(Self { shear, kappa })
    }
}

impl PointState for PronyNeoHookean {
    type State = PronyState;

    fn initial_state(&self) -> PronyState {
        PronyState {
            h: [Mat3::zeros(); MAX_TERMS],
            s_iso: Mat3::zeros(),
        }
    }
}

impl Material3 for PronyNeoHookean {
    fn update(
        &self,
        state_n: &PronyState,
        f: &Mat3,
        dt: f64,
        trial: &mut PronyState,
    ) -> nlvid_material::Result<PointResponse3> {
        let s = split(f)?;
        let fi = f
            .try_inverse()
            .ok_or_else(|| MaterialError::Deformation("singular F".into()))?;
        let mu = self.shear.g0();
        let s_iso = mu * fi * s.p_iso;
        // S = S_vol + g_∞ S_iso + Σ g_k h_k, with the hereditary variables
        // h_k^{n+1} = e^{−x} h_k^n + (1 − e^{−x})/x (S_iso^{n+1} − S_iso^n),
        // x = Δt/τ_k; so S = S_vol + β S_iso + H with H fixed by the history.
        let mut beta = self.shear.prony().long_term_weight();
        let mut hist = Mat3::zeros();
        for (k, term) in self.shear.prony().terms().iter().enumerate() {
            let (g, tau) = (term.weight, term.tau);
            let x = dt / tau;
            let (e, c) = if x > 1e-8 {
                ((-x).exp(), (1.0 - (-x).exp()) / x)
            } else {
                (1.0 - x, 1.0 - 0.5 * x)
            };
            trial.h[k] = e * state_n.h[k] + c * (s_iso - state_n.s_iso);
            beta += g * c;
            hist += g * (e * state_n.h[k] - c * state_n.s_iso);
        }
        trial.s_iso = s_iso;
        let p = self.kappa * s.p_vol + beta * mu * s.p_iso + f * hist;
        let mut a = self.kappa * s.a_vol + beta * mu * s.a_iso;
        for i in 0..3 {
            for jj in 0..3 {
                for l in 0..3 {
                    a[(3 * i + jj, 3 * i + l)] += hist[(jj, l)];
                }
            }
        }
        Ok(response(f, p, a))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nlvid_model::Prony;

    fn shear(g0: f64, terms: &[(f64, f64)]) -> Relaxation {
        Relaxation::new("G0", g0, Prony::new("G", terms).unwrap()).unwrap()
    }

    fn fd_check<M: Material3>(m: &M, state: &M::State, dt: f64) {
        let f = Mat3::new(1.12, 0.08, 0.0, -0.05, 0.91, 0.0, 0.0, 0.0, 1.04);
        let mut trial = state.clone();
        let r = m.update(state, &f, dt, &mut trial).unwrap();
        let h = 1e-6;
        for k in 0..3 {
            for l in 0..3 {
                let mut fp = f;
                let mut fm = f;
                fp[(k, l)] += h;
                fm[(k, l)] -= h;
                let pp = m.update(state, &fp, dt, &mut trial).unwrap().first_piola;
                let pm = m.update(state, &fm, dt, &mut trial).unwrap().first_piola;
                for i in 0..3 {
                    for j in 0..3 {
                        let fd = (pp[(i, j)] - pm[(i, j)]) / (2.0 * h);
                        let an = r.tangent[(3 * i + j, 3 * k + l)];
                        assert!(
                            (fd - an).abs() < 1e-6 * (1.0 + an.abs()),
                            "A[{i}{j}{k}{l}] {an} vs fd {fd}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn neo_hookean_tangent_matches_finite_differences() {
        fd_check(
            &NeoHookean {
                mu: 1.3,
                kappa: 40.0,
            },
            &(),
            0.1,
        );
    }

    #[test]
    fn prony_tangent_matches_finite_differences_with_history() {
        let m = PronyNeoHookean::new(shear(1.0, &[(0.3, 0.5), (0.3, 10.0)]), 50.0).unwrap();
        let mut s0 = m.initial_state();
        let mut s1 = s0.clone();
        let f0 = Mat3::new(1.05, 0.02, 0.0, 0.01, 0.97, 0.0, 0.0, 0.0, 0.99);
        m.update(&s0, &f0, 0.2, &mut s1).unwrap();
        s0 = s1;
        fd_check(&m, &s0, 0.3);
    }

    #[test]
    fn small_shear_relaxes_like_the_prony_series() {
        // Step shear γ held: σ_12(t)/γ → G(t) for γ ≪ 1.
        let m = PronyNeoHookean::new(shear(2.0, &[(0.3, 0.5), (0.3, 10.0)]), 1e4).unwrap();
        let gamma = 1e-6;
        let f = Mat3::new(1.0, gamma, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0);
        let mut s = m.initial_state();
        let mut trial = s.clone();
        m.update(&s, &f, 1e-12, &mut trial).unwrap();
        s = trial.clone();
        let mut t = 0.0;
        for _ in 0..200 {
            let dt = 0.1;
            t += dt;
            let r = m.update(&s, &f, dt, &mut trial).unwrap();
            s = trial.clone();
            let g = r.cauchy[(0, 1)] / gamma;
            assert!(
                (g - m.shear.value(t)).abs() < 1e-5 * m.shear.g0(),
                "t={t} {g}"
            );
        }
    }
}
