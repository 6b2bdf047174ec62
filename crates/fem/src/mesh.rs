//! Axisymmetric meshes of 4-node quadrilaterals in the (r, z) half-plane and
//! their generators: a graded block (half-space tests) and the oblate cell of
//! thesis §5.3 (Fig. 5.11).

use crate::sets::NamedSets;
use crate::{FemError, Result};

/// A mesh of 4-node quadrilaterals in the (r, z) half-plane, r ≥ 0.
///
/// Nodes are numbered counter-clockwise in every element. Named node sets
/// carry the boundaries; a *surface* is an ordered node set (a polyline).
#[derive(Debug, Clone)]
pub struct Mesh {
    /// Node coordinates (r, z) in metres.
    pub nodes: Vec<[f64; 2]>,
    /// Element connectivity, counter-clockwise.
    pub elements: Vec<[usize; 4]>,
    pub(crate) sets: NamedSets<usize>,
}

/// Geometric grading of `n` intervals on [0, 1]: the last interval is
/// `bias` times the first (`bias` < 1 refines toward 1).
pub fn graded(n: usize, bias: f64) -> Vec<f64> {
    if n == 0 {
        return vec![0.0];
    }
    let q = if n > 1 {
        bias.powf(1.0 / (n as f64 - 1.0))
    } else {
        1.0
    };
    let mut x = Vec::with_capacity(n + 1);
    x.push(0.0);
    let mut h = 1.0;
    let mut s = 0.0;
    for _ in 0..n {
        s += h;
        x.push(s);
        h *= q;
    }
    for v in &mut x {
        *v /= s;
    }
    x
}

impl Mesh {
    /// A mesh from raw parts; checks connectivity and orientation.
    ///
    /// # Errors
    /// [`FemError::Mesh`] if a node index is out of range, a node has r < 0,
    /// or an element is inverted at one of its Gauss points.
    pub fn new(nodes: Vec<[f64; 2]>, elements: Vec<[usize; 4]>) -> Result<Self> {
        let mesh = Self {
            nodes,
            elements,
            sets: NamedSets::new("node"),
        };
        mesh.check()?;
        Ok(mesh)
    }

    fn check(&self) -> Result<()> {
        for (i, p) in self.nodes.iter().enumerate() {
            if !(p[0] >= -1e-12 * (1.0 + p[1].abs())) || !p[1].is_finite() {
                return Err(FemError::Mesh(format!("node {i} at r = {} < 0", p[0])));
            }
        }
        for (e, conn) in self.elements.iter().enumerate() {
            if conn.iter().any(|&a| a >= self.nodes.len()) {
                return Err(FemError::Mesh(format!(
                    "element {e} refers to a missing node"
                )));
            }
            let x = conn.map(|a| self.nodes[a]);
            for &(xi, eta) in &crate::element::GAUSS {
                let (_, _, det) = crate::element::shape_gradients(&x, xi, eta);
                if !(det > 0.0) {
                    return Err(FemError::Mesh(format!(
                        "element {e} is inverted or degenerate (det J = {det:.3e})"
                    )));
                }
            }
        }
        Ok(())
    }

    /// Adds (or replaces) a named node set.
    pub fn set_nodes(&mut self, name: &str, nodes: Vec<usize>) {
        self.sets.insert(name, nodes);
    }

    /// The node set called `name`.
    ///
    /// # Errors
    /// [`FemError::Mesh`] if there is no such set.
    pub fn nodes_in(&self, name: &str) -> Result<&[usize]> {
        self.sets.get(name)
    }

