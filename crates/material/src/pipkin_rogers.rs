//! The Pipkin–Rogers single-integral NLV model (§2.2, eqs. 2.1–2.2) with the
//! coefficient choice of §2.5 (eqs. 2.53–2.55, Φ = exp(−a(I1 − 3)), eq. 2.54)
//! and Prony relaxation functions G1, G2 (App. D, eqs. D.3–D.4).
//!
//! Convention: the coefficients carry the factor 2 of eq. 2.55, so
//! `G1(0) = C1` and `G2(0) = C2` of the instantaneous Mooney–Rivlin response
//! in eq. 4.1's convention (`W = C1(I1 − 3) + C2(I2 − 3)`, small-strain
//! shear modulus `2 (G1(0) + G2(0))`), with γ0 = G2(0)/G1(0). Ch. II's
//! `G1(0)` is the study key and parameter name `G10` (`docs/theory/model.md`);
//! App. D's UMAT eq. D.2 drops the 2: its `G10` is twice ours
//! ([`PipkinRogers::from_umat_d2`] converts).
//!
//! By Cayley–Hamilton, `R[C, t] = G1(t) A1(C) + G2(t) A2(C)` with
//! `A1 = 2(I − Φ I3 C⁻¹)` and `A2 = 2(I1 I − C − 2Φ I3 C⁻¹)`, so the
//! hereditary integral of eq. 2.1 is
//! `−G10 Σ g1k H1k(t) − G20 Σ g2k H2k(t)`,
//! `Hαk(t) = ∫_0^t (1/ταk) e^{−(t−s)/ταk} Aα(C(s)) ds`, updated recursively
//! ([`HistoryRule`]). In 3D the constraint is replaced by the penalty
//! `K J (J − 1)` of eqs. 2.50/D.5 (the thesis evaluates R on `C`, not `C̄`,
//! and so do we).

use crate::PointState;
use crate::history::advance;
use crate::hyperelastic::{add_volumetric, check_bulk};
use crate::kernel::{IsoStress, Kin, XC, XCI, XH, XI};
use crate::model::Kernel;
use nlvid_model::{Prony, Relaxation};

use crate::{HistoryRule, Mat3, MaterialError, MooneyRivlin, Result};

/// Pipkin–Rogers material, eqs. 2.1–2.2, 2.53–2.55, D.3–D.4.
#[derive(Debug, Clone, PartialEq)]
pub struct PipkinRogers {
    g1: Relaxation,
    g2: Relaxation,
    a: f64,
    bulk: f64,
    rule: HistoryRule,
}

/// History of a Pipkin–Rogers point: one tensor per Prony term of G1 and G2
/// plus `A1`, `A2` at the last converged step.
#[derive(Debug, PartialEq)]
pub struct PipkinRogersState {
    h1: Vec<Mat3>,
    h2: Vec<Mat3>,
    a1: Mat3,
    a2: Mat3,
}

/// `clone_from` reuses the history vectors (see `PronyViscoelasticState`).
impl Clone for PipkinRogersState {
    fn clone(&self) -> Self {
        Self {
            h1: self.h1.clone(),
            h2: self.h2.clone(),
            a1: self.a1,
            a2: self.a2,
        }
    }

    fn clone_from(&mut self, source: &Self) {
        self.h1.clone_from(&source.h1);
        self.h2.clone_from(&source.h2);
        self.a1 = source.a1;
        self.a2 = source.a2;
    }
}

/// Ch. II's parametrisation (eqs. 2.56–2.57 in dimensional form): one
/// exponential per relaxation function, long-term *fractions* `g_α`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Eq256 {
    /// `G10 = G1(0)` in Pa (the thesis's "C1 = G1(0)" of §2.5; the
    /// Mooney–Rivlin C1 of eq. 4.1 at t = 0⁺).
    pub g10: f64,
    /// Instantaneous Mooney–Rivlin ratio `γ0 = G2(0)/G1(0)`.
    pub gamma0: f64,
    /// Long-term fraction `g_1 = G1(∞)/G1(0)` in (0, 1].
    pub g1_fraction: f64,
    /// Long-term fraction `g_2 = G2(∞)/G2(0)` in (0, 1].
    pub g2_fraction: f64,
    /// Relaxation time `τ1` in s.
    pub tau1: f64,
    /// Ratio `c = τ1/τ2` (> 0).
    pub c: f64,
    /// Exponent `a` of Φ, eq. 2.54 (≥ 0).
    pub a: f64,
}

fn check_a(a: f64) -> Result<()> {
    if !(a.is_finite() && a >= 0.0) {
        return Err(MaterialError::Parameter {
            name: "a",
            value: a,
            reason: "the exponent of Φ = exp(−a(I1−3)), eq. 2.54, must be finite and ≥ 0",
        });
    }
    Ok(())
}

