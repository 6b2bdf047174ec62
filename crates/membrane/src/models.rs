//! Membrane point updates of ch. II: the ch. II Pipkin–Rogers membrane
//! (eqs. 2.53–2.56, trapezoidal hereditary sums of eq. 2.48) as a thin
//! adapter over [`nlvid_material::PipkinRogers`] (plane stress with
//! λ3 = 1/(λ1 λ2)), so the viscoelastic law lives in one place and this module
//! only holds the ch. II parametrisation (G10, γ0, g1, g2, c, τ1, a) and its
//! validation; and the closed-form incompressible Mooney–Rivlin membrane
//! (eq. 2.4) used by the elastic sweeps.
//!
//! Both implement [`MembraneMaterial`], so the solver does not know which one
//! it runs.

use nlvid_material::{MaterialError, MembraneMaterial, MembraneResponse, PointState};
use serde::{Deserialize, Serialize};

use crate::{MembraneError, Result};

fn check_stretches(l: [f64; 2]) -> std::result::Result<(), MaterialError> {
    if l[0] > 0.0 && l[1] > 0.0 && l[0].is_finite() && l[1].is_finite() {
        Ok(())
    } else {
        Err(MaterialError::Deformation(format!(
            "principal stretches must be positive and finite, got [{}, {}]",
            l[0], l[1]
        )))
    }
}

/// Incompressible Mooney–Rivlin membrane, W = C1 (I1 − 3) + C2 (I2 − 3):
/// σα = 2 (λα² − λ3²)(C1 + C2 λβ²), λ3 = 1/(λ1 λ2) (eq. 4.1 with σ3 = 0;
/// `C1`, `C2` in eq. 4.1's convention, docs/theory/model.md).
///
/// Kept in closed form (not delegated to `nlvid_material::MooneyRivlin`)
/// because the elastic sweeps call it millions of times and the 3D kernel
/// costs ≈ 10× more; `mooney_rivlin_membrane_equals_nlvid_material` checks
/// that both agree.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MooneyRivlinMembrane {
    /// C1 (stress units).
    pub c1: f64,
    /// C2 = γ C1 (stress units).
    pub c2: f64,
}

impl MooneyRivlinMembrane {
    /// Mooney–Rivlin membrane with C1 and γ = C2/C1.
    ///
    /// # Errors
    /// [`MembraneError::Input`] when C1 ≤ 0 or γ < 0.
    pub fn new(c1: f64, gamma: f64) -> Result<Self> {
        if !(c1 > 0.0 && c1.is_finite()) {
            return Err(MembraneError::Input {
                name: "c1",
                value: c1,
                reason: "C1 must be positive".into(),
            });
        }
        if !(gamma >= 0.0 && gamma.is_finite()) {
            return Err(MembraneError::Input {
                name: "gamma",
                value: gamma,
                reason: "the Mooney–Rivlin parameter γ = C2/C1 must be ≥ 0".into(),
            });
        }
        Ok(Self { c1, c2: gamma * c1 })
    }
}

impl PointState for MooneyRivlinMembrane {
    type State = ();

    fn initial_state(&self) -> Self::State {}
}

impl MembraneMaterial for MooneyRivlinMembrane {
    fn update(
        &self,
        _state_n: &(),
        l: [f64; 2],
        _dt: f64,
        _trial: &mut (),
    ) -> nlvid_material::Result<MembraneResponse> {
        check_stretches(l)?;
        let [l1, l2] = l;
        let l3s = 1.0 / (l1 * l1 * l2 * l2);
        let m1 = self.c1 + self.c2 * l2 * l2;
        let m2 = self.c1 + self.c2 * l1 * l1;
        let s1 = 2.0 * (l1 * l1 - l3s) * m1;
        let s2 = 2.0 * (l2 * l2 - l3s) * m2;
        let t11 = 2.0 * (2.0 * l1 + 2.0 * l3s / l1) * m1;
        let t12 = 2.0 * (2.0 * l3s / l2) * m1 + 2.0 * (l1 * l1 - l3s) * 2.0 * self.c2 * l2;
        let t22 = 2.0 * (2.0 * l2 + 2.0 * l3s / l2) * m2;
        let t21 = 2.0 * (2.0 * l3s / l1) * m2 + 2.0 * (l2 * l2 - l3s) * 2.0 * self.c2 * l1;
        Ok(MembraneResponse {
            cauchy: [s1, s2],
            tangent: [[t11, t12], [t21, t22]],
        })
    }
}

