//! The 8-node hexahedral F-bar element (total Lagrangian), the 3D sibling of
//! the axisymmetric Q4 in [`crate::element`].
//!
//! Displacements are trilinear; at each of the 2×2×2 Gauss points
//! `F = I + Σ_a u_a ⊗ ∇N_a` (∇ in the reference configuration). Volumetric
//! locking is removed by the same variational F-bar (mean-dilatation) form:
//! the material sees `F̄ = (J̄/J)^{1/3} F` with `J̄ = ∫J dV₀ / ∫dV₀` the
//! element's mean Jacobian, and the element is the stationary point of
//! `∫ Ψ(F̄(u)) dV₀`: residual `∫ P(F̄) : ∂F̄/∂u dV₀`, tangent its exact
//! derivative. For a decoupled energy this is the Q1/P0 element of
//! Simo–Taylor–Pister with the pressure condensed out; with full 2×2×2
//! integration the element has no spurious zero-energy (hourglass) modes
//! (test `stiffness_at_rest_has_exactly_the_six_rigid_modes`), and only one
//! volumetric constraint per element (test
//! `fbar_has_one_volumetric_constraint_per_element_plain_has_seven`).
//!
//! Node order: the reference cube's corners (ξ, η, ζ) =
//! (−−−, +−−, ++−, −+−, −−+, +−+, +++, −++), so that nodes 0–3 are the
//! ζ = −1 face counter-clockwise seen from +ζ.

use crate::fbar::{FbarMaterialPoint, FbarPoint};
use nlvid_material::{Mat3, Material3, MaterialError};

/// Corner signs (ξ_a, η_a, ζ_a).
pub const CORNERS: [[f64; 3]; 8] = [
    [-1.0, -1.0, -1.0],
    [1.0, -1.0, -1.0],
    [1.0, 1.0, -1.0],
    [-1.0, 1.0, -1.0],
    [-1.0, -1.0, 1.0],
    [1.0, -1.0, 1.0],
    [1.0, 1.0, 1.0],
    [-1.0, 1.0, 1.0],
];

/// The six faces of a hexahedron with the corner order of [`CORNERS`],
/// each counter-clockwise seen from outside (outward normal by the right
/// hand); tests of the element and of the cavity's face volumes use them.
#[cfg(test)]
pub(crate) const FACES: [[usize; 4]; 6] = [
    [0, 3, 2, 1],
    [4, 5, 6, 7],
    [0, 1, 5, 4],
    [1, 2, 6, 5],
    [2, 3, 7, 6],
    [3, 0, 4, 7],
];

/// The unit cube [0, 1]³ with the corner order of [`CORNERS`] (tests).
#[cfg(test)]
pub(crate) fn unit_cube() -> [[f64; 3]; 8] {
    CORNERS.map(|c| [0.5 * (c[0] + 1.0), 0.5 * (c[1] + 1.0), 0.5 * (c[2] + 1.0)])
}

/// 2×2×2 Gauss points; all weights are 1.
pub const GAUSS: [[f64; 3]; 8] = {
    const G: f64 = 0.577_350_269_189_625_8;
    let mut p = [[0.0; 3]; 8];
    let mut a = 0;
    while a < 8 {
        p[a] = [G * CORNERS[a][0], G * CORNERS[a][1], G * CORNERS[a][2]];
        a += 1;
    }
    p
};

/// Degrees of freedom of one element.
pub const DOFS: usize = 24;

/// Shape functions, their reference gradients ∂N/∂X and det(∂X/∂ξ) at `xi`
/// for an element with nodes `x`.
pub fn shape_gradients(x: &[[f64; 3]; 8], xi: [f64; 3]) -> ([f64; 8], [[f64; 3]; 8], f64) {
    let mut n = [0.0; 8];
    let mut dn = [[0.0; 3]; 8];
    for a in 0..8 {
        let c = CORNERS[a];
        let f = [1.0 + c[0] * xi[0], 1.0 + c[1] * xi[1], 1.0 + c[2] * xi[2]];
        n[a] = 0.125 * f[0] * f[1] * f[2];
        dn[a] = [
            0.125 * c[0] * f[1] * f[2],
            0.125 * c[1] * f[0] * f[2],
            0.125 * c[2] * f[0] * f[1],
        ];
    }
    // jac[i][k] = ∂X_i/∂ξ_k.
    let mut jac = [[0.0; 3]; 3];
    for a in 0..8 {
        for i in 0..3 {
            for k in 0..3 {
                jac[i][k] += x[a][i] * dn[a][k];
            }
        }
    }
    let (det, inv) = inverse3(&jac);
    let mut dx = [[0.0; 3]; 8];
    for a in 0..8 {
        for i in 0..3 {
            dx[a][i] = dn[a][0] * inv[0][i] + dn[a][1] * inv[1][i] + dn[a][2] * inv[2][i];
        }
    }
    (n, dx, det)
}

