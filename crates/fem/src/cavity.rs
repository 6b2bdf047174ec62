//! The enclosed volume of a fluid cavity from its boundary cells, with its
//! exact first and second derivatives with respect to the nodal positions
//! (thesis §4.3: incompressible, inviscid fluid filling the capsule; ABAQUS
//! models it with hydrostatic F3D4 elements on the wall's inner surface).
//!
//! By the divergence theorem (div x = 3) the volume of a region is
//! `V = ⅓ ∮ x · n dA`. On a symmetry plane through the origin x · n = 0, so
//! when every symmetry plane of the model passes through the origin
//! (x = 0, y = 0, z = 0), the open boundary made of the wall's inner faces
//! alone gives the exact volume of the cut cavity — the symmetry planes
//! close it without contributing. Nodes on a plane stay on it (roller
//! supports), so this holds in every deformed state.
//!
//! - 3D: bilinear quadrilaterals; `x · (x_s × x_t)` is a polynomial of
//!   degree ≤ 2 in each of s, t, so 2×2 Gauss integrates it exactly: the
//!   volume is exact for the faceted (bilinear) surface, not a quadrature.
//! - Axisymmetric: straight segments of the (r, z) profile; the volume of
//!   revolution `V = ∮ π r² dz` is exact per segment,
//!   `π (z₂ − z₁)(r₁² + r₁r₂ + r₂²)/3`; the axis (r = 0) and a symmetry
//!   plane z = 0 (dz = 0) contribute nothing.
//!
//! Signs: a cell's contribution is positive when its normal points out of
//! the fluid; the model flips the sign of the whole boundary if its
//! reference volume comes out negative, so only the cells' mutual
//! orientation matters.

use crate::mesh3::quad_shape;

/// `S(v)_{ij} = ε_ijk v_k`, so that `(e_j × v)_i = S(v)_ij`.
fn skew(v: &[f64; 3]) -> [[f64; 3]; 3] {
    [[0.0, v[2], -v[1]], [-v[2], 0.0, v[0]], [v[1], -v[0], 0.0]]
}

fn cross(a: &[f64; 3], b: &[f64; 3]) -> [f64; 3] {
    crate::mesh3::cross(a, b)
}

/// Volume contribution `⅓ ∫ x · (x_s × x_t) ds dt` of one bilinear face
/// with current nodal positions `x`, its gradient (dof `3a + i`) and
/// Hessian.
pub(crate) fn quad_volume(x: &[[f64; 3]; 4]) -> (f64, [f64; 12], [[f64; 12]; 12]) {
    let g = 0.577_350_269_189_625_8;
    let mut v = 0.0;
    let mut grad = [0.0; 12];
    let mut hess = [[0.0; 12]; 12];
    for (s, t) in [(-g, -g), (g, -g), (g, g), (-g, g)] {
        let (n, ns, nt) = quad_shape(s, t);
        let (mut p, mut ps, mut pt) = ([0.0; 3], [0.0; 3], [0.0; 3]);
        for a in 0..4 {
            for i in 0..3 {
                p[i] += n[a] * x[a][i];
                ps[i] += ns[a] * x[a][i];
                pt[i] += nt[a] * x[a][i];
            }
        }
        let c = cross(&ps, &pt);
        v += (p[0] * c[0] + p[1] * c[1] + p[2] * c[2]) / 3.0;
        let tx = cross(&pt, &p);
        let xs = cross(&p, &ps);
        let (sp, sps, spt) = (skew(&p), skew(&ps), skew(&pt));
        for a in 0..4 {
            for i in 0..3 {
                grad[3 * a + i] += (n[a] * c[i] + ns[a] * tx[i] + nt[a] * xs[i]) / 3.0;
                for b in 0..4 {
                    for j in 0..3 {
                        let h = n[a] * (ns[b] * spt[i][j] - nt[b] * sps[i][j])
                            + ns[a] * (nt[b] * sp[i][j] - n[b] * spt[i][j])
                            + nt[a] * (n[b] * sps[i][j] - ns[b] * sp[i][j]);
                        hess[3 * a + i][3 * b + j] += h / 3.0;
                    }
                }
            }
        }
    }
    (v, grad, hess)
}

