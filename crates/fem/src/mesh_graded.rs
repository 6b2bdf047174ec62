//! Meshes graded to the contact point (issue 15): rings of quadrilaterals
//! centred on the pole of the body (where the probe touches), whose radii
//! grow geometrically, so the element size is a fixed fraction of the
//! distance to the pole everywhere. Any contact radius a between the core
//! and the last ring is then resolved by the same number of surface
//! segments per a (≈ 1/(q − 1)), from the shallowest indentation
//! (a = √(Rδ) = 0.35 µm at δ = 0.05 µm, R = 2.5 µm) to the deepest, with
//! few elements far away.
//!
//! Layout (r, z half-plane, pole P on the axis at the top surface):
//! - core: a k × k block in the corner at P, its top row on the surface,
//!   element size h₀ (`spacing`);
//! - rings 1…N: circular arcs of radius ρ_j = ρ₁ q^{j−1} centred on P, from
//!   the axis to the surface, each with m = 2k elements; ring 1 joins the
//!   core's outer polyline (bottom and side edges); the angles of the
//!   nodes on every ring are those of the core's outer nodes seen from P;
//! - the cell ([`Mesh::contact_graded_cell`]): a transfinite patch from the
//!   last ring (ρ_N ≈ 0.6 H) to the base and the rest of the free surface;
//!   the half space ([`Mesh::contact_graded_half_space`]): rings out to the
//!   outer radius, which is the far boundary.

use crate::mesh::graded;
use crate::{FemError, Mesh, Result};

/// Size parameters of a mesh graded to the contact.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ContactMesh {
    /// Element size at the pole, h₀ (m): the core is `core` × `core_depth`
    /// square elements of this size.
    pub spacing: f64,
    /// Core elements along the surface, k_r.
    pub core: usize,
    /// Core elements in depth along the axis, k_z; every ring has
    /// k_r + k_z elements, their angular spacing ≈ 1/k_r rad at the
    /// surface and 1/k_z rad at the axis.
    pub core_depth: usize,
    /// Ratio of consecutive ring radii q (> 1): the element size is
    /// ≈ (q − 1) × the distance to the pole.
    pub growth: f64,
}

impl ContactMesh {
    /// The default for a cell indented by a sphere of radius
    /// `probe_radius` (docs/theory/fem.md, "Mesh").
    pub fn cell_default(probe_radius: f64) -> Self {
        Self {
            spacing: probe_radius / 250.0,
            core: 12,
            core_depth: 4,
            growth: 1.1,
        }
    }

    /// A coarser grading for protocols whose forces matter from
    /// δ = 0.1 µm on: h₀ = R/100 instead of the default's R/250, 684
    /// elements on setup 1 instead of 912. On the elastic dome
    /// ([`crate::afm::AfmSetup::elastic_dome`]) every force from 0.1 µm is
    /// within 0.36 % of the 4×-refined default mesh, but 0.59 % at 0.05 µm
    /// (docs/theory/fem.md, "Session 23"): use the default below 0.1 µm.
    pub fn cell_from_tenth_micron(probe_radius: f64) -> Self {
        Self {
            spacing: probe_radius / 100.0,
            core: 10,
            ..Self::cell_default(probe_radius)
        }
    }

    /// The same layout refined `factor` times in every direction: h₀ and
    /// the core elements' size / factor (core × factor per side), ring
    /// ratio q^{1/factor} (so factor rings per ring), and the far patch
    /// refined alike.
    pub fn refined(&self, factor: usize) -> Self {
        let f = factor.max(1);
        Self {
            spacing: self.spacing / f as f64,
            core: self.core * f,
            core_depth: self.core_depth * f,
            growth: self.growth.powf(1.0 / f as f64),
        }
    }

    fn check(&self) -> Result<()> {
        let bad = |name, value, reason| {
            Err(FemError::Setting {
                name,
                value,
                reason,
            })
        };
        if !(self.spacing > 0.0 && self.spacing.is_finite()) {
            return bad(
                "mesh spacing",
                self.spacing,
                "must be positive and finite (m)",
            );
        }
        if self.core < 1 {
            return bad("mesh core elements", self.core as f64, "must be at least 1");
        }
        if self.core_depth < 1 {
            return bad(
                "mesh core depth",
                self.core_depth as f64,
                "must be at least 1",
            );
        }
        if !(self.growth > 1.0 && self.growth <= 2.0) {
            return bad("mesh growth", self.growth, "must be in (1, 2]");
        }
        Ok(())
    }
}

/// Node positions of the rings: the core's outer angles seen from the pole.
struct Rings {
    /// Angle from the downward axis of each node of the core's outer
    /// polyline (k_r + k_z + 1 values from 0 to π/2).
    angles: Vec<f64>,
    radii: Vec<f64>,
}