impl PipkinRogers {
    /// General model from the two relaxation functions (eq. 2.55 convention:
    /// `G1(0) = C1`, `G2(0) = C2` at t = 0⁺), `a` of eq. 2.54 and the
    /// volumetric penalty `K` (3D only).
    ///
    /// # Errors
    /// [`MaterialError::Parameter`] for `a < 0`, `K < 0`, `G1(0) ≤ 0`.
    pub fn new(g1: Relaxation, g2: Relaxation, a: f64, bulk: f64) -> Result<Self> {
        check_a(a)?;
        check_bulk(bulk)?;
        if g1.g0() <= 0.0 {
            return Err(MaterialError::Parameter {
                name: "G10",
                value: g1.g0(),
                reason: "G1(0) must be > 0 (Pa)",
            });
        }
        Ok(Self {
            g1,
            g2,
            a,
            bulk,
            rule: HistoryRule::default(),
        })
    }

    /// Quasi-linear viscoelasticity: `G2 = β G1` (eq. 2.16 with §2.5).
    ///
    /// # Errors
    /// As [`PipkinRogers::new`]; `β` must be finite and ≥ 0.
    pub fn qlv(g: Relaxation, beta: f64, a: f64, bulk: f64) -> Result<Self> {
        if !(beta.is_finite() && beta >= 0.0) {
            return Err(MaterialError::Parameter {
                name: "beta",
                value: beta,
                reason: "QLV ratio G2/G1 must be finite and ≥ 0",
            });
        }
        let g2 = g.scaled(beta);
        Self::new(g, g2, a, bulk)
    }

    /// From ch. II's parameters (eq. 2.56): `G1(0) = G10`, `G2(0) = γ0 G10`,
    /// `τ2 = τ1 / c`.
    ///
    /// # Errors
    /// [`MaterialError::Parameter`] naming the parameter.
    pub fn from_eq_2_56(p: &Eq256, bulk: f64) -> Result<Self> {
        if !(p.gamma0.is_finite() && p.gamma0 >= 0.0) {
            return Err(MaterialError::Parameter {
                name: "gamma0",
                value: p.gamma0,
                reason: "γ0 = G2(0)/G1(0) must be finite and ≥ 0",
            });
        }
        if !(p.c.is_finite() && p.c > 0.0) {
            return Err(MaterialError::Parameter {
                name: "c",
                value: p.c,
                reason: "c = τ1/τ2 must be finite and > 0",
            });
        }
        let g1 = crate::ThreeParameterSolid {
            g0: p.g10,
            long_term_fraction: p.g1_fraction,
            tau: p.tau1,
        }
        .to_relaxation("G1")?;
        let g2 = crate::ThreeParameterSolid {
            g0: p.gamma0 * p.g10,
            long_term_fraction: p.g2_fraction,
            tau: p.tau1 / p.c,
        }
        .to_relaxation("G2")?;
        Self::new(g1, g2, p.a, bulk)
    }

    /// From App. D's UMAT parameters (eqs. D.2–D.4, no factor 2):
    /// `G10_umat`, `d = G20/G10`, the normalised Prony series of G1 and G2.
    /// Ours is `G1 = G10_umat/2 · prony1`, `G2 = d · G10_umat/2 · prony2`.
    ///
    /// # Errors
    /// As [`PipkinRogers::new`].
    pub fn from_umat_d2(
        g10_umat: f64,
        d: f64,
        prony1: Prony,
        prony2: Prony,
        a: f64,
        bulk: f64,
    ) -> Result<Self> {
        let g1 = Relaxation::new("G10", 0.5 * g10_umat, prony1)?;
        let g2 = Relaxation::new("d", 0.5 * d * g10_umat, prony2)?;
        Self::new(g1, g2, a, bulk)
    }

    /// Chooses the one-step quadrature of the hereditary integral.
    pub fn with_rule(mut self, rule: HistoryRule) -> Self {
        self.rule = rule;
        self
    }

    /// `G1(t)` (eq. 2.55 convention).
    pub fn g1(&self) -> &Relaxation {
        &self.g1
    }
    /// `G2(t)` (eq. 2.55 convention).
    pub fn g2(&self) -> &Relaxation {
        &self.g2
    }
    /// Exponent `a` of Φ.
    pub fn a(&self) -> f64 {
        self.a
    }
    /// History quadrature in use.
    pub fn rule(&self) -> HistoryRule {
        self.rule
    }

    /// Mooney–Rivlin solid of the instantaneous response at t = 0⁺
    /// (`C1 = G1(0)`, `C2 = G2(0) = γ0 C1`, eq. 2.4).
    ///
    /// # Errors
    /// Never for a valid model; typed for uniformity.
    pub fn instantaneous(&self) -> Result<MooneyRivlin> {
        MooneyRivlin::new(self.g1.g0(), self.g2.g0(), self.bulk)
    }

    /// Mooney–Rivlin solid of the long-time response (`C1 = G1(∞)`,
    /// `C2 = G2(∞)`, `γ∞ = (g2/g1) γ0`, eq. 2.57).
    ///
    /// # Errors
    /// Never for a valid model; typed for uniformity.
    pub fn long_time(&self) -> Result<MooneyRivlin> {
        MooneyRivlin::new(self.g1.g_inf(), self.g2.g_inf(), self.bulk)
    }

