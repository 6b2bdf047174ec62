//! Finite-strain Prony viscoelasticity of the ABAQUS form (§4.3, eqs.
//! 4.1–4.3; ABAQUS Theory Manual §4.8.2), with a Mooney–Rivlin (capsules,
//! 6 parameters C1, α = C2/C1, g1, τ1, g2, τ2) or neo-Hookean (cells,
//! 5 parameters G0, g1, g2, τ1, τ2 of eq. 5.1) elastic part.
//!
//! Moduli follow `docs/theory/model.md`: `C1`, `C2` are the constants of
//! eq. 4.1 and the shear relaxation modulus is `G(t) = 2 (C1 + C2) g(t)`,
//! so a cell of shear modulus `G0` has `C1 = G0/2`.
//!
//! The deviatoric hereditary integral
//! `τᴰ(t) = τ0ᴰ(t) + dev{F̄(t) [∫_0^t Ġ(s)/G0 F̄⁻¹(t−s) τ0ᴰ(t−s) F̄⁻ᵀ(t−s) ds] F̄ᵀ(t)}`
//! is written with `S̄0 = F̄⁻¹ τ0ᴰ F̄⁻ᵀ` (the isochoric elastic stress pulled
//! back by F̄) as `τᴰ = dev{F̄ [S̄0(t) − Σ g_k H_k(t)] F̄ᵀ}`,
//! `H_k(t) = ∫_0^t (1/τ_k) e^{−(t−s)/τ_k} S̄0(s) ds`, updated recursively.
//! The bulk response does not relax (`K(s) = K`): `τᴴ = K J (J − 1) I`.

use crate::PointState;
use crate::history::advance_with;
use crate::hyperelastic::add_volumetric;
use crate::kernel::{IsoStress, Kin, XCI, XH};
use crate::model::Kernel;
use crate::{F64x4, Lane};
use nalgebra::Matrix3;
use nlvid_model::{Prony, Relaxation};

use crate::{HistoryRule, Mat3, MooneyRivlin};

/// ABAQUS-form finite-strain viscoelasticity, eqs. 4.1–4.3 / 5.1.
#[derive(Debug, Clone, PartialEq)]
pub struct PronyViscoelastic {
    elastic: MooneyRivlin,
    prony: Prony,
    rule: HistoryRule,
}

/// History of a [`PronyViscoelastic`] point: `H_k` per Prony term and `S̄0`
/// at the last converged step.
#[derive(Debug, PartialEq)]
pub struct PronyViscoelasticState {
    h: Vec<Mat3>,
    sbar: Mat3,
}

/// `clone_from` reuses the history vector: a finite-element model commits
/// thousands of trial states per step (`clone_from_slice`), and the derived
/// `clone_from` would allocate a new vector for each.
impl Clone for PronyViscoelasticState {
    fn clone(&self) -> Self {
        Self {
            h: self.h.clone(),
            sbar: self.sbar,
        }
    }

    fn clone_from(&mut self, source: &Self) {
        self.h.clone_from(&source.h);
        self.sbar = source.sbar;
    }
}

impl PronyViscoelastic {
    /// Instantaneous elastic part `elastic` (its `C1`, `C2` are the t = 0⁺
    /// constants, its `K` the volumetric penalty) relaxed by `prony`
    /// (weights `g_k`, `g∞ = 1 − Σ g_k`, eq. 4.3).
    pub fn new(elastic: MooneyRivlin, prony: Prony) -> Self {
        Self {
            elastic,
            prony,
            rule: HistoryRule::default(),
        }
    }

    /// The 5-parameter cell model of eq. 5.1 from its shear relaxation
    /// modulus `G(t) = G0 [g∞ + Σ g_k e^{−t/τ_k}]`: a neo-Hookean elastic
    /// part with `C1 = G0/2` (eq. 4.1, [`MooneyRivlin::from_shear_modulus`])
    /// relaxed by `shear`'s Prony series, and the volumetric penalty
    /// `K = bulk`.
    ///
    /// # Errors
    /// [`crate::MaterialError`] naming the parameter (`G0 = 0`, `K < 0`).
    pub fn cell(shear: &Relaxation, bulk: f64) -> crate::Result<Self> {
        Ok(Self::new(
            MooneyRivlin::from_shear_modulus(shear.g0(), 0.0, bulk)?,
            shear.prony().clone(),
        ))
    }

