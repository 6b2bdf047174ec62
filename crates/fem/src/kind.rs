//! The element kinds a [`crate::Model`] can be built from: the mesh type,
//! the number of displacement components per node and the element kernel.
//!
//! - [`Axisymmetric`]: [`crate::Mesh`] of 4-node quadrilaterals in the
//!   (r, z) half-plane, dofs (u_r, u_z), the F-bar Q4 of [`crate::element`].
//! - [`Solid`]: [`crate::Mesh3`] of 8-node hexahedra, dofs (u_x, u_y, u_z),
//!   the F-bar hexahedron of [`crate::hex`].
//!
//! Everything else in the model (supports, rigid planes, the fluid cavity,
//! the sparse solver, Newton and the time stepping) is shared.

use crate::element::{ElementOutput, PointGeometry};
use crate::fbar::{fbar_energy, fbar_kernel};
use crate::hex::{HexOutput, HexPoint};
use crate::local::{Local, PointFailure, TangentPart};
use crate::sets::NamedSets;
use crate::{FemError, Mesh, Mesh3, Result};
use nlvid_material::{F64x4, Mat3, Material3};

/// Axisymmetric solids (module docs).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Axisymmetric;

/// 3D solids (module docs).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Solid;

/// The boundary of a fluid cavity, as the mesh describes it.
#[doc(hidden)]
#[derive(Debug, Clone)]
pub enum CavityCells {
    /// Straight segments (a, b) of an (r, z) polyline (axisymmetric).
    Segments(Vec<[usize; 2]>),
    /// Bilinear quadrilaterals (3D).
    Quads(Vec<[usize; 4]>),
}

/// What a mesh offers the model (implemented by [`Mesh`], [`Mesh3`] and
/// [`crate::MembraneMesh`]): its nodes, cells and named node sets
/// ([`Topology::parts`]), from which the provided methods read counts,
/// positions, connectivity and sets.
///
/// Surfaces (contact, cavity) are by default ordered node sets of an
/// axisymmetric mesh read as polylines in the (r, z) half-plane (the
/// quadrilateral and membrane meshes); [`Mesh3`] reads face sets instead.
pub trait Topology: Send + Sync {
    /// Reference coordinates of one node (`[f64; 2]` or `[f64; 3]`, m).
    type Point: AsRef<[f64]>;
    /// Nodes of one element.
    type Cell: AsRef<[usize]>;
    /// The VTK cell type of the elements (9 quadrilateral, 12 hexahedron,
    /// 3 line), for [`crate::vtu`].
    const VTK_CELL: u8;

    /// Every node's reference coordinates, every element's nodes and the
    /// named node sets.
    #[doc(hidden)]
    fn parts(&self) -> (&[Self::Point], &[Self::Cell], &NamedSets<usize>);

    /// Number of nodes.
    fn node_count(&self) -> usize {
        self.parts().0.len()
    }
    /// Reference coordinates of node `a` (2 or 3 components).
    fn position(&self, a: usize) -> &[f64] {
        self.parts().0[a].as_ref()
    }
    /// Number of elements.
    fn element_count(&self) -> usize {
        self.parts().1.len()
    }
    /// Nodes of element `e`.
    fn connectivity(&self, e: usize) -> &[usize] {
        self.parts().1[e].as_ref()
    }
    /// The node set `name`.
    ///
    /// # Errors
    /// [`FemError::Mesh`] if there is no such set.
    fn node_set(&self, name: &str) -> Result<&[usize]> {
        self.parts().2.get(name)
    }
    /// The VTK cell type of the elements ([`Topology::VTK_CELL`]).
    fn vtk_cell_type(&self) -> u8 {
        Self::VTK_CELL
    }
    /// Nodes of the contact surface `name`, their tributary areas (m², the
    /// full revolved area for axisymmetric meshes) and spacings (m). By
    /// default the ordered node set `name` read as an (r, z) polyline
    /// ([`tributary`]).
    ///
    /// # Errors
    /// [`FemError::Mesh`] if there is no such surface.
    fn contact_weights(&self, name: &str) -> Result<(Vec<usize>, Vec<f64>, Vec<f64>)> {
        let nodes = self.node_set(name)?;
        let (area, len) = tributary(
            |a| {
                let x = self.position(a);
                [x[0], x[1]]
            },
            nodes,
        );
        Ok((nodes.to_vec(), area, len))
    }
    /// The cells bounding the cavity `name`. By default the ordered node
    /// set `name` read as an (r, z) polyline (consecutive nodes joined).
    ///
    /// # Errors
    /// [`FemError::Mesh`] if there is no such boundary.
    #[doc(hidden)]
    fn cavity_cells(&self, name: &str) -> Result<CavityCells> {
        let nodes = self.node_set(name)?;
        if nodes.len() < 2 {
            return Err(FemError::Mesh(format!(
                "cavity boundary `{name}` needs at least two nodes"
            )));
        }
        Ok(CavityCells::Segments(
            nodes.windows(2).map(|w| [w[0], w[1]]).collect(),
        ))
    }
}