/// Volume of revolution `π (z₂ − z₁)(r₁² + r₁r₂ + r₂²)/3` swept by one
/// (r, z) segment about the axis, its gradient (dofs r₁, z₁, r₂, z₂) and
/// Hessian.
pub(crate) fn segment_volume(x: &[[f64; 2]; 2]) -> (f64, [f64; 4], [[f64; 4]; 4]) {
    let c = std::f64::consts::PI / 3.0;
    let ([r1, z1], [r2, z2]) = (x[0], x[1]);
    let dz = z2 - z1;
    let q = r1 * r1 + r1 * r2 + r2 * r2;
    let (q1, q2) = (2.0 * r1 + r2, r1 + 2.0 * r2);
    let v = c * dz * q;
    let grad = [c * dz * q1, -c * q, c * dz * q2, c * q];
    let hess = [
        [2.0 * c * dz, -c * q1, c * dz, c * q1],
        [-c * q1, 0.0, -c * q2, 0.0],
        [c * dz, -c * q2, 2.0 * c * dz, c * q2],
        [c * q1, 0.0, c * q2, 0.0],
    ];
    (v, grad, hess)
}

/// Area-weighted normals `∫ N_a n dA` of the nodes of one bilinear face
/// (dof `3a + i`; exact by 2×2 Gauss): the consistent nodal forces of a
/// unit pressure. For a node free to move they equal ∂V/∂x_a; at a node on
/// a symmetry plane they are the physical force normal to the plane, where
/// the volume formula's derivative is not (module docs).
pub(crate) fn quad_area_normals(x: &[[f64; 3]; 4]) -> [f64; 12] {
    let g = 0.577_350_269_189_625_8;
    let mut out = [0.0; 12];
    for (s, t) in [(-g, -g), (g, -g), (g, g), (-g, g)] {
        let (n, ns, nt) = quad_shape(s, t);
        let (mut ps, mut pt) = ([0.0; 3], [0.0; 3]);
        for a in 0..4 {
            for i in 0..3 {
                ps[i] += ns[a] * x[a][i];
                pt[i] += nt[a] * x[a][i];
            }
        }
        let c = cross(&ps, &pt);
        for a in 0..4 {
            for i in 0..3 {
                out[3 * a + i] += n[a] * c[i];
            }
        }
    }
    out
}