    /// The 6-parameter capsule model of §4.3: Mooney–Rivlin `C1`,
    /// `C2 = α C1` (eq. 4.1) and two Prony terms (eqs. 4.2–4.3).
    ///
    /// # Errors
    /// [`crate::MaterialError`] naming the parameter or Prony term.
    pub fn capsule(
        c1: f64,
        alpha: f64,
        (g1, tau1): (f64, f64),
        (g2, tau2): (f64, f64),
        bulk: f64,
    ) -> crate::Result<Self> {
        Ok(Self::new(
            MooneyRivlin::with_ratio(c1, alpha, bulk)?,
            Prony::new("G", &[(g1, tau1), (g2, tau2)])?,
        ))
    }

    /// Chooses the one-step quadrature of the hereditary integral.
    pub fn with_rule(mut self, rule: HistoryRule) -> Self {
        self.rule = rule;
        self
    }

    /// Elastic (instantaneous) part.
    pub fn elastic(&self) -> &MooneyRivlin {
        &self.elastic
    }
    /// Normalised Prony series `g(t)`.
    pub fn prony(&self) -> &Prony {
        &self.prony
    }

    /// Long-time elastic response: Mooney–Rivlin with `g∞ C1`, `g∞ C2`.
    ///
    /// # Errors
    /// Never for a valid model; typed for uniformity.
    pub fn long_time(&self) -> crate::Result<MooneyRivlin> {
        let g = self.prony.long_term_weight();
        MooneyRivlin::new(
            g * self.elastic.c1(),
            g * self.elastic.c2(),
            self.elastic.bulk(),
        )
    }

    /// The small-strain shear relaxation modulus of eq. 5.1,
    /// `G(t) = 2 (C1 + C2) g(t)` (so `G0 = 2 (C1 + C2)`, `docs/theory/model.md`).
    /// [`PronyViscoelastic::cell`] of this modulus is the same material.
    ///
    /// # Errors
    /// Never for a valid model (C1 > 0, C2 ≥ 0); typed for uniformity.
    pub fn shear_relaxation(&self) -> crate::Result<Relaxation> {
        Ok(Relaxation::new(
            nlvid_model::names::G0,
            self.elastic.shear_modulus(),
            self.prony.clone(),
        )?)
    }
}

impl PointState for PronyViscoelastic {
    type State = PronyViscoelasticState;

    fn initial_state(&self) -> PronyViscoelasticState {
        PronyViscoelasticState {
            h: vec![Mat3::zeros(); self.prony.len()],
            sbar: Mat3::zeros(),
        }
    }
}

impl PronyViscoelastic {
    /// The kernel ([`Kernel::eval`]) for one point (`T = f64`) or one point
    /// per lane ([`crate::Lane`]): the history at `t_n` read by `h_n(k)`
    /// (`H_k`) and `sbar_n` (`S̄0`), the trial history written by
    /// `h_out(k, ·)` and `sbar_out`; the stress to `out` (zero on entry).
    /// Always inlined (see [`Kernel::eval`]).
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn eval_generic<T: Lane>(
        &self,
        h_n: impl Fn(usize) -> Matrix3<T>,
        sbar_n: &Matrix3<T>,
        k: &Kin<T>,
        dt: f64,
        h_out: impl FnMut(usize, Matrix3<T>),
        sbar_out: impl FnOnce(Matrix3<T>),
        bulk: f64,
        out: &mut IsoStress<T>,
    ) {
        if self.prony.is_empty() {
            // No Prony term (an elastic cell): no history and no H term;
            // the general path below would add exact zeros only.
            self.elastic.add_isochoric(k, 1.0, out);
            add_volumetric(k, bulk, out);
            return;
        }
        let mut iso = IsoStress::default();
        self.elastic.add_isochoric(k, 1.0, &mut iso);
        let j23 = k.j23;
        let sbar = iso.pk2(k) * (T::one() / j23);
        let (frozen, sum_b1) = advance_with(self.rule, &self.prony, dt, h_n, sbar_n, &sbar, h_out);
        sbar_out(sbar);
        out.add_scaled(&iso, 1.0 - sum_b1);
        // J^{-2/3} DEV(frozen) = J^{-2/3} [h − (h:C)/3 C⁻¹].
        let hc = frozen.dot(&k.c);
        out.h = frozen;
        let zero = T::zero();
        out.add(
            XH,
            j23,
            k.grad(zero, zero, T::splat(-2.0 / 3.0) * j23 / k.j, zero),
        );
        out.add(
            XCI,
            -j23 * hc / 3.0,
            k.grad(zero, zero, T::splat(2.0 / 9.0) * j23 * hc / k.j, -j23 / 3.0),
        );
        add_volumetric(k, bulk, out);
    }
}

