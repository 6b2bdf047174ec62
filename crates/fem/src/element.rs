//! The axisymmetric 4-node F-bar element (total Lagrangian).
//!
//! Displacements (u_r, u_z) are bilinear. At each of the 2×2 Gauss points
//! the deformation gradient has the components, in the frame (r, z, θ),
//!
//! ```text
//! F = [[1 + ∂u_r/∂R, ∂u_r/∂Z, 0], [∂u_z/∂R, 1 + ∂u_z/∂Z, 0], [0, 0, 1 + u_r/R]]
//! ```
//!
//! (hoop stretch F_θθ = r/R). Volumetric locking is removed by the F-bar
//! idea in its variational (mean-dilatation) form: the material sees
//! `F̄ = (J̄/J)^{1/3} F`, where `J̄ = ∫J dV₀ / ∫dV₀` is the element's mean
//! Jacobian. The element is the stationary point of `∫ Ψ(F̄(u)) dV₀`, so its
//! residual is `∫ P(F̄) : ∂F̄/∂u dV₀` and its tangent is the exact second
//! derivative (symmetric whenever ∂P/∂F is). For a decoupled energy
//! Ψ = Ψ_iso(F) + U(J) this is exactly the Q1/P0 mixed element of
//! Simo–Taylor–Pister with the pressure condensed out.

use crate::fbar::{FbarMaterialPoint, FbarPoint, KernelScratch, PointUpdate};
use crate::local::LocalOutput;
#[doc(hidden)]
pub use crate::local::{PointFailure, TangentPart};
use nlvid_material::{F64x4, Lane, Mat3, Material3, MaterialError};

/// 2×2 Gauss points (ξ, η); all weights are 1.
pub const GAUSS: [(f64, f64); 4] = {
    const G: f64 = 0.577_350_269_189_625_8;
    [(-G, -G), (G, -G), (G, G), (-G, G)]
};

#[cfg(test)]
/// Components of F stored by the element, and their index in the 3×3
/// matrix (row-major `3i+J`): rR, rZ, zR, zZ, θθ
/// (`nlvid_material::AXISYMMETRIC_COMPONENTS`).
pub(crate) const FIDX: [(usize, usize); 5] = [(0, 0), (0, 1), (1, 0), (1, 1), (2, 2)];

/// Shape functions N, their reference gradients ∂N/∂(R, Z) and det J at
/// (ξ, η) for an element with nodes `x`.
pub fn shape_gradients(x: &[[f64; 2]; 4], xi: f64, eta: f64) -> ([f64; 4], [[f64; 2]; 4], f64) {
    let sx = [-1.0, 1.0, 1.0, -1.0];
    let se = [-1.0, -1.0, 1.0, 1.0];
    let mut n = [0.0; 4];
    let mut dn = [[0.0; 2]; 4];
    for a in 0..4 {
        n[a] = 0.25 * (1.0 + sx[a] * xi) * (1.0 + se[a] * eta);
        dn[a] = [
            0.25 * sx[a] * (1.0 + se[a] * eta),
            0.25 * se[a] * (1.0 + sx[a] * xi),
        ];
    }
    let mut jac = [[0.0; 2]; 2];
    for a in 0..4 {
        for i in 0..2 {
            for k in 0..2 {
                jac[i][k] += x[a][i] * dn[a][k];
            }
        }
    }
    let det = jac[0][0] * jac[1][1] - jac[0][1] * jac[1][0];
    let inv = [
        [jac[1][1] / det, -jac[0][1] / det],
        [-jac[1][0] / det, jac[0][0] / det],
    ];
    let mut dx = [[0.0; 2]; 4];
    for a in 0..4 {
        for i in 0..2 {
            dx[a][i] = dn[a][0] * inv[0][i] + dn[a][1] * inv[1][i];
        }
    }
    (n, dx, det)
}

/// Reference-configuration data of one Gauss point (`T` =
/// [`nlvid_material::F64x4`]: of the same point of four elements, one per
/// lane, [`PointGeometry::lanes`]).
#[derive(Debug, Clone, Copy)]
pub struct PointGeometry<T = f64> {
    /// Shape functions.
    pub n: [T; 4],
    /// ∂N/∂R, ∂N/∂Z.
    pub dn: [[T; 2]; 4],
    /// Reference radius R.
    pub r: T,
    /// N/R (the hoop row of ∂F/∂u), precomputed for the element loop.
    pub n_over_r: [T; 4],
    /// Integration weight 2π R det J (m³).
    pub weight: T,
}

