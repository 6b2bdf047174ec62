//! The F-bar (mean-dilatation) element kernel, one piece of code for the
//! axisymmetric Q4 of [`crate::element`] (F stored as 5 components, 8 dofs,
//! 4 Gauss points) and the hexahedron of [`crate::hex`] (9 components, 24
//! dofs, 8 Gauss points).
//!
//! An element kind supplies its Gauss-point geometry as a [`FbarPoint`]: how
//! F and `Bᵀ v` follow from the dofs, `J = det F` with its derivatives with
//! respect to the stored components, and the material update in its storage.
//! The kernel is generic over the point type and the three sizes, so it is
//! monomorphised per element kind and material: the loops have constant
//! bounds as in a hand-written kernel, no allocation, no dynamic dispatch.
//! It is generic over the number type too ([`nlvid_material::Lane`]): `f64`
//! for one element, [`nlvid_material::F64x4`] for four elements at once, one
//! per AVX2 lane (`crate::element::fbar_kernel_lanes`: the axisymmetric Q4
//! with the material crate's cell models, docs/theory/fem.md "Session 20").
//! Every lane performs the one-element arithmetic in the same order, so its
//! results are bitwise the one-element results.
//!
//! The material sees `F̄ = (J̄/J)^{1/3} F` with `J̄ = ∫J dV₀ / ∫dV₀`; the
//! element is the stationary point of `∫ Ψ(F̄(u)) dV₀` (module docs of
//! [`crate::element`] and [`crate::hex`]).

use crate::local::{LocalOutput, PointFailure, TangentPart, bad_length};
use nlvid_material::{Lane, Mat3, Material3, MaterialError};

/// One Gauss point of an element whose deformation gradient is stored as
/// `NF` components and whose dof vector has `ND` entries: its geometry, in
/// numbers of type `T` (`f64`, or one element per lane of
/// [`nlvid_material::F64x4`]).
#[doc(hidden)]
pub trait FbarPoint<T: Lane, const NF: usize, const ND: usize> {
    /// Integration weight (m³).
    fn weight(&self) -> T;
    /// The stored F components for element displacements `u`.
    fn deformation(&self, u: &[T; ND]) -> [T; NF];
    /// `Bᵀ v` with B = ∂F/∂u (constant: F is linear in u).
    fn bt_v(&self, v: &[T; NF]) -> [T; ND];
    /// `out += Bᵀ M B`, rows `r` and columns `c ≤ r` only if `lower`.
    fn add_bt_m_b(&self, out: &mut [[T; ND]; ND], m: &[[T; NF]; NF], lower: bool);
    /// J = det F, its gradient and Hessian w.r.t. the stored components.
    fn jacobian(f: &[T; NF]) -> (T, [T; NF], [[T; NF]; NF]);
    /// `m += c H_J` with H_J = ∂²J/∂F² at `f` (the Hessian of
    /// [`FbarPoint::jacobian`]); a kind whose Hessian is sparse adds only
    /// its non-zero entries (adding `c · 0` leaves `m` unchanged).
    #[inline]
    fn add_jacobian_hessian(f: &[T; NF], c: T, m: &mut [[T; NF]; NF]) {
        let h = Self::jacobian(f).2;
        for i in 0..NF {
            for k in 0..NF {
                m[i][k] += c * h[i][k];
            }
        }
    }
}

/// A [`FbarPoint`] of one element (`f64`) with its material update.
#[doc(hidden)]
pub trait FbarMaterialPoint<const NF: usize, const ND: usize>: FbarPoint<f64, NF, ND> {
    /// The 3×3 matrix of the stored components.
    fn matrix(f: &[f64; NF]) -> Mat3;
    /// First Piola–Kirchhoff stress P and ∂P/∂F (stored components) of the
    /// point update at F (the tangent only if `tangent`; else unspecified).
    ///
    /// # Errors
    /// The material's error.
    fn update<M: Material3>(
        material: &M,
        state_n: &M::State,
        f: &[f64; NF],
        dt: f64,
        trial: &mut M::State,
        tangent: bool,
    ) -> Result<([f64; NF], [[f64; NF]; NF]), MaterialError>;
}