impl Kernel for PronyViscoelastic {
    const LANES: bool = true;

    fn bulk(&self) -> f64 {
        self.elastic.bulk()
    }

    /// Always inlined: the F-bar kernel of `nlvid-fem` compiles the point
    /// update for the CPU's SIMD width (runtime dispatch), which reaches
    /// only inlined code.
    #[inline(always)]
    fn eval(
        &self,
        st: &PronyViscoelasticState,
        k: &Kin,
        dt: f64,
        trial: &mut PronyViscoelasticState,
        bulk: f64,
    ) -> IsoStress {
        if !self.prony.is_empty() {
            trial.h.resize(self.prony.len(), Mat3::zeros());
        }
        let (h, sbar) = (&mut trial.h, &mut trial.sbar);
        let mut out = IsoStress::default();
        self.eval_generic(
            |k| st.h[k],
            &st.sbar,
            k,
            dt,
            |k, x| h[k] = x,
            |x| *sbar = x,
            bulk,
            &mut out,
        );
        out
    }

    /// [`Kernel::eval`] of four points, one per lane: the histories are
    /// gathered into lanes and the trial histories scattered back.
    #[inline(always)]
    fn eval_lanes(
        &self,
        st: [&PronyViscoelasticState; 4],
        k: &Kin<F64x4>,
        dt: f64,
        trial: [&mut PronyViscoelasticState; 4],
        bulk: f64,
    ) -> IsoStress<F64x4> {
        let gather = |m: [&Mat3; 4]| {
            Matrix3::from_fn(|r, c| F64x4([m[0][(r, c)], m[1][(r, c)], m[2][(r, c)], m[3][(r, c)]]))
        };
        let [t0, t1, t2, t3] = trial;
        let mut h = [&mut t0.h, &mut t1.h, &mut t2.h, &mut t3.h];
        let sbar = [&mut t0.sbar, &mut t1.sbar, &mut t2.sbar, &mut t3.sbar];
        if !self.prony.is_empty() {
            for x in h.iter_mut() {
                x.resize(self.prony.len(), Mat3::zeros());
            }
        }
        let sbar_n = gather(st.map(|s| &s.sbar));
        let mut out = IsoStress::default();
        self.eval_generic(
            |k| gather(st.map(|s| &s.h[k])),
            &sbar_n,
            k,
            dt,
            |k, x| {
                let [h0, h1, h2, h3] = &mut h;
                scatter(&x, [&mut h0[k], &mut h1[k], &mut h2[k], &mut h3[k]]);
            },
            |x| scatter(&x, sbar),
            bulk,
            &mut out,
        );
        out
    }
}

/// Lane `l` of `x` to `out[l]`. Not inlined: inside the element kernel the
/// 36 scalar stores of the four lanes led LLVM to vectorise the history
/// update across matrix entries instead of lanes, and the kernel then read
/// that result back through misaligned partial stores (a store-forwarding
/// stall, ≈ 4.5 % of the kernel's samples on one load).
#[inline(never)]
fn scatter(x: &Matrix3<F64x4>, out: [&mut Mat3; 4]) {
    for (l, m) in out.into_iter().enumerate() {
        *m = Mat3::from_fn(|r, c| x[(r, c)].0[l]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Material3;

    #[test]
    fn clone_from_copies_the_state_into_the_existing_allocation() {
        let g = Relaxation::from_named(&nlvid_model::names::PRONY2, &[1000.0, 0.3, 0.3, 0.5, 10.0])
            .expect("valid");
        let m = PronyViscoelastic::cell(&g, 1e5).expect("valid");
        let s0 = PointState::initial_state(&m);
        let mut s1 = s0.clone();
        let f = Mat3::new(1.1, 0.1, 0.0, 0.0, 0.95, 0.0, 0.0, 0.0, 0.97);
        m.update(&s0, &f, 0.1, &mut s1).expect("update");
        let mut target = s0.clone();
        let ptr = target.h.as_ptr();
        target.clone_from(&s1);
        assert_eq!(target, s1);
        assert_ne!(target, s0);
        assert_eq!(target.h.as_ptr(), ptr, "history vector reallocated");
    }
}
