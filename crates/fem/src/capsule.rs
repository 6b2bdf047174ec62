//! Outputs of a fluid-filled capsule between rigid plates at the converged
//! state (thesis §4.2–4.4), for 3D, axisymmetric-solid and membrane models
//! alike: plate force, fluid pressure and volume of the whole capsule, the
//! contact patch measured two ways (§4.4.3), the loss of contact inside the
//! patch (Fig. 4.16) and the contact-pressure paths along the long and short
//! axes.
//!
//! **Contact area, two ways.**
//! - *Pressure area*: the current tributary area of the surface nodes that
//!   carry positive contact pressure (the nodal reading of "the area where
//!   the contact pressure is positive"; it steps as nodes close).
//! - *Ellipse area* π a b (§4.4.3: "the contact region is approximated as an
//!   ellipse, … using the two contact pressure paths"): a and b are where the
//!   contact ends along the long (x) and short (y) axes. The last closed
//!   node is decided at the penalty's penetration scale, so the edge is
//!   taken from the lift-off profile just outside it: the gap grows as
//!   (s − a)^e (e = 3/2 for a solid wall, Hertz; e = 2 for a membrane,
//!   which leaves the plate tangentially with finite curvature), so g^{1/e}
//!   through the first two open nodes clear of the penetration scale
//!   (gap > 10 × the deepest penetration) is linear with its zero at a.
//!   Axisymmetric models have a = b, the contact radius.
//!
//! **Loss of contact** (Fig. 4.16: the pressure drops to zero inside the
//! patch): a surface node is flagged when it carries no contact pressure, is
//! clear of the plate by more than 10 × the deepest penetration, and lies
//! strictly inside the convex hull of the pressed nodes (with their mirror
//! images in the symmetry planes x = 0 and y = 0, or r → −r).
//!
//! Paths and sides assume the capsule's centre at the origin and the axes of
//! the mesh generators ([`crate::shell`], [`Mesh::spherical_shell`],
//! [`MembraneMesh::spherical`]): the long axis is x, the short y; a plate
//! above touches the nodes with reference z ≥ 0, a plate below those with
//! z ≤ 0.

use crate::kind::{ElementKind, Topology};
use crate::{FemError, MembraneMesh, Mesh, Mesh3, Model, PlaneSide, Result};
use nlvid_material::Material3;

/// How many copies of the modelled part make the whole capsule.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Symmetry {
    /// Copies in the whole capsule's volume.
    pub volume_copies: f64,
    /// Copies of the modelled part of one plate's contact patch (force and
    /// area).
    pub patch_copies: f64,
    /// Share of the plates' approach d that the modelled plate moves: 1/2
    /// when the model is cut by z = 0 (each plate moves by d/2 toward it),
    /// 1 when the top plate moves by d against a fixed bottom plate.
    pub plate_share: f64,
}

impl Symmetry {
    const fn copies(volume_copies: f64, patch_copies: f64, plate_share: f64) -> Self {
        Self {
            volume_copies,
            patch_copies,
            plate_share,
        }
    }
    /// The whole capsule.
    pub const FULL: Self = Self::copies(1.0, 1.0, 1.0);
    /// Cut by x = 0 and y = 0, both plates modelled.
    pub const QUARTER: Self = Self::copies(4.0, 4.0, 1.0);
    /// Cut by x = 0, y = 0 and z = 0 (symmetric load).
    pub const EIGHTH: Self = Self::copies(8.0, 4.0, 0.5);
    /// Axisymmetric upper half (z ≥ 0): areas and forces of axisymmetric
    /// models are already those of the whole revolution.
    pub const AXISYMMETRIC_HALF: Self = Self::copies(2.0, 1.0, 0.5);
}

/// Exponent e of the gap near the contact edge, g ∝ (s − a)^e (module
/// docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LiftOff {
    /// A solid wall: e = 3/2 (Hertz).
    Solid,
    /// A membrane: e = 2.
    Membrane,
}

