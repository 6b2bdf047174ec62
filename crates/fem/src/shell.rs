//! Hexahedral meshes of thick ellipsoidal shells: the gelatin capsule of
//! thesis §4.3 (outer semi-axes a = 4.98 mm, b = c = 3.255 mm, wall t1 =
//! 0.62 mm at the ends of the long axis, t2 = t3 = 0.4 mm at the ends of the
//! short ones) and spheres with a uniform wall for verification.
//!
//! **Surface.** Each octant of the outer ellipsoid is covered by three
//! structured patches, the projections of the three faces of the unit
//! cube's corner (a "cube sphere"): a cube point c with max cᵢ = 1, its
//! in-face coordinates warped by tan(π/4 ·) (equal angles on the sphere),
//! gives the direction s = c/|c| and the outer point `P = (a s_x, b s_y,
//! c s_z)`. No element is degenerate (no poles), and the octant's edges lie
//! on the coordinate planes, so symmetric parts (eighth, quarter) are cut
//! along element boundaries and nodes on a cut have exact zero coordinates.
//! The patch divisions along x, y, z are chosen from `element_size` (the
//! longest patch edge on the outer surface divided by the size).
//!
//! **Wall.** Through the wall the nodes lie on the outer normal
//! `n ∝ (x/a², y/b², z/c²)`: layer k of `layers` at `P − (k/layers) t(n) n`.
//! The thesis gives the thickness only at the three axes; between them the
//! thickness law is (choice, `docs/theory/fem.md`)
//!
//! ```text
//! t(n) = (t1 |n_x|^q + t2 |n_y|^q + t3 |n_z|^q) / (|n_x|^q + |n_y|^q + |n_z|^q),
//! ```
//!
//! which is t1, t2, t3 at the axes for any q > 0, smooth for q ≥ 2, and for
//! q = 2 (the default) simply `t1 n_x² + t2 n_y² + t3 n_z²`; a larger q
//! keeps the wall near t2 = t3 further toward the ends (the thick part
//! confined to the caps). Nodes on a symmetry plane have n in that plane,
//! so the wall's cut faces stay on it.
//!
//! **Sets.** Face sets `outer` (contact with the plates) and `inner` (the
//! cavity boundary, oriented out of the fluid), with node sets of the same
//! names; node sets `x0`, `y0`, `z0` of the nodes on the planes x = 0,
//! y = 0, z = 0 when they are cuts; node sets `top` and `bottom` (the outer
//! poles on the z axis, where present) and `side_y` (the outer nodes on the
//! y axis).

use crate::{FemError, Mesh3, Result};

/// Which part of the shell to mesh.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ShellPart {
    /// x, y, z ≥ 0: cut by all three coordinate planes.
    Eighth,
    /// x, y ≥ 0: cut by x = 0 and y = 0.
    Quarter,
    /// The whole shell.
    Full,
}

/// Geometry and mesh density of an ellipsoidal shell (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct ShellSpec {
    /// Outer semi-axes a, b, c along x, y, z (m).
    pub semi_axes: [f64; 3],
    /// Wall thickness at the ends of the x, y, z axes: t1, t2, t3 (m).
    pub thickness: [f64; 3],
    /// Exponent q of the thickness law (module docs); 2 by default.
    pub thickness_exponent: f64,
    /// Elements through the wall (the thesis uses 4).
    pub layers: usize,
    /// Target element size along the outer surface (m).
    pub element_size: f64,
    /// Part to mesh.
    pub part: ShellPart,
}

impl ShellSpec {
    /// The capsule of thesis §4.3 (module docs), one eighth, four elements
    /// through the wall, the given in-plane element size.
    pub fn thesis_capsule(element_size: f64) -> Self {
        Self {
            semi_axes: [4.98e-3, 3.255e-3, 3.255e-3],
            thickness: [0.62e-3, 0.4e-3, 0.4e-3],
            thickness_exponent: 2.0,
            layers: 4,
            element_size,
            part: ShellPart::Eighth,
        }
    }