impl Rings {
    fn new(spec: &ContactMesh, outer: f64) -> Self {
        let (kr, kz) = (spec.core, spec.core_depth);
        let (cr, cz) = (spec.spacing * kr as f64, spec.spacing * kz as f64);
        // Outer polyline of the core: bottom edge (axis → corner), then the
        // side edge (corner → surface); angle from the downward axis.
        let mut angles = Vec::with_capacity(kr + kz + 1);
        for i in 0..=kr {
            angles.push((spec.spacing * i as f64).atan2(cz));
        }
        for j in (0..kz).rev() {
            angles.push(cr.atan2(spec.spacing * j as f64));
        }
        // Ring 1 clear of the core's corner, then ×q.
        let mut radii = vec![1.25 * cr.hypot(cz)];
        while radii.last().is_some_and(|&r| r * spec.growth < outer) {
            let next = radii.last().copied().unwrap_or(cr) * spec.growth;
            radii.push(next);
        }
        Self { angles, radii }
    }
}

/// Quadrilateral with its nodes in counter-clockwise order.
fn quad(nodes: &[[f64; 2]], q: [usize; 4]) -> [usize; 4] {
    let p = q.map(|a| nodes[a]);
    let mut area = 0.0;
    for i in 0..4 {
        let (a, b) = (p[i], p[(i + 1) % 4]);
        area += a[0] * b[1] - b[0] * a[1];
    }
    if area < 0.0 {
        [q[0], q[3], q[2], q[1]]
    } else {
        q
    }
}

/// Builds core and rings for a pole at (0, `top(0)`) with the top surface
/// z = `top(r)` and the surface point at distance ρ from the pole given by
/// `surface_at(ρ)`; returns (nodes, elements, axis, surface, last ring).
type Rings2 = (
    Vec<[f64; 2]>,
    Vec<[usize; 4]>,
    Vec<usize>,
    Vec<usize>,
    Vec<usize>,
);

fn core_and_rings(
    spec: &ContactMesh,
    outer: f64,
    top: &dyn Fn(f64) -> f64,
    surface_at: &dyn Fn(f64) -> [f64; 2],
) -> Rings2 {
    let (kr, kz) = (spec.core, spec.core_depth);
    let h = spec.spacing;
    let pole = [0.0, top(0.0)];
    let rings = Rings::new(spec, outer);
    let mut nodes: Vec<[f64; 2]> = Vec::new();
    let mut elements = Vec::new();
    // Core: node (i, j), i along r, j down from the surface.
    let mut core = vec![vec![0; kr + 1]; kz + 1];
    for (j, row) in core.iter_mut().enumerate() {
        for (i, id) in row.iter_mut().enumerate() {
            let r = h * i as f64;
            *id = nodes.len();
            nodes.push([r, top(r) - h * j as f64]);
        }
    }
    for j in 0..kz {
        for i in 0..kr {
            let q = [
                core[j + 1][i],
                core[j + 1][i + 1],
                core[j][i + 1],
                core[j][i],
            ];
            elements.push(quad(&nodes, q));
        }
    }
    let mut axis: Vec<usize> = (0..=kz).map(|j| core[j][0]).collect();
    let mut surface: Vec<usize> = (0..=kr).map(|i| core[0][i]).collect();
    // The core's outer polyline, axis → surface.
    let mut previous: Vec<usize> = (0..=kr).map(|i| core[kz][i]).collect();
    previous.extend((0..kz).rev().map(|j| core[j][kr]));
    for &rho in &rings.radii {
        let s = surface_at(rho);
        let phi_s = s[0].atan2(pole[1] - s[1]);
        let ring: Vec<usize> = rings
            .angles
            .iter()
            .enumerate()
            .map(|(i, &phi)| {
                let id = nodes.len();
                if i + 1 == rings.angles.len() {
                    nodes.push(s);
                } else {
                    let a = phi * phi_s / std::f64::consts::FRAC_PI_2;
                    nodes.push([rho * a.sin(), pole[1] - rho * a.cos()]);
                }
                id
            })
            .collect();
        for i in 0..ring.len() - 1 {
            let q = [previous[i], previous[i + 1], ring[i + 1], ring[i]];
            elements.push(quad(&nodes, q));
        }
        axis.push(ring[0]);
        surface.push(ring[ring.len() - 1]);
        previous = ring;
    }
    (nodes, elements, axis, surface, previous)
}