impl LiftOff {
    fn exponent(self) -> f64 {
        match self {
            LiftOff::Solid => 1.5,
            LiftOff::Membrane => 2.0,
        }
    }
}

/// Which plate and surface to measure, and how to scale to the whole
/// capsule.
#[derive(Debug, Clone, PartialEq)]
pub struct PatchSpec {
    /// Index of the plate in [`crate::Parts::planes`].
    pub plane: usize,
    /// The contact surface of that plate (its name in the mesh).
    pub surface: String,
    /// Copies of the modelled part.
    pub symmetry: Symmetry,
    /// Gap profile near the edge.
    pub lift_off: LiftOff,
}

/// A node of a contact surface: reference and current positions
/// (axisymmetric meshes: (r, 0, z)) and current tributary area (m²; the
/// whole revolution for axisymmetric meshes).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceNode {
    /// Node index.
    pub node: usize,
    /// Reference position.
    pub reference: [f64; 3],
    /// Current position.
    pub current: [f64; 3],
    /// Current tributary area ∫N_a dA.
    pub area: f64,
}

/// Meshes whose contact surfaces can be measured in the current
/// configuration.
pub trait Footprint: Topology {
    /// The model is axisymmetric (one contact path, along r).
    const AXISYMMETRIC: bool;

    /// The nodes of `surface` in the order of the mesh's contact weights,
    /// at nodal displacements `u` (node-major).
    ///
    /// # Errors
    /// [`FemError::Mesh`] for a missing surface.
    fn footprint(&self, surface: &str, u: &[f64]) -> Result<Vec<SurfaceNode>>;
}

/// Footprint of an ordered node set of an axisymmetric mesh.
fn footprint_2d(x: &[[f64; 2]], nodes: &[usize], u: &[f64]) -> Vec<SurfaceNode> {
    let current: Vec<[f64; 2]> = x
        .iter()
        .enumerate()
        .map(|(a, p)| [p[0] + u[2 * a], p[1] + u[2 * a + 1]])
        .collect();
    let (area, _) = crate::kind::tributary(|a| current[a], nodes);
    nodes
        .iter()
        .zip(area)
        .map(|(&a, area)| SurfaceNode {
            node: a,
            reference: [x[a][0], 0.0, x[a][1]],
            current: [current[a][0], 0.0, current[a][1]],
            area,
        })
        .collect()
}

impl Footprint for Mesh {
    const AXISYMMETRIC: bool = true;
    fn footprint(&self, surface: &str, u: &[f64]) -> Result<Vec<SurfaceNode>> {
        Ok(footprint_2d(&self.nodes, self.nodes_in(surface)?, u))
    }
}

impl Footprint for MembraneMesh {
    const AXISYMMETRIC: bool = true;
    fn footprint(&self, surface: &str, u: &[f64]) -> Result<Vec<SurfaceNode>> {
        Ok(footprint_2d(&self.nodes, self.nodes_in(surface)?, u))
    }
}

impl Footprint for Mesh3 {
    const AXISYMMETRIC: bool = false;
    fn footprint(&self, surface: &str, u: &[f64]) -> Result<Vec<SurfaceNode>> {
        let mut moved = self.clone();
        for (a, p) in moved.nodes.iter_mut().enumerate() {
            for i in 0..3 {
                p[i] += u[3 * a + i];
            }
        }
        let (nodes, area, _) = moved.tributary(surface)?;
        Ok(nodes
            .iter()
            .zip(area)
            .map(|(&a, area)| SurfaceNode {
                node: a,
                reference: self.nodes[a],
                current: moved.nodes[a],
                area,
            })
            .collect())
    }
}

