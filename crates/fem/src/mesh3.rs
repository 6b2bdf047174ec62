//! 3D meshes of 8-node hexahedra ([`crate::hex`]) with named node sets and
//! named sets of quadrilateral boundary faces (contact surfaces, fluid
//! cavities), and a structured-block generator.

use crate::sets::NamedSets;
use crate::{FemError, Result};

/// A mesh of 8-node hexahedra (node order of [`crate::hex::CORNERS`]).
///
/// Node sets carry supports; face sets (4-node quadrilaterals) carry contact
/// surfaces and cavity boundaries. A face's orientation is that of
/// `(x₁ − x₀) × (x₃ − x₀)` (its nodes counter-clockwise seen from the side
/// its normal points to).
#[derive(Debug, Clone)]
pub struct Mesh3 {
    /// Node coordinates (x, y, z) in metres.
    pub nodes: Vec<[f64; 3]>,
    /// Element connectivity.
    pub elements: Vec<[usize; 8]>,
    pub(crate) node_sets: NamedSets<usize>,
    face_sets: NamedSets<[usize; 4]>,
}

impl Mesh3 {
    /// A mesh from raw parts; checks connectivity and orientation.
    ///
    /// # Errors
    /// [`FemError::Mesh`] if a node index is out of range, a coordinate is
    /// not finite, or an element is inverted or degenerate at one of its
    /// Gauss points (naming the element).
    pub fn new(nodes: Vec<[f64; 3]>, elements: Vec<[usize; 8]>) -> Result<Self> {
        for (i, p) in nodes.iter().enumerate() {
            if p.iter().any(|x| !x.is_finite()) {
                return Err(FemError::Mesh(format!(
                    "node {i} has a non-finite coordinate"
                )));
            }
        }
        for (e, conn) in elements.iter().enumerate() {
            if conn.iter().any(|&a| a >= nodes.len()) {
                return Err(FemError::Mesh(format!(
                    "element {e} refers to a missing node"
                )));
            }
            let x = conn.map(|a| nodes[a]);
            if let Err((q, det)) = crate::hex::element_geometry(&x) {
                return Err(FemError::Mesh(format!(
                    "element {e} is inverted or degenerate at Gauss point {q} (det J = {det:.3e})"
                )));
            }
        }
        Ok(Self {
            nodes,
            elements,
            node_sets: NamedSets::new("node"),
            face_sets: NamedSets::new("face"),
        })
    }

    /// Adds (or replaces) a named node set.
    pub fn set_nodes(&mut self, name: &str, nodes: Vec<usize>) {
        self.node_sets.insert(name, nodes);
    }

    /// The node set called `name`.
    ///
    /// # Errors
    /// [`FemError::Mesh`] if there is no such set.
    pub fn nodes_in(&self, name: &str) -> Result<&[usize]> {
        self.node_sets.get(name)
    }

    /// Adds (or replaces) a named face set; also defines the node set of
    /// the same name (its nodes, sorted) unless one exists.
    ///
    /// # Errors
    /// [`FemError::Mesh`] if a face refers to a missing node.
    pub fn set_faces(&mut self, name: &str, faces: Vec<[usize; 4]>) -> Result<()> {
        if let Some(f) = faces
            .iter()
            .find(|f| f.iter().any(|&a| a >= self.nodes.len()))
        {
            return Err(FemError::Mesh(format!(
                "face set `{name}`: face {f:?} refers to a missing node"
            )));
        }
        if !self.node_sets.contains(name) {
            let mut nodes: Vec<usize> = faces.iter().flatten().copied().collect();
            nodes.sort_unstable();
            nodes.dedup();
            self.set_nodes(name, nodes);
        }
        self.face_sets.insert(name, faces);
        Ok(())
    }

    /// The face set called `name`.
    ///
    /// # Errors
    /// [`FemError::Mesh`] if there is no such set.
    pub fn faces_in(&self, name: &str) -> Result<&[[usize; 4]]> {
        self.face_sets.get(name)
    }