    /// A spherical shell of outer radius `radius` and uniform wall `wall`.
    pub fn sphere(
        radius: f64,
        wall: f64,
        layers: usize,
        element_size: f64,
        part: ShellPart,
    ) -> Self {
        Self {
            semi_axes: [radius; 3],
            thickness: [wall; 3],
            thickness_exponent: 2.0,
            layers,
            element_size,
            part,
        }
    }

    /// Wall thickness for the outer unit normal `n` (module docs).
    pub fn thickness_at(&self, n: [f64; 3]) -> f64 {
        let q = self.thickness_exponent;
        let w = n.map(|x| x.abs().powf(q));
        let sum: f64 = w.iter().sum();
        (0..3).map(|i| self.thickness[i] * w[i]).sum::<f64>() / sum
    }

    fn check(&self) -> Result<()> {
        let setting = |name: &'static str, value: f64, reason: &'static str| {
            Err(FemError::Setting {
                name,
                value,
                reason,
            })
        };
        for &a in &self.semi_axes {
            if !(a > 0.0 && a.is_finite()) {
                return setting("shell semi-axis", a, "must be positive and finite (m)");
            }
        }
        for (&t, &a) in self.thickness.iter().zip(&self.semi_axes) {
            if !(t > 0.0 && t.is_finite()) {
                return setting("shell wall thickness", t, "must be positive and finite (m)");
            }
            let rmin = self
                .semi_axes
                .iter()
                .fold(f64::INFINITY, |m: f64, &x| m.min(x));
            // The smallest principal radius of curvature of the outer
            // ellipsoid is min(a)²/max(a); the inward offset must not fold.
            let rmax = self.semi_axes.iter().fold(0.0f64, |m, &x| m.max(x));
            if t >= rmin * rmin / rmax || t >= a {
                return setting(
                    "shell wall thickness",
                    t,
                    "must be below the smallest radius of curvature of the outer surface (min(a,b,c)²/max(a,b,c))",
                );
            }
        }
        if !(self.thickness_exponent >= 1.0 && self.thickness_exponent.is_finite()) {
            return setting(
                "thickness exponent",
                self.thickness_exponent,
                "must be ≥ 1 and finite",
            );
        }
        if self.layers == 0 {
            return setting("layers", 0.0, "at least one element through the wall");
        }
        if !(self.element_size > 0.0 && self.element_size.is_finite()) {
            return setting(
                "element size",
                self.element_size,
                "must be positive and finite (m)",
            );
        }
        Ok(())
    }
}

/// Outer point for a cube point `c` (max cᵢ = 1, already warped).
fn outer_point(axes: &[f64; 3], c: [f64; 3]) -> [f64; 3] {
    let r = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt();
    [axes[0] * c[0] / r, axes[1] * c[1] / r, axes[2] * c[2] / r]
}

/// The cube point of patch `k` (the face c_k = 1) at in-face parameters
/// (u, v) ∈ [0, 1]² along the next two axes (k+1, k+2 mod 3).
fn cube_point(k: usize, u: f64, v: f64) -> [f64; 3] {
    // tan(π/4) rounds to 1 − 2⁻⁵³: pin the ends so seams coincide exactly.
    let warp = |x: f64| {
        if x >= 1.0 {
            1.0
        } else {
            (0.25 * std::f64::consts::PI * x).tan()
        }
    };
    let mut c = [0.0; 3];
    c[k] = 1.0;
    c[(k + 1) % 3] = warp(u);
    c[(k + 2) % 3] = warp(v);
    c
}

/// Length of the outer curve of patch `k` along its edge where the other
/// in-face parameter is `at`, in direction `dir` (0: u, 1: v).
fn edge_length(axes: &[f64; 3], k: usize, dir: usize, at: f64) -> f64 {
    let n = 200;
    let mut len = 0.0;
    let mut prev = None;
    for i in 0..=n {
        let s = i as f64 / n as f64;
        let (u, v) = if dir == 0 { (s, at) } else { (at, s) };
        let p = outer_point(axes, cube_point(k, u, v));
        if let Some(q) = prev {
            let q: [f64; 3] = q;
            len += ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt();
        }
        prev = Some(p);
    }
    len
}