    /// Scalar coefficients `α0, α1, α2` of eq. 2.55 at invariants `(I1, I2)`
    /// and time `t`.
    pub fn alphas(&self, i1: f64, i2: f64, t: f64) -> [f64; 3] {
        let phi = (-self.a * (i1 - 3.0)).exp();
        let (g1, g2) = (self.g1.value(t), self.g2.value(t));
        [
            2.0 * g1 * (1.0 - i2 * phi) + 2.0 * g2 * (i1 - 2.0 * i2 * phi),
            2.0 * g1 * i1 * phi + 2.0 * g2 * (2.0 * i1 * phi - 1.0),
            -2.0 * phi * (g1 + 2.0 * g2),
        ]
    }

    /// `R[C, t] = α0 I + α1 C + α2 C²`, eq. 2.2 with eq. 2.55 (direct form,
    /// no Cayley–Hamilton): the reference the tests and eq. 2.48 use.
    pub fn r_tensor(&self, c: &Mat3, t: f64) -> Mat3 {
        let i1 = c.trace();
        let i2 = 0.5 * (i1 * i1 - (c * c).trace());
        let [a0, a1, a2] = self.alphas(i1, i2, t);
        Mat3::identity() * a0 + c * a1 + c * c * a2
    }

    /// `∂R[C, u]/∂u` (the integrand of eq. 2.1 at `u = t − s`).
    pub fn r_rate(&self, c: &Mat3, u: f64) -> Mat3 {
        let i1 = c.trace();
        let i2 = 0.5 * (i1 * i1 - (c * c).trace());
        let phi = (-self.a * (i1 - 3.0)).exp();
        let (d1, d2) = (self.g1.derivative(u), self.g2.derivative(u));
        let a0 = 2.0 * d1 * (1.0 - i2 * phi) + 2.0 * d2 * (i1 - 2.0 * i2 * phi);
        let a1 = 2.0 * d1 * i1 * phi + 2.0 * d2 * (2.0 * i1 * phi - 1.0);
        let a2 = -2.0 * phi * (d1 + 2.0 * d2);
        Mat3::identity() * a0 + c * a1 + c * c * a2
    }
}

/// `A1(C)`, `A2(C)` and Φ (see the module doc).
fn basis(k: &Kin, a: f64) -> (Mat3, Mat3, f64) {
    let phi = (-a * (k.i1 - 3.0)).exp();
    let i3 = k.j * k.j;
    let ci = k.cinv * (2.0 * phi * i3);
    let id = Mat3::identity();
    (id * 2.0 - ci, id * (2.0 * k.i1) - k.c * 2.0 - ci * 2.0, phi)
}

impl PointState for PipkinRogers {
    type State = PipkinRogersState;

    fn initial_state(&self) -> PipkinRogersState {
        PipkinRogersState {
            h1: vec![Mat3::zeros(); self.g1.prony().len()],
            h2: vec![Mat3::zeros(); self.g2.prony().len()],
            a1: Mat3::zeros(),
            a2: Mat3::zeros(),
        }
    }
}

impl Kernel for PipkinRogers {
    fn bulk(&self) -> f64 {
        self.bulk
    }

    fn eval(
        &self,
        st: &PipkinRogersState,
        k: &Kin,
        dt: f64,
        trial: &mut PipkinRogersState,
        bulk: f64,
    ) -> IsoStress {
        let (a1, a2, phi) = basis(k, self.a);
        let (f1, b1) = advance(
            self.rule,
            self.g1.prony(),
            dt,
            (&st.h1, &st.a1),
            &a1,
            &mut trial.h1,
        );
        let (f2, b2) = advance(
            self.rule,
            self.g2.prony(),
            dt,
            (&st.h2, &st.a2),
            &a2,
            &mut trial.h2,
        );
        trial.a1 = a1;
        trial.a2 = a2;
        let c1 = self.g1.g0() * (1.0 - b1);
        let c2 = self.g2.g0() * (1.0 - b2);
        let mut out = IsoStress {
            h: f1 * self.g1.g0() + f2 * self.g2.g0(),
            ..IsoStress::default()
        };
        out.add(
            XI,
            2.0 * c1 + 2.0 * c2 * k.i1,
            k.grad(2.0 * c2, 0.0, 0.0, 0.0),
        );
        out.add(XC, -2.0 * c2, [0.0; 4]);
        let p = 2.0 * (c1 + 2.0 * c2) * phi;
        out.add(
            XCI,
            -p * k.j * k.j,
            k.grad(self.a * p * k.j * k.j, 0.0, -2.0 * p * k.j, 0.0),
        );
        out.add(XH, 1.0, [0.0; 4]);
        add_volumetric(k, bulk, &mut out);
        out
    }
}