    /// Contact weights of a face set: its nodes (sorted), each node's
    /// consistent tributary area `∫ N_a dA` (exact for bilinear faces, 2×2
    /// Gauss) and its local spacing h_a (mean √area of the faces around it).
    ///
    /// # Errors
    /// [`FemError::Mesh`] for a missing or empty face set.
    pub fn tributary(&self, name: &str) -> Result<(Vec<usize>, Vec<f64>, Vec<f64>)> {
        let faces = self.faces_in(name)?;
        if faces.is_empty() {
            return Err(FemError::Mesh(format!("face set `{name}` is empty")));
        }
        let mut nodes: Vec<usize> = faces.iter().flatten().copied().collect();
        nodes.sort_unstable();
        nodes.dedup();
        let index = |a: usize| nodes.binary_search(&a).unwrap_or(0);
        let mut area = vec![0.0; nodes.len()];
        let mut spacing = vec![0.0; nodes.len()];
        let mut count = vec![0usize; nodes.len()];
        for f in faces {
            let x = f.map(|a| self.nodes[a]);
            let g = 0.577_350_269_189_625_8;
            let mut face_area = 0.0;
            for (s, t) in [(-g, -g), (g, -g), (g, g), (-g, g)] {
                let (n, ns, nt) = quad_shape(s, t);
                let mut xs = [0.0; 3];
                let mut xt = [0.0; 3];
                for k in 0..4 {
                    for i in 0..3 {
                        xs[i] += ns[k] * x[k][i];
                        xt[i] += nt[k] * x[k][i];
                    }
                }
                let da = norm(&cross(&xs, &xt));
                face_area += da;
                for k in 0..4 {
                    area[index(f[k])] += n[k] * da;
                }
            }
            for &a in f {
                spacing[index(a)] += face_area.sqrt();
                count[index(a)] += 1;
            }
        }
        for (h, c) in spacing.iter_mut().zip(&count) {
            *h /= *c as f64;
        }
        Ok((nodes, area, spacing))
    }

    /// A structured block of `n[0] × n[1] × n[2]` hexahedra whose node
    /// (i, j, k) sits at `position(i, j, k)` (i < n[0]+1, …), numbered
    /// `i + (n[0]+1)(j + (n[1]+1) k)`. Node and face sets `x0`, `x1`, `y0`,
    /// `y1`, `z0`, `z1` are the six sides of the index box (faces oriented
    /// outward from the block).
    ///
    /// # Errors
    /// [`FemError::Setting`] for a zero count; [`FemError::Mesh`] if the map
    /// inverts an element.
    pub fn structured(
        n: [usize; 3],
        position: impl Fn(usize, usize, usize) -> [f64; 3],
    ) -> Result<Self> {
        if n.contains(&0) {
            return Err(FemError::Setting {
                name: "elements per side",
                value: 0.0,
                reason: "must be at least 1",
            });
        }
        let id = |i: usize, j: usize, k: usize| i + (n[0] + 1) * (j + (n[1] + 1) * k);
        let mut nodes = Vec::with_capacity((n[0] + 1) * (n[1] + 1) * (n[2] + 1));
        for k in 0..=n[2] {
            for j in 0..=n[1] {
                for i in 0..=n[0] {
                    nodes.push(position(i, j, k));
                }
            }
        }
        let mut elements = Vec::with_capacity(n[0] * n[1] * n[2]);
        for k in 0..n[2] {
            for j in 0..n[1] {
                for i in 0..n[0] {
                    elements.push(crate::hex::CORNERS.map(|c| {
                        id(
                            i + usize::from(c[0] > 0.0),
                            j + usize::from(c[1] > 0.0),
                            k + usize::from(c[2] > 0.0),
                        )
                    }));
                }
            }
        }
        let mut mesh = Self::new(nodes, elements)?;
        // Outward faces of the six sides: (a, b) the in-face index ranges.
        let side = |axis: usize, at: usize, outward: bool| -> Vec<[usize; 4]> {
            let (p, q) = ((axis + 1) % 3, (axis + 2) % 3);
            let mut faces = Vec::new();
            for b in 0..n[q] {
                for a in 0..n[p] {
                    let node = |da: usize, db: usize| {
                        let mut ijk = [0; 3];
                        ijk[axis] = at;
                        ijk[p] = a + da;
                        ijk[q] = b + db;
                        id(ijk[0], ijk[1], ijk[2])
                    };
                    // (e_p × e_q) = e_axis: counter-clockwise in (p, q) points +axis.
                    let f = [node(0, 0), node(1, 0), node(1, 1), node(0, 1)];
                    faces.push(if outward { f } else { [f[0], f[3], f[2], f[1]] });
                }
            }
            faces
        };
        for (axis, name) in ["x", "y", "z"].iter().enumerate() {
            mesh.set_faces(&format!("{name}0"), side(axis, 0, false))?;
            mesh.set_faces(&format!("{name}1"), side(axis, n[axis], true))?;
        }
        Ok(mesh)
    }
}