impl PointGeometry<F64x4> {
    /// The same point of four elements, one per lane.
    #[inline]
    pub fn lanes(g: [&PointGeometry; 4]) -> Self {
        let z = F64x4::default();
        let mut out = Self {
            n: [z; 4],
            dn: [[z; 2]; 4],
            r: z,
            n_over_r: [z; 4],
            weight: z,
        };
        for (l, p) in g.into_iter().enumerate() {
            for a in 0..4 {
                out.n[a].0[l] = p.n[a];
                out.dn[a][0].0[l] = p.dn[a][0];
                out.dn[a][1].0[l] = p.dn[a][1];
                out.n_over_r[a].0[l] = p.n_over_r[a];
            }
            out.r.0[l] = p.r;
            out.weight.0[l] = p.weight;
        }
        out
    }
}

/// Gauss-point geometry of one element.
pub fn element_geometry(x: &[[f64; 2]; 4]) -> [PointGeometry; 4] {
    GAUSS.map(|(xi, eta)| {
        let (n, dn, det) = shape_gradients(x, xi, eta);
        let r: f64 = (0..4).map(|a| n[a] * x[a][0]).sum();
        PointGeometry {
            n,
            dn,
            r,
            n_over_r: n.map(|na| na / r),
            weight: 2.0 * std::f64::consts::PI * r * det,
        }
    })
}

#[cfg(test)]
/// ∂F/∂u at a point: row = stored F component (see `FIDX`), column =
/// element dof (u_r0, u_z0, u_r1, …). F is linear in u, so this is constant.
pub(crate) fn grad_operator(g: &PointGeometry) -> [[f64; 8]; 5] {
    let mut b = [[0.0; 8]; 5];
    for a in 0..4 {
        b[0][2 * a] = g.dn[a][0];
        b[1][2 * a] = g.dn[a][1];
        b[2][2 * a + 1] = g.dn[a][0];
        b[3][2 * a + 1] = g.dn[a][1];
        b[4][2 * a] = g.n[a] / g.r;
    }
    b
}

#[cfg(test)]
/// The stored F components at a point for element displacements `u`.
pub(crate) fn deformation(b: &[[f64; 8]; 5], u: &[f64; 8]) -> [f64; 5] {
    let mut f = [1.0, 0.0, 0.0, 1.0, 1.0];
    for (fc, row) in f.iter_mut().zip(b) {
        *fc += row.iter().zip(u).map(|(x, y)| x * y).sum::<f64>();
    }
    f
}

/// J = det F for stored components, its gradient and Hessian w.r.t. them.
#[inline(always)]
pub(crate) fn jacobian_derivatives<T: Lane>(f: &[T; 5]) -> (T, [T; 5], [[T; 5]; 5]) {
    let j2 = f[0] * f[3] - f[1] * f[2];
    let h = f[4];
    let dj = [f[3] * h, -f[2] * h, -f[1] * h, f[0] * h, j2];
    let mut hj = [[T::zero(); 5]; 5];
    hj[0][3] = h;
    hj[3][0] = h;
    hj[1][2] = -h;
    hj[2][1] = -h;
    hj[0][4] = f[3];
    hj[4][0] = f[3];
    hj[3][4] = f[0];
    hj[4][3] = f[0];
    hj[1][4] = -f[2];
    hj[4][1] = -f[2];
    hj[2][4] = -f[1];
    hj[4][2] = -f[1];
    (j2 * h, dj, hj)
}

#[cfg(test)]
/// Bᵀ v for a 5×8 operator.
pub(crate) fn bt_v(b: &[[f64; 8]; 5], v: &[f64; 5]) -> [f64; 8] {
    let mut out = [0.0; 8];
    for (row, &vi) in b.iter().zip(v) {
        for (o, &x) in out.iter_mut().zip(row) {
            *o += x * vi;
        }
    }
    out
}

#[cfg(test)]
/// Bᵀ M B for a 5×8 operator and a 5×5 matrix, added to `out` with factor `w`.
pub(crate) fn add_bt_m_b(out: &mut [[f64; 8]; 8], b: &[[f64; 8]; 5], m: &[[f64; 5]; 5], w: f64) {
    let mut mb = [[0.0; 8]; 5];
    for i in 0..5 {
        for k in 0..5 {
            let mik = m[i][k];
            if mik != 0.0 {
                for c in 0..8 {
                    mb[i][c] += mik * b[k][c];
                }
            }
        }
    }
    for r in 0..8 {
        for i in 0..5 {
            let bir = b[i][r] * w;
            if bir != 0.0 {
                for c in 0..8 {
                    out[r][c] += bir * mb[i][c];
                }
            }
        }
    }
}