/// Deduplicates points by exact coordinates (cuts and seams are generated
/// identically from both sides, and reflections are exact negations).
struct Points {
    coords: Vec<[f64; 3]>,
    index: std::collections::HashMap<[u64; 3], usize>,
}

impl Points {
    fn id(&mut self, p: [f64; 3]) -> usize {
        // +0.0 and −0.0 are the same point.
        let key = p.map(|x| if x == 0.0 { 0u64 } else { x.to_bits() });
        let next = self.coords.len();
        *self.index.entry(key).or_insert_with(|| {
            self.coords.push(p);
            next
        })
    }
}

/// Meshes the shell of `spec` (module docs).
///
/// # Errors
/// [`FemError::Setting`] for a non-positive size, a wall too thick for the
/// curvature or zero layers; [`FemError::Mesh`] if an element comes out
/// inverted.
pub fn ellipsoidal_shell(spec: &ShellSpec) -> Result<Mesh3> {
    spec.check()?;
    let axes = spec.semi_axes;
    // Divisions along the cube's x, y, z edges, from the longest outer
    // edge each of them divides.
    let mut m = [1usize; 3];
    for axis in 0..3 {
        // Patches whose in-face directions include `axis`.
        let mut longest: f64 = 0.0;
        for k in 0..3 {
            for dir in 0..2 {
                if (k + 1 + dir) % 3 == axis {
                    for at in [0.0, 1.0] {
                        longest = longest.max(edge_length(&axes, k, dir, at));
                    }
                }
            }
        }
        m[axis] = ((longest / spec.element_size).ceil() as usize).max(1);
    }
    // The outer surface of the positive octant: patches of quads, nodes
    // merged along the seams; then reflected into the requested part.
    let mut surface = Points {
        coords: Vec::new(),
        index: Default::default(),
    };
    let mut quads: Vec<[usize; 4]> = Vec::new();
    for k in 0..3 {
        let (nu, nv) = (m[(k + 1) % 3], m[(k + 2) % 3]);
        for j in 0..nv {
            for i in 0..nu {
                let corner = |di: usize, dj: usize| {
                    outer_point(
                        &axes,
                        cube_point(k, (i + di) as f64 / nu as f64, (j + dj) as f64 / nv as f64),
                    )
                };
                // (u, v) along (k+1, k+2): counter-clockwise seen from
                // outside (e_{k+1} × e_{k+2} = e_k, the outward direction).
                quads.push([
                    surface.id(corner(0, 0)),
                    surface.id(corner(1, 0)),
                    surface.id(corner(1, 1)),
                    surface.id(corner(0, 1)),
                ]);
            }
        }
    }
    let mirrors: Vec<[f64; 3]> = match spec.part {
        ShellPart::Eighth => vec![[1.0, 1.0, 1.0]],
        ShellPart::Quarter => vec![[1.0, 1.0, 1.0], [1.0, 1.0, -1.0]],
        ShellPart::Full => (0..8)
            .map(|b| [0, 1, 2].map(|i| if b >> i & 1 == 1 { -1.0 } else { 1.0 }))
            .collect(),
    };
    let mut all = Points {
        coords: Vec::new(),
        index: Default::default(),
    };
    let mut faces: Vec<[usize; 4]> = Vec::new();
    for s in &mirrors {
        let flip = s[0] * s[1] * s[2] < 0.0;
        for q in &quads {
            let f = q.map(|a| {
                let p = surface.coords[a];
                all.id([s[0] * p[0], s[1] * p[1], s[2] * p[2]])
            });
            // A reflection reverses orientation.
            faces.push(if flip { [f[0], f[3], f[2], f[1]] } else { f });
        }
    }
    let outer = all.coords;
    let ns = outer.len();
    let layers = spec.layers;
    // Node (surface node a, layer k): k = 0 outer, k = layers inner.
    let id = |a: usize, k: usize| k * ns + a;
    let mut nodes = vec![[0.0; 3]; ns * (layers + 1)];
    for (a, p) in outer.iter().enumerate() {
        let g = [
            p[0] / (axes[0] * axes[0]),
            p[1] / (axes[1] * axes[1]),
            p[2] / (axes[2] * axes[2]),
        ];
        let gn = (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]).sqrt();
        let n = g.map(|x| x / gn);
        let t = spec.thickness_at(n);
        for k in 0..=layers {
            let d = t * k as f64 / layers as f64;
            // Keep exact zeros on the cuts.
            nodes[id(a, k)] =
                std::array::from_fn(|i| if p[i] == 0.0 { 0.0 } else { p[i] - d * n[i] });
        }
    }
    let mut elements = Vec::with_capacity(faces.len() * layers);
    for f in &faces {
        for k in 0..layers {
            // ζ from inner (k+1) to outer (k): the face order is
            // counter-clockwise seen from outside, i.e. from +ζ.
            elements.push([
                id(f[0], k + 1),
                id(f[1], k + 1),
                id(f[2], k + 1),
                id(f[3], k + 1),
                id(f[0], k),
                id(f[1], k),
                id(f[2], k),
                id(f[3], k),
            ]);
        }
    }
    let mut mesh = Mesh3::new(nodes, elements)?;
    mesh.set_faces("outer", faces.iter().map(|f| f.map(|a| id(a, 0))).collect())?;
    mesh.set_faces(
        "inner",
        faces.iter().map(|f| f.map(|a| id(a, layers))).collect(),
    )?;
    let cut = |axis: usize| -> Vec<usize> {
        (0..mesh.nodes.len())
            .filter(|&a| mesh.nodes[a][axis] == 0.0)
            .collect()
    };
    let (x0, y0, z0) = (cut(0), cut(1), cut(2));
    match spec.part {
        ShellPart::Eighth => {
            mesh.set_nodes("x0", x0);
            mesh.set_nodes("y0", y0);
            mesh.set_nodes("z0", z0);
        }
        ShellPart::Quarter => {
            mesh.set_nodes("x0", x0);
            mesh.set_nodes("y0", y0);
        }
        ShellPart::Full => {}
    }
    let on_axis = |a: usize, axis: usize| (0..3).all(|i| i == axis || outer[a][i] == 0.0);
    let pole = |sign: f64| -> Vec<usize> {
        (0..ns)
            .filter(|&a| on_axis(a, 2) && outer[a][2] * sign > 0.0)
            .collect()
    };
    mesh.set_nodes("top", pole(1.0));
    mesh.set_nodes("bottom", pole(-1.0));
    mesh.set_nodes(
        "side_y",
        (0..ns)
            .filter(|&a| on_axis(a, 1) && outer[a][1] != 0.0)
            .collect(),
    );
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cavity::quad_volume;

    fn enclosed(mesh: &Mesh3, set: &str) -> f64 {
        mesh.faces_in(set)
            .unwrap()
            .iter()
            .map(|f| quad_volume(&f.map(|a| mesh.nodes[a])).0)
            .sum()
    }

    fn solid_volume(mesh: &Mesh3) -> f64 {
        mesh.elements
            .iter()
            .map(|e| {
                crate::hex::element_geometry(&e.map(|a| mesh.nodes[a]))
                    .unwrap()
                    .iter()
                    .map(|p| p.weight)
                    .sum::<f64>()
            })
            .sum()
    }

    #[test]
    fn thickness_law_matches_the_thesis_at_the_axes() {
        let spec = ShellSpec::thesis_capsule(0.3e-3);
        for q in [2.0, 4.0] {
            let s = ShellSpec {
                thickness_exponent: q,
                ..spec.clone()
            };
            assert!((s.thickness_at([1.0, 0.0, 0.0]) - 0.62e-3).abs() < 1e-15);
            assert!((s.thickness_at([0.0, 1.0, 0.0]) - 0.4e-3).abs() < 1e-15);
            assert!((s.thickness_at([0.0, 0.0, -1.0]) - 0.4e-3).abs() < 1e-15);
        }
        // q = 2: t1 n_x² + t2 (1 − n_x²) with t2 = t3.
        let n = [0.6, 0.0, 0.8];
        assert!((spec.thickness_at(n) - (0.62e-3 * 0.36 + 0.4e-3 * 0.64)).abs() < 1e-15);
    }

    #[test]
    fn wall_and_cavity_fill_the_outer_ellipsoid() {
        // The hexahedra and the cavity exactly fill the volume inside the
        // outer faces (both from the same nodes: a consistency identity),
        // and that volume converges to πabc/6 (one eighth) at second order.
        let mut errors = Vec::new();
        for size in [0.8e-3, 0.4e-3] {
            let mesh = ellipsoidal_shell(&ShellSpec::thesis_capsule(size)).unwrap();
            let (outer, inner, wall) = (
                enclosed(&mesh, "outer"),
                enclosed(&mesh, "inner"),
                solid_volume(&mesh),
            );
            assert!(
                (outer - inner - wall).abs() < 1e-12 * outer,
                "{outer} {inner} {wall}"
            );
            let exact = std::f64::consts::PI * 4.98e-3 * 3.255e-3 * 3.255e-3 / 6.0;
            errors.push((outer / exact - 1.0).abs());
        }
        assert!(
            errors[1] < errors[0] / 3.0 && errors[1] < 5e-3,
            "{errors:?}"
        );
    }

    #[test]
    fn uniform_sphere_cavity_converges_to_the_inner_sphere() {
        let (r, t): (f64, f64) = (1.0, 0.2);
        let exact = std::f64::consts::PI * (r - t).powi(3) / 6.0;
        let mut errors = Vec::new();
        for size in [0.2, 0.1] {
            let mesh =
                ellipsoidal_shell(&ShellSpec::sphere(r, t, 2, size, ShellPart::Eighth)).unwrap();
            // Every inner node lies on the sphere of radius r − t.
            for &a in mesh.nodes_in("inner").unwrap() {
                let p = mesh.nodes[a];
                assert!(((p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt() - (r - t)).abs() < 1e-14);
            }
            errors.push((enclosed(&mesh, "inner") / exact - 1.0).abs());
        }
        assert!(errors[1] < errors[0] / 3.0, "{errors:?}");
    }

    #[test]
    fn parts_have_the_expected_counts_cuts_and_volumes() {
        let spec = |part| ShellSpec {
            part,
            ..ShellSpec::thesis_capsule(0.6e-3)
        };
        let eighth = ellipsoidal_shell(&spec(ShellPart::Eighth)).unwrap();
        let quarter = ellipsoidal_shell(&spec(ShellPart::Quarter)).unwrap();
        let full = ellipsoidal_shell(&spec(ShellPart::Full)).unwrap();
        let ne = eighth.elements.len();
        assert_eq!(quarter.elements.len(), 2 * ne);
        assert_eq!(full.elements.len(), 8 * ne);
        let v = solid_volume(&eighth);
        assert!((solid_volume(&quarter) / (2.0 * v) - 1.0).abs() < 1e-12);
        assert!((solid_volume(&full) / (8.0 * v) - 1.0).abs() < 1e-12);
        assert!(
            (enclosed(&full, "inner") / (8.0 * enclosed(&eighth, "inner")) - 1.0).abs() < 1e-12
        );
        // The cuts are the nodes on the planes, through the whole wall.
        for set in ["x0", "y0", "z0"] {
            assert!(!eighth.nodes_in(set).unwrap().is_empty());
        }
        assert!(quarter.nodes_in("z0").is_err());
        assert_eq!(full.nodes_in("top").unwrap().len(), 1);
        assert_eq!(full.nodes_in("bottom").unwrap().len(), 1);
        assert!(eighth.nodes_in("bottom").unwrap().is_empty());
    }

    #[test]
    fn too_thick_a_wall_is_rejected() {
        let mut spec = ShellSpec::thesis_capsule(0.5e-3);
        spec.thickness[0] = 2.2e-3; // > b²/a = 2.13 mm
        assert!(ellipsoidal_shell(&spec).is_err());
    }
}