/// Bilinear quadrilateral shape functions and their (s, t) derivatives.
pub(crate) fn quad_shape(s: f64, t: f64) -> ([f64; 4], [f64; 4], [f64; 4]) {
    (
        [
            0.25 * (1.0 - s) * (1.0 - t),
            0.25 * (1.0 + s) * (1.0 - t),
            0.25 * (1.0 + s) * (1.0 + t),
            0.25 * (1.0 - s) * (1.0 + t),
        ],
        [
            -0.25 * (1.0 - t),
            0.25 * (1.0 - t),
            0.25 * (1.0 + t),
            -0.25 * (1.0 + t),
        ],
        [
            -0.25 * (1.0 - s),
            -0.25 * (1.0 + s),
            0.25 * (1.0 + s),
            0.25 * (1.0 - s),
        ],
    )
}

pub(crate) fn cross(a: &[f64; 3], b: &[f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn norm(a: &[f64; 3]) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn block_sides_have_outward_faces_and_exact_areas() {
        let (lx, ly, lz) = (2.0, 1.0, 0.5);
        let mesh = Mesh3::structured([4, 3, 2], |i, j, k| {
            [
                lx * i as f64 / 4.0,
                ly * j as f64 / 3.0,
                lz * k as f64 / 2.0,
            ]
        })
        .unwrap();
        assert_eq!(mesh.elements.len(), 24);
        for (name, axis, sign, area) in [
            ("x0", 0, -1.0, ly * lz),
            ("x1", 0, 1.0, ly * lz),
            ("y1", 1, 1.0, lx * lz),
            ("z0", 2, -1.0, lx * ly),
            ("z1", 2, 1.0, lx * ly),
        ] {
            for f in mesh.faces_in(name).unwrap() {
                let x = f.map(|a| mesh.nodes[a]);
                let d1 = [x[1][0] - x[0][0], x[1][1] - x[0][1], x[1][2] - x[0][2]];
                let d3 = [x[3][0] - x[0][0], x[3][1] - x[0][1], x[3][2] - x[0][2]];
                assert!(cross(&d1, &d3)[axis] * sign > 0.0, "{name}");
            }
            let (_, a, h) = mesh.tributary(name).unwrap();
            assert!((a.iter().sum::<f64>() - area).abs() < 1e-14, "{name}");
            assert!(h.iter().all(|&h| h > 0.0));
        }
    }

    #[test]
    fn inverted_hexahedron_is_rejected() {
        let mut nodes: Vec<[f64; 3]> = crate::hex::CORNERS.to_vec();
        nodes.swap(0, 6);
        let e = Mesh3::new(nodes, vec![[0, 1, 2, 3, 4, 5, 6, 7]]).unwrap_err();
        assert!(e.to_string().contains("element 0"), "{e}");
    }
}
