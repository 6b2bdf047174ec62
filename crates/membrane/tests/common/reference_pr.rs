//! A second, separately written implementation of the ch. II Pipkin–Rogers
//! membrane (eqs. 2.53–2.56, trapezoid of eq. 2.48 as an exact recursion for
//! exponential kernels) directly in principal stretches. It was the membrane
//! crate's own point update in session 1; the crate now delegates to
//! `nlvid-material`, and this copy is kept only as an independent reference
//! for the tests.
#![allow(dead_code)]

use nlvid_material::{MaterialError, MembraneMaterial, MembraneResponse, PointState};
use nlvid_membrane::PipkinRogersParams;

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

/// Reference principal-stretch Pipkin–Rogers membrane (see `PipkinRogersParams`).
///
/// R[C, τ] = G1(τ) A(C) + G2(τ) B(C) with A, B from eq. 2.55:
/// A = 2(1 − I2Φ) I + 2 I1Φ C − 2Φ C², B = 2(I1 − 2 I2Φ) I + 2(2 I1Φ − 1) C − 4Φ C².
/// σα = λα² Sα − λ3² S3 (eqs. 2.21–2.24), S = R[C(t), 0] + ∫ ∂τ R[C(s), t − s] ds,
/// the integral by the trapezoidal rule (eq. 2.48), which for the exponential
/// kernels of eq. 2.56 is exactly the recursion
/// Iα(tn+1) = e^{−Δ/τα} Iα(tn) + Δ/2 [kα(Δ) Mα(tn) + kα(0) Mα(tn+1)].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PipkinRogersMembrane {
    pub p: PipkinRogersParams,
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
    /// G1(0), G2(0), G1(∞), G2(∞), τ1, τ2.
    fn moduli(&self) -> (f64, f64, f64, f64, f64, f64) {
        let p = &self.p;
        let g10 = p.g10;
        let g20 = p.gamma0 * p.g10;
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

impl PointState for PipkinRogersMembrane {
    type State = PipkinRogersState;

    fn initial_state(&self) -> Self::State {
        // A(I) = B(I) = 0 (eq. 2.11 with K = 0): the undeformed history is zero.
        PipkinRogersState::default()
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