#[cfg(test)]
/// out += w (a ⊗ b).
pub(crate) fn add_outer(out: &mut [[f64; 8]; 8], a: &[f64; 8], b: &[f64; 8], w: f64) {
    for r in 0..8 {
        let ar = a[r] * w;
        for c in 0..8 {
            out[r][c] += ar * b[c];
        }
    }
}

/// A distorted element off the axis and a large displacement of it (tests).
#[cfg(test)]
pub(crate) fn distorted_element() -> ([PointGeometry; 4], [f64; 8]) {
    let x = [[0.5, 0.0], [1.4, 0.1], [1.3, 1.0], [0.4, 0.8]];
    let u = [0.05, -0.02, 0.11, 0.03, -0.04, -0.09, 0.02, 0.06];
    (element_geometry(&x), u)
}

/// Residual and tangent of one element (8 dofs u_r0, u_z0, u_r1, …).
#[doc(hidden)]
pub type ElementOutput = LocalOutput<8>;

/// The Q4 point in the shared F-bar kernel ([`crate::fbar::fbar_kernel`]):
/// F stored as (rR, rZ, zR, zZ, θθ), B used through its sparsity (each
/// column has at most 3 non-zeros), the material's axisymmetric update.
impl<T: Lane> FbarPoint<T, 5, 8> for PointGeometry<T> {
    #[inline(always)]
    fn weight(&self) -> T {
        self.weight
    }

    /// The stored F components at a point, from the shape functions directly
    /// (same as `deformation(&grad_operator(g), u)`).
    #[inline(always)]
    fn deformation(&self, u: &[T; 8]) -> [T; 5] {
        let g = self;
        let (one, zero) = (T::one(), T::zero());
        let mut f = [one, zero, zero, one, one];
        for a in 0..4 {
            let (ur, uz) = (u[2 * a], u[2 * a + 1]);
            f[0] += g.dn[a][0] * ur;
            f[1] += g.dn[a][1] * ur;
            f[2] += g.dn[a][0] * uz;
            f[3] += g.dn[a][1] * uz;
            f[4] += g.n_over_r[a] * ur;
        }
        f
    }

    #[inline(always)]
    fn bt_v(&self, v: &[T; 5]) -> [T; 8] {
        let g = self;
        let mut out = [T::zero(); 8];
        for a in 0..4 {
            out[2 * a] = g.dn[a][0] * v[0] + g.dn[a][1] * v[1] + g.n_over_r[a] * v[4];
            out[2 * a + 1] = g.dn[a][0] * v[2] + g.dn[a][1] * v[3];
        }
        out
    }

    /// Always inlined, so it is compiled in the kernel's SIMD dispatch
    /// ([`crate::fbar::fbar_kernel`]).
    #[inline(always)]
    fn add_bt_m_b(&self, out: &mut [[T; 8]; 8], m: &[[T; 5]; 5], lower: bool) {
        let g = self;
        // Column c of B as (row, value) pairs: even c → rows 0, 1, 4; odd c → 2, 3.
        let mut col = [[T::zero(); 3]; 4];
        for a in 0..4 {
            col[a] = [g.dn[a][0], g.dn[a][1], g.n_over_r[a]];
        }
        // MB (5×8) as array literals, so every entry is built in place: a
        // zeroed array filled afterwards cost a 1.3 kB memset per point in
        // lanes. (Functions, not closures: a closure the optimiser leaves
        // out of line is compiled for the baseline instruction set.)
        let mb = [
            mb_row(&m[0], &col),
            mb_row(&m[1], &col),
            mb_row(&m[2], &col),
            mb_row(&m[3], &col),
            mb_row(&m[4], &col),
        ];
        for a in 0..4 {
            let c = &col[a];
            let (ee, eo) = if lower {
                (2 * a + 1, 2 * a + 2)
            } else {
                (8, 8)
            };
            let re = &mut out[2 * a];
            for k in 0..ee {
                re[k] += c[0] * mb[0][k] + c[1] * mb[1][k] + c[2] * mb[4][k];
            }
            let ro = &mut out[2 * a + 1];
            for k in 0..eo {
                ro[k] += c[0] * mb[2][k] + c[1] * mb[3][k];
            }
        }
    }