/// `Err` naming point `q` unless `j = det F > 0` (in every lane; the value
/// of the first lane that fails is named).
#[inline]
pub(crate) fn positive_jacobian<T: Lane>(q: usize, j: T) -> Result<(), PointFailure> {
    if j.all_positive() {
        Ok(())
    } else {
        let j = (0..T::WIDTH)
            .map(|i| j.lane(i))
            .find(|x| !(*x > 0.0))
            .unwrap_or(f64::NAN);
        Err((
            q,
            MaterialError::Deformation(format!("det F = {j:.3e} ≤ 0")),
        ))
    }
}

/// The material update at the Gauss points of the element(s) the kernel
/// evaluates: `P` and `∂P/∂F` (stored components; the tangent only if
/// `tangent`) at point `q` for `f`, writing the point's trial history.
#[doc(hidden)]
pub trait PointUpdate<T, const NF: usize> {
    /// The update at point `q`: `P` to `p`, `∂P/∂F` to `a` if `tangent`.
    ///
    /// # Errors
    /// The material's error.
    fn update(
        &mut self,
        q: usize,
        f: &[T; NF],
        tangent: bool,
        p: &mut [T; NF],
        a: &mut [[T; NF]; NF],
    ) -> Result<(), MaterialError>;
}

/// The points of one element: `material` with the element's histories,
/// updated through [`FbarMaterialPoint::update`].
pub(crate) struct ElementPoints<'a, M: Material3, P, const ND: usize> {
    pub material: &'a M,
    pub state_n: &'a [M::State],
    pub trial: &'a mut [M::State],
    pub dt: f64,
    /// The point type and its number of dofs.
    pub point: std::marker::PhantomData<(P, [f64; ND])>,
}

impl<M, P, const NF: usize, const ND: usize> PointUpdate<f64, NF> for ElementPoints<'_, M, P, ND>
where
    M: Material3,
    P: FbarMaterialPoint<NF, ND>,
{
    /// Always inlined into the kernel's SIMD dispatch.
    #[inline(always)]
    fn update(
        &mut self,
        q: usize,
        f: &[f64; NF],
        tangent: bool,
        p: &mut [f64; NF],
        a: &mut [[f64; NF]; NF],
    ) -> Result<(), MaterialError> {
        (*p, *a) = P::update(
            self.material,
            &self.state_n[q],
            f,
            self.dt,
            &mut self.trial[q],
            tangent,
        )?;
        Ok(())
    }
}

/// `Σ x` in the order of `f64`'s `Sum` (from −0, which adds exactly).
#[inline(always)]
fn sum<T: Lane>(x: impl IntoIterator<Item = T>) -> T {
    x.into_iter().fold(T::splat(-0.0), |s, y| s + y)
}