    /// A block [0, width] × [0, height] with `nr` × `nz` elements, graded
    /// toward the top of the axis (r = 0, z = height): the element at the
    /// top of the axis is `bias` times smaller than the far ones.
    ///
    /// Sets: `axis` (r = 0), `base` (z = 0), `outer` (r = width), `top`
    /// (z = height, ordered from the axis outward).
    ///
    /// # Errors
    /// [`FemError::Setting`] for non-positive sizes or counts.
    pub fn graded_block(width: f64, height: f64, nr: usize, nz: usize, bias: f64) -> Result<Self> {
        positive("width", width)?;
        positive("height", height)?;
        positive("bias", bias)?;
        if nr == 0 || nz == 0 {
            return Err(FemError::Setting {
                name: "elements per side",
                value: 0.0,
                reason: "must be at least 1",
            });
        }
        let rs: Vec<f64> = graded(nr, bias).iter().map(|s| s * width).collect();
        let zs: Vec<f64> = graded(nz, bias)
            .iter()
            .rev()
            .map(|s| (1.0 - s) * height)
            .collect();
        let id = |i: usize, j: usize| j * (nr + 1) + i;
        let mut nodes = Vec::with_capacity((nr + 1) * (nz + 1));
        for &z in &zs {
            for &r in &rs {
                nodes.push([r, z]);
            }
        }
        let mut elements = Vec::with_capacity(nr * nz);
        for j in 0..nz {
            for i in 0..nr {
                elements.push([id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        let mut mesh = Self::new(nodes, elements)?;
        mesh.set_nodes("axis", (0..=nz).map(|j| id(0, j)).collect());
        mesh.set_nodes("base", (0..=nr).map(|i| id(i, 0)).collect());
        mesh.set_nodes("outer", (0..=nz).map(|j| id(nr, j)).collect());
        mesh.set_nodes("top", (0..=nr).map(|i| id(i, nz)).collect());
        Ok(mesh)
    }

    /// The oblate cell of thesis §5.3: a half-ellipse of height `height` and
    /// base diameter `diameter` (profile z = H √(1 − (2r/D)²)), meshed as one
    /// transfinite (Coons) patch with `n` × `n` elements whose corners are
    /// the base centre, the base rim, the point of the profile at parametric
    /// angle 45° and the top pole. Elements are graded toward the pole (the
    /// probe contact) by `bias` (ratio of coarsest to finest spacing).
    ///
    /// `n` = 35, 65, 129 give 1225, 4225, 16641 elements, the three meshes of
    /// Fig. 5.11 (1192, 4213, 16582).
    ///
    /// Sets: `axis`, `base`, `surface` (the free top surface from the pole
    /// to the base rim, ordered from the pole outward).
    ///
    /// # Errors
    /// [`FemError::Setting`] for non-positive sizes, `n` < 2 or `bias` < 1.
    pub fn oblate_cell(height: f64, diameter: f64, n: usize, bias: f64) -> Result<Self> {
        positive("cell height", height)?;
        positive("cell diameter", diameter)?;
        if n < 2 {
            return Err(FemError::Setting {
                name: "elements per side",
                value: n as f64,
                reason: "must be at least 2",
            });
        }
        if !(bias >= 1.0) {
            return Err(FemError::Setting {
                name: "mesh bias",
                value: bias,
                reason: "must be ≥ 1 (coarsest/finest spacing)",
            });
        }
        let a = 0.5 * diameter;
        let h = height;
        let ellipse = |theta: f64| [a * theta.sin(), h * theta.cos()];
        let theta_p = std::f64::consts::FRAC_PI_4;
        // u: 0 at the axis, fine there; v: 0 at the base, fine at the top.
        let us = graded(n, bias);
        let vs: Vec<f64> = graded(n, bias).iter().rev().map(|s| 1.0 - s).collect();
        let o = [0.0, 0.0];
        let rim = [a, 0.0];
        let pole = [0.0, h];
        let p = ellipse(theta_p);
        let id = |i: usize, j: usize| j * (n + 1) + i;
        let mut nodes = vec![[0.0; 2]; (n + 1) * (n + 1)];
        for (j, &v) in vs.iter().enumerate() {
            for (i, &u) in us.iter().enumerate() {
                let bottom = [a * u, 0.0];
                let top = ellipse(theta_p * u);
                let left = [0.0, h * v];
                let right = ellipse(
                    std::f64::consts::FRAC_PI_2 - (std::f64::consts::FRAC_PI_2 - theta_p) * v,
                );
                let mut x = [0.0; 2];
                for k in 0..2 {
                    x[k] = (1.0 - v) * bottom[k] + v * top[k] + (1.0 - u) * left[k] + u * right[k]
                        - ((1.0 - u) * (1.0 - v) * o[k]
                            + u * (1.0 - v) * rim[k]
                            + (1.0 - u) * v * pole[k]
                            + u * v * p[k]);
                }
                x[0] = x[0].max(0.0);
                nodes[id(i, j)] = x;
            }
        }
        let mut elements = Vec::with_capacity(n * n);
        for j in 0..n {
            for i in 0..n {
                elements.push([id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        let mut mesh = Self::new(nodes, elements)?;
        mesh.set_nodes("axis", (0..=n).map(|j| id(0, j)).collect());
        mesh.set_nodes("base", (0..=n).map(|i| id(i, 0)).collect());
        let mut surface: Vec<usize> = (0..=n).map(|i| id(i, n)).collect();
        surface.extend((0..n).rev().map(|j| id(n, j)));
        mesh.set_nodes("surface", surface);
        Ok(mesh)
    }
}

impl Mesh {
    /// A quarter of a spherical shell in the (r, z) half-plane, r, z ≥ 0
    /// (the axisymmetric counterpart of [`crate::shell`]'s sphere): outer
    /// radius `radius`, uniform `wall`, `layers` elements through the wall
    /// and `n_arc` along the meridian from the pole (θ = 0) to the equator
    /// (θ = π/2), equally spaced in θ — the spacing of the 3D cube-sphere
    /// mesh's meridians in the coordinate planes when `n_arc` = 2m.
    ///
    /// Sets: `axis` (r = 0), `equator` (z = 0), and the ordered surfaces
    /// `outer` and `inner` (from the pole to the equator).
    ///
    /// # Errors
    /// [`FemError::Setting`] for non-positive sizes, a wall not thinner than
    /// the radius, or zero counts.
    pub fn spherical_shell(radius: f64, wall: f64, layers: usize, n_arc: usize) -> Result<Self> {
        positive("shell radius", radius)?;
        positive("shell wall", wall)?;
        if !(wall < radius) {
            return Err(FemError::Setting {
                name: "shell wall",
                value: wall,
                reason: "must be thinner than the radius",
            });
        }
        if layers == 0 || n_arc == 0 {
            return Err(FemError::Setting {
                name: "elements per side",
                value: 0.0,
                reason: "must be at least 1",
            });
        }
        let id = |i: usize, j: usize| j * (n_arc + 1) + i;
        let mut nodes = Vec::with_capacity((n_arc + 1) * (layers + 1));
        for j in 0..=layers {
            let rho = radius - wall + wall * j as f64 / layers as f64;
            for i in 0..=n_arc {
                let theta = 0.5 * std::f64::consts::PI * i as f64 / n_arc as f64;
                // Exact zeros on the axis and the equator.
                let (s, c) = match i {
                    0 => (0.0, 1.0),
                    _ if i == n_arc => (1.0, 0.0),
                    _ => theta.sin_cos(),
                };
                nodes.push([rho * s, rho * c]);
            }
        }
        let mut elements = Vec::with_capacity(n_arc * layers);
        for j in 0..layers {
            for i in 0..n_arc {
                elements.push([id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        let mut mesh = Self::new(nodes, elements)?;
        mesh.set_nodes("axis", (0..=layers).map(|j| id(0, j)).collect());
        mesh.set_nodes("equator", (0..=layers).map(|j| id(n_arc, j)).collect());
        mesh.set_nodes("outer", (0..=n_arc).map(|i| id(i, layers)).collect());
        mesh.set_nodes("inner", (0..=n_arc).map(|i| id(i, 0)).collect());
        Ok(mesh)
    }
}

fn positive(name: &'static str, value: f64) -> Result<()> {
    if value > 0.0 && value.is_finite() {
        Ok(())
    } else {
        Err(FemError::Setting {
            name,
            value,
            reason: "must be positive and finite",
        })
    }
}

/// Area of the (r, z) section of `mesh` by 2×2 Gauss quadrature (tests).
#[cfg(test)]
pub(crate) fn section_area(mesh: &Mesh) -> f64 {
    let mut total = 0.0;
    for conn in &mesh.elements {
        let x = conn.map(|a| mesh.nodes[a]);
        for &(xi, eta) in &crate::element::GAUSS {
            total += crate::element::shape_gradients(&x, xi, eta).2;
        }
    }
    total
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn graded_spacing_has_requested_bias() {
        let x = graded(10, 8.0);
        let first = x[1] - x[0];
        let last = x[10] - x[9];
        assert!((last / first - 8.0).abs() < 1e-12);
        assert!((x[10] - 1.0).abs() < 1e-15);
    }

    #[test]
    fn oblate_cell_area_converges_to_quarter_ellipse() {
        // Area of the half-ellipse section: π a H / 4.
        let (h, d) = (12.22e-6, 28.88e-6);
        let exact = std::f64::consts::PI * 0.5 * d * h / 4.0;
        let coarse = (section_area(&Mesh::oblate_cell(h, d, 16, 4.0).unwrap()) - exact).abs();
        let fine = (section_area(&Mesh::oblate_cell(h, d, 32, 4.0).unwrap()) - exact).abs();
        assert!(fine / exact < 2e-3, "relative area error {}", fine / exact);
        assert!(
            fine < coarse / 3.0,
            "polygon error should fall ~4× per halving"
        );
    }

    #[test]
    fn oblate_cell_counts_match_fig_5_11() {
        for (n, count) in [(35, 1225), (65, 4225)] {
            let mesh = Mesh::oblate_cell(12.22e-6, 28.88e-6, n, 6.0).unwrap();
            assert_eq!(mesh.elements.len(), count);
            assert_eq!(mesh.nodes_in("surface").unwrap().len(), 2 * n + 1);
        }
    }

    #[test]
    fn inverted_element_is_rejected() {
        let nodes = vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        assert!(Mesh::new(nodes, vec![[0, 3, 2, 1]]).is_err());
    }
}