    #[inline(always)]
    fn jacobian(f: &[T; 5]) -> (T, [T; 5], [[T; 5]; 5]) {
        jacobian_derivatives(f)
    }

    /// The 12 non-zero entries of the Hessian of [`jacobian_derivatives`].
    #[inline(always)]
    fn add_jacobian_hessian(f: &[T; 5], c: T, m: &mut [[T; 5]; 5]) {
        let h = f[4];
        for (i, k, x) in [
            (0, 3, h),
            (1, 2, -h),
            (0, 4, f[3]),
            (3, 4, f[0]),
            (1, 4, -f[2]),
            (2, 4, -f[1]),
        ] {
            m[i][k] += c * x;
            m[k][i] += c * x;
        }
    }
}

/// Row `m_i B` of M B for one row `mi` of M and the columns `col` of the
/// Q4's B ([`FbarPoint::add_bt_m_b`]): an even column c = 2a has the
/// entries (rows 0, 1, 4) `col[a]`, an odd one (rows 2, 3) its first two.
#[inline(always)]
fn mb_row<T: Lane>(mi: &[T; 5], col: &[[T; 3]; 4]) -> [T; 8] {
    [
        mb_even(mi, &col[0]),
        mb_odd(mi, &col[0]),
        mb_even(mi, &col[1]),
        mb_odd(mi, &col[1]),
        mb_even(mi, &col[2]),
        mb_odd(mi, &col[2]),
        mb_even(mi, &col[3]),
        mb_odd(mi, &col[3]),
    ]
}

/// Entry of [`mb_row`] in an even column (u_r of a node).
#[inline(always)]
fn mb_even<T: Lane>(mi: &[T; 5], c: &[T; 3]) -> T {
    mi[0] * c[0] + mi[1] * c[1] + mi[4] * c[2]
}

/// Entry of [`mb_row`] in an odd column (u_z of a node).
#[inline(always)]
fn mb_odd<T: Lane>(mi: &[T; 5], c: &[T; 3]) -> T {
    mi[2] * c[0] + mi[3] * c[1]
}

impl FbarMaterialPoint<5, 8> for PointGeometry {
    fn matrix(f: &[f64; 5]) -> Mat3 {
        Mat3::new(f[0], f[1], 0.0, f[2], f[3], 0.0, 0.0, 0.0, f[4])
    }

    /// Always inlined, so the point update is compiled in the kernel's
    /// SIMD dispatch ([`crate::fbar::fbar_kernel`]).
    #[inline(always)]
    fn update<M: Material3>(
        material: &M,
        state_n: &M::State,
        f: &[f64; 5],
        dt: f64,
        trial: &mut M::State,
        tangent: bool,
    ) -> Result<([f64; 5], [[f64; 5]; 5]), MaterialError> {
        let resp = material.update_axisymmetric(state_n, f, dt, trial, tangent)?;
        Ok((resp.first_piola, resp.tangent))
    }
}

/// What the model keeps for [`fbar_kernel_lanes`] from one group of four
/// elements to the next: the lane output and the kernel's intermediates
/// (kept, not rebuilt per group, so they are not zeroed every time).
#[doc(hidden)]
#[derive(Default)]
pub struct LaneBuffers {
    out: LocalOutput<8, F64x4>,
    scratch: KernelScratch<F64x4, 5, 8, 4>,
}

/// The points of four elements, one per lane: [`Material3::update_axisymmetric_lanes`].
struct LanePoints<'a, M: Material3> {
    material: &'a M,
    state_n: [&'a [M::State]; 4],
    trial: [&'a mut [M::State]; 4],
    dt: f64,
}

impl<M: Material3> PointUpdate<F64x4, 5> for LanePoints<'_, M> {
    /// Always inlined into the kernel's SIMD dispatch; a lane that fails
    /// fails the group (an error without a message: the caller evaluates
    /// the elements one by one).
    #[inline(always)]
    fn update(
        &mut self,
        q: usize,
        f: &[F64x4; 5],
        tangent: bool,
        p: &mut [F64x4; 5],
        a: &mut [[F64x4; 5]; 5],
    ) -> Result<(), MaterialError> {
        let [t0, t1, t2, t3] = &mut self.trial;
        if self.material.update_axisymmetric_lanes(
            self.state_n.map(|s| &s[q]),
            f,
            self.dt,
            [&mut t0[q], &mut t1[q], &mut t2[q], &mut t3[q]],
            tangent,
            p,
            a,
        ) {
            Ok(())
        } else {
            Err(MaterialError::Deformation(String::new()))
        }
    }
}