/// The contact patch of one plate (module docs). Forces and areas are the
/// whole capsule's (× [`Symmetry::patch_copies`]).
#[derive(Debug, Clone, PartialEq)]
pub struct ContactPatch {
    /// Force between the plate and the capsule (N, ≥ 0).
    pub force: f64,
    /// Area carrying positive contact pressure (m²).
    pub pressure_area: f64,
    /// Semi-axes a (along x, the long axis) and b (along y) of the ellipse
    /// through the contact boundary (m); 0 without contact, NaN where the
    /// edge is not resolved (fewer than two open nodes beyond it).
    pub semi_axes: [f64; 2],
    /// π a b (m²).
    pub ellipse_area: f64,
    /// Nodes of the modelled part flagged as lost contact.
    pub lost_nodes: Vec<usize>,
    /// Their tributary area (m², whole capsule).
    pub lost_area: f64,
    /// Contact-pressure paths from the patch centre along x and y:
    /// (current distance in m, contact pressure in Pa), ordered outward
    /// (axisymmetric: both along r).
    pub paths: [Vec<[f64; 2]>; 2],
}

impl ContactPatch {
    /// Contact is lost somewhere inside the patch (Fig. 4.16).
    pub fn lost_contact(&self) -> bool {
        !self.lost_nodes.is_empty()
    }
}

/// The capsule at one converged time.
#[derive(Debug, Clone, PartialEq)]
pub struct CapsuleRecord {
    /// Time (s).
    pub time: f64,
    /// Height of the moving plate ([`crate::Control::plane_z`], m).
    pub plate_z: f64,
    /// Plate force, whole capsule (N).
    pub force: f64,
    /// Fluid pressure (Pa); NaN without a cavity.
    pub pressure: f64,
    /// Fluid volume, whole capsule (m³); NaN without a cavity.
    pub volume: f64,
    /// The contact patch of the plate.
    pub patch: ContactPatch,
}

/// Where the contact ends along a path of (distance, gap), ordered outward
/// (module docs); 0 without contact, None if not resolved.
fn edge(path: &[(f64, f64)], exponent: f64) -> Option<f64> {
    let penetration = path.iter().map(|p| -p.1).fold(0.0f64, f64::max);
    let Some(last) = path.iter().rposition(|p| p.1 <= 0.0) else {
        return Some(0.0);
    };
    let open: Vec<(f64, f64)> = path[last + 1..]
        .iter()
        .filter(|p| p.1 > 10.0 * penetration)
        .take(2)
        .copied()
        .collect();
    if open.len() < 2 {
        return None;
    }
    let (s1, s2) = (
        open[0].1.powf(1.0 / exponent),
        open[1].1.powf(1.0 / exponent),
    );
    if !(s2 > s1) {
        return None;
    }
    Some(open[0].0 - s1 * (open[1].0 - open[0].0) / (s2 - s1))
}

/// Convex hull (counter-clockwise, Andrew's monotone chain) of points.
fn convex_hull(mut p: Vec<[f64; 2]>) -> Vec<[f64; 2]> {
    p.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    p.dedup();
    if p.len() < 3 {
        return p;
    }
    let cross = |o: [f64; 2], a: [f64; 2], b: [f64; 2]| {
        (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
    };
    let mut hull: Vec<[f64; 2]> = Vec::with_capacity(2 * p.len());
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &[f64; 2]>> = if pass == 0 {
            Box::new(p.iter())
        } else {
            Box::new(p.iter().rev())
        };
        for &q in iter {
            while hull.len() >= start + 2
                && cross(hull[hull.len() - 2], hull[hull.len() - 1], q) <= 0.0
            {
                hull.pop();
            }
            hull.push(q);
        }
        hull.pop();
    }
    hull
}

/// `q` lies inside the counter-clockwise convex polygon `hull` by more than
/// `tol` (distance) from every edge.
fn strictly_inside(hull: &[[f64; 2]], q: [f64; 2], tol: f64) -> bool {
    if hull.len() < 3 {
        return false;
    }
    (0..hull.len()).all(|k| {
        let (a, b) = (hull[k], hull[(k + 1) % hull.len()]);
        let (ex, ey) = (b[0] - a[0], b[1] - a[1]);
        let len = ex.hypot(ey);
        len > 0.0 && (ex * (q[1] - a[1]) - ey * (q[0] - a[0])) / len > tol
    })
}