/// Internal force and tangent of one F-bar element (module docs), F-bar if
/// `fbar`, plain displacement element otherwise (for the locking
/// comparison). Writes the trial history of the element's points.
/// `part` = [`TangentPart::Lower`] computes the entries `k[r][c]`, `c ≤ r`,
/// only (the rest stays zero); they are the same numbers as with
/// [`TangentPart::Full`].
///
/// The tangent K = Σ_q w_q ∂²Ψ(F̄_q)/∂u² is assembled in a regrouped form
/// (one Bᵀ M B product per Gauss point plus rank-one terms) that is
/// algebraically identical to the direct form; with
/// ln α = (ln J̄ − ln J_q)/3, F̄ = α F, B̄ = α B + F ⊗ ∂α:
///
/// ```text
/// K = Σ_q Bᵀ [w α² A + c_q H_J] B                     (c_q = S w_q /(3 V J̄) − s_q /(3 J_q))
///   + Σ_q [v_q ⊗ ∂lnα + ∂lnα ⊗ v'_q + (α² Fᵀ w A F + s_q) ∂lnα ⊗ ∂lnα + s_q/(3J_q²) ∂J ⊗ ∂J]
///   − (S/3) ∂lnJ̄ ⊗ ∂lnJ̄ ,
/// v_q = α² Bᵀ w A F + w α Bᵀ P,  v'_q = α² Bᵀ w Aᵀ F + w α Bᵀ P,
/// s_q = w α P : F,  S = Σ_q s_q ,
/// ```
///
/// A = ∂P/∂F at F̄_q, H_J = ∂²J/∂F², V the element volume. The test
/// `regrouped_tangent_equals_direct_form` (crates/fem/src/element.rs) checks
/// it against the direct form, and the finite-difference tests of both
/// element kinds against the residual.
///
/// The kernel is compiled for the widest SIMD instruction set of the CPU,
/// chosen at run time (`pulp::Arch::dispatch`; AVX2 on current x86-64), so
/// LLVM vectorises its small fixed-size loops 4 wide instead of the
/// baseline's 2 wide (SSE2). Rust never fuses `a * b + c` into a
/// multiply–add, so the results are bitwise those of the baseline build.
///
/// # Errors
/// The failing Gauss point and the material's error (also for det F ≤ 0
/// and for a dof vector `u` without `ND` entries).
#[allow(clippy::too_many_arguments)]
pub(crate) fn fbar_kernel<M, P, const NF: usize, const ND: usize, const NQ: usize>(
    material: &M,
    geometry: &[P; NQ],
    u: &[f64],
    state_n: &[M::State],
    trial: &mut [M::State],
    dt: f64,
    fbar: bool,
    part: TangentPart,
    out: &mut LocalOutput<ND>,
) -> Result<(), PointFailure>
where
    M: Material3,
    P: FbarMaterialPoint<NF, ND>,
{
    let u: &[f64; ND] = u.try_into().map_err(|_| bad_length(u.len()))?;
    let points = ElementPoints::<M, P, ND> {
        material,
        state_n,
        trial,
        dt,
        point: std::marker::PhantomData,
    };
    let mut scratch = KernelScratch::default();
    fbar_kernel_in(geometry, u, points, fbar, part, &mut scratch, out)
}

/// The per-point intermediates of [`fbar_kernel_in`] at its `NQ` points,
/// in numbers of type `T`: F, ∂J/∂u, w ∂P/∂F, ∂ln α/∂u, P and Bᵀ P
/// (≈ 7.5 kB for four elements in lanes). A caller that evaluates many
/// elements keeps one and passes it to every call, so it is not zeroed at
/// every call (six memsets per group of four elements in lanes); each call
/// writes every entry it reads.
#[doc(hidden)]
pub struct KernelScratch<T, const NF: usize, const ND: usize, const NQ: usize> {
    f: [[T; NF]; NQ],
    dju: [[T; ND]; NQ],
    wa: [[[T; NF]; NF]; NQ],
    dlnalpha: [[T; ND]; NQ],
    p: [[T; NF]; NQ],
    bp: [[T; ND]; NQ],
}

impl<T: Lane, const NF: usize, const ND: usize, const NQ: usize> Default
    for KernelScratch<T, NF, ND, NQ>
{
    fn default() -> Self {
        let zero = T::zero();
        Self {
            f: [[zero; NF]; NQ],
            dju: [[zero; ND]; NQ],
            wa: [[[zero; NF]; NF]; NQ],
            dlnalpha: [[zero; ND]; NQ],
            p: [[zero; NF]; NQ],
            bp: [[zero; ND]; NQ],
        }
    }
}

/// [`fbar_kernel`] for numbers of type `T` ([`nlvid_material::Lane`]): one
/// element (`f64`) or one element per lane, the material update given by
/// `points`. The same code for both, so each lane's result is bitwise the
/// one-element result. `scratch` holds the intermediates (its contents on
/// entry do not matter).
///
/// # Errors
/// As [`fbar_kernel`].
pub(crate) fn fbar_kernel_in<T, P, U, const NF: usize, const ND: usize, const NQ: usize>(
    geometry: &[P; NQ],
    u: &[T; ND],
    points: U,
    fbar: bool,
    part: TangentPart,
    scratch: &mut KernelScratch<T, NF, ND, NQ>,
    out: &mut LocalOutput<ND, T>,
) -> Result<(), PointFailure>
where
    T: Lane,
    P: FbarPoint<T, NF, ND>,
    U: PointUpdate<T, NF>,
{
    pulp::Arch::new().dispatch(Dispatch {
        geometry,
        u,
        points,
        fbar,
        part,
        scratch,
        out,
    })
}