/// The F-bar kernel ([`crate::fbar::fbar_kernel`]) on four elements at once,
/// one per lane of [`F64x4`] (the same code, so each element's output and
/// trial history are bitwise those of the one-element kernel). Element `l`
/// has the nodes `nodes[l]` and its dofs are read from the global dof
/// vector `u` (two per node) straight into the lanes. `false` if the
/// material has no lane update or any element fails (det F ≤ 0, a material
/// error): the caller then evaluates the four one by one, which rewrites
/// every trial history and reports the error.
///
/// With [`TangentPart::Lower`] only the lower triangle of each element
/// tangent is written to `out` (the rest is not read: the model's slot
/// table has no slot for it).
#[allow(clippy::too_many_arguments)]
pub(crate) fn fbar_kernel_lanes<M: Material3>(
    material: &M,
    geometry: &[PointGeometry<F64x4>; 4],
    u: &[f64],
    nodes: [&[usize]; 4],
    state_n: [&[M::State]; 4],
    trial: [&mut [M::State]; 4],
    dt: f64,
    fbar: bool,
    part: TangentPart,
    lanes: &mut LaneBuffers,
    out: [&mut ElementOutput; 4],
) -> bool {
    let (Ok(n0), Ok(n1), Ok(n2), Ok(n3)) = (
        <&[usize; 4]>::try_from(nodes[0]),
        <&[usize; 4]>::try_from(nodes[1]),
        <&[usize; 4]>::try_from(nodes[2]),
        <&[usize; 4]>::try_from(nodes[3]),
    ) else {
        return false;
    };
    if !M::AXISYMMETRIC_LANES
        || state_n.iter().any(|s| s.len() != 4)
        || trial.iter().any(|s| s.len() != 4)
    {
        return false;
    }
    // Dof k of element l: component k % 2 of its node k / 2.
    let mut ul = [F64x4::default(); 8];
    for (l, n) in [n0, n1, n2, n3].into_iter().enumerate() {
        for (k, y) in ul.iter_mut().enumerate() {
            y.0[l] = u[2 * n[k / 2] + k % 2];
        }
    }
    let points = LanePoints {
        material,
        state_n,
        trial,
        dt,
    };
    let LaneBuffers {
        out: lanes,
        scratch,
    } = lanes;
    if crate::fbar::fbar_kernel_in(geometry, &ul, points, fbar, part, scratch, lanes).is_err() {
        return false;
    }
    let [o0, o1, o2, o3] = out;
    for c in 0..8 {
        [o0.r[c], o1.r[c], o2.r[c], o3.r[c]] = lanes.r[c].0;
    }
    if part != TangentPart::None {
        for r in 0..8 {
            let end = if part == TangentPart::Lower { r + 1 } else { 8 };
            for c in 0..end {
                [o0.k[r][c], o1.k[r][c], o2.k[r][c], o3.k[r][c]] = lanes.k[r][c].0;
            }
        }
    }
    true
}