/// Area-weighted normals `2π ∫ N_a r (dz, −dr)` of the two nodes of one
/// (r, z) segment of a surface of revolution (dofs r₁, z₁, r₂, z₂); see
/// [`quad_area_normals`].
pub(crate) fn segment_area_normals(x: &[[f64; 2]; 2]) -> [f64; 4] {
    let ([r1, z1], [r2, z2]) = (x[0], x[1]);
    let c = 2.0 * std::f64::consts::PI / 6.0;
    let (w1, w2) = (c * (2.0 * r1 + r2), c * (r1 + 2.0 * r2));
    let (dr, dz) = (r2 - r1, z2 - z1);
    [w1 * dz, -w1 * dr, w2 * dz, -w2 * dr]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check_derivatives<const N: usize>(
        f: impl Fn(&[f64; N]) -> (f64, [f64; N], [[f64; N]; N]),
        x: [f64; N],
    ) {
        let (_, g, h) = f(&x);
        let eps = 1e-6;
        for k in 0..N {
            let (mut xp, mut xm) = (x, x);
            xp[k] += eps;
            xm[k] -= eps;
            let (vp, gp, _) = f(&xp);
            let (vm, gm, _) = f(&xm);
            assert!(((vp - vm) / (2.0 * eps) - g[k]).abs() < 1e-9, "grad[{k}]");
            for i in 0..N {
                assert!(
                    ((gp[i] - gm[i]) / (2.0 * eps) - h[i][k]).abs() < 1e-9,
                    "hess[{i}][{k}]"
                );
                assert!(
                    (h[i][k] - h[k][i]).abs() < 1e-14,
                    "asymmetric hess[{i}][{k}]"
                );
            }
        }
    }

    #[test]
    fn quad_volume_derivatives_match_finite_differences() {
        let x = [0.9, 0.1, 1.2, 2.1, -0.2, 0.8, 2.3, 1.9, 1.1, 0.7, 2.2, 1.6];
        let f = |x: &[f64; 12]| {
            quad_volume(&[
                [x[0], x[1], x[2]],
                [x[3], x[4], x[5]],
                [x[6], x[7], x[8]],
                [x[9], x[10], x[11]],
            ])
        };
        check_derivatives(f, x);
    }

    #[test]
    fn segment_volume_derivatives_match_finite_differences() {
        let f = |x: &[f64; 4]| segment_volume(&[[x[0], x[1]], [x[2], x[3]]]);
        check_derivatives(f, [0.7, 1.3, 1.9, 0.4]);
    }

    #[test]
    fn faces_of_a_warped_hexahedron_enclose_its_volume() {
        // The six outward faces of a distorted hexahedron enclose exactly
        // the volume its own 2×2×2 quadrature integrates (the trilinear map's
        // Jacobian is integrated exactly), whatever the origin.
        let mut x = crate::hex::unit_cube();
        x[6] = [1.2, 1.1, 1.3];
        x[1] = [0.9, -0.1, 0.05];
        x[4] = [0.1, 0.05, 0.8];
        let faces = crate::hex::FACES;
        let exact: f64 = crate::hex::element_geometry(&x)
            .unwrap()
            .iter()
            .map(|p| p.weight)
            .sum();
        for origin in [[0.0; 3], [3.0, -2.0, 5.0]] {
            let v: f64 = faces
                .iter()
                .map(|f| {
                    quad_volume(&f.map(|a| {
                        [
                            x[a][0] - origin[0],
                            x[a][1] - origin[1],
                            x[a][2] - origin[2],
                        ]
                    }))
                    .0
                })
                .sum();
            assert!((v - exact).abs() < 1e-14, "{v} vs {exact}");
        }
    }

    #[test]
    fn area_normals_are_the_volume_gradient_on_a_closed_surface() {
        // Faces of a distorted hexahedron: the gradient of the enclosed
        // volume w.r.t. a node is the sum of its area-weighted normals over
        // the faces around it; the normals of a closed surface sum to zero.
        let mut x = crate::hex::unit_cube();
        x[6] = [1.2, 1.1, 1.3];
        x[1] = [0.9, -0.1, 0.05];
        let faces = crate::hex::FACES;
        let mut grad = [[0.0; 3]; 8];
        let mut normal = [[0.0; 3]; 8];
        for f in faces {
            let p = f.map(|a| x[a]);
            let (_, g, _) = quad_volume(&p);
            let n = quad_area_normals(&p);
            for k in 0..4 {
                for i in 0..3 {
                    grad[f[k]][i] += g[3 * k + i];
                    normal[f[k]][i] += n[3 * k + i];
                }
            }
        }
        let total: [f64; 3] = std::array::from_fn(|i| normal.iter().map(|n| n[i]).sum());
        for a in 0..8 {
            for i in 0..3 {
                assert!((grad[a][i] - normal[a][i]).abs() < 1e-14, "node {a}");
                assert!(total[i].abs() < 1e-14);
            }
        }
        // Revolution: the frustum's profile closed by the axis and z = 0;
        // interior node of the profile: gradient = area normal.
        let profile = [[0.0, 3.0], [2.0, 3.0], [1.0, 0.0]];
        let (_, g1, _) = segment_volume(&[profile[0], profile[1]]);
        let (_, g2, _) = segment_volume(&[profile[1], profile[2]]);
        let n1 = segment_area_normals(&[profile[0], profile[1]]);
        let n2 = segment_area_normals(&[profile[1], profile[2]]);
        for i in 0..2 {
            assert!((g1[2 + i] + g2[i] - n1[2 + i] - n2[i]).abs() < 1e-13);
        }
    }

    #[test]
    fn segments_of_a_revolved_trapezoid_enclose_its_volume() {
        // Frustum r from 1 (z = 0) to 2 (z = 3), closed by the axis and the
        // plane z = 0: V = π h (R₁² + R₁R₂ + R₂²)/3 = 7π, traversed from the
        // axis at the top down to the base.
        let profile = [[0.0, 3.0], [2.0, 3.0], [1.0, 0.0]];
        let v: f64 = profile
            .windows(2)
            .map(|w| segment_volume(&[w[0], w[1]]).0)
            .sum();
        assert!((v.abs() - 7.0 * std::f64::consts::PI).abs() < 1e-13, "{v}");
    }
}