/// Parameters of the ch. II Pipkin–Rogers membrane (eqs. 2.53–2.56) in the
/// thesis's form: G1(t) = G10 [g1 + (1 − g1) e^{−t/τ1}],
/// G2(t) = γ0 G10 [g2 + (1 − g2) e^{−c t/τ1}] (c = τ1/τ2), Φ = e^{−a (I1 − 3)}.
/// `G10` = G1(0) is what §2.5 calls "C1 = G1(0)"; with eq. 2.55's factor 2
/// it is the eq. 4.1 constant C1 of the instantaneous Mooney–Rivlin
/// response (docs/theory/membrane.md).
///
/// `g1`, `g2` are the long-term *fractions* Gα∞/Gα0 of eq. 2.56 (not Prony
/// weights). With G10 = 1 and τ1 = 1 everything is in the dimensionless units
/// of eq. 2.47 (σ̄ = σ/G10, t0 = t/τ1).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PipkinRogersParams {
    /// G10 = G1(0) (stress units; 1 for dimensionless runs).
    #[serde(rename = "G10")]
    pub g10: f64,
    /// γ0 = G2(0)/G1(0), the instantaneous Mooney–Rivlin parameter.
    pub gamma0: f64,
    /// g1 = G1(∞)/G1(0), a long-term fraction (`g1_long_term` in studies).
    #[serde(rename = "g1_long_term")]
    pub g1: f64,
    /// g2 = G2(∞)/G2(0), a long-term fraction (`g2_long_term` in studies).
    #[serde(rename = "g2_long_term")]
    pub g2: f64,
    /// c = τ1/τ2.
    pub c: f64,
    /// τ1 (time units; 1 for dimensionless runs).
    pub tau1: f64,
    /// Exponent `a` of Φ (eq. 2.54); the thesis's code uses 0.
    pub a: f64,
}

impl Default for PipkinRogersParams {
    /// QLV case of Fig. 2.6: g1 = g2 = 0.2, c = 1, γ0 = 0.1, G10 = τ1 = 1, a = 0.
    fn default() -> Self {
        Self {
            g10: 1.0,
            gamma0: 0.1,
            g1: 0.2,
            g2: 0.2,
            c: 1.0,
            tau1: 1.0,
            a: 0.0,
        }
    }
}

impl PipkinRogersParams {
    /// The dimensionless setting of the ch. II figures (Figs. 2.6–2.14:
    /// G10 = τ1 = 1, γ0 = 0.1, a = 0) with the given g1, g2 and c = τ1/τ2.
    pub fn chapter2(g1: f64, g2: f64, c: f64) -> Self {
        Self {
            g1,
            g2,
            c,
            ..Self::default()
        }
    }

    /// γ∞ = (g2/g1) γ0 (eq. 2.57).
    pub fn gamma_inf(&self) -> f64 {
        self.g2 / self.g1 * self.gamma0
    }

    /// Validate and build the point update.
    ///
    /// # Errors
    /// [`MembraneError::Input`] naming the parameter out of range.
    pub fn check(&self) -> Result<PipkinRogersMembrane> {
        let bad = |name: &'static str, value: f64, reason: &str| MembraneError::Input {
            name,
            value,
            reason: reason.into(),
        };
        let pos = |v: f64| v > 0.0 && v.is_finite();
        if !pos(self.g10) {
            return Err(bad("G10", self.g10, "G10 = G1(0) must be positive"));
        }
        if !(self.gamma0 >= 0.0 && self.gamma0.is_finite()) {
            return Err(bad("gamma0", self.gamma0, "γ0 must be ≥ 0"));
        }
        for (name, g) in [("g1", self.g1), ("g2", self.g2)] {
            if !(g > 0.0 && g <= 1.0) {
                return Err(bad(name, g, "long-term fraction must lie in (0, 1]"));
            }
        }
        if !pos(self.c) {
            return Err(bad("c", self.c, "c = τ1/τ2 must be positive"));
        }
        if !pos(self.tau1) {
            return Err(bad("tau1", self.tau1, "τ1 must be positive"));
        }
        if !(self.a >= 0.0 && self.a.is_finite()) {
            return Err(bad("a", self.a, "Φ exponent a must be ≥ 0"));
        }
        let inner = nlvid_material::PipkinRogers::from_eq_2_56(
            &nlvid_material::Eq256 {
                g10: self.g10,
                gamma0: self.gamma0,
                g1_fraction: self.g1,
                g2_fraction: self.g2,
                tau1: self.tau1,
                c: self.c,
                a: self.a,
            },
            0.0,
        )
        .map_err(|e| bad("pipkin_rogers", f64::NAN, &e.to_string()))?
        .with_rule(nlvid_material::HistoryRule::Trapezoid);
        Ok(PipkinRogersMembrane { p: *self, inner })
    }
}

