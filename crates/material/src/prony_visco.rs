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
//!
//! Per Newton iteration the update costs O(1) in the number of terms: of
//! `H_k(t_{n+1}) = E_k H_k(t_n) + β0_k S̄0(t_n) + β1_k S̄0(t_{n+1})` only the
//! last term depends on the iterate, so the step-constant parts
//! `old_k = E_k H_k(t_n) + β0_k S̄0(t_n)` and the frozen stress
//! `−Σ g_k old_k` are computed once per point and step, kept in the trial
//! state ([`PronyViscoelasticState`], a cache keyed by the committed
//! state's identity, Δt and the material) and reused by every later
//! iteration of the same step. A state stores `old_k` and `β1_k` with
//! `S̄0` instead of `H_k`: `H_k = old_k + β1_k S̄0` is formed when the
//! next step reads it (the same floating-point operations as forming it at
//! once, so results are bitwise those of the direct recursion).

use crate::PointState;
use crate::history::{advance_with, fresh_ids};
use crate::hyperelastic::add_volumetric;
use crate::kernel::{IsoStress, Kin, XCI, XH};
use crate::model::Kernel;
use crate::{F64x4, Lane};
use nalgebra::Matrix3;
use nlvid_model::{Prony, Relaxation};

use crate::{HistoryRule, Mat3, MooneyRivlin};

/// ABAQUS-form finite-strain viscoelasticity, eqs. 4.1–4.3 / 5.1.
#[derive(Clone)]
pub struct PronyViscoelastic {
    elastic: MooneyRivlin,
    prony: Prony,
    rule: HistoryRule,
    /// Identifies (series, rule) in the step cache of the states: unique
    /// per construction ([`fresh_ids`]), shared by clones (which are the
    /// same material); not part of the material's value (`PartialEq`,
    /// `Debug`).
    stamp: u64,
}

impl PartialEq for PronyViscoelastic {
    fn eq(&self, other: &Self) -> bool {
        self.elastic == other.elastic && self.prony == other.prony && self.rule == other.rule
    }
}

impl std::fmt::Debug for PronyViscoelastic {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PronyViscoelastic")
            .field("elastic", &self.elastic)
            .field("prony", &self.prony)
            .field("rule", &self.rule)
            .finish()
    }
}

/// History of a [`PronyViscoelastic`] point at one time `t`: `S̄0(t)` and
/// per Prony term `H_k(t)`, stored as `old_k` and `β1_k` of the step that
/// produced it (`H_k(t) = old_k + S̄0(t) β1_k`, [`PronyViscoelasticState::history`]);
/// plus the step cache of a trial state (module docs).
///
/// The cache is valid for the step from committed state `c` over `dt` with
/// material `m` when its key is `(c.id, dt, m.stamp)`. Every evaluation
/// gives the state it writes a new `id` (unique in the process, so two
/// states with one `id` are copies of one evaluation's result), whether or
/// not it used the cache: a copy of any trial is a valid committed state,
/// and no other state can pass for it, whatever the caller does with its
/// buffers (retried steps with a new or the same Δt, equal Δt on
/// successive steps, one scratch trial for many points, swapped buffers).
pub struct PronyViscoelasticState {
    terms: Vec<PendingTerm>,
    sbar: Mat3,
    /// Identity of this state's contents; 0 for the initial state (all
    /// initial states of one material are equal).
    id: u64,
    step: StepCache,
}

/// `H_k = old + S̄0 β1` of one term.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct PendingTerm {
    old: Mat3,
    beta1: f64,
}

/// The step-constant part of the update that wrote a trial state: valid
/// for committed state `source`, time step `dt` (bits) and material
/// `stamp`; `frozen = −Σ g_k old_k`, `sum_b1 = Σ g_k β1_k`. The `old_k`
/// themselves are the trial's `terms`.
#[derive(Debug, Clone, Copy)]
struct StepCache {
    source: u64,
    dt: u64,
    stamp: u64,
    frozen: Mat3,
    sum_b1: f64,
}

impl StepCache {
    /// Matches nothing (identifiers are never `u64::MAX`).
    const EMPTY: StepCache = StepCache {
        source: u64::MAX,
        dt: 0,
        stamp: u64::MAX,
        frozen: Mat3::new(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0),
        sum_b1: 0.0,
    };