/// Determinant and inverse of a 3×3 matrix (inverse meaningless if det = 0).
fn inverse3(m: &[[f64; 3]; 3]) -> (f64, [[f64; 3]; 3]) {
    let c = [
        [
            m[1][1] * m[2][2] - m[1][2] * m[2][1],
            m[1][2] * m[2][0] - m[1][0] * m[2][2],
            m[1][0] * m[2][1] - m[1][1] * m[2][0],
        ],
        [
            m[0][2] * m[2][1] - m[0][1] * m[2][2],
            m[0][0] * m[2][2] - m[0][2] * m[2][0],
            m[0][1] * m[2][0] - m[0][0] * m[2][1],
        ],
        [
            m[0][1] * m[1][2] - m[0][2] * m[1][1],
            m[0][2] * m[1][0] - m[0][0] * m[1][2],
            m[0][0] * m[1][1] - m[0][1] * m[1][0],
        ],
    ];
    let det = m[0][0] * c[0][0] + m[0][1] * c[0][1] + m[0][2] * c[0][2];
    let mut inv = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            // inv = adj / det, adj[i][j] = cofactor[j][i].
            inv[i][j] = c[j][i] / det;
        }
    }
    (det, inv)
}

/// Reference-configuration data of one Gauss point.
#[derive(Debug, Clone, Copy)]
pub struct HexPoint {
    /// ∂N_a/∂X.
    pub dn: [[f64; 3]; 8],
    /// Integration weight det(∂X/∂ξ) (m³).
    pub weight: f64,
}

/// Gauss-point geometry of one element; `Err(point)` names the first Gauss
/// point where the element is inverted or degenerate (det ≤ 0).
pub fn element_geometry(x: &[[f64; 3]; 8]) -> std::result::Result<[HexPoint; 8], (usize, f64)> {
    let mut out = [HexPoint {
        dn: [[0.0; 3]; 8],
        weight: 0.0,
    }; 8];
    for (q, p) in GAUSS.iter().enumerate() {
        let (_, dn, det) = shape_gradients(x, *p);
        if !(det > 0.0) {
            return Err((q, det));
        }
        out[q] = HexPoint { dn, weight: det };
    }
    Ok(out)
}

/// Residual and tangent of one hexahedron (dof `3a + i`).
#[doc(hidden)]
pub type HexOutput = crate::local::LocalOutput<DOFS>;

/// J = det F, its gradient ∂J/∂F (the cofactor J F⁻ᵀ) and Hessian
/// ∂²J/∂F_iJ∂F_kL = ε_ikm ε_JLN F_mN, row-major indices `3i+J`.
pub(crate) fn jacobian_derivatives(f: &[f64; 9]) -> (f64, [f64; 9], [[f64; 9]; 9]) {
    let m = |i: usize, j: usize| f[3 * i + j];
    let cof = [
        m(1, 1) * m(2, 2) - m(1, 2) * m(2, 1),
        m(1, 2) * m(2, 0) - m(1, 0) * m(2, 2),
        m(1, 0) * m(2, 1) - m(1, 1) * m(2, 0),
        m(0, 2) * m(2, 1) - m(0, 1) * m(2, 2),
        m(0, 0) * m(2, 2) - m(0, 2) * m(2, 0),
        m(0, 1) * m(2, 0) - m(0, 0) * m(2, 1),
        m(0, 1) * m(1, 2) - m(0, 2) * m(1, 1),
        m(0, 2) * m(1, 0) - m(0, 0) * m(1, 2),
        m(0, 0) * m(1, 1) - m(0, 1) * m(1, 0),
    ];
    let j = m(0, 0) * cof[0] + m(0, 1) * cof[1] + m(0, 2) * cof[2];
    let mut h = [[0.0; 9]; 9];
    for i in 0..3 {
        for k in 0..3 {
            if i == k {
                continue;
            }
            let mi = 3 - i - k;
            let eik = levi(i, k, mi);
            for jj in 0..3 {
                for l in 0..3 {
                    if jj == l {
                        continue;
                    }
                    let n = 3 - jj - l;
                    h[3 * i + jj][3 * k + l] = eik * levi(jj, l, n) * m(mi, n);
                }
            }
        }
    }
    (j, cof, h)
}