impl Topology for Mesh {
    type Point = [f64; 2];
    type Cell = [usize; 4];
    const VTK_CELL: u8 = 9;
    fn parts(&self) -> (&[[f64; 2]], &[[usize; 4]], &NamedSets<usize>) {
        (&self.nodes, &self.elements, &self.sets)
    }
}

impl Topology for Mesh3 {
    type Point = [f64; 3];
    type Cell = [usize; 8];
    const VTK_CELL: u8 = 12;
    fn parts(&self) -> (&[[f64; 3]], &[[usize; 8]], &NamedSets<usize>) {
        (&self.nodes, &self.elements, &self.node_sets)
    }
    /// The face set `name` ([`Mesh3::tributary`]).
    fn contact_weights(&self, name: &str) -> Result<(Vec<usize>, Vec<f64>, Vec<f64>)> {
        self.tributary(name)
    }
    /// The face set `name`.
    fn cavity_cells(&self, name: &str) -> Result<CavityCells> {
        let faces = self.faces_in(name)?;
        if faces.is_empty() {
            return Err(FemError::Mesh(format!("cavity boundary `{name}` is empty")));
        }
        Ok(CavityCells::Quads(faces.to_vec()))
    }
}

/// Consistent tributary areas 2π∫N_a r ds and spacings of an ordered
/// surface node set of an axisymmetric mesh with node positions `x`
/// (reference or current) `x(a)`.
pub(crate) fn tributary(x: impl Fn(usize) -> [f64; 2], nodes: &[usize]) -> (Vec<f64>, Vec<f64>) {
    let mut area = vec![0.0; nodes.len()];
    let mut len = vec![0.0; nodes.len()];
    for k in 0..nodes.len().saturating_sub(1) {
        let a = x(nodes[k]);
        let b = x(nodes[k + 1]);
        let l = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
        let tp = 2.0 * std::f64::consts::PI * l;
        area[k] += tp * (a[0] / 3.0 + b[0] / 6.0);
        area[k + 1] += tp * (a[0] / 6.0 + b[0] / 3.0);
        len[k] += 0.5 * l;
        len[k + 1] += 0.5 * l;
    }
    // End nodes have one segment: use its full length as the spacing.
    if let Some(f) = len.first_mut() {
        *f *= 2.0;
    }
    if let Some(l) = len.last_mut() {
        *l *= 2.0;
    }
    (area, len)
}

/// An element kind (module docs) for the material `M`. Implemented by
/// [`Axisymmetric`] and [`Solid`] (any [`Material3`]) and
/// [`crate::Membrane`] (materials that also have a plane-stress membrane
/// update, [`nlvid_material::MembraneMaterial`]).
pub trait ElementKind<M: Material3>: Send + Sync + 'static {
    /// Displacement components per node.
    const DIM: usize;
    /// Nodes per element.
    const NODES: usize;
    /// Quadrature points per element.
    const POINTS: usize;
    /// Mesh type.
    type Mesh: Topology;
    /// Precomputed reference geometry of one element.
    #[doc(hidden)]
    type Geometry: Send + Sync;
    /// Residual and tangent storage of one element.
    #[doc(hidden)]
    type Output: Local;
    /// Reference geometry of four elements in SIMD lanes
    /// ([`ElementKind::evaluate_lanes`]; `()` for kinds without).
    #[doc(hidden)]
    type LaneGeometry: Send + Sync;
    /// The output of four elements in lanes and the kernel's intermediates
    /// (buffers the model keeps, so they are not cleared at every group).
    #[doc(hidden)]
    type LaneOutput: Send + Default;

    /// An empty output.
    #[doc(hidden)]
    fn output() -> Self::Output {
        Self::Output::default()
    }

    /// Reference geometry of every element.
    ///
    /// # Errors
    /// [`FemError::Mesh`] for a degenerate element.
    #[doc(hidden)]
    fn geometry(mesh: &Self::Mesh) -> Result<Vec<Self::Geometry>>;

    /// Residual (and tangent unless `part` is [`TangentPart::None`]) of one
    /// element for its dof values `u` (node-major).
    #[doc(hidden)]
    #[allow(clippy::too_many_arguments)]
    fn evaluate(
        material: &M,
        geometry: &Self::Geometry,
        u: &[f64],
        state_n: &[M::State],
        trial: &mut [M::State],
        dt: f64,
        fbar: bool,
        part: TangentPart,
        out: &mut Self::Output,
    ) -> std::result::Result<(), PointFailure>;

    /// Whether [`ElementKind::evaluate_lanes`] can evaluate elements (for
    /// this material).
    #[doc(hidden)]
    const LANES: bool = false;

    /// The reference geometry of four elements in lanes (built once per
    /// model if [`ElementKind::LANES`]).
    #[doc(hidden)]
    fn lane_geometry(geometry: [&Self::Geometry; 4]) -> Self::LaneGeometry;

    /// [`ElementKind::evaluate`] of four elements at once, one per SIMD
    /// lane, each output bitwise the one-element result; `false` if not
    /// implemented or any element fails (the caller then evaluates them one
    /// by one, which rewrites their trial histories and reports the error).
    /// Element `l` has the nodes `nodes[l]`; its dofs are read from the
    /// global dof vector `u` directly into the lanes (no per-element copy).
    #[doc(hidden)]
    #[allow(clippy::too_many_arguments)]
    fn evaluate_lanes(
        _material: &M,
        _geometry: &Self::LaneGeometry,
        _u: &[f64],
        _nodes: [&[usize]; 4],
        _state_n: [&[M::State]; 4],
        _trial: [&mut [M::State]; 4],
        _dt: f64,
        _fbar: bool,
        _part: TangentPart,
        _lanes: &mut Self::LaneOutput,
        _out: [&mut Self::Output; 4],
    ) -> bool {
        false
    }

    /// The element residual.
    #[doc(hidden)]
    fn residual(out: &Self::Output) -> &[f64] {
        out.residual()
    }

    /// Row `a` of the element tangent.
    #[doc(hidden)]
    fn tangent_row(out: &Self::Output, a: usize) -> &[f64] {
        out.tangent_row(a)
    }

    /// `Σ_q w_q ψ(F̄_q)` of one element for a strain-energy density `psi`.
    #[doc(hidden)]
    fn energy(geometry: &Self::Geometry, u: &[f64], fbar: bool, psi: &dyn Fn(&Mat3) -> f64) -> f64;
}