/// A plate's side, its surface's nodes, their contact forces and gaps.
type PlateSurface = (
    PlaneSide,
    Vec<SurfaceNode>,
    Vec<(usize, f64)>,
    Vec<(usize, f64)>,
);

impl<M: Material3, K: ElementKind<M>> Model<M, K>
where
    K::Mesh: Footprint,
{
    /// The plate of `spec`: side, surface nodes (current), contact forces
    /// and gaps, in one order.
    ///
    /// # Errors
    /// As [`Model::contact_patch`].
    pub(crate) fn plate_surface(&self, spec: &PatchSpec) -> Result<PlateSurface> {
        let side = self.plane_side(spec.plane).ok_or(FemError::Setting {
            name: "plate index",
            value: spec.plane as f64,
            reason: "the model has no rigid plane with this index (order of Parts::planes)",
        })?;
        let forces = self.plane_contact_forces(spec.plane);
        let gaps = self.plane_contact_gaps(spec.plane);
        let surface = self
            .mesh()
            .footprint(&spec.surface, self.nodal_displacements())?;
        if surface.len() != forces.len() || surface.iter().zip(&forces).any(|(s, f)| s.node != f.0)
        {
            return Err(FemError::Mesh(format!(
                "surface `{}` is not the contact surface of plate {}",
                spec.surface, spec.plane
            )));
        }
        Ok((side, surface, forces, gaps))
    }

    /// The contact patch of one plate at the converged state (module docs).
    ///
    /// # Errors
    /// [`FemError::Setting`] for a plate index the model does not have;
    /// [`FemError::Mesh`] for a missing surface or one that is not that
    /// plate's.
    pub fn contact_patch(&self, spec: &PatchSpec) -> Result<ContactPatch> {
        let (side, surface, forces, gaps) = self.plate_surface(spec)?;
        let copies = spec.symmetry.patch_copies;
        let upper = matches!(side, PlaneSide::Above);
        let extent = surface
            .iter()
            .flat_map(|s| s.reference.iter())
            .fold(0.0f64, |m, x| m.max(x.abs()));
        let on_axis = |x: f64| x.abs() <= 1e-12 * extent;
        // The nodes facing this plate.
        let facing: Vec<usize> = (0..surface.len())
            .filter(|&k| {
                let z = surface[k].reference[2];
                if upper {
                    z >= -1e-12 * extent
                } else {
                    z <= 1e-12 * extent
                }
            })
            .collect();
        let penetration = facing.iter().map(|&k| -gaps[k].1).fold(0.0f64, f64::max);
        let mut force = 0.0;
        let mut pressure_area = 0.0;
        let mut closed = Vec::new();
        for &k in &facing {
            if forces[k].1 > 0.0 {
                force += forces[k].1;
                pressure_area += surface[k].area;
                let c = surface[k].current;
                closed.push([c[0], c[1]]);
            }
        }
        // Paths along x (reference y = 0, x ≥ 0) and y (x = 0, y ≥ 0).
        let mut paths: [Vec<[f64; 2]>; 2] = [Vec::new(), Vec::new()];
        let mut semi_axes = [0.0; 2];
        for (axis, path) in paths.iter_mut().enumerate() {
            let along = if K::Mesh::AXISYMMETRIC { 0 } else { axis };
            let mut nodes: Vec<usize> = facing
                .iter()
                .copied()
                .filter(|&k| {
                    let r = surface[k].reference;
                    on_axis(r[1 - along]) && r[along] >= -1e-12 * extent
                })
                .collect();
            nodes.sort_by(|&p, &q| surface[p].current[along].total_cmp(&surface[q].current[along]));
            *path = nodes
                .iter()
                .map(|&k| {
                    let p = if surface[k].area > 0.0 {
                        forces[k].1 / surface[k].area
                    } else {
                        0.0
                    };
                    [surface[k].current[along], p]
                })
                .collect();
            let profile: Vec<(f64, f64)> = nodes
                .iter()
                .map(|&k| (surface[k].current[along], gaps[k].1))
                .collect();
            semi_axes[axis] = edge(&profile, spec.lift_off.exponent()).unwrap_or(f64::NAN);
        }
        // Loss of contact: open nodes clear of the plate inside the hull of
        // the pressed nodes and their mirror images.
        let mut lost_nodes = Vec::new();
        let mut lost_area = 0.0;
        if !closed.is_empty() {
            let tol = 1e-9 * extent;
            let open: Vec<usize> = facing
                .iter()
                .copied()
                .filter(|&k| forces[k].1 == 0.0 && gaps[k].1 > 10.0 * penetration)
                .collect();
            if K::Mesh::AXISYMMETRIC {
                let reach = closed.iter().fold(0.0f64, |m, c| m.max(c[0].abs()));
                for k in open {
                    if surface[k].current[0].abs() < reach - tol {
                        lost_nodes.push(surface[k].node);
                        lost_area += surface[k].area;
                    }
                }
            } else {
                let mut pts = Vec::with_capacity(4 * closed.len());
                for c in &closed {
                    for (sx, sy) in [(1.0, 1.0), (-1.0, 1.0), (1.0, -1.0), (-1.0, -1.0)] {
                        pts.push([sx * c[0], sy * c[1]]);
                    }
                }
                let hull = convex_hull(pts);
                for k in open {
                    let c = surface[k].current;
                    if strictly_inside(&hull, [c[0], c[1]], tol) {
                        lost_nodes.push(surface[k].node);
                        lost_area += surface[k].area;
                    }
                }
            }
        }
        Ok(ContactPatch {
            force: copies * force,
            pressure_area: copies * pressure_area,
            semi_axes,
            ellipse_area: std::f64::consts::PI * semi_axes[0] * semi_axes[1],
            lost_nodes,
            lost_area: copies * lost_area,
            paths,
        })
    }

    /// The capsule's outputs at the converged state (module docs).
    ///
    /// # Errors
    /// As [`Model::contact_patch`].
    pub fn capsule_record(&self, spec: &PatchSpec) -> Result<CapsuleRecord> {
        let patch = self.contact_patch(spec)?;
        let last = self.records().last();
        Ok(CapsuleRecord {
            time: self.time(),
            plate_z: self.last_control().plane_z,
            force: patch.force,
            pressure: last.map_or(f64::NAN, |r| r.cavity_pressure),
            volume: spec.symmetry.volume_copies * last.map_or(f64::NAN, |r| r.cavity_volume),
            patch,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn edge_of_a_hertzian_gap_profile_is_exact() {
        // g = (s − a)^{3/2} beyond a = 0.37, −1e-9 inside.
        let a = 0.37;
        let path: Vec<(f64, f64)> = (0..20)
            .map(|k| {
                let s = 0.05 * k as f64;
                (s, if s < a { -1e-9 } else { (s - a).powf(1.5) })
            })
            .collect();
        let got = edge(&path, 1.5).unwrap();
        assert!((got - a).abs() < 1e-12, "{got}");
        // No contact: 0; edge at the end of the path: unresolved.
        assert_eq!(edge(&[(0.0, 1.0), (1.0, 2.0)], 1.5), Some(0.0));
        assert_eq!(edge(&[(0.0, -1.0), (1.0, -1.0)], 1.5), None);
    }

    #[test]
    fn hull_and_inside_test() {
        let hull = convex_hull(vec![
            [0.0, 0.0],
            [1.0, 0.0],
            [1.0, 1.0],
            [0.0, 1.0],
            [0.5, 0.5],
            [0.5, 0.0],
        ]);
        assert_eq!(hull.len(), 4);
        assert!(strictly_inside(&hull, [0.5, 0.5], 1e-9));
        assert!(!strictly_inside(&hull, [0.5, 0.0], 1e-9));
        assert!(!strictly_inside(&hull, [1.5, 0.5], 1e-9));
    }
}