/// The Levi-Civita symbol for distinct indices.
fn levi(i: usize, j: usize, k: usize) -> f64 {
    if (i + 1) % 3 == j && (j + 1) % 3 == k {
        1.0
    } else if i != j && j != k && i != k {
        -1.0
    } else {
        0.0
    }
}

/// The hexahedron's point in the shared F-bar kernel
/// ([`crate::fbar::fbar_kernel`]): F stored row-major (`3i+J`), the
/// material's 3D update.
impl FbarPoint<f64, 9, DOFS> for HexPoint {
    #[inline]
    fn weight(&self) -> f64 {
        self.weight
    }

    /// `F = I + Σ_a u_a ⊗ ∇N_a`, row-major.
    #[inline]
    fn deformation(&self, u: &[f64; DOFS]) -> [f64; 9] {
        let mut f = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];
        for a in 0..8 {
            for i in 0..3 {
                let ui = u[3 * a + i];
                for jj in 0..3 {
                    f[3 * i + jj] += ui * self.dn[a][jj];
                }
            }
        }
        f
    }

    /// `(Bᵀ v)_{3a+i} = Σ_J v_{3i+J} ∂N_a/∂X_J`.
    #[inline]
    fn bt_v(&self, v: &[f64; 9]) -> [f64; DOFS] {
        let mut out = [0.0; DOFS];
        for a in 0..8 {
            let d = &self.dn[a];
            for i in 0..3 {
                out[3 * a + i] = v[3 * i] * d[0] + v[3 * i + 1] * d[1] + v[3 * i + 2] * d[2];
            }
        }
        out
    }

    #[inline]
    fn add_bt_m_b(&self, out: &mut [[f64; DOFS]; DOFS], m: &[[f64; 9]; 9], lower: bool) {
        // MB[(3i+J)][(3b+k)] = Σ_L M[3i+J][3k+L] ∂N_b/∂X_L.
        let mut mb = [[0.0; DOFS]; 9];
        for (row, mrow) in mb.iter_mut().zip(m) {
            for b in 0..8 {
                let d = &self.dn[b];
                for k in 0..3 {
                    row[3 * b + k] =
                        mrow[3 * k] * d[0] + mrow[3 * k + 1] * d[1] + mrow[3 * k + 2] * d[2];
                }
            }
        }
        for a in 0..8 {
            let d = &self.dn[a];
            for i in 0..3 {
                let (m0, m1, m2) = (&mb[3 * i], &mb[3 * i + 1], &mb[3 * i + 2]);
                let r = 3 * a + i;
                let row = &mut out[r];
                let end = if lower { r + 1 } else { DOFS };
                for c in 0..end {
                    row[c] += d[0] * m0[c] + d[1] * m1[c] + d[2] * m2[c];
                }
            }
        }
    }

    #[inline]
    fn jacobian(f: &[f64; 9]) -> (f64, [f64; 9], [[f64; 9]; 9]) {
        jacobian_derivatives(f)
    }
}

impl FbarMaterialPoint<9, DOFS> for HexPoint {
    fn matrix(f: &[f64; 9]) -> Mat3 {
        Mat3::from_row_slice(f)
    }