/// The ch. II Pipkin–Rogers membrane point update (see [`PipkinRogersParams`]):
/// [`nlvid_material::PipkinRogers`] built by `from_eq_2_56` (factor 2 of
/// eq. 2.55 kept, G1(0) = G10) with the trapezoidal rule of eq. 2.48
/// ([`nlvid_material::HistoryRule::Trapezoid`]), evaluated in plane stress.
#[derive(Debug, Clone, PartialEq)]
pub struct PipkinRogersMembrane {
    p: PipkinRogersParams,
    inner: nlvid_material::PipkinRogers,
}

/// History of one Pipkin–Rogers membrane point (the hereditary integrals of
/// [`nlvid_material::PipkinRogersState`]).
#[derive(Debug, Clone, PartialEq)]
pub struct PipkinRogersState(nlvid_material::PipkinRogersState);

impl PipkinRogersMembrane {
    /// The parameters.
    pub fn params(&self) -> &PipkinRogersParams {
        &self.p
    }

    /// The `nlvid-material` model this adapter evaluates.
    pub fn material(&self) -> &nlvid_material::PipkinRogers {
        &self.inner
    }
}

impl PointState for PipkinRogersMembrane {
    type State = PipkinRogersState;

    fn initial_state(&self) -> Self::State {
        PipkinRogersState(self.inner.initial_state())
    }
}

