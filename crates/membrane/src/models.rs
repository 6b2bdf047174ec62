//! Membrane point updates of ch. II used by the solver until (and alongside)
//! the `nlvid-material` implementations: an incompressible Mooney–Rivlin
//! membrane and the ch. II Pipkin–Rogers membrane (eqs. 2.53–2.56) with the
//! trapezoidal hereditary sums of eq. 2.48 written as a recursive update.
//!
//! Both implement [`MembraneMaterial`], so the solver does not know which one
//! it runs; swap in `nlvid-material`'s types when they land.

use nlvid_material::{MaterialError, MembraneMaterial, MembraneResponse};
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
/// σα = 2 (λα² − λ3²)(C1 + C2 λβ²), λ3 = 1/(λ1 λ2) (eq. 2.4 with σ3 = 0).
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

impl MembraneMaterial for MooneyRivlinMembrane {
    type State = ();

    fn initial_state(&self) -> Self::State {}

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
/// thesis's form: G1(t) = C1 [g1 + (1 − g1) e^{−t/τ1}],
/// G2(t) = γ0 C1 [g2 + (1 − g2) e^{−c t/τ1}] (c = τ1/τ2), Φ = e^{−a (I1 − 3)}.
///
/// `g1`, `g2` are the long-term *fractions* Gα∞/Gα0 of eq. 2.56 (not Prony
/// weights). With C1 = 1 and τ1 = 1 everything is in the dimensionless units
/// of eq. 2.47 (σ̄ = σ/C1, t0 = t/τ1).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PipkinRogersParams {
    /// C1 = G1(0) (stress units; 1 for dimensionless runs).
    pub c1: f64,
    /// γ0 = G2(0)/G1(0), the instantaneous Mooney–Rivlin parameter.
    pub gamma0: f64,
    /// g1 = G1(∞)/G1(0).
    pub g1: f64,
    /// g2 = G2(∞)/G2(0).
    pub g2: f64,
    /// c = τ1/τ2.
    pub c: f64,
    /// τ1 (time units; 1 for dimensionless runs).
    pub tau1: f64,
    /// Exponent `a` of Φ (eq. 2.54); the thesis's code uses 0.
    pub a: f64,
}

impl Default for PipkinRogersParams {
    /// QLV case of Fig. 2.6: g1 = g2 = 0.2, c = 1, γ0 = 0.1, C1 = τ1 = 1, a = 0.
    fn default() -> Self {
        Self {
            c1: 1.0,
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
        if !pos(self.c1) {
            return Err(bad("c1", self.c1, "C1 = G1(0) must be positive"));
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
        Ok(PipkinRogersMembrane { p: *self })
    }
}

/// The ch. II Pipkin–Rogers membrane point update (see [`PipkinRogersParams`]).
///
/// R[C, τ] = G1(τ) A(C) + G2(τ) B(C) with A, B from eq. 2.55:
/// A = 2(1 − I2Φ) I + 2 I1Φ C − 2Φ C², B = 2(I1 − 2 I2Φ) I + 2(2 I1Φ − 1) C − 4Φ C².
/// σα = λα² Sα − λ3² S3 (eqs. 2.21–2.24), S = R[C(t), 0] + ∫ ∂τ R[C(s), t − s] ds,
/// the integral by the trapezoidal rule (eq. 2.48), which for the exponential
/// kernels of eq. 2.56 is exactly the recursion
/// Iα(tn+1) = e^{−Δ/τα} Iα(tn) + Δ/2 [kα(Δ) Mα(tn) + kα(0) Mα(tn+1)].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PipkinRogersMembrane {
    p: PipkinRogersParams,
}

/// History of one Pipkin–Rogers membrane point: the two hereditary integrals
/// and the last A(C), B(C) (principal components 1, 2, 3).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PipkinRogersState {
    i1: [f64; 3],
    i2: [f64; 3],
    a_prev: [f64; 3],
    b_prev: [f64; 3],
}

impl PipkinRogersMembrane {
    /// The parameters.
    pub fn params(&self) -> &PipkinRogersParams {
        &self.p
    }

    /// G1(0), G2(0), G1(∞), G2(∞), τ1, τ2.
    fn moduli(&self) -> (f64, f64, f64, f64, f64, f64) {
        let p = &self.p;
        let g10 = p.c1;
        let g20 = p.gamma0 * p.c1;
        (g10, g20, p.g1 * g10, p.g2 * g20, p.tau1, p.tau1 / p.c)
    }