impl<M: Material3> ElementKind<M> for Axisymmetric {
    const DIM: usize = 2;
    const NODES: usize = 4;
    const POINTS: usize = 4;
    type Mesh = Mesh;
    type Geometry = [PointGeometry; 4];
    type Output = ElementOutput;
    type LaneGeometry = [PointGeometry<F64x4>; 4];
    type LaneOutput = crate::element::LaneBuffers;

    fn geometry(mesh: &Mesh) -> Result<Vec<[PointGeometry; 4]>> {
        Ok(mesh
            .elements
            .iter()
            .map(|conn| crate::element::element_geometry(&conn.map(|a| mesh.nodes[a])))
            .collect())
    }

    fn evaluate(
        material: &M,
        geometry: &[PointGeometry; 4],
        u: &[f64],
        state_n: &[M::State],
        trial: &mut [M::State],
        dt: f64,
        fbar: bool,
        part: TangentPart,
        out: &mut ElementOutput,
    ) -> std::result::Result<(), PointFailure> {
        fbar_kernel(material, geometry, u, state_n, trial, dt, fbar, part, out)
    }

    const LANES: bool = M::AXISYMMETRIC_LANES;

    fn lane_geometry(g: [&[PointGeometry; 4]; 4]) -> [PointGeometry<F64x4>; 4] {
        [0, 1, 2, 3].map(|q| PointGeometry::lanes(g.map(|e| &e[q])))
    }

    fn evaluate_lanes(
        material: &M,
        geometry: &[PointGeometry<F64x4>; 4],
        u: &[f64],
        nodes: [&[usize]; 4],
        state_n: [&[M::State]; 4],
        trial: [&mut [M::State]; 4],
        dt: f64,
        fbar: bool,
        part: TangentPart,
        lanes: &mut crate::element::LaneBuffers,
        out: [&mut ElementOutput; 4],
    ) -> bool {
        crate::element::fbar_kernel_lanes(
            material, geometry, u, nodes, state_n, trial, dt, fbar, part, lanes, out,
        )
    }

    fn energy(
        geometry: &[PointGeometry; 4],
        u: &[f64],
        fbar: bool,
        psi: &dyn Fn(&Mat3) -> f64,
    ) -> f64 {
        fbar_energy(geometry, u, fbar, psi)
    }
}

impl<M: Material3> ElementKind<M> for Solid {
    const DIM: usize = 3;
    const NODES: usize = 8;
    const POINTS: usize = 8;
    type Mesh = Mesh3;
    type Geometry = [HexPoint; 8];
    type Output = HexOutput;
    type LaneGeometry = ();
    type LaneOutput = ();

    fn lane_geometry(_: [&[HexPoint; 8]; 4]) {}

    fn geometry(mesh: &Mesh3) -> Result<Vec<[HexPoint; 8]>> {
        mesh.elements
            .iter()
            .enumerate()
            .map(|(e, conn)| {
                crate::hex::element_geometry(&conn.map(|a| mesh.nodes[a])).map_err(|(q, det)| {
                    FemError::Mesh(format!(
                        "element {e} is inverted or degenerate at Gauss point {q} (det J = {det:.3e})"
                    ))
                })
            })
            .collect()
    }

    fn evaluate(
        material: &M,
        geometry: &[HexPoint; 8],
        u: &[f64],
        state_n: &[M::State],
        trial: &mut [M::State],
        dt: f64,
        fbar: bool,
        part: TangentPart,
        out: &mut HexOutput,
    ) -> std::result::Result<(), PointFailure> {
        fbar_kernel(material, geometry, u, state_n, trial, dt, fbar, part, out)
    }

    fn energy(geometry: &[HexPoint; 8], u: &[f64], fbar: bool, psi: &dyn Fn(&Mat3) -> f64) -> f64 {
        fbar_energy(geometry, u, fbar, psi)
    }
}