impl MembraneMaterial for PipkinRogersMembrane {
    fn update(
        &self,
        state_n: &PipkinRogersState,
        l: [f64; 2],
        dt: f64,
        trial: &mut PipkinRogersState,
    ) -> nlvid_material::Result<MembraneResponse> {
        MembraneMaterial::update(&self.inner, &state_n.0, l, dt, &mut trial.0)
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    fn mr_closed_form(l1: f64, l2: f64, c1: f64, c2: f64) -> [f64; 2] {
        // Independent: σα = 2 λα² ∂W/∂I1-type derivation, W = C1(I1−3)+C2(I2−3),
        // σα − σ3 = 2(λα² − λ3²)(C1 + C2 λβ²).
        let l3 = 1.0 / (l1 * l2);
        [
            2.0 * (l1 * l1 - l3 * l3) * (c1 + c2 * l2 * l2),
            2.0 * (l2 * l2 - l3 * l3) * (c1 + c2 * l1 * l1),
        ]
    }

    fn fd_tangent<M: MembraneMaterial>(
        m: &M,
        st: &M::State,
        l: [f64; 2],
        dt: f64,
    ) -> [[f64; 2]; 2] {
        let h = 1e-6;
        let mut t = [[0.0; 2]; 2];
        let mut tr = m.initial_state();
        for beta in 0..2 {
            let mut lp = l;
            let mut lm = l;
            lp[beta] += h;
            lm[beta] -= h;
            let sp = m.update(st, lp, dt, &mut tr).unwrap().cauchy;
            let sm = m.update(st, lm, dt, &mut tr).unwrap().cauchy;
            for alpha in 0..2 {
                t[alpha][beta] = (sp[alpha] - sm[alpha]) / (2.0 * h);
            }
        }
        t
    }

    #[test]
    fn mooney_rivlin_tangent_matches_finite_differences() {
        let m = MooneyRivlinMembrane::new(1.3, 0.2).unwrap();
        for l in [[1.1, 1.3], [1.7, 1.05], [0.9, 1.4]] {
            let r = m.update(&(), l, 0.0, &mut ()).unwrap();
            let fd = fd_tangent(&m, &(), l, 0.0);
            for a in 0..2 {
                for b in 0..2 {
                    approx::assert_relative_eq!(r.tangent[a][b], fd[a][b], max_relative = 1e-7);
                }
            }
        }
    }

    #[test]
    fn mooney_rivlin_membrane_equals_nlvid_material() {
        let m = MooneyRivlinMembrane::new(1.3, 0.2).unwrap();
        let n = nlvid_material::MooneyRivlin::new(1.3, 0.26, 0.0).unwrap();
        for l in [[1.1, 1.3], [1.7, 1.05], [0.9, 1.4]] {
            let a = m.update(&(), l, 0.0, &mut ()).unwrap();
            let b = MembraneMaterial::update(&n, &(), l, 0.0, &mut ()).unwrap();
            for i in 0..2 {
                approx::assert_relative_eq!(a.cauchy[i], b.cauchy[i], max_relative = 1e-12);
                for j in 0..2 {
                    approx::assert_relative_eq!(
                        a.tangent[i][j],
                        b.tangent[i][j],
                        max_relative = 1e-10
                    );
                }
            }
        }
    }

    #[test]
    fn pipkin_rogers_instantaneous_response_is_mooney_rivlin_for_any_phi() {
        for a in [0.0, 0.3] {
            let p = PipkinRogersParams {
                a,
                gamma0: 0.15,
                g10: 2.0,
                ..Default::default()
            };
            let m = p.check().unwrap();
            let mut tr = m.initial_state();
            for l in [[1.1, 1.3], [1.7, 1.05]] {
                let r = m.update(&m.initial_state(), l, 0.0, &mut tr).unwrap();
                let cf = mr_closed_form(l[0], l[1], 2.0, 0.3);
                approx::assert_relative_eq!(r.cauchy[0], cf[0], max_relative = 1e-12);
                approx::assert_relative_eq!(r.cauchy[1], cf[1], max_relative = 1e-12);
            }
        }
    }

    #[test]
    fn pipkin_rogers_tangent_matches_finite_differences_with_history() {
        let p = PipkinRogersParams {
            a: 0.2,
            g1: 0.3,
            g2: 0.6,
            c: 2.0,
            gamma0: 0.2,
            ..Default::default()
        };
        let m = p.check().unwrap();
        let mut s0 = m.initial_state();
        let mut s1 = m.initial_state();
        m.update(&s0, [1.2, 1.1], 0.0, &mut s1).unwrap();
        s0 = s1.clone();
        m.update(&s0, [1.4, 1.2], 0.3, &mut s1).unwrap();
        let l = [1.5, 1.25];
        let dt = 0.2;
        let r = m.update(&s1, l, dt, &mut s0.clone()).unwrap();
        let fd = fd_tangent(&m, &s1, l, dt);
        for a in 0..2 {
            for b in 0..2 {
                approx::assert_relative_eq!(r.tangent[a][b], fd[a][b], max_relative = 1e-6);
            }
        }
    }

    #[test]
    fn pipkin_rogers_step_relaxation_follows_trapezoidal_g() {
        // QLV (g1 = g2, c = 1): under a held stretch σ(t)/σ(0) = G_trap(t)/G(0), where
        // G_trap is the trapezoidal integral of the kernel written here separately.
        let p = PipkinRogersParams {
            g1: 0.2,
            g2: 0.2,
            c: 1.0,
            ..Default::default()
        };
        let m = p.check().unwrap();
        let l = [1.3, 1.2];
        let mut st = m.initial_state();
        let mut tr = m.initial_state();
        let s0 = m.update(&st, l, 0.0, &mut tr).unwrap().cauchy;
        st = tr.clone();
        let dt = 0.1;
        let k = |tau: f64| -(1.0 - 0.2) * (-tau).exp();
        for n in 1..=20 {
            let s = m.update(&st, l, dt, &mut tr).unwrap().cauchy;
            st = tr.clone();
            let t = n as f64 * dt;
            let g_trap = 1.0
                + (0..n)
                    .map(|j| 0.5 * dt * (k(t - j as f64 * dt) + k(t - (j + 1) as f64 * dt)))
                    .sum::<f64>();
            approx::assert_relative_eq!(s[0] / s0[0], g_trap, max_relative = 1e-12);
            approx::assert_relative_eq!(s[1] / s0[1], g_trap, max_relative = 1e-12);
            // and the trapezoid is close to the exact G(t)
            approx::assert_relative_eq!(g_trap, 0.2 + 0.8 * (-t).exp(), max_relative = 2e-3);
        }
    }
}