/// The arguments of [`fbar_kernel_in`] as a `pulp::WithSimd` operation: its
/// `with_simd` is inlined into pulp's `#[target_feature]` entry points, and
/// the kernel into it, so the whole kernel (material update included) is
/// compiled for that instruction set. (A closure would stay a separate
/// function compiled for the baseline.)
struct Dispatch<'a, T, P, U, const NF: usize, const ND: usize, const NQ: usize> {
    geometry: &'a [P; NQ],
    u: &'a [T; ND],
    points: U,
    fbar: bool,
    part: TangentPart,
    scratch: &'a mut KernelScratch<T, NF, ND, NQ>,
    out: &'a mut LocalOutput<ND, T>,
}

impl<T, P, U, const NF: usize, const ND: usize, const NQ: usize> pulp::WithSimd
    for Dispatch<'_, T, P, U, NF, ND, NQ>
where
    T: Lane,
    P: FbarPoint<T, NF, ND>,
    U: PointUpdate<T, NF>,
{
    type Output = Result<(), PointFailure>;

    /// The body of [`fbar_kernel`], inlined into pulp's entry point for
    /// the instruction set.
    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) -> Self::Output {
        let Self {
            geometry,
            u,
            mut points,
            fbar,
            part,
            scratch,
            out,
        } = self;
        let KernelScratch {
            f,
            dju,
            wa,
            dlnalpha,
            p,
            bp,
        } = scratch;
        let zero = T::zero();
        let tangent = part != TangentPart::None;
        let lower = part == TangentPart::Lower;
        out.r = [zero; ND];
        if tangent {
            out.k = [[zero; ND]; ND];
        }
        let mut jq = [zero; NQ];
        let mut vol = zero;
        let mut jbar = zero;
        let mut djbar = [zero; ND];
        for q in 0..NQ {
            let g = &geometry[q];
            f[q] = g.deformation(u);
            let (j, dj, _) = P::jacobian(&f[q]);
            positive_jacobian(q, j)?;
            jq[q] = j;
            if fbar {
                let w = g.weight();
                dju[q] = g.bt_v(&dj);
                vol += w;
                jbar += w * j;
                for c in 0..ND {
                    djbar[c] += w * dju[q][c];
                }
            }
        }
        // Divisions are the slowest arithmetic of the kernel (a 4-wide
        // division costs ≈ 8 multiplications): each divisor is inverted once.
        let third = T::splat(1.0 / 3.0);
        let mut dlnjbar = [zero; ND];
        if fbar {
            jbar /= vol;
            let s = T::one() / (vol * jbar);
            for c in 0..ND {
                dlnjbar[c] = djbar[c] * s;
            }
        }
        // Pass 1: material response at every point, residual, per-point terms.
        let mut alpha = [T::one(); NQ];
        let mut s_q = [zero; NQ];
        if !fbar {
            // Read by the residual below (the plain element has α = 1).
            *dlnalpha = [[zero; ND]; NQ];
        } else {
            // Every point's α (a cube root: a chain of dependent divisions)
            // before the first material update, so the CPU overlaps the
            // points' chains instead of waiting for each in turn.
            for q in 0..NQ {
                let ij = T::one() / jq[q];
                for c in 0..ND {
                    dlnalpha[q][c] = (dlnjbar[c] - dju[q][c] * ij) * third;
                }
                alpha[q] = (jbar / jq[q]).cube_root();
            }
        }
        for q in 0..NQ {
            let g = &geometry[q];
            let w = g.weight();
            let a = alpha[q];
            let fbar_q = f[q].map(|x| a * x);
            points
                .update(q, &fbar_q, tangent, &mut p[q], &mut wa[q])
                .map_err(|e| (q, e))?;
            if tangent {
                for m in wa[q].iter_mut().flatten() {
                    *m = w * *m;
                }
            }
            // r = w B̄ᵀ P = w α Bᵀ P + w (P : F) ∂α.
            let gp = g.bt_v(&p[q]);
            bp[q] = gp;
            let pf = sum((0..NF).map(|i| p[q][i] * f[q][i]));
            s_q[q] = w * a * pf;
            for c in 0..ND {
                out.r[c] += w * a * gp[c] + s_q[q] * dlnalpha[q][c];
            }
        }
        if !tangent {
            return Ok(());
        }
        let s_total = sum(s_q);
        for q in 0..NQ {
            let g = &geometry[q];
            let w = g.weight();
            let a = alpha[q];
            let waq = &wa[q];
            let mut mq = [[zero; NF]; NF];
            for i in 0..NF {
                for k in 0..NF {
                    mq[i][k] = a * a * waq[i][k];
                }
            }
            if fbar {
                let three = T::splat(3.0);
                let cq = s_total * w / (three * vol * jbar) - s_q[q] / (three * jq[q]);
                P::add_jacobian_hessian(&f[q], cq, &mut mq);
            }
            g.add_bt_m_b(&mut out.k, &mq, lower);
            if !fbar {
                continue;
            }
            // Fᵀ(wA), (wA)F and Fᵀ(wA)F.
            let mut af = [zero; NF];
            let mut fa = [zero; NF];
            for i in 0..NF {
                for k in 0..NF {
                    af[i] += waq[i][k] * f[q][k];
                    fa[k] += f[q][i] * waq[i][k];
                }
            }
            let mut faf = zero;
            for i in 0..NF {
                faf += f[q][i] * af[i];
            }
            let baf = g.bt_v(&af);
            let bfa = g.bt_v(&fa);
            let mut v = [zero; ND];
            let mut vt = [zero; ND];
            for c in 0..ND {
                v[c] = a * a * baf[c] + w * a * bp[q][c];
                vt[c] = a * a * bfa[c] + w * a * bp[q][c];
            }
            let dl = &dlnalpha[q];
            let cc = a * a * faf + s_q[q];
            let cj = s_q[q] / (T::splat(3.0) * jq[q] * jq[q]);
            let dj = &dju[q];
            for r in 0..ND {
                let (vr, dlr, cdl, cjr) = (v[r], dl[r], cc * dl[r], cj * dj[r]);
                let row = &mut out.k[r];
                let end = if lower { r + 1 } else { ND };
                for c in 0..end {
                    row[c] += vr * dl[c] + dlr * vt[c] + cdl * dl[c] + cjr * dj[c];
                }
            }
        }
        if fbar {
            let w = -s_total / 3.0;
            for r in 0..ND {
                let ar = dlnjbar[r] * w;
                let end = if lower { r + 1 } else { ND };
                for c in 0..end {
                    out.k[r][c] += ar * dlnjbar[c];
                }
            }
        }
        Ok(())
    }
}