impl Mesh {
    /// The oblate cell of thesis §5.3 (half-ellipse profile z = H √(1 −
    /// (2r/D)²), base fixed) meshed with rings graded to the pole (module
    /// docs): rings out to ρ = 0.6 H, then a transfinite patch to the base
    /// and the rim, graded on with the same ratio.
    ///
    /// Sets: `axis`, `base`, `surface` (free surface from the pole to the
    /// rim, ordered).
    ///
    /// # Errors
    /// [`FemError::Setting`] for non-positive sizes or a spec whose core
    /// does not fit well inside the rings (`spacing` × `core` ≥ 0.1 H).
    pub fn contact_graded_cell(height: f64, diameter: f64, spec: &ContactMesh) -> Result<Self> {
        spec.check()?;
        for (name, v) in [("cell height", height), ("cell diameter", diameter)] {
            if !(v > 0.0 && v.is_finite()) {
                return Err(FemError::Setting {
                    name,
                    value: v,
                    reason: "must be positive and finite",
                });
            }
        }
        let (a, hh) = (0.5 * diameter, height);
        let core = spec.spacing * (spec.core.max(spec.core_depth)) as f64;
        if core * 1.8 * spec.growth >= 0.6 * hh.min(a) {
            return Err(FemError::Setting {
                name: "mesh spacing",
                value: spec.spacing,
                reason: "the core (spacing × core elements) must be well inside the cell: \
                         ≤ 0.3 × min(height, diameter / 2) / growth",
            });
        }
        let top = move |r: f64| hh * (1.0 - (r / a).powi(2)).max(0.0).sqrt();
        // The core is a flat block under a curved surface: the surface must
        // drop by less than half the core depth over the core width.
        let (width, depth) = (
            spec.spacing * spec.core as f64,
            spec.spacing * spec.core_depth as f64,
        );
        if width >= a || hh - top(width) >= 0.5 * depth {
            return Err(FemError::Setting {
                name: "mesh spacing",
                value: spec.spacing,
                reason: "the cell surface curves too much over the mesh core (spacing × core \
                         elements) and would invert its elements: the pole's radius of \
                         curvature D²/(4H) is too small for this spacing; use a smaller \
                         spacing (or fewer core elements)",
            });
        }
        let ellipse = move |theta: f64| [a * theta.sin(), hh * theta.cos()];
        // Surface point at distance ρ from the pole: bisection on the
        // parametric angle (the distance grows with it on [0, π/2]).
        let surface_at = move |rho: f64| -> [f64; 2] {
            let (mut lo, mut hi) = (0.0, std::f64::consts::FRAC_PI_2);
            for _ in 0..80 {
                let mid = 0.5 * (lo + hi);
                let p = ellipse(mid);
                if (p[0] * p[0] + (hh - p[1]).powi(2)).sqrt() < rho {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            ellipse(0.5 * (lo + hi))
        };
        let (mut nodes, mut elements, mut axis, mut surface, last) =
            core_and_rings(spec, 0.6 * hh, &top, &surface_at);
        // Far patch: rows l = 0 (the last ring) … p (the base); columns
        // i = 0 (axis) … m (free surface).
        let m = last.len() - 1;
        let a_n = nodes[last[0]];
        let s_n = nodes[last[m]];
        let theta_n = s_n[0]
            .atan2(s_n[1] * a / hh)
            .clamp(0.0, std::f64::consts::FRAC_PI_2);
        let rho_n = (a_n[1] - hh).abs();
        let first = (spec.growth - 1.0) * rho_n;
        let side = a_n[1].max(a * (std::f64::consts::FRAC_PI_2 - theta_n));
        let mut p = 2;
        while graded_first(p, spec.growth, side) > first && p < 1000 {
            p += 1;
        }
        let v = graded(p, spec.growth.powi(p as i32 - 1));
        // Fraction of each ring node along the ring (its angle over the
        // surface angle), reused for the base.
        let phi_n = s_n[0].atan2(hh - s_n[1]);
        let u: Vec<f64> = last
            .iter()
            .map(|&id| {
                let x = nodes[id];
                (x[0].atan2(hh - x[1]) / phi_n).clamp(0.0, 1.0)
            })
            .collect();
        let axis_at = |t: f64| [0.0, a_n[1] * (1.0 - t)];
        let surf_at = |t: f64| ellipse(theta_n + (std::f64::consts::FRAC_PI_2 - theta_n) * t);
        let base_at = |s: f64| [a * s, 0.0];
        let mut grid = vec![last.clone()];
        for &t in v.iter().skip(1) {
            let row: Vec<usize> = (0..=m)
                .map(|i| {
                    let id = if i == 0 {
                        axis_at(t)
                    } else if i == m {
                        surf_at(t)
                    } else {
                        let s = u[i];
                        let arc = nodes[last[i]];
                        let base = base_at(s);
                        let (ax, sf) = (axis_at(t), surf_at(t));
                        let corners = [a_n, s_n, [0.0, 0.0], [a, 0.0]];
                        let mut x = [0.0; 2];
                        for c in 0..2 {
                            x[c] = (1.0 - t) * arc[c] + t * base[c] + (1.0 - s) * ax[c] + s * sf[c]
                                - ((1.0 - s) * (1.0 - t) * corners[0][c]
                                    + s * (1.0 - t) * corners[1][c]
                                    + (1.0 - s) * t * corners[2][c]
                                    + s * t * corners[3][c]);
                        }
                        x
                    };
                    nodes.push([id[0].max(0.0), id[1].max(0.0)]);
                    nodes.len() - 1
                })
                .collect();
            grid.push(row);
        }
        for l in 0..p {
            for i in 0..m {
                let q = [
                    grid[l][i],
                    grid[l][i + 1],
                    grid[l + 1][i + 1],
                    grid[l + 1][i],
                ];
                elements.push(quad(&nodes, q));
            }
        }
        axis.extend((1..=p).map(|l| grid[l][0]));
        surface.extend((1..=p).map(|l| grid[l][m]));
        let base: Vec<usize> = grid[p].clone();
        // Exact zeros on the axis and the base.
        for &id in &axis {
            nodes[id][0] = 0.0;
        }
        for &id in &base {
            nodes[id][1] = 0.0;
        }
        let mut mesh = Self::new(nodes, elements)?;
        mesh.set_nodes("axis", axis);
        mesh.set_nodes("base", base);
        mesh.set_nodes("surface", surface);
        Ok(mesh)
    }

    /// A half space z ≤ 0… represented by the quarter disc of radius
    /// `radius` around the pole (0, `radius`), meshed with rings graded to
    /// the pole (module docs) out to `radius`: the Hertz check geometry.
    ///
    /// Sets: `axis`, `surface` (the flat top from the pole outward), `outer`
    /// (the last ring, to be fixed: the far field).
    ///
    /// # Errors
    /// [`FemError::Setting`] for a bad spec or a core wider than
    /// `radius` / 10.
    pub fn contact_graded_half_space(radius: f64, spec: &ContactMesh) -> Result<Self> {
        spec.check()?;
        if !(radius > 0.0 && radius.is_finite()) {
            return Err(FemError::Setting {
                name: "half-space radius",
                value: radius,
                reason: "must be positive and finite",
            });
        }
        if spec.spacing * (spec.core.max(spec.core_depth)) as f64 * 16.0 >= radius {
            return Err(FemError::Setting {
                name: "mesh spacing",
                value: spec.spacing,
                reason: "the core (spacing × core elements) must be below radius / 16",
            });
        }
        let top = move |_r: f64| radius;
        let surface_at = move |rho: f64| [rho, radius];
        // The last ring exactly at `radius`.
        let (mut nodes, elements, axis, surface, last) =
            core_and_rings(spec, radius * (1.0 + 1e-12), &top, &surface_at);
        let rho_last = radius - nodes[last[0]][1];
        let scale = radius / rho_last;
        for &id in &last {
            let x = nodes[id];
            nodes[id] = [x[0] * scale, radius - (radius - x[1]) * scale];
        }
        for &id in &axis {
            nodes[id][0] = 0.0;
        }
        let mut mesh = Self::new(nodes, elements)?;
        mesh.set_nodes("axis", axis);
        mesh.set_nodes("surface", surface);
        mesh.set_nodes("outer", last);
        Ok(mesh)
    }
}

/// First interval of `graded(n, q^{n−1})` scaled to `length`.
fn graded_first(n: usize, q: f64, length: f64) -> f64 {
    let x = graded(n, q.powi(n as i32 - 1));
    (x[1] - x[0]) * length
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn graded_cell_covers_the_quarter_ellipse() {
        let (h, d) = (12.22e-6, 28.88e-6);
        let spec = ContactMesh {
            spacing: 0.025e-6,
            core: 4,
            core_depth: 4,
            growth: 1.1,
        };
        let mesh = Mesh::contact_graded_cell(h, d, &spec).unwrap();
        eprintln!(
            "{} elements, {} nodes",
            mesh.elements.len(),
            mesh.nodes.len()
        );
        let exact = std::f64::consts::PI * 0.5 * d * h / 4.0;
        let rel = (crate::mesh::section_area(&mesh) - exact).abs() / exact;
        assert!(rel < 5e-3, "area error {rel}");
        // Surface nodes lie on the ellipse, ordered from the pole outward.
        let surface = mesh.nodes_in("surface").unwrap();
        let mut last_r = -1.0;
        for &id in surface {
            let [r, z] = mesh.nodes[id];
            let e = (2.0 * r / d).powi(2) + (z / h).powi(2) - 1.0;
            assert!(e.abs() < 1e-9, "node {id} off the ellipse by {e}");
            assert!(r > last_r);
            last_r = r;
        }
    }
}