    #[inline(always)]
    fn hit(&self, source: u64, dt: u64, stamp: u64) -> bool {
        self.source == source && self.dt == dt && self.stamp == stamp
    }
}

impl PronyViscoelasticState {
    /// `H_k` of term `k` at this state's time.
    fn history(&self, k: usize) -> Mat3 {
        let t = &self.terms[k];
        formed(t.old, &self.sbar, t.beta1)
    }
}

/// `H_k = old_k + S̄0 β1_k`: the operations of the direct recursion.
#[inline(always)]
fn formed<T: Lane>(old: Matrix3<T>, sbar: &Matrix3<T>, beta1: T) -> Matrix3<T> {
    old + sbar * beta1
}

/// `clone_from` reuses the history vector: a finite-element model commits
/// thousands of trial states per step (`clone_from_slice`), and the derived
/// `clone_from` would allocate a new vector for each.
impl Clone for PronyViscoelasticState {
    fn clone(&self) -> Self {
        Self {
            terms: self.terms.clone(),
            sbar: self.sbar,
            id: self.id,
            step: self.step,
        }
    }

    fn clone_from(&mut self, source: &Self) {
        self.terms.clone_from(&source.terms);
        self.sbar = source.sbar;
        self.id = source.id;
        self.step = source.step;
    }
}

/// The history's value: `H_k` and `S̄0` (not how `H_k` is stored, not the
/// identity or the step cache).
impl PartialEq for PronyViscoelasticState {
    fn eq(&self, other: &Self) -> bool {
        self.sbar == other.sbar
            && self.terms.len() == other.terms.len()
            && (0..self.terms.len()).all(|k| self.history(k) == other.history(k))
    }
}

/// The history's value, `h` (`H_k`) and `sbar` (`S̄0`), as [`PartialEq`].
impl std::fmt::Debug for PronyViscoelasticState {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let h: Vec<Mat3> = (0..self.terms.len()).map(|k| self.history(k)).collect();
        f.debug_struct("PronyViscoelasticState")
            .field("h", &h)
            .field("sbar", &self.sbar)
            .finish()
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
            stamp: fresh_ids::<1>()[0],
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
        // Another material: states cached for the old rule must miss.
        self.stamp = fresh_ids::<1>()[0];
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
            terms: vec![PendingTerm::default(); self.prony.len()],
            sbar: Mat3::zeros(),
            id: 0,
            step: StepCache::EMPTY,
        }
    }
}