    #[inline]
    fn update<M: Material3>(
        material: &M,
        state_n: &M::State,
        f: &[f64; 9],
        dt: f64,
        trial: &mut M::State,
        _tangent: bool,
    ) -> Result<([f64; 9], [[f64; 9]; 9]), MaterialError> {
        let resp = material.update(state_n, &Self::matrix(f), dt, trial)?;
        let mut p = [0.0; 9];
        for i in 0..3 {
            for jj in 0..3 {
                p[3 * i + jj] = resp.first_piola[(i, jj)];
            }
        }
        let mut a = [[0.0; 9]; 9];
        for (r, row) in a.iter_mut().enumerate() {
            for (c, x) in row.iter_mut().enumerate() {
                *x = resp.tangent[(r, c)];
            }
        }
        Ok((p, a))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fbar::{fbar_energy as element_energy, fbar_kernel as fbar_hex};
    use crate::local::TangentPart;
    use crate::reference::NeoHookean;
    use nlvid_material::PointState;

    /// A distorted, non-parallel hexahedron around the unit cube.
    fn distorted() -> [[f64; 3]; 8] {
        let mut x = unit_cube();
        let shift = [
            [0.05, -0.02, 0.03],
            [0.1, 0.04, -0.05],
            [-0.03, 0.12, 0.02],
            [0.02, -0.06, 0.07],
            [-0.04, 0.03, 0.1],
            [0.08, -0.05, -0.02],
            [0.15, 0.1, 0.05],
            [-0.06, 0.02, -0.04],
        ];
        for a in 0..8 {
            for i in 0..3 {
                x[a][i] += shift[a][i];
            }
        }
        x
    }

    /// A large, non-uniform displacement field (seeded pseudo-random).
    fn displacement(scale: f64) -> [f64; DOFS] {
        let mut s: u64 = 0x2545_f491_4f6c_dd1d;
        let mut u = [0.0; DOFS];
        for v in &mut u {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            *v = scale * ((s >> 11) as f64 / (1u64 << 53) as f64 - 0.5);
        }
        u
    }

    #[test]
    fn weights_integrate_the_volume_of_a_distorted_element() {
        // Volume by the divergence theorem over the 6 bilinear faces,
        // independent of the element's own quadrature: V = ⅓ ∮ X·n dA, each
        // face integrated exactly by 2×2 Gauss (cubic in each variable).
        let x = distorted();
        let faces = FACES;
        let g = 0.577_350_269_189_625_8;
        let mut v = 0.0;
        for face in faces {
            for (s, t) in [(-g, -g), (g, -g), (g, g), (-g, g)] {
                let n = [
                    0.25 * (1.0 - s) * (1.0 - t),
                    0.25 * (1.0 + s) * (1.0 - t),
                    0.25 * (1.0 + s) * (1.0 + t),
                    0.25 * (1.0 - s) * (1.0 + t),
                ];
                let ns = [
                    -0.25 * (1.0 - t),
                    0.25 * (1.0 - t),
                    0.25 * (1.0 + t),
                    -0.25 * (1.0 + t),
                ];
                let nt = [
                    -0.25 * (1.0 - s),
                    -0.25 * (1.0 + s),
                    0.25 * (1.0 + s),
                    0.25 * (1.0 - s),
                ];
                let (mut p, mut ps, mut pt) = ([0.0; 3], [0.0; 3], [0.0; 3]);
                for k in 0..4 {
                    for i in 0..3 {
                        p[i] += n[k] * x[face[k]][i];
                        ps[i] += ns[k] * x[face[k]][i];
                        pt[i] += nt[k] * x[face[k]][i];
                    }
                }
                let c = [
                    ps[1] * pt[2] - ps[2] * pt[1],
                    ps[2] * pt[0] - ps[0] * pt[2],
                    ps[0] * pt[1] - ps[1] * pt[0],
                ];
                v += (p[0] * c[0] + p[1] * c[1] + p[2] * c[2]) / 3.0;
            }
        }
        let w: f64 = element_geometry(&x).unwrap().iter().map(|p| p.weight).sum();
        assert!((w - v).abs() < 1e-14, "{w} vs {v}");
    }

    fn tangent_fd<M: Material3>(mat: &M, fbar: bool, scale: f64, dt: f64) {
        let geo = element_geometry(&distorted()).unwrap();
        let u = displacement(scale);
        let s0: Vec<M::State> = (0..8).map(|_| mat.initial_state()).collect();
        // Some history first (half the displacement), so viscous terms enter.
        let mut sn = s0.clone();
        let mut tr = s0.clone();
        let half = u.map(|x| 0.5 * x);
        let mut out = HexOutput::zero();
        fbar_hex(
            mat,
            &geo,
            &half,
            &s0,
            &mut sn,
            dt,
            fbar,
            TangentPart::None,
            &mut out,
        )
        .unwrap();
        fbar_hex(
            mat,
            &geo,
            &u,
            &sn,
            &mut tr,
            dt,
            fbar,
            TangentPart::Full,
            &mut out,
        )
        .unwrap();
        let kmax = out.k.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
        let h = 1e-6;
        let (mut op, mut om) = (HexOutput::zero(), HexOutput::zero());
        for c in 0..DOFS {
            let (mut up, mut um) = (u, u);
            up[c] += h;
            um[c] -= h;
            fbar_hex(
                mat,
                &geo,
                &up,
                &sn,
                &mut tr,
                dt,
                fbar,
                TangentPart::None,
                &mut op,
            )
            .unwrap();
            fbar_hex(
                mat,
                &geo,
                &um,
                &sn,
                &mut tr,
                dt,
                fbar,
                TangentPart::None,
                &mut om,
            )
            .unwrap();
            for r in 0..DOFS {
                let fd = (op.r[r] - om.r[r]) / (2.0 * h);
                assert!(
                    (fd - out.k[r][c]).abs() < 1e-6 * kmax,
                    "fbar={fbar} K[{r}][{c}] = {} vs fd {fd}",
                    out.k[r][c]
                );
            }
        }
        // The exact Hessian of one potential is symmetric.
        for r in 0..DOFS {
            for c in 0..DOFS {
                assert!((out.k[r][c] - out.k[c][r]).abs() < 1e-11 * kmax);
            }
        }
    }

    #[test]
    fn tangent_matches_finite_differences_at_large_distortion() {
        let neo = NeoHookean {
            mu: 1.0,
            kappa: 30.0,
        };
        tangent_fd(&neo, true, 0.3, 0.0);
        tangent_fd(&neo, false, 0.3, 0.0);
    }

    #[test]
    fn tangent_matches_finite_differences_for_the_capsule_material() {
        // Mooney–Rivlin with C2 = 0.37 C1 and two Prony terms (§4.3), with
        // history and a time step so the viscous terms enter.
        let capsule =
            nlvid_material::PronyViscoelastic::capsule(1.0, 0.37, (0.5, 0.06), (0.2, 1.4), 200.0)
                .unwrap();
        tangent_fd(&capsule, true, 0.25, 0.05);
    }

    #[test]
    fn residual_is_the_gradient_of_the_element_energy() {
        // Ψ = μ/2 (J^{-2/3} I1 − 3) + κ/2 (J − 1)² (reference::NeoHookean).
        let (mu, kappa) = (1.3, 40.0);
        let mat = NeoHookean { mu, kappa };
        let psi = move |f: &Mat3| {
            let j = f.determinant();
            0.5 * mu * (j.powf(-2.0 / 3.0) * f.norm_squared() - 3.0)
                + 0.5 * kappa * (j - 1.0).powi(2)
        };
        let geo = element_geometry(&distorted()).unwrap();
        let u = displacement(0.3);
        let mut out = HexOutput::zero();
        let (sn, mut tr) = ([(); 8], [(); 8]);
        for fbar in [true, false] {
            fbar_hex(
                &mat,
                &geo,
                &u,
                &sn,
                &mut tr,
                0.0,
                fbar,
                TangentPart::None,
                &mut out,
            )
            .unwrap();
            let h = 1e-6;
            let rmax = out.r.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            for c in 0..DOFS {
                let (mut up, mut um) = (u, u);
                up[c] += h;
                um[c] -= h;
                let fd = (element_energy(&geo, &up, fbar, &psi)
                    - element_energy(&geo, &um, fbar, &psi))
                    / (2.0 * h);
                assert!(
                    (fd - out.r[c]).abs() < 1e-7 * rmax,
                    "r[{c}] = {} vs {fd}",
                    out.r[c]
                );
            }
        }
    }

    /// Eigenvalues of the symmetric element stiffness at F = I.
    fn stiffness_spectrum(fbar: bool, kappa: f64) -> Vec<f64> {
        let mat = NeoHookean { mu: 1.0, kappa };
        let geo = element_geometry(&distorted()).unwrap();
        let mut out = HexOutput::zero();
        fbar_hex(
            &mat,
            &geo,
            &[0.0; DOFS],
            &[(); 8],
            &mut [(); 8],
            0.0,
            fbar,
            TangentPart::Full,
            &mut out,
        )
        .unwrap();
        let k = nalgebra::DMatrix::from_fn(DOFS, DOFS, |r, c| 0.5 * (out.k[r][c] + out.k[c][r]));
        let mut ev: Vec<f64> = k.symmetric_eigen().eigenvalues.iter().copied().collect();
        ev.sort_by(f64::total_cmp);
        ev
    }

    #[test]
    fn stiffness_at_rest_has_exactly_the_six_rigid_modes() {
        // Full 2×2×2 integration: 24 − 6 = 18 deformation modes, all with
        // positive stiffness (no hourglass modes), F-bar and plain alike.
        for fbar in [true, false] {
            let ev = stiffness_spectrum(fbar, 10.0);
            let top = ev[DOFS - 1];
            assert!(ev[..6].iter().all(|e| e.abs() < 1e-12 * top), "{ev:?}");
            assert!(
                ev[6] > 1e-3 * top,
                "smallest deformation mode {} (max {top})",
                ev[6]
            );
        }
    }

    #[test]
    fn fbar_has_one_volumetric_constraint_per_element_plain_has_seven() {
        // Eigenvalues that grow with κ are the volumetric constraints the
        // element imposes. Mean dilatation (F-bar) imposes one per element —
        // the count that lets a mesh deform isochorically (no locking); the
        // fully integrated displacement element imposes seven (one per Gauss
        // point, less the one combination its trilinear field cannot
        // produce), which locks near-incompressible meshes.
        for (fbar, expected) in [(true, 1), (false, 7)] {
            let deviatoric = stiffness_spectrum(fbar, 0.0)[DOFS - 1];
            let stiff = stiffness_spectrum(fbar, 1e6);
            let volumetric = stiff.iter().filter(|&&e| e > 100.0 * deviatoric).count();
            assert_eq!(volumetric, expected, "fbar={fbar}: {stiff:?}");
        }
    }

    #[test]
    fn uniform_stretch_patch_leaves_interior_node_in_equilibrium() {
        // 2×2×2 patch of distorted hexahedra around an off-centre interior
        // node, homogeneous finite deformation u = (F0 − I) X: every Gauss
        // point sees F0 exactly, the interior node's assembled force vanishes
        // and each element's nodal forces are ∫ P(F0) ∇N_a dV.
        let f0 = [[1.3, 0.1, -0.05], [0.08, 0.85, 0.12], [-0.1, 0.04, 1.1]];
        let mat =
            nlvid_material::PronyViscoelastic::capsule(1.0, 0.37, (0.5, 0.06), (0.2, 1.4), 500.0)
                .unwrap();
        let grid = |i: usize, j: usize, k: usize| -> [f64; 3] {
            if (i, j, k) == (1, 1, 1) {
                [0.93, 1.07, 1.12]
            } else {
                let w = [0.0, 1.0, 2.0];
                [
                    w[i] + 0.03 * w[j] * w[k],
                    w[j] - 0.02 * w[i],
                    w[k] + 0.04 * w[i] * w[j],
                ]
            }
        };
        let mut force = [0.0; 3];
        let mut scale = 0.0f64;
        for (ei, ej, ek) in (0..8).map(|e| (e & 1, (e >> 1) & 1, e >> 2)) {
            let mut x = [[0.0; 3]; 8];
            let mut centre_local = 0;
            for a in 0..8 {
                let c = CORNERS[a];
                let (i, j, k) = (
                    ei + usize::from(c[0] > 0.0),
                    ej + usize::from(c[1] > 0.0),
                    ek + usize::from(c[2] > 0.0),
                );
                x[a] = grid(i, j, k);
                if (i, j, k) == (1, 1, 1) {
                    centre_local = a;
                }
            }
            let mut u = [0.0; DOFS];
            for a in 0..8 {
                for i in 0..3 {
                    u[3 * a + i] = (0..3).map(|jj| f0[i][jj] * x[a][jj]).sum::<f64>() - x[a][i];
                }
            }
            let geo = element_geometry(&x).unwrap();
            let s: Vec<_> = (0..8).map(|_| mat.initial_state()).collect();
            let mut tr = s.clone();
            let mut out = HexOutput::zero();
            fbar_hex(
                &mat,
                &geo,
                &u,
                &s,
                &mut tr,
                0.0,
                true,
                TangentPart::None,
                &mut out,
            )
            .unwrap();
            // Element nodal forces from P(F0) directly.
            let fm = Mat3::from_fn(|i, jj| f0[i][jj]);
            let p = mat.update(&s[0], &fm, 0.0, &mut tr[0]).unwrap().first_piola;
            for a in 0..8 {
                for i in 0..3 {
                    let direct: f64 = geo
                        .iter()
                        .map(|g| g.weight * (0..3).map(|jj| p[(i, jj)] * g.dn[a][jj]).sum::<f64>())
                        .sum();
                    scale = scale.max(direct.abs());
                    assert!((out.r[3 * a + i] - direct).abs() < 1e-12 * (1.0 + direct.abs()));
                }
            }
            for i in 0..3 {
                force[i] += out.r[3 * centre_local + i];
            }
        }
        for f in force {
            assert!(
                f.abs() < 1e-13 * scale,
                "interior force {force:?} (scale {scale})"
            );
        }
    }
}