#[cfg(test)]
/// The direct (unfactored) form of [`crate::fbar::fbar_kernel`], kept as an independent
/// check of its regrouped tangent: internal force and tangent of one element,
/// F-bar if `fbar`, plain displacement element otherwise (for the locking
/// comparison). Writes the trial history of the element's four points.
#[allow(clippy::too_many_arguments)]
pub(crate) fn fbar_element_reference<M: nlvid_material::Material3>(
    material: &M,
    geometry: &[PointGeometry; 4],
    u: &[f64; 8],
    state_n: &[M::State],
    trial: &mut [M::State],
    dt: f64,
    fbar: bool,
    tangent: bool,
    out: &mut ElementOutput,
) -> std::result::Result<(), PointFailure> {
    *out = ElementOutput::zero();
    let mut b = [[[0.0; 8]; 5]; 4];
    let mut f = [[0.0; 5]; 4];
    let mut jq = [0.0; 4];
    let mut dju = [[0.0; 8]; 4];
    let mut hju = [[[0.0; 8]; 8]; 4];
    let mut vol = 0.0;
    let mut jbar = 0.0;
    let mut djbar = [0.0; 8];
    let mut d2jbar = [[0.0; 8]; 8];
    for q in 0..4 {
        b[q] = grad_operator(&geometry[q]);
        f[q] = deformation(&b[q], u);
        let (j, dj, hj) = jacobian_derivatives(&f[q]);
        crate::fbar::positive_jacobian(q, j)?;
        jq[q] = j;
        if fbar {
            let w = geometry[q].weight;
            dju[q] = bt_v(&b[q], &dj);
            if tangent {
                add_bt_m_b(&mut hju[q], &b[q], &hj, 1.0);
            }
            vol += w;
            jbar += w * j;
            for c in 0..8 {
                djbar[c] += w * dju[q][c];
            }
            if tangent {
                for r in 0..8 {
                    for c in 0..8 {
                        d2jbar[r][c] += w * hju[q][r][c];
                    }
                }
            }
        }
    }
    let mut dlnjbar = [0.0; 8];
    let mut d2lnjbar = [[0.0; 8]; 8];
    if fbar {
        jbar /= vol;
        for c in 0..8 {
            djbar[c] /= vol;
            dlnjbar[c] = djbar[c] / jbar;
        }
        if tangent {
            for r in 0..8 {
                for c in 0..8 {
                    d2lnjbar[r][c] = d2jbar[r][c] / vol / jbar - dlnjbar[r] * dlnjbar[c];
                }
            }
        }
    }
    for q in 0..4 {
        let w = geometry[q].weight;
        let (alpha, dlnalpha) = if fbar {
            let mut d = [0.0; 8];
            for c in 0..8 {
                d[c] = (dlnjbar[c] - dju[q][c] / jq[q]) / 3.0;
            }
            ((jbar / jq[q]).cbrt(), d)
        } else {
            (1.0, [0.0; 8])
        };
        let mut fbar_q = f[q];
        for x in &mut fbar_q {
            *x *= alpha;
        }
        let resp = material
            .update(
                &state_n[q],
                &PointGeometry::matrix(&fbar_q),
                dt,
                &mut trial[q],
            )
            .map_err(|e| (q, e))?;
        let mut p5 = [0.0; 5];
        let mut a5 = [[0.0; 5]; 5];
        for (i, &(i0, j0)) in FIDX.iter().enumerate() {
            p5[i] = resp.first_piola[(i0, j0)];
            if tangent {
                for (k, &(k0, l0)) in FIDX.iter().enumerate() {
                    a5[i][k] = resp.tangent[(3 * i0 + j0, 3 * k0 + l0)];
                }
            }
        }
        let mut dalpha = [0.0; 8];
        for c in 0..8 {
            dalpha[c] = alpha * dlnalpha[c];
        }
        let mut bb = b[q];
        for i in 0..5 {
            for c in 0..8 {
                bb[i][c] = alpha * b[q][i][c] + f[q][i] * dalpha[c];
            }
        }
        let rq = bt_v(&bb, &p5);
        for c in 0..8 {
            out.r[c] += w * rq[c];
        }
        if !tangent {
            continue;
        }
        add_bt_m_b(&mut out.k, &bb, &a5, w);
        if fbar {
            let gp = bt_v(&b[q], &p5);
            add_outer(&mut out.k, &gp, &dalpha, w);
            add_outer(&mut out.k, &dalpha, &gp, w);
            let pf: f64 = (0..5).map(|i| p5[i] * f[q][i]).sum();
            let s = w * pf * alpha;
            let jj = jq[q];
            for r in 0..8 {
                for c in 0..8 {
                    let d2lnj = hju[q][r][c] / jj - dju[q][r] * dju[q][c] / (jj * jj);
                    let d2lnalpha = (d2lnjbar[r][c] - d2lnj) / 3.0;
                    out.k[r][c] += s * (dlnalpha[r] * dlnalpha[c] + d2lnalpha);
                }
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fbar::fbar_kernel;

    /// The kernel on [`distorted_element`] at `u` from fresh history over
    /// Δt = 0.1.
    fn evaluate<M: Material3>(
        mat: &M,
        u: &[f64; 8],
        fbar: bool,
        part: TangentPart,
    ) -> ElementOutput {
        let (geo, _) = distorted_element();
        let sn: Vec<M::State> = (0..4).map(|_| mat.initial_state()).collect();
        let mut tr = sn.clone();
        let mut out = ElementOutput::zero();
        fbar_kernel(mat, &geo, u, &sn, &mut tr, 0.1, fbar, part, &mut out).unwrap();
        out
    }

    fn tangent_fd(fbar: bool) {
        let mat = crate::reference::NeoHookean {
            mu: 1.0,
            kappa: 30.0,
        };
        let (_, u) = distorted_element();
        let out = evaluate(&mat, &u, fbar, TangentPart::Full);
        let h = 1e-7;
        for c in 0..8 {
            let mut up = u;
            let mut um = u;
            up[c] += h;
            um[c] -= h;
            let op = evaluate(&mat, &up, fbar, TangentPart::None);
            let om = evaluate(&mat, &um, fbar, TangentPart::None);
            for r in 0..8 {
                let fd = (op.r[r] - om.r[r]) / (2.0 * h);
                assert!(
                    (fd - out.k[r][c]).abs() < 1e-5 * (1.0 + fd.abs()),
                    "K[{r}][{c}] = {} vs fd {fd}",
                    out.k[r][c]
                );
            }
        }
    }

    #[test]
    fn fbar_tangent_matches_finite_differences_of_residual() {
        tangent_fd(true);
    }

    #[test]
    fn displacement_tangent_matches_finite_differences_of_residual() {
        tangent_fd(false);
    }

    fn compare_with_direct_form<M: nlvid_material::Material3>(mat: &M, fbar: bool) {
        let (geo, u) = distorted_element();
        let sn: Vec<M::State> = (0..4).map(|_| mat.initial_state()).collect();
        let mut tr = sn.clone();
        let fast = evaluate(mat, &u, fbar, TangentPart::Full);
        let mut direct = ElementOutput::zero();
        fbar_element_reference(mat, &geo, &u, &sn, &mut tr, 0.1, fbar, true, &mut direct).unwrap();
        let kmax = direct
            .k
            .iter()
            .flatten()
            .fold(0.0f64, |m, x| m.max(x.abs()));
        let rmax = direct.r.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        for r in 0..8 {
            assert!((fast.r[r] - direct.r[r]).abs() <= 1e-13 * rmax, "r[{r}]");
            for c in 0..8 {
                assert!(
                    (fast.k[r][c] - direct.k[r][c]).abs() <= 1e-12 * kmax,
                    "K[{r}][{c}] = {} vs direct {}",
                    fast.k[r][c],
                    direct.k[r][c]
                );
            }
        }
    }

    /// G(t) of the AFM cell model in the tests below: G0 = 1 (C1 = 0.5),
    /// g1 = g2 = 0.3, τ1 = 0.5, τ2 = 10.
    fn afm_cell_shear() -> nlvid_model::Relaxation {
        nlvid_model::Relaxation::from_named(
            &nlvid_model::names::PRONY2,
            &[1.0, 0.3, 0.3, 0.5, 10.0],
        )
        .unwrap()
    }

    #[test]
    fn regrouped_tangent_equals_direct_form() {
        let neo = crate::reference::NeoHookean {
            mu: 1.0,
            kappa: 30.0,
        };
        compare_with_direct_form(&neo, true);
        compare_with_direct_form(&neo, false);
        // A history-dependent material of the `material` crate (the AFM cell
        // model), evaluated with a time step so the viscous terms enter.
        let cell = nlvid_material::PronyViscoelastic::cell(&afm_cell_shear(), 1000.0).unwrap();
        compare_with_direct_form(&cell, true);
    }

    /// Four different elements through [`fbar_kernel_lanes`] and one by one
    /// through [`fbar_kernel`]: outputs and trial histories bitwise equal,
    /// for the cell material with history and a time step (and without
    /// Prony terms), every tangent part, F-bar and plain; a group with an
    /// inverted element is refused.
    #[test]
    fn lanes_are_bitwise_the_one_element_kernel() {
        use nlvid_material::{PointState, PronyViscoelastic};
        let (_, u0) = distorted_element();
        let base = [[0.5, 0.0], [1.4, 0.1], [1.3, 1.0], [0.4, 0.8]];
        let geo: [[PointGeometry; 4]; 4] = std::array::from_fn(|e| {
            element_geometry(&std::array::from_fn(|a| {
                let s = ((3 * e + a) as f64 * 1.7).sin();
                [
                    base[a][0] + 0.3 * e as f64 + 0.05 * s,
                    base[a][1] + 0.04 * s,
                ]
            }))
        });
        let lane_geo = [0, 1, 2, 3].map(|q| PointGeometry::lanes(geo.each_ref().map(|g| &g[q])));
        let us: [[f64; 8]; 4] = std::array::from_fn(|e| {
            std::array::from_fn(|k| u0[k] * (1.0 - 0.2 * e as f64) + 0.01 * (k + e) as f64)
        });
        let bits = |o: &ElementOutput| {
            let mut v: Vec<u64> = o.r.iter().map(|x| x.to_bits()).collect();
            v.extend(o.k.iter().flatten().map(|x| x.to_bits()));
            v
        };
        let elastic = nlvid_model::Relaxation::new(
            nlvid_model::names::G0,
            1.0,
            nlvid_model::Prony::elastic(),
        )
        .unwrap();
        for shear in [afm_cell_shear(), elastic] {
            let cell = PronyViscoelastic::cell(&shear, 1000.0).unwrap();
            // History after one step to half the displacement.
            let fresh: Vec<_> = (0..4).map(|_| cell.initial_state()).collect();
            let mut sn = [(); 4].map(|_| fresh.clone());
            for e in 0..4 {
                let half = us[e].map(|x| 0.5 * x);
                let mut out = ElementOutput::zero();
                let part = TangentPart::None;
                fbar_kernel(
                    &cell, &geo[e], &half, &fresh, &mut sn[e], 0.3, true, part, &mut out,
                )
                .unwrap();
            }
            // The four elements at `u` through the lanes: whether the group
            // was accepted, the outputs and the trial histories.
            let lanes_at = |u: &[[f64; 8]; 4], fbar: bool, part: TangentPart| {
                let mut tr = sn.clone();
                let mut out = [ElementOutput::zero(); 4];
                let [t0, t1, t2, t3] = &mut tr;
                let [o0, o1, o2, o3] = &mut out;
                // Element l's nodes 4l..4l + 4 in a global dof vector.
                let global: Vec<f64> = u.iter().flatten().copied().collect();
                let nodes: [[usize; 4]; 4] =
                    std::array::from_fn(|l| [0, 1, 2, 3].map(|a| 4 * l + a));
                let ok = fbar_kernel_lanes(
                    &cell,
                    &lane_geo,
                    &global,
                    nodes.each_ref().map(|n| &n[..]),
                    sn.each_ref().map(|s| &s[..]),
                    [&mut t0[..], &mut t1[..], &mut t2[..], &mut t3[..]],
                    0.2,
                    fbar,
                    part,
                    &mut Default::default(),
                    [o0, o1, o2, o3],
                );
                (ok, out, tr)
            };
            for fbar in [true, false] {
                for part in [TangentPart::None, TangentPart::Full, TangentPart::Lower] {
                    let mut tr_one = sn.clone();
                    let mut one = [ElementOutput::zero(); 4];
                    for e in 0..4 {
                        fbar_kernel(
                            &cell,
                            &geo[e],
                            &us[e],
                            &sn[e],
                            &mut tr_one[e],
                            0.2,
                            fbar,
                            part,
                            &mut one[e],
                        )
                        .unwrap();
                    }
                    let (ok, lanes, tr_lanes) = lanes_at(&us, fbar, part);
                    assert!(ok);
                    for e in 0..4 {
                        assert_eq!(bits(&lanes[e]), bits(&one[e]), "element {e} {part:?}");
                        assert_eq!(format!("{:?}", tr_lanes[e]), format!("{:?}", tr_one[e]));
                    }
                }
            }
            // An inverted element in the group: refused (the caller then
            // evaluates the four one by one and reports the error).
            let mut bad = us;
            // The top nodes below the bottom ones: F_zZ < 0.
            bad[2][5] = -3.0;
            bad[2][7] = -3.0;
            let (ok, _, mut tr) = lanes_at(&bad, true, TangentPart::Full);
            assert!(!ok);
            let mut one = ElementOutput::zero();
            let (sn2, tr2) = (&sn[2], &mut tr[2]);
            assert!(
                fbar_kernel(
                    &cell,
                    &geo[2],
                    &bad[2],
                    sn2,
                    tr2,
                    0.2,
                    true,
                    TangentPart::Full,
                    &mut one
                )
                .is_err()
            );
        }
    }

    #[test]
    fn weights_integrate_ring_volume() {
        // Square [1,2]×[0,1]: volume of the ring = π (2² − 1²) · 1.
        let x = [[1.0, 0.0], [2.0, 0.0], [2.0, 1.0], [1.0, 1.0]];
        let v: f64 = element_geometry(&x).iter().map(|g| g.weight).sum();
        assert!((v - 3.0 * std::f64::consts::PI).abs() < 1e-12);
    }
}