impl PronyViscoelastic {
    /// The kernel ([`Kernel::eval`]) for one point (`T = f64`) or one point
    /// per lane ([`crate::Lane`]), given the step-constant part
    /// `step = (−Σ g_k old_k, Σ g_k β1_k)` of the history (`None` without
    /// Prony terms): the stress to `out` (zero on entry), `S̄0(t_{n+1})` to
    /// `sbar_out`. Always inlined (see [`Kernel::eval`]).
    #[inline(always)]
    fn eval_generic<T: Lane>(
        &self,
        k: &Kin<T>,
        step: Option<(Matrix3<T>, f64)>,
        sbar_out: impl FnOnce(Matrix3<T>),
        bulk: f64,
        out: &mut IsoStress<T>,
    ) {
        let Some((frozen, sum_b1)) = step else {
            // No Prony term (an elastic cell): no history and no H term;
            // the general path below would add exact zeros only.
            self.elastic.add_isochoric(k, 1.0, out);
            add_volumetric(k, bulk, out);
            return;
        };
        let mut iso = IsoStress::default();
        self.elastic.add_isochoric(k, 1.0, &mut iso);
        let j23 = k.j23;
        let sbar = iso.pk2(k) * (T::one() / j23);
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

    /// The step-constant part of the history update from the committed
    /// histories (`H_k(t_n)` read by `h_n(k)`, `S̄0(t_n)`), once per point
    /// and step: `old_k`, `β1_k` to `term_out(k, ·, ·)`; returns
    /// `(−Σ g_k old_k, Σ g_k β1_k)`.
    #[inline(always)]
    fn step_constant<T: Lane>(
        &self,
        h_n: impl Fn(usize) -> Matrix3<T>,
        sbar_n: &Matrix3<T>,
        dt: f64,
        term_out: impl FnMut(usize, Matrix3<T>, f64),
    ) -> (Matrix3<T>, f64) {
        advance_with(self.rule, &self.prony, dt, h_n, sbar_n, term_out)
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
        let mut out = IsoStress::default();
        let n = self.prony.len();
        let step = if n == 0 {
            None
        } else if trial.terms.len() == n && trial.step.hit(st.id, dt.to_bits(), self.stamp) {
            Some((trial.step.frozen, trial.step.sum_b1))
        } else {
            trial.terms.resize(n, PendingTerm::default());
            let terms = &mut trial.terms;
            let (frozen, sum_b1) = self.step_constant(
                |k| formed(st.terms[k].old, &st.sbar, st.terms[k].beta1),
                &st.sbar,
                dt,
                |k, old, beta1| terms[k] = PendingTerm { old, beta1 },
            );
            trial.step = StepCache {
                source: st.id,
                dt: dt.to_bits(),
                stamp: self.stamp,
                frozen,
                sum_b1,
            };
            Some((frozen, sum_b1))
        };
        if n > 0 {
            trial.id = fresh_ids::<1>()[0];
        }
        let sbar = &mut trial.sbar;
        self.eval_generic(k, step, |x| *sbar = x, bulk, &mut out);
        out
    }

    /// [`Kernel::eval`] of four points, one per lane: the histories are
    /// gathered into lanes and the trial histories scattered back. The
    /// step cache is used only if it is valid in all four lanes (else all
    /// four are recomputed, which rewrites a valid lane's cache with the
    /// same values).
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
        let n = self.prony.len();
        let dt_bits = dt.to_bits();
        let step = if n == 0 {
            None
        } else if [&*t0, &*t1, &*t2, &*t3]
            .iter()
            .zip(st)
            .all(|(t, s)| t.terms.len() == n && t.step.hit(s.id, dt_bits, self.stamp))
        {
            let frozen = gather([
                &t0.step.frozen,
                &t1.step.frozen,
                &t2.step.frozen,
                &t3.step.frozen,
            ]);
            Some((frozen, t0.step.sum_b1))
        } else {
            let mut terms = [&mut t0.terms, &mut t1.terms, &mut t2.terms, &mut t3.terms];
            for x in terms.iter_mut() {
                x.resize(n, PendingTerm::default());
            }
            let sbar_n = gather(st.map(|s| &s.sbar));
            let (frozen, sum_b1) = self.step_constant(
                |k| {
                    let old = gather(st.map(|s| &s.terms[k].old));
                    formed(old, &sbar_n, F64x4(st.map(|s| s.terms[k].beta1)))
                },
                &sbar_n,
                dt,
                |k, old, beta1| {
                    let [h0, h1, h2, h3] = &mut terms;
                    let out = [&mut h0[k], &mut h1[k], &mut h2[k], &mut h3[k]];
                    scatter(
                        &old,
                        out.map(|t| {
                            t.beta1 = beta1;
                            &mut t.old
                        }),
                    );
                },
            );
            for (t, s) in [&mut *t0, &mut *t1, &mut *t2, &mut *t3].into_iter().zip(st) {
                t.step.source = s.id;
                t.step.dt = dt_bits;
                t.step.stamp = self.stamp;
                t.step.sum_b1 = sum_b1;
            }
            scatter(
                &frozen,
                [
                    &mut t0.step.frozen,
                    &mut t1.step.frozen,
                    &mut t2.step.frozen,
                    &mut t3.step.frozen,
                ],
            );
            Some((frozen, sum_b1))
        };
        if n > 0 {
            let ids = fresh_ids::<4>();
            t0.id = ids[0];
            t1.id = ids[1];
            t2.id = ids[2];
            t3.id = ids[3];
        }
        let sbar = [&mut t0.sbar, &mut t1.sbar, &mut t2.sbar, &mut t3.sbar];
        let mut out = IsoStress::default();
        self.eval_generic(k, step, |x| scatter(&x, sbar), bulk, &mut out);
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

    /// A two-term cell material (G0 1000 Pa, g 0.3 / 0.3, τ 0.5 / 10 s,
    /// κ 1e5 Pa) the state tests share.
    fn two_term_cell() -> PronyViscoelastic {
        let g = Relaxation::from_named(&nlvid_model::names::PRONY2, &[1000.0, 0.3, 0.3, 0.5, 10.0])
            .expect("valid");
        PronyViscoelastic::cell(&g, 1e5).expect("valid")
    }

    #[test]
    fn clone_from_copies_the_state_into_the_existing_allocation() {
        let m = two_term_cell();
        let s0 = PointState::initial_state(&m);
        let mut s1 = s0.clone();
        let f = Mat3::new(1.1, 0.1, 0.0, 0.0, 0.95, 0.0, 0.0, 0.0, 0.97);
        m.update(&s0, &f, 0.1, &mut s1).expect("update");
        let mut target = s0.clone();
        let ptr = target.terms.as_ptr();
        target.clone_from(&s1);
        assert_eq!(target, s1);
        assert_ne!(target, s0);
        assert_eq!(target.terms.as_ptr(), ptr, "history vector reallocated");
    }

    /// The step cache against the direct recursion, bitwise: four points
    /// through a sequence of Newton-like iterations into the same trial
    /// buffers (lanes and one by one, alternately) with rejected steps
    /// retried with another and with the same Δt, equal Δt on successive
    /// steps, Δt = 0, a material change within a step, commits by copy and
    /// by swap, and one scratch trial shared by all points; against
    /// updates into fresh trial states (no cache) and against
    /// `H_k(t_{n+1}) = E_k H_k(t_n) + β0_k S̄0(t_n) + β1_k S̄0(t_{n+1})`.
    #[test]
    fn step_cache_is_bitwise_the_direct_recursion() {
        use crate::{AxisymmetricResponse, F64x4};
        let m = two_term_cell();
        let trapezoid = m.clone().with_rule(HistoryRule::Trapezoid);
        let f_at = |step: usize, it: usize, p: usize| -> [f64; 5] {
            let s = 0.02 * (step as f64 + 1.0) + 0.003 * it as f64 + 0.01 * p as f64;
            [1.0 + s, 0.3 * s, -0.2 * s, 1.0 - 0.5 * s, 1.0 - 0.4 * s]
        };
        let bits = |r: &AxisymmetricResponse| -> Vec<u64> {
            r.first_piola
                .iter()
                .chain(r.tangent.iter().flatten())
                .map(|x| x.to_bits())
                .collect()
        };
        // One point's update with tangent, into `trial`.
        let one = |mat: &PronyViscoelastic,
                   st: &PronyViscoelasticState,
                   f: &[f64; 5],
                   dt: f64,
                   trial: &mut PronyViscoelasticState| {
            Material3::update_axisymmetric(mat, st, f, dt, trial, true).expect("update")
        };
        // (Δt, iterations, accepted)
        let plan = [
            (0.1, 3, true),
            (0.1, 2, true),
            (0.4, 3, false),
            (0.2, 3, true),
            (0.2, 2, false),
            (0.2, 4, true),
            (0.0, 2, true),
            (0.05, 3, true),
            (0.05, 1, true),
        ];
        let init = PointState::initial_state(&m);
        let mut committed = vec![init.clone(); 4];
        let mut trial = vec![init.clone(); 4];
        let mut reference = vec![init.clone(); 4];
        let mut scratch = init.clone();
        let mut direct_h = vec![vec![Mat3::zeros(); 2]; 4];
        let mut direct_sbar = vec![Mat3::zeros(); 4];
        for (step, &(dt, iterations, accepted)) in plan.iter().enumerate() {
            let mut last_ref = vec![init.clone(); 4];
            for it in 0..iterations {
                let mat = if step == 3 && it == 1 { &trapezoid } else { &m };
                let f: Vec<[f64; 5]> = (0..4).map(|p| f_at(step, it, p)).collect();
                // The reference: a fresh trial state every time.
                let want: Vec<AxisymmetricResponse> = (0..4)
                    .map(|p| {
                        let mut fresh = init.clone();
                        let r = Material3::update_axisymmetric(
                            mat,
                            &reference[p],
                            &f[p],
                            dt,
                            &mut fresh,
                            true,
                        )
                        .expect("update");
                        last_ref[p] = fresh;
                        r
                    })
                    .collect();
                if it % 2 == 0 {
                    let fl: [F64x4; 5] =
                        std::array::from_fn(|c| F64x4(std::array::from_fn(|l| f[l][c])));
                    let mut p_out = [F64x4([0.0; 4]); 5];
                    let mut a_out = [[F64x4([0.0; 4]); 5]; 5];
                    let [c0, c1, c2, c3] = &committed[..] else {
                        unreachable!()
                    };
                    let [t0, t1, t2, t3] = &mut trial[..] else {
                        unreachable!()
                    };
                    assert!(Material3::update_axisymmetric_lanes(
                        mat,
                        [c0, c1, c2, c3],
                        &fl,
                        dt,
                        [t0, t1, t2, t3],
                        true,
                        &mut p_out,
                        &mut a_out,
                    ));
                    for (p, w) in want.iter().enumerate() {
                        let got = AxisymmetricResponse {
                            first_piola: p_out.map(|x| x.0[p]),
                            tangent: a_out.map(|row| row.map(|x| x.0[p])),
                        };
                        assert_eq!(bits(&got), bits(w), "lanes, step {step} it {it} point {p}");
                    }
                } else {
                    for p in 0..4 {
                        let got = one(mat, &committed[p], &f[p], dt, &mut trial[p]);
                        assert_eq!(bits(&got), bits(&want[p]), "step {step} it {it} point {p}");
                    }
                }
                if it == 0 {
                    // One scratch trial for every point (equal Δt, states
                    // of the same step).
                    for p in 0..4 {
                        let got = one(mat, &committed[p], &f[p], dt, &mut scratch);
                        assert_eq!(bits(&got), bits(&want[p]), "scratch, step {step} point {p}");
                    }
                }
            }
            for p in 0..4 {
                assert_eq!(format!("{:?}", trial[p]), format!("{:?}", last_ref[p]));
            }
            if !accepted {
                continue;
            }
            for p in 0..4 {
                // H_k(t_{n+1}) by the direct recursion (the last iteration
                // used `m`, the default rule).
                let sbar_new = last_ref[p].sbar;
                for (k, term) in m.prony().terms().iter().enumerate() {
                    let w = HistoryRule::ExponentialLinear.weights(dt, term.tau);
                    direct_h[p][k] =
                        direct_h[p][k] * w.decay + direct_sbar[p] * w.beta0 + sbar_new * w.beta1;
                }
                direct_sbar[p] = sbar_new;
                reference[p] = last_ref[p].clone();
                if step % 2 == 0 {
                    committed[p].clone_from(&trial[p]);
                } else {
                    std::mem::swap(&mut committed[p], &mut trial[p]);
                }
                assert_eq!(committed[p], reference[p]);
                assert_eq!(
                    committed[p].sbar.map(f64::to_bits),
                    direct_sbar[p].map(f64::to_bits)
                );
                for k in 0..2 {
                    assert_eq!(
                        committed[p].history(k).map(f64::to_bits),
                        direct_h[p][k].map(f64::to_bits),
                        "H_{k} at step {step}, point {p}"
                    );
                }
            }
        }
        assert_ne!(direct_h[0][0], Mat3::zeros());
    }

    /// Two trial states of one step (after different iterations, so with
    /// different `S̄0`) used as committed states into one trial buffer
    /// with the same Δt: the second must not reuse the first's cache.
    #[test]
    fn every_evaluation_gives_its_state_a_new_identity() {
        let m = two_term_cell();
        let s0 = PointState::initial_state(&m);
        let f1 = Mat3::new(1.1, 0.1, 0.0, 0.0, 0.95, 0.0, 0.0, 0.0, 0.97);
        let f2 = Mat3::new(1.2, 0.1, 0.0, 0.0, 0.9, 0.0, 0.0, 0.0, 0.93);
        let mut trial = s0.clone();
        m.update(&s0, &f1, 0.1, &mut trial).expect("update");
        let a = trial.clone();
        m.update(&s0, &f2, 0.1, &mut trial).expect("update");
        let b = trial.clone();
        assert_ne!(a, b);
        let mut scratch = s0.clone();
        m.update(&a, &f2, 0.1, &mut scratch).expect("update");
        let got = m.update(&b, &f2, 0.1, &mut scratch).expect("update");
        let mut fresh = s0.clone();
        let want = m.update(&b, &f2, 0.1, &mut fresh).expect("update");
        assert_eq!(got, want);
        assert_eq!(scratch, fresh);
    }
}