/// The stored energy `Σ_q w_q ψ(F̄_q)` of one element for a strain-energy
/// density `psi` (J; the full revolution for axisymmetric elements): the
/// potential whose gradient [`fbar_kernel`] returns. NaN if `u` does not
/// have `ND` entries.
pub(crate) fn fbar_energy<P, const NF: usize, const ND: usize, const NQ: usize>(
    geometry: &[P; NQ],
    u: &[f64],
    fbar: bool,
    psi: &dyn Fn(&Mat3) -> f64,
) -> f64
where
    P: FbarMaterialPoint<NF, ND>,
{
    let Ok(u) = <&[f64; ND]>::try_from(u) else {
        return f64::NAN;
    };
    let mut f = [[0.0; NF]; NQ];
    let mut jq = [0.0; NQ];
    let (mut vol, mut jbar) = (0.0, 0.0);
    for q in 0..NQ {
        f[q] = geometry[q].deformation(u);
        jq[q] = P::jacobian(&f[q]).0;
        vol += geometry[q].weight();
        jbar += geometry[q].weight() * jq[q];
    }
    jbar /= vol;
    let mut e = 0.0;
    for q in 0..NQ {
        let a = if fbar {
            nlvid_material::cube_root(jbar / jq[q])
        } else {
            1.0
        };
        e += geometry[q].weight() * psi(&P::matrix(&f[q].map(|x| a * x)));
    }
    e
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::PointGeometry;
    use crate::hex::HexPoint;
    use nlvid_material::PointState;

    /// ∂J/∂F and ∂²J/∂F² of a storage `P` against central differences of
    /// J, and J against the determinant of the 3×3 matrix.
    fn jacobian_matches_finite_differences<P, const NF: usize, const ND: usize>(
        f: [f64; NF],
        tol: f64,
    ) where
        P: FbarMaterialPoint<NF, ND>,
    {
        let (j, dj, hj) = P::jacobian(&f);
        let h = 1e-6;
        for k in 0..NF {
            let (mut fp, mut fm) = (f, f);
            fp[k] += h;
            fm[k] -= h;
            let (jp, dp, _) = P::jacobian(&fp);
            let (jm, dm, _) = P::jacobian(&fm);
            assert!(((jp - jm) / (2.0 * h) - dj[k]).abs() < tol, "dJ[{k}]");
            for i in 0..NF {
                assert!(
                    ((dp[i] - dm[i]) / (2.0 * h) - hj[i][k]).abs() < tol,
                    "H[{i}][{k}]"
                );
            }
        }
        assert!((j - P::matrix(&f).determinant()).abs() < 1e-15);
        let mut m = [[0.0; NF]; NF];
        P::add_jacobian_hessian(&f, 1.0, &mut m);
        assert_eq!(m, hj, "add_jacobian_hessian");
    }

    #[test]
    fn jacobian_gradient_and_hessian_match_finite_differences() {
        jacobian_matches_finite_differences::<PointGeometry, 5, 8>(
            [1.1, 0.2, -0.15, 0.93, 1.07],
            1e-8,
        );
        jacobian_matches_finite_differences::<HexPoint, 9, 24>(
            [1.1, 0.2, -0.15, 0.05, 0.93, 0.07, -0.1, 0.12, 1.07],
            1e-9,
        );
    }

    /// The AFM cell material with history and a time step, a distorted
    /// element, large deformation: the full tangent is symmetric to
    /// round-off (it is the Hessian of the incremental potential), so the
    /// lower triangle carries all of it; `Lower` computes exactly that
    /// triangle and leaves the rest zero.
    fn lower_is_the_lower_triangle<P, const NF: usize, const ND: usize, const NQ: usize>(
        geo: &[P; NQ],
        u: [f64; ND],
    ) where
        P: FbarMaterialPoint<NF, ND>,
    {
        let shear = nlvid_model::Relaxation::from_named(
            &nlvid_model::names::PRONY2,
            &[1.0, 0.3, 0.3, 0.5, 10.0],
        )
        .unwrap();
        let cell = nlvid_material::PronyViscoelastic::cell(&shear, 100.0).unwrap();
        let s0: Vec<_> = (0..NQ).map(|_| cell.initial_state()).collect();
        let mut sn = s0.clone();
        let mut out = LocalOutput::zero();
        let half = u.map(|x| 0.5 * x);
        let part = TangentPart::None;
        fbar_kernel(&cell, geo, &half, &s0, &mut sn, 0.3, true, part, &mut out).unwrap();
        let [full, low] = [TangentPart::Full, TangentPart::Lower].map(|part| {
            let mut tr = s0.clone();
            let mut out = LocalOutput::zero();
            fbar_kernel(&cell, geo, &u, &sn, &mut tr, 0.2, true, part, &mut out).unwrap();
            out
        });
        let kmax = full.k.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
        assert_eq!(full.r, low.r);
        for r in 0..ND {
            for c in 0..ND {
                assert!(
                    (full.k[r][c] - full.k[c][r]).abs() <= 1e-12 * kmax,
                    "asymmetric K[{r}][{c}]"
                );
                if c <= r {
                    assert_eq!(low.k[r][c], full.k[r][c], "K[{r}][{c}]");
                } else {
                    assert_eq!(low.k[r][c], 0.0);
                }
            }
        }
    }

    #[test]
    fn lower_tangent_is_the_lower_triangle_of_a_symmetric_full_tangent() {
        let (geo, u) = crate::element::distorted_element();
        lower_is_the_lower_triangle(&geo, u);
        let mut x = crate::hex::unit_cube();
        for (a, p) in x.iter_mut().enumerate() {
            for (i, c) in p.iter_mut().enumerate() {
                *c += 0.05 * ((3 * a + i) as f64 * 1.3).sin();
            }
        }
        let u = std::array::from_fn(|k| 0.08 * (k as f64 * 0.7).cos());
        lower_is_the_lower_triangle(&crate::hex::element_geometry(&x).unwrap(), u);
    }
}