    /// A(C), B(C) and their derivatives with respect to λ1 and λ2.
    #[allow(clippy::type_complexity)]
    fn ab(&self, l1: f64, l2: f64) -> ([f64; 3], [f64; 3], [[f64; 3]; 2], [[f64; 3]; 2]) {
        let c = [l1 * l1, l2 * l2, 1.0 / (l1 * l1 * l2 * l2)];
        // dc[β][i] = ∂c_i/∂λβ
        let dc = [
            [2.0 * l1, 0.0, -2.0 * c[2] / l1],
            [0.0, 2.0 * l2, -2.0 * c[2] / l2],
        ];
        let i1 = c[0] + c[1] + c[2];
        let i2 = c[0] * c[1] + c[1] * c[2] + c[2] * c[0];
        let phi = (-self.p.a * (i1 - 3.0)).exp();
        let mut a = [0.0; 3];
        let mut b = [0.0; 3];
        let mut da = [[0.0; 3]; 2];
        let mut db = [[0.0; 3]; 2];
        for i in 0..3 {
            a[i] = 2.0 * (1.0 - i2 * phi) + 2.0 * i1 * phi * c[i] - 2.0 * phi * c[i] * c[i];
            b[i] = 2.0 * (i1 - 2.0 * i2 * phi) + 2.0 * (2.0 * i1 * phi - 1.0) * c[i]
                - 4.0 * phi * c[i] * c[i];
        }
        for beta in 0..2 {
            let d = &dc[beta];
            let di1 = d[0] + d[1] + d[2];
            let di2 = d[0] * (i1 - c[0]) + d[1] * (i1 - c[1]) + d[2] * (i1 - c[2]);
            let dphi = -self.p.a * phi * di1;
            for i in 0..3 {
                da[beta][i] = -2.0 * (di2 * phi + i2 * dphi)
                    + 2.0 * (di1 * phi * c[i] + i1 * dphi * c[i] + i1 * phi * d[i])
                    - 2.0 * (dphi * c[i] * c[i] + 2.0 * phi * c[i] * d[i]);
                db[beta][i] = 2.0 * (di1 - 2.0 * di2 * phi - 2.0 * i2 * dphi)
                    + 2.0 * (2.0 * di1 * phi + 2.0 * i1 * dphi) * c[i]
                    + 2.0 * (2.0 * i1 * phi - 1.0) * d[i]
                    - 4.0 * (dphi * c[i] * c[i] + 2.0 * phi * c[i] * d[i]);
            }
        }
        (a, b, da, db)
    }
}

impl MembraneMaterial for PipkinRogersMembrane {
    type State = PipkinRogersState;

    fn initial_state(&self) -> Self::State {
        // A(I) = B(I) = 0 (eq. 2.11 with K = 0): the undeformed history is zero.
        PipkinRogersState::default()
    }

    fn update(
        &self,
        state_n: &PipkinRogersState,
        l: [f64; 2],
        dt: f64,
        trial: &mut PipkinRogersState,
    ) -> nlvid_material::Result<MembraneResponse> {
        check_stretches(l)?;
        if !(dt >= 0.0 && dt.is_finite()) {
            return Err(MaterialError::Deformation(format!(
                "time increment must be ≥ 0, got {dt}"
            )));
        }
        let [l1, l2] = l;
        let (g10, g20, g1i, g2i, tau1, tau2) = self.moduli();
        // kα(τ) = dGα/dτ = −(Gα0 − Gα∞)/τα e^{−τ/τα}
        let k1_0 = -(g10 - g1i) / tau1;
        let k2_0 = -(g20 - g2i) / tau2;
        let e1 = (-dt / tau1).exp();
        let e2 = (-dt / tau2).exp();
        let (a, b, da, db) = self.ab(l1, l2);
        let w1 = g10 + 0.5 * dt * k1_0; // weight of the current A in S
        let w2 = g20 + 0.5 * dt * k2_0;
        let mut s = [0.0; 3];
        for i in 0..3 {
            trial.i1[i] =
                e1 * state_n.i1[i] + 0.5 * dt * (k1_0 * e1 * state_n.a_prev[i] + k1_0 * a[i]);
            trial.i2[i] =
                e2 * state_n.i2[i] + 0.5 * dt * (k2_0 * e2 * state_n.b_prev[i] + k2_0 * b[i]);
            trial.a_prev[i] = a[i];
            trial.b_prev[i] = b[i];
            s[i] = g10 * a[i] + g20 * b[i] + trial.i1[i] + trial.i2[i];
        }
        let c = [l1 * l1, l2 * l2, 1.0 / (l1 * l1 * l2 * l2)];
        let dc = [
            [2.0 * l1, 0.0, -2.0 * c[2] / l1],
            [0.0, 2.0 * l2, -2.0 * c[2] / l2],
        ];
        let sig = [c[0] * s[0] - c[2] * s[2], c[1] * s[1] - c[2] * s[2]];
        let mut tan = [[0.0; 2]; 2];
        for alpha in 0..2 {
            for beta in 0..2 {
                let ds = |i: usize| w1 * da[beta][i] + w2 * db[beta][i];
                tan[alpha][beta] = dc[beta][alpha] * s[alpha] + c[alpha] * ds(alpha)
                    - dc[beta][2] * s[2]
                    - c[2] * ds(2);
            }
        }
        Ok(MembraneResponse {
            cauchy: sig,
            tangent: tan,
        })
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
    fn pipkin_rogers_instantaneous_response_is_mooney_rivlin_for_any_phi() {
        for a in [0.0, 0.3] {
            let p = PipkinRogersParams {
                a,
                gamma0: 0.15,
                c1: 2.0,
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
        s0 = s1;
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
        st = tr;
        let dt = 0.1;
        let k = |tau: f64| -(1.0 - 0.2) * (-tau).exp();
        for n in 1..=20 {
            let s = m.update(&st, l, dt, &mut tr).unwrap().cauchy;
            st = tr;
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
