//! The finite-element model: mesh + material + supports + rigid bodies +
//! fluid cavity, global assembly, Newton with line search and adaptive time
//! stepping — for axisymmetric ([`Axisymmetric`]) and 3D ([`Solid`])
//! meshes alike (`Model<M>` is the axisymmetric model, `Model<M, Solid>`
//! the 3D one).
//!
//! Unknowns are the nodal displacements ((u_r, u_z) or (u_x, u_y, u_z)),
//! one vertical displacement `w` of the rigid spherical probe
//! (axisymmetric only), and, with a fluid cavity, its pressure p (stored as
//! `s = p L / G`, L = V₀^{1/3}, so that its equation is a force in N). The
//! probe is driven in one of three ways ([`ProbeDrive`]): its displacement
//! prescribed (rigid cantilever), a force applied to it (force-controlled
//! engagement), or a linear spring between it and a prescribed point (the
//! cantilever whose free end follows the piezo). The total potential is
//!
//! ```text
//! Π = Σ_e ∫ Ψ(F̄) dV₀ + Σ_a ½ ε_a ⟨−g_a⟩² + ½ k (w − z_free)² + F w
//!     − p (V(u) − V₀ − ΔV_in) − p² V₀ / (2 K_f) ,
//! ```
//!
//! g_a the gap between surface node a and the sphere (or a plane), V the
//! enclosed cavity volume ([`crate::cavity`]), ΔV_in the fluid injected
//! ([`Control::fluid_injected`]), K_f the fluid's bulk modulus (∞ for an
//! incompressible fluid: then V = V₀ + ΔV_in exactly). The tangent is the
//! exact Hessian and symmetric for hyperelastic materials (indefinite with
//! a cavity: p is a Lagrange multiplier).

use crate::cavity::{quad_area_normals, quad_volume, segment_area_normals, segment_volume};
use crate::contact::{self, ContactSurface, Obstacle};
use crate::history::History;
use crate::kind::{Axisymmetric, CavityCells, ElementKind, Solid, Topology};
use crate::local::TangentPart;
use crate::sparse::{NO_SLOT, SparseSystem};
use crate::{FemError, NonConvergence, Result};
use nlvid_material::{Mat3, Material3};

/// Chord steps in a row before a Newton step gets its own tangent again
/// (`Settings::chord_contraction`).
const MAX_CHORD_STEPS: usize = 2;

/// Displacement component of a support.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Component {
    /// Radial (axisymmetric models).
    R,
    /// Axial (axisymmetric) or vertical (3D).
    Z,
    /// x (3D models).
    X,
    /// y (3D models).
    Y,
}

impl Component {
    /// The component's index among a node's `dim` dofs, if it has one.
    fn index(self, dim: usize) -> Option<usize> {
        match (self, dim) {
            (Component::R, 2) | (Component::X, 3) => Some(0),
            (Component::Y, 3) => Some(1),
            (Component::Z, _) => Some(dim - 1),
            _ => None,
        }
    }

    fn checked_index(self, dim: usize) -> Result<usize> {
        self.index(dim).ok_or(FemError::Setting {
            name: "support component",
            value: dim as f64,
            reason: "R and Z apply to axisymmetric models (2 dofs per node), X, Y and Z to 3D ones",
        })
    }
}

/// A prescribed displacement on every node of a named set; its value at
/// time t is `value × Control::support_scale`.
#[derive(Debug, Clone, PartialEq)]
pub struct Support {
    /// Node set name.
    pub set: String,
    /// Constrained component.
    pub component: Component,
    /// Displacement at support scale 1 (m).
    pub value: f64,
}

impl Support {
    /// A fixed (zero) displacement.
    pub fn fixed(set: &str, component: Component) -> Self {
        Self {
            set: set.to_owned(),
            component,
            value: 0.0,
        }
    }
}

/// A rigid sphere moving along the axis, in frictionless penalty contact
/// with an ordered surface node set.
#[derive(Debug, Clone, PartialEq)]
pub struct SphereProbe {
    /// Sphere radius (m).
    pub radius: f64,
    /// Height of the centre at w = 0 (m).
    pub centre_z: f64,
    /// Ordered surface node set that may touch it.
    pub surface: String,
}

/// A rigid horizontal plane (normal along z), in frictionless penalty
/// contact with a surface that may separate from it again.
#[derive(Debug, Clone, PartialEq)]
pub struct RigidPlane {
    /// The surface that may touch it: an ordered node set (axisymmetric) or
    /// a face set (3D).
    pub surface: String,
    /// Where it is and which way it faces.
    pub side: PlaneSide,
}

/// Position of a [`RigidPlane`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PlaneSide {
    /// Above the body, facing down, at height [`Control::plane_z`] (the
    /// moving plate).
    Above,
    /// Below the body, facing up, fixed at this height (m).
    Below(f64),
}

impl RigidPlane {
    /// The plane above `surface` driven by [`Control::plane_z`].
    pub fn above(surface: &str) -> Self {
        Self {
            surface: surface.to_owned(),
            side: PlaneSide::Above,
        }
    }

    /// A fixed plane at height `z` below `surface`.
    pub fn below(surface: &str, z: f64) -> Self {
        Self {
            surface: surface.to_owned(),
            side: PlaneSide::Below(z),
        }
    }
}

/// The fluid filling a [`Cavity`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Fluid {
    /// Volume conserved exactly (the thesis's oil, §4.3): p is a Lagrange
    /// multiplier.
    Incompressible,
    /// Linear barotropic fluid p = K_f (V₀ + ΔV_in − V)/V₀.
    Compressible {
        /// Bulk modulus K_f (Pa).
        bulk_modulus: f64,
    },
}

/// A closed fluid-filled cavity bounded by a surface of the body (and by
/// symmetry planes through the origin, which need no cells; see
/// [`crate::cavity`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Cavity {
    /// Its boundary: an ordered (r, z) node polyline (axisymmetric) or a
    /// face set (3D) with consistently oriented faces.
    pub boundary: String,
    /// The fluid.
    pub fluid: Fluid,
}

/// Everything a model holds besides its mesh and material.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Parts {
    /// Prescribed displacements (supports, symmetry rollers).
    pub supports: Vec<Support>,
    /// The rigid sphere (axisymmetric models only).
    pub probe: Option<SphereProbe>,
    /// Rigid planes.
    pub planes: Vec<RigidPlane>,
    /// A fluid cavity.
    pub cavity: Option<Cavity>,
}

impl Parts {
    /// The eighth of a fluid-filled capsule compressed by a plate
    /// (§4.3): symmetry rollers on the planes x = 0, y = 0, z = 0 (node
    /// sets `x0`, `y0`, `z0` of [`crate::ellipsoidal_shell`]), a rigid
    /// plate above the outer surface (`outer`) and the fluid in the
    /// cavity bounded by `inner`.
    pub fn eighth_capsule(fluid: Fluid) -> Self {
        Self {
            supports: vec![
                Support::fixed("x0", Component::X),
                Support::fixed("y0", Component::Y),
                Support::fixed("z0", Component::Z),
            ],
            planes: vec![RigidPlane::above("outer")],
            cavity: Some(Cavity {
                boundary: "inner".into(),
                fluid,
            }),
            ..Self::default()
        }
    }
}

/// How the probe's vertical displacement w is driven.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ProbeDrive {
    /// w prescribed (m): the rigid-cantilever option.
    Displacement(f64),
    /// A downward force (N) on the probe: force-controlled engagement.
    Force(f64),
    /// A spring of `stiffness` (N/m) between the probe and a point whose
    /// vertical displacement is `free_end` (m): the cantilever.
    Spring {
        /// Spring constant k (N/m).
        stiffness: f64,
        /// Displacement of the spring's free end (m, z up).
        free_end: f64,
    },
}

/// Loads at one instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Control {
    /// Probe drive.
    pub probe: ProbeDrive,
    /// Plane height (m), if there is a plane.
    pub plane_z: f64,
    /// Scale of the prescribed support displacements.
    pub support_scale: f64,
    /// Volume of fluid injected into the cavity since t = 0 (m³; the
    /// cavity's own volume units: the full revolved volume for
    /// axisymmetric models, the modelled part for cut 3D models).
    pub fluid_injected: f64,
}

impl Default for Control {
    fn default() -> Self {
        Self {
            probe: ProbeDrive::Displacement(0.0),
            plane_z: f64::INFINITY,
            support_scale: 1.0,
            fluid_injected: 0.0,
        }
    }
}

/// Solver settings.
#[derive(Debug, Clone, PartialEq)]
pub struct Settings {
    /// Use the F-bar element (true) or the plain displacement element.
    pub fbar: bool,
    /// Residual tolerance relative to the gross internal force.
    pub rtol: f64,
    /// Absolute residual tolerance (N): a step also counts as converged when
    /// the residual norm is below it. 0 (the default) disables it; set it
    /// to ≈ rtol × the run's peak force when the load passes through zero
    /// (contact separation), where `rtol` × the vanishing current force is
    /// below round-off.
    pub atol: f64,
    /// Newton iterations allowed per attempt.
    pub max_iterations: usize,
    /// Step reductions allowed in the line search (each to between 0.1
    /// and 0.5 of the last trial, by the residual model of
    /// `backtrack_step`).
    pub line_search: usize,
    /// Contact penalty ε = penalty · G / h (G from the material at F = I,
    /// h the local surface spacing): penetration ≈ p h / (penalty G).
    pub penalty: f64,
    /// Step growth factor after an easy step (≤ `easy_iterations`).
    pub growth: f64,
    /// Newton iterations below which a step counts as easy.
    pub easy_iterations: usize,
    /// Step reduction factor after a failed attempt.
    pub cutback: f64,
    /// Smallest step, as a fraction of the stage duration.
    pub min_step_fraction: f64,
    /// Extrapolate the last increment as the Newton predictor.
    pub extrapolate: bool,
    /// Tangent (Euler) predictor for a step that moves the probe (a
    /// prescribed displacement, the spring's free end or the applied
    /// force): the increment
    /// K Δu = −(∂R/∂λ) Δλ with the last factorised tangent (one
    /// back-substitution), instead of extrapolating the last increment.
    pub tangent_predictor: bool,
    /// The material tangent is symmetric: factorise with LDLᵀ (LU
    /// fallback); false forces LU.
    pub symmetric: bool,
    /// Largest rise of the residual norm accepted for a full Newton step
    /// (× the previous norm); above it, the line search halves the step
    /// until the residual decreases.
    pub residual_growth: f64,
    /// Residual-only trial points near convergence: when the residual norm
    /// is within this factor of the tolerance, the Newton step is expected
    /// to converge (quadratic convergence), so its trial points are assembled
    /// without the tangent and the tangent is assembled only if the accepted
    /// point turns out not converged (then, with `chord_contraction`, a
    /// chord step may follow instead). 0 disables. Default 1e5 (session 3:
    /// 1e4 without chord steps; with them 1e5 measured best on the thesis
    /// run and the elastic dome, docs/theory/fem.md "Speed").
    pub lazy_tangent: f64,
    /// Chord steps near convergence: after a residual-only (lazy)
    /// assembly that is not converged but shows the residual contracted by
    /// at least this factor in the last step, the next correction reuses
    /// the last factors (no tangent assembly, no factorisation) and is kept
    /// only if it contracts the residual by this factor again; otherwise
    /// the tangent is assembled at that point. 0 disables. Default 0.1.
    pub chord_contraction: f64,
    /// Dense output: largest estimated interpolation error of the probe
    /// (or plane) force between steps, relative to the force (floor
    /// 1e-7 G L²); steps that exceed `output_rejection` × it are redone
    /// smaller, and the next step is sized for it (module `dense`). 0
    /// disables. Default 2e-4.
    pub output_tolerance: f64,
    /// Dense output: a converged step whose estimated interpolation error
    /// exceeds this multiple of `output_tolerance` is rejected and redone
    /// smaller (the next step is sized for 0.9× the tolerance either
    /// way). Default 2.5 (session 12; 1.5 before): the estimate bounds
    /// the error of the quadratic while the written curve is the cubic, and
    /// at 1.5 one step in 8–16 was redone (docs/theory/fem.md, "Speed").
    pub output_rejection: f64,
    /// Threads for the element loop (material updates); 0 or 1 = serial. The
    /// result is bitwise the same for any number (element outputs are
    /// computed in parallel, then added in element order). The loop
    /// evaluates four elements at a time, one per SIMD lane, where the
    /// element kind and material have a lane form (the axisymmetric Q4 with
    /// this crate's cell materials; docs/theory/fem.md, "Session 20"),
    /// bitwise the one-element results; threaded, one group of four per
    /// task. (No setting of its own: a field here would enter the models'
    /// identity, and with it the study hash of every run store, for a choice
    /// that changes no result.)
    pub threads: usize,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            fbar: true,
            rtol: 1e-9,
            atol: 0.0,
            max_iterations: 14,
            line_search: 6,
            penalty: 100.0,
            growth: 1.5,
            easy_iterations: 4,
            cutback: 0.25,
            min_step_fraction: 1e-6,
            extrapolate: true,
            tangent_predictor: true,
            symmetric: true,
            residual_growth: 1.0,
            lazy_tangent: 1e5,
            chord_contraction: 0.1,
            output_tolerance: 2e-4,
            output_rejection: 2.5,
            threads: 1,
        }
    }
}

/// One loading stage: the control as a function of time up to `end`.
pub struct Stage<'a> {
    /// Name for reports.
    pub name: &'a str,
    /// End time (s).
    pub end: f64,
    /// First step size (s).
    pub dt_initial: f64,
    /// Largest step size (s).
    pub dt_max: f64,
    /// Loads at time t.
    pub control: &'a dyn Fn(f64) -> Control,
}

/// State after a converged step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepRecord {
    /// Time (s).
    pub time: f64,
    /// Probe displacement w (m, z up).
    pub probe_w: f64,
    /// Spring free-end displacement (m); NaN without a spring.
    pub free_end: f64,
    /// Upward force of the body on the probe from contact (N).
    pub contact_force: f64,
    /// Upward force of the body on the plane(s) above it (N).
    pub plane_force: f64,
    /// Downward force of the body on the plane(s) below it (N).
    pub base_force: f64,
    /// Deepest penetration into the probe (m, ≥ 0).
    pub penetration: f64,
    /// Cavity pressure p (Pa); NaN without a cavity.
    pub cavity_pressure: f64,
    /// Cavity volume V (m³); NaN without a cavity.
    pub cavity_volume: f64,
    /// Newton iterations of the step.
    pub iterations: usize,
    /// Stage of the step (1, 2, … in the order run; 0: the initial state).
    /// Dense output does not interpolate across stages.
    pub stage: usize,
}

/// Counters of a run. Times are CPU time of the calling thread
/// (`CLOCK_THREAD_CPUTIME_ID`), so they do not grow when other processes
/// load the machine.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Counters {
    /// Assembly in total (element loop + contact + loads), s.
    pub assembly_seconds: f64,
    /// Part of `assembly_seconds` in the element loop (kinematics, material
    /// updates, scatter into the sparse matrix), s.
    pub element_seconds: f64,
    /// Numeric factorisations and solves, s.
    pub solve_seconds: f64,
    /// Converged steps.
    pub steps: usize,
    /// Failed attempts that were cut back.
    pub cutbacks: usize,
    /// Converged steps rejected for their dense-output error and redone
    /// smaller.
    pub rejected_steps: usize,
    /// Newton iterations (linear solves) in total.
    pub iterations: usize,
    /// Global assemblies in total (including line-search trials).
    pub assemblies: usize,
    /// Part of `assemblies` without the tangent (residual only).
    pub residual_only_assemblies: usize,
    /// Numeric factorisations of the tangent (Newton iterations less the
    /// chord steps).
    pub factorisations: usize,
    /// Numeric factorisations that fell back from LDLᵀ to LU.
    pub lu_fallbacks: usize,
}

struct ContactSet {
    nodes: Vec<usize>,
    eps: Vec<f64>,
    /// Per node, 3×3 slots over (first, last displacement component, w)
    /// (plane: only the vertical diagonal, slot 4, is used).
    slots: Vec<[usize; 9]>,
}

/// The fluid cavity's data in the model (module docs).
struct CavityModel {
    cells: CavityCells,
    /// +1 or −1: makes the reference volume positive.
    sign: f64,
    /// Reference volume V₀ (m³).
    v0: f64,
    /// p = k s (Pa per m).
    k: f64,
    /// 1/K_f (0: incompressible).
    compliance: f64,
    /// Dof of s.
    dof: usize,
    /// Per cell, its local tangent slots (row-major, local dof count²).
    cell_slots: Vec<usize>,
    /// Per free boundary dof d: (d, slot of (d, s), slot of (s, d)).
    coupling: Vec<(usize, usize, usize)>,
    /// Dofs the pressure acts on, and whether the force is p × the area
    /// normal (a supported dof normal to a symmetry plane) rather than
    /// −p ∂V/∂u (all others), so that reactions are physical.
    loaded: Vec<(usize, bool)>,
    /// Scratch: area-weighted normals over all dofs.
    normals: Vec<f64>,
    /// Slot of (s, s).
    diagonal: usize,
    /// Scratch: ∂V/∂u over all dofs.
    dvdu: Vec<f64>,
}

#[derive(Debug, Default, Clone, Copy)]
struct Assembly {
    scale: f64,
    contact_force: f64,
    plane_force: f64,
    base_force: f64,
    penetration: f64,
    pressure: f64,
    volume: f64,
    active: usize,
}

/// Finite-strain model of an axisymmetric (`K` = [`Axisymmetric`], the
/// default) or 3D (`K` = [`Solid`]) body (see module docs).
pub struct Model<M: Material3, K: ElementKind<M> = Axisymmetric> {
    mesh: K::Mesh,
    material: M,
    settings: Settings,
    geometry: Vec<K::Geometry>,
    /// The geometry of elements 4g … 4g + 3 in lanes, for every full group
    /// g (empty unless the lanes are used: serial loop, [`Settings::threads`]).
    lane_geometry: Vec<K::LaneGeometry>,
    history: History<M::State>,
    dof_eq: Vec<usize>,
    prescribed: Vec<(usize, f64)>,
    u: Vec<f64>,
    u_committed: Vec<f64>,
    u_previous: Vec<f64>,
    /// Converged state of the last step rejected by the output control
    /// (the predictor of its shorter retry).
    u_rejected: Vec<f64>,
    time: f64,
    last_dt: f64,
    elem_slots: Vec<usize>,
    probe: Option<(SphereProbe, ContactSurface)>,
    /// Reference (r, z) of every node (2D models with a probe; else empty).
    positions2: Vec<[f64; 2]>,
    planes: Vec<(PlaneSide, ContactSet)>,
    cavity: Option<CavityModel>,
    system: SparseSystem,
    residual: Vec<f64>,
    rhs: Vec<f64>,
    /// One element's output, or four (the lanes of a serial loop).
    element_out: [K::Output; 4],
    /// The four elements' output in lanes.
    lane_out: K::LaneOutput,
    /// Per-element outputs for the parallel element loop (empty if serial).
    element_outs: Vec<K::Output>,
    pool: Option<rayon::ThreadPool>,
    probe_diag: f64,
    length: f64,
    /// Shear modulus at F = I (Pa).
    modulus: f64,
    /// Stages run so far (the current one during `run_stage`).
    stage: usize,
    /// Absolute floor of the dense-output force scale: 1e-7 G L².
    output_floor: f64,
    /// Force below which residuals are round-off, whatever the loads:
    /// 32 ε K L² (K ≈ the stiffest modulus at F = I, L the model size).
    force_floor: f64,
    records: Vec<StepRecord>,
    /// Loads of the last converged step.
    control: Control,
    /// The last factorised tangent belongs to the Newton iterations of the
    /// last converged step (not to a rejected or failed attempt since).
    factors_current: bool,
    counters: Counters,
}

impl<M: Material3, K: ElementKind<M>> std::fmt::Debug for Model<M, K> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "Model({} nodes, {} elements, {:?})",
            self.mesh.node_count(),
            self.mesh.element_count(),
            self.system
        )
    }
}

impl<M: Material3> Model<M> {
    /// Builds an axisymmetric model with at most one (upper) plane: see
    /// [`Model::build`].
    ///
    /// # Errors
    /// As [`Model::build`].
    pub fn new(
        mesh: crate::Mesh,
        material: M,
        supports: &[Support],
        probe: Option<SphereProbe>,
        plane: Option<RigidPlane>,
        settings: Settings,
    ) -> Result<Self> {
        let parts = Parts {
            supports: supports.to_vec(),
            probe,
            planes: plane.into_iter().collect(),
            cavity: None,
        };
        Self::build(mesh, material, &parts, settings)
    }

    /// Converged nodal displacements, (u_r, u_z) per node.
    pub fn displacements(&self) -> impl Iterator<Item = [f64; 2]> + '_ {
        self.u_committed[..2 * self.mesh.node_count()]
            .chunks_exact(2)
            .map(|c| [c[0], c[1]])
    }
}

impl<M: Material3> Model<M, Solid> {
    /// Converged nodal displacements, (u_x, u_y, u_z) per node.
    pub fn displacements(&self) -> impl Iterator<Item = [f64; 3]> + '_ {
        self.u_committed[..3 * self.mesh.node_count()]
            .chunks_exact(3)
            .map(|c| [c[0], c[1], c[2]])
    }
}

impl<M: Material3, K: ElementKind<M>> Model<M, K> {
    /// Builds the model: dof numbering, sparse pattern, symbolic LDLᵀ and LU,
    /// contact penalties, cavity volume.
    ///
    /// # Errors
    /// [`FemError::Mesh`] for a missing node or face set or a degenerate
    /// cavity; [`FemError::Setting`] for a support component the mesh does
    /// not have, a probe on a 3D mesh or a non-positive fluid bulk modulus;
    /// [`FemError::Material`] if the material cannot be evaluated at F = I;
    /// [`FemError::Solver`] if the symbolic factorisation fails.
    pub fn build(mesh: K::Mesh, material: M, parts: &Parts, settings: Settings) -> Result<Self> {
        let dim = K::DIM;
        let nd = K::NODES * dim;
        let nn = mesh.node_count();
        let wdof = dim * nn;
        let sdof = wdof + 1;
        let ndof = wdof + 1 + usize::from(parts.cavity.is_some());
        let probe = parts.probe.clone();
        if probe.is_some() && dim != 2 {
            return Err(FemError::Setting {
                name: "probe",
                value: dim as f64,
                reason: "the rigid sphere moves along the axis of an axisymmetric model; 3D models take planes",
            });
        }
        let mut constrained = vec![false; ndof];
        let mut prescribed = Vec::new();
        for s in &parts.supports {
            let c = s.component.checked_index(dim)?;
            for &a in mesh.node_set(&s.set)? {
                let dof = dim * a + c;
                if !constrained[dof] {
                    constrained[dof] = true;
                    prescribed.push((dof, s.value));
                }
            }
        }
        if probe.is_none() {
            constrained[wdof] = true;
            prescribed.push((wdof, 0.0));
        }
        let mut dof_eq = vec![NO_SLOT; ndof];
        let mut neq = 0;
        for (d, eq) in dof_eq.iter_mut().enumerate() {
            if !constrained[d] {
                *eq = neq;
                neq += 1;
            }
        }
        let elem_eqs = |conn: &[usize]| -> Vec<usize> {
            (0..nd)
                .map(|k| dof_eq[dim * conn[k / dim] + k % dim])
                .collect()
        };
        let ne = mesh.element_count();
        let mut blocks: Vec<Vec<usize>> = Vec::with_capacity(ne + 1);
        for e in 0..ne {
            blocks.push(
                elem_eqs(mesh.connectivity(e))
                    .into_iter()
                    .filter(|&e| e != NO_SLOT)
                    .collect(),
            );
        }
        let probe_nodes = match &probe {
            Some(p) => mesh.node_set(&p.surface)?.to_vec(),
            None => Vec::new(),
        };
        if probe.is_some() {
            // The probe couples with each surface segment's two nodes (2D).
            blocks.extend(contact::blocks(&probe_nodes, &dof_eq, Some(dof_eq[wdof])));
            blocks.push(vec![dof_eq[wdof]]);
        }
        // The cavity: each cell couples its nodes; s couples with every
        // boundary node (not the nodes with each other).
        let cavity_cells = match &parts.cavity {
            Some(c) => Some(mesh.cavity_cells(&c.boundary)?),
            None => None,
        };
        let cell_nodes = |cells: &CavityCells| -> Vec<Vec<usize>> {
            match cells {
                CavityCells::Segments(v) => v.iter().map(|c| c.to_vec()).collect(),
                CavityCells::Quads(v) => v.iter().map(|c| c.to_vec()).collect(),
            }
        };
        let mut cavity_dofs = Vec::new();
        let mut loaded_dofs = Vec::new();
        if let Some(cells) = &cavity_cells {
            let cn = cell_nodes(cells);
            for nodes in &cn {
                blocks.push(
                    nodes
                        .iter()
                        .flat_map(|&a| (0..dim).map(move |i| dim * a + i))
                        .map(|d| dof_eq[d])
                        .filter(|&e| e != NO_SLOT)
                        .collect(),
                );
            }
            let mut nodes: Vec<usize> = cn.into_iter().flatten().collect();
            nodes.sort_unstable();
            nodes.dedup();
            for a in nodes {
                // The pressure's force −p ∂V/∂u on every dof except a
                // supported one normal to a coordinate plane the node lies
                // on: there ∂V/∂u is that of the volume formula with the
                // symmetry plane moved, and the physical force is p × the
                // area-weighted normal (`crate::cavity`).
                for i in 0..dim {
                    let on_plane = dof_eq[dim * a + i] == NO_SLOT && mesh.position(a)[i] == 0.0;
                    loaded_dofs.push((dim * a + i, on_plane));
                }
                let mut b: Vec<usize> = (0..dim)
                    .map(|i| dim * a + i)
                    .filter(|&d| dof_eq[d] != NO_SLOT)
                    .collect();
                cavity_dofs.extend_from_slice(&b);
                b.iter_mut().for_each(|d| *d = dof_eq[*d]);
                b.push(dof_eq[sdof]);
                blocks.push(b);
            }
            blocks.push(vec![dof_eq[sdof]]);
        }
        let system = SparseSystem::new(neq, &blocks, settings.symmetric)?;
        let mut elem_slots = Vec::with_capacity(nd * nd * ne);
        let mut tmp = Vec::with_capacity(nd * nd);
        // Local (row, column) → stored slot; in symmetric mode the element
        // (or cell) computes its lower triangle only (`TangentPart::Lower`):
        // entry (a, b), b ≤ a, goes to the stored slot of the pair,
        // whichever orientation is stored.
        let lower_slots = |tmp: &[usize], n: usize, out: &mut Vec<usize>| {
            if settings.symmetric {
                for a in 0..n {
                    for b in 0..n {
                        out.push(if b > a {
                            NO_SLOT
                        } else if tmp[n * a + b] != NO_SLOT {
                            tmp[n * a + b]
                        } else {
                            tmp[n * b + a]
                        });
                    }
                }
            } else {
                out.extend_from_slice(tmp);
            }
        };
        for e in 0..ne {
            system.block_slots(&elem_eqs(mesh.connectivity(e)), &mut tmp)?;
            lower_slots(&tmp, nd, &mut elem_slots);
        }
        // Shear modulus at F = I for the penalty scale, and the stiffest
        // modulus (≈ K + 4G/3) for the round-off floor of the residual.
        let (g0, stiffest) = {
            let s0 = material.initial_state();
            let mut tr = s0.clone();
            let resp = material
                .update(&s0, &Mat3::identity(), 1e-6, &mut tr)
                .map_err(|source| FemError::Material {
                    element: 0,
                    point: 0,
                    source,
                })?;
            let stiffest = resp.tangent.iter().fold(0.0f64, |m, c| m.max(c.abs()));
            (resp.tangent[(1, 1)], stiffest)
        };
        let make_set = |surface: &str, with_w: bool, tmp: &mut Vec<usize>| -> Result<ContactSet> {
            let (nodes, area, len) = mesh.contact_weights(surface)?;
            let eps = area
                .iter()
                .zip(&len)
                .map(|(a, h)| settings.penalty * g0 * a / h.max(f64::MIN_POSITIVE))
                .collect();
            let mut slots = Vec::with_capacity(nodes.len());
            for &a in &nodes {
                let w = if with_w { dof_eq[wdof] } else { NO_SLOT };
                system.block_slots(&[dof_eq[dim * a], dof_eq[dim * a + dim - 1], w], tmp)?;
                let mut s = [NO_SLOT; 9];
                s.copy_from_slice(tmp);
                slots.push(s);
            }
            Ok(ContactSet { nodes, eps, slots })
        };
        // The probe (2D only, checked above): contact integrated along the
        // surface segments (`crate::contact`).
        let positions2: Vec<[f64; 2]> = if probe.is_some() {
            (0..nn)
                .map(|a| {
                    let x = mesh.position(a);
                    [x[0], x[dim - 1]]
                })
                .collect()
        } else {
            Vec::new()
        };
        let probe = match probe {
            Some(p) => {
                let surface = ContactSurface::new(
                    &positions2,
                    &probe_nodes,
                    &dof_eq,
                    Some(dof_eq[wdof]),
                    settings.penalty,
                    g0,
                    &system,
                )?;
                Some((p, surface))
            }
            None => None,
        };
        let mut planes = Vec::with_capacity(parts.planes.len());
        for p in &parts.planes {
            planes.push((p.side, make_set(&p.surface, false, &mut tmp)?));
        }
        let probe_diag = probe
            .as_ref()
            .map(|(_, s)| s.stiffness_scale())
            .unwrap_or(1.0)
            .max(f64::MIN_POSITIVE);
        let geometry = K::geometry(&mesh)?;
        let history = History::new(&material, ne, K::POINTS);
        let length = (0..nn)
            .flat_map(|a| mesh.position(a).iter())
            .fold(0.0, |m: f64, p| m.max(p.abs()));
        let cavity = match (&parts.cavity, cavity_cells) {
            (Some(spec), Some(cells)) => {
                let compliance = match spec.fluid {
                    Fluid::Incompressible => 0.0,
                    Fluid::Compressible { bulk_modulus } => {
                        if !(bulk_modulus > 0.0 && bulk_modulus.is_finite()) {
                            return Err(FemError::Setting {
                                name: "fluid bulk modulus",
                                value: bulk_modulus,
                                reason: "must be positive and finite (Pa); use Fluid::Incompressible for K_f = ∞",
                            });
                        }
                        1.0 / bulk_modulus
                    }
                };
                let mut cell_slots = Vec::new();
                for nodes in cell_nodes(&cells) {
                    let eqs: Vec<usize> = nodes
                        .iter()
                        .flat_map(|&a| (0..dim).map(move |i| dim * a + i))
                        .map(|d| dof_eq[d])
                        .collect();
                    system.block_slots(&eqs, &mut tmp)?;
                    lower_slots(&tmp, eqs.len(), &mut cell_slots);
                }
                let seq = dof_eq[sdof];
                let mut coupling = Vec::with_capacity(cavity_dofs.len());
                for &d in &cavity_dofs {
                    let (r, c) = (system.slot(dof_eq[d], seq)?, system.slot(seq, dof_eq[d])?);
                    coupling.push((d, r, if settings.symmetric { NO_SLOT } else { c }));
                }
                let mut model = CavityModel {
                    cells,
                    sign: 1.0,
                    v0: 0.0,
                    k: 0.0,
                    compliance,
                    dof: sdof,
                    cell_slots,
                    coupling,
                    loaded: loaded_dofs,
                    normals: vec![0.0; ndof],
                    diagonal: system.slot(seq, seq)?,
                    dvdu: vec![0.0; ndof],
                };
                let zero = vec![0.0; ndof];
                let v = model.volume(&mesh, dim, &zero);
                if !(v.abs() > 0.0) || !v.is_finite() {
                    return Err(FemError::Mesh(format!(
                        "cavity `{}` encloses no volume (V₀ = {v:.3e} m³): its cells must form \
                         the closed boundary together with symmetry planes through the origin",
                        spec.boundary
                    )));
                }
                model.sign = v.signum();
                model.v0 = v.abs();
                model.k = g0 / model.v0.cbrt();
                Some(model)
            }
            _ => None,
        };
        Ok(Self {
            lane_geometry: if K::LANES {
                geometry
                    .chunks_exact(4)
                    .map(|g| K::lane_geometry([&g[0], &g[1], &g[2], &g[3]]))
                    .collect()
            } else {
                Vec::new()
            },
            geometry,
            history,
            dof_eq,
            prescribed,
            u: vec![0.0; ndof],
            u_committed: vec![0.0; ndof],
            u_previous: vec![0.0; ndof],
            u_rejected: vec![0.0; ndof],
            time: 0.0,
            last_dt: 0.0,
            elem_slots,
            probe,
            planes,
            cavity,
            residual: vec![0.0; ndof],
            rhs: vec![0.0; neq],
            element_out: std::array::from_fn(|_| K::output()),
            lane_out: Default::default(),
            element_outs: if settings.threads > 1 {
                (0..ne).map(|_| K::output()).collect()
            } else {
                Vec::new()
            },
            pool: if settings.threads > 1 {
                Some(
                    rayon::ThreadPoolBuilder::new()
                        .num_threads(settings.threads)
                        .build()
                        .map_err(|e| FemError::Solver(format!("thread pool: {e}")))?,
                )
            } else {
                None
            },
            probe_diag,
            length,
            modulus: g0,
            stage: 0,
            output_floor: 1e-7 * g0.abs() * length * length,
            // Residual round-off: stresses, in particular the pressure
            // K(J − 1), carry an absolute error ≈ ε K whatever the
            // deformation (measured: the residual of a 1e-12 m indentation
            // stalls at ≈ 5 ε K L² for K = 1e6 G).
            force_floor: 32.0 * f64::EPSILON * stiffest * length * length,
            positions2,
            records: Vec::new(),
            control: Control::default(),
            factors_current: false,
            counters: Counters::default(),
            system,
            mesh,
            material,
            settings,
        })
    }

    /// The mesh.
    pub fn mesh(&self) -> &K::Mesh {
        &self.mesh
    }

    /// Current time (s).
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Sets the clock (before the first stage).
    pub fn set_time(&mut self, t: f64) {
        self.time = t;
    }

    /// Places the probe at displacement `w` (m, z up) before the first
    /// stage, e.g. above the body so that it starts out of contact.
    pub fn set_probe_displacement(&mut self, w: f64) {
        let wdof = K::DIM * self.mesh.node_count();
        self.u[wdof] = w;
        self.u_committed[wdof] = w;
        self.u_previous[wdof] = w;
    }

    /// Converged nodal displacements, node-major (`K::DIM` per node).
    pub fn nodal_displacements(&self) -> &[f64] {
        &self.u_committed[..K::DIM * self.mesh.node_count()]
    }

    /// The material, the element geometry, the point histories and the
    /// converged dofs: read access for this crate's output modules.
    #[allow(clippy::type_complexity)]
    pub(crate) fn converged_parts(&self) -> (&M, &[K::Geometry], &History<M::State>, &[f64]) {
        (
            &self.material,
            &self.geometry,
            &self.history,
            &self.u_committed,
        )
    }

    /// Converged probe displacement w (m).
    pub fn probe_displacement(&self) -> f64 {
        self.u_committed[K::DIM * self.mesh.node_count()]
    }

    /// Reference volume V₀ of the cavity (m³), if there is one.
    pub fn cavity_reference_volume(&self) -> Option<f64> {
        self.cavity.as_ref().map(|c| c.v0)
    }

    /// Stored energy `Σ_e Σ_q w_q ψ(F̄_q)` of the converged state for a
    /// strain-energy density `psi` of the deformation gradient (J; the full
    /// revolved body for axisymmetric models): the potential the elements
    /// are the gradient of, when `psi` is the material's.
    pub fn strain_energy(&self, psi: &dyn Fn(&Mat3) -> f64) -> f64 {
        let dim = K::DIM;
        let nd = K::NODES * dim;
        let mut ue = [0.0; 24];
        let mut total = 0.0;
        for e in 0..self.mesh.element_count() {
            let conn = self.mesh.connectivity(e);
            for k in 0..nd {
                ue[k] = self.u_committed[dim * conn[k / dim] + k % dim];
            }
            total += K::energy(&self.geometry[e], &ue[..nd], self.settings.fbar, psi);
        }
        total
    }

    /// The element with the smallest det F over its Gauss points at the
    /// converged state (plain F, not F̄), and that determinant; None for an
    /// empty mesh.
    pub fn smallest_jacobian(&self) -> Option<(usize, f64)> {
        let dim = K::DIM;
        let nd = K::NODES * dim;
        let mut ue = [0.0; 24];
        let mut best: Option<(usize, f64)> = None;
        for e in 0..self.mesh.element_count() {
            let conn = self.mesh.connectivity(e);
            for k in 0..nd {
                ue[k] = self.u_committed[dim * conn[k / dim] + k % dim];
            }
            let smallest = std::cell::Cell::new(f64::INFINITY);
            K::energy(&self.geometry[e], &ue[..nd], false, &|f: &Mat3| {
                smallest.set(smallest.get().min(f.determinant()));
                0.0
            });
            let j = smallest.get();
            if best.is_none_or(|b| j < b.1) {
                best = Some((e, j));
            }
        }
        best
    }

    /// Gap of node `a` to a plane on `side` at the converged state (m,
    /// negative when it penetrates): g = z_plane − z above, z − z_plane
    /// below.
    fn converged_plane_gap(&self, side: PlaneSide, a: usize) -> f64 {
        let dim = K::DIM;
        let z = self.mesh.position(a)[dim - 1] + self.u_committed[dim * a + dim - 1];
        match side {
            PlaneSide::Above => self.control.plane_z - z,
            PlaneSide::Below(zb) => z - zb,
        }
    }

    /// Energy stored in the contact penalties at the converged state,
    /// `Σ ½ ε_a ⟨−g_a⟩²` over the planes (J).
    pub fn plane_contact_energy(&self) -> f64 {
        let mut total = 0.0;
        for (side, set) in &self.planes {
            for (k, &a) in set.nodes.iter().enumerate() {
                let g = self.converged_plane_gap(*side, a);
                if g < 0.0 {
                    total += 0.5 * set.eps[k] * g * g;
                }
            }
        }
        total
    }

    /// Contact force of every node of plane `index` (in the order of
    /// [`Parts::planes`]) at the converged state: (node, force ≥ 0 in N).
    /// Empty for a missing plane.
    pub fn plane_contact_forces(&self, index: usize) -> Vec<(usize, f64)> {
        let Some((side, set)) = self.planes.get(index) else {
            return Vec::new();
        };
        set.nodes
            .iter()
            .enumerate()
            .map(|(k, &a)| {
                let g = self.converged_plane_gap(*side, a);
                (a, (-set.eps[k] * g).max(0.0))
            })
            .collect()
    }

    /// Gap of every node of plane `index` (in the order of
    /// [`Parts::planes`]) at the converged state: (node, gap in m, negative
    /// when the node penetrates the plane). Empty for a missing plane.
    pub fn plane_contact_gaps(&self, index: usize) -> Vec<(usize, f64)> {
        let Some((side, set)) = self.planes.get(index) else {
            return Vec::new();
        };
        set.nodes
            .iter()
            .map(|&a| {
                let g = self.converged_plane_gap(*side, a);
                (a, g)
            })
            .collect()
    }

    /// Side of plane `index` (in the order of [`Parts::planes`]), if there
    /// is one.
    pub fn plane_side(&self, index: usize) -> Option<PlaneSide> {
        self.planes.get(index).map(|p| p.0)
    }

    /// Loads of the last converged step.
    pub fn last_control(&self) -> Control {
        self.control
    }

    /// Records of all converged steps so far.
    pub fn records(&self) -> &[StepRecord] {
        &self.records
    }

    /// Run counters.
    pub fn counters(&self) -> Counters {
        self.counters
    }

    /// Number of equations.
    pub fn equations(&self) -> usize {
        self.system.dim()
    }

    /// Sum over a node set of the internal force in `component` at the last
    /// converged state: the support reaction on the body there (N).
    ///
    /// # Errors
    /// [`FemError::Mesh`] for a missing set; [`FemError::Setting`] for a
    /// component the mesh does not have.
    pub fn reaction(&self, set: &str, component: Component) -> Result<f64> {
        let dim = K::DIM;
        let c = component.checked_index(dim)?;
        Ok(self
            .mesh
            .node_set(set)?
            .iter()
            .map(|&a| self.residual[dim * a + c])
            .sum())
    }

    fn assemble(&mut self, ctl: &Control, dt: f64, tangent: bool) -> Result<Assembly> {
        let clock = cpu_time::ThreadTime::now();
        let out = self.assemble_inner(ctl, dt, tangent);
        self.counters.assembly_seconds += clock.elapsed().as_secs_f64();
        out
    }

    fn assemble_inner(&mut self, ctl: &Control, dt: f64, tangent: bool) -> Result<Assembly> {
        self.counters.assemblies += 1;
        if !tangent {
            self.counters.residual_only_assemblies += 1;
        }
        self.residual.fill(0.0);
        if tangent {
            self.system.values.fill(0.0);
        }
        let mut gross = 0.0;
        let fbar = self.settings.fbar;
        let part = match (tangent, self.settings.symmetric) {
            (false, _) => TangentPart::None,
            (true, true) => TangentPart::Lower,
            (true, false) => TangentPart::Full,
        };
        let clock = cpu_time::ThreadTime::now();
        let dim = K::DIM;
        let nd = K::NODES * dim;
        let np = K::POINTS;
        if let Some(pool) = &self.pool {
            let (committed, trial) = self.history.split();
            let (mesh, material, geometry, lane_geometry, u) = (
                &self.mesh,
                &self.material,
                &self.geometry,
                &self.lane_geometry,
                &self.u,
            );
            // One task per group of four elements, in lanes as in the
            // serial loop below (so the outputs are bitwise the serial
            // ones); a failing or short group one by one.
            let failures: Vec<Option<(usize, crate::local::PointFailure)>> = pool.install(|| {
                use rayon::prelude::*;
                self.element_outs
                    .par_chunks_mut(4)
                    .zip(trial.par_chunks_mut(4 * np))
                    .enumerate()
                    .map_init(K::LaneOutput::default, |lane_out, (g, (outs, tr))| {
                        let e0 = 4 * g;
                        let gather = |e: usize| {
                            let conn = mesh.connectivity(e);
                            let mut ue = [0.0; 24];
                            for k in 0..nd {
                                ue[k] = u[dim * conn[k / dim] + k % dim];
                            }
                            ue
                        };
                        if let (Some(lane_geo), Ok(four)) = (
                            lane_geometry.get(g),
                            <&mut [K::Output; 4]>::try_from(&mut *outs),
                        ) {
                            let ue: [[f64; 24]; 4] = std::array::from_fn(|l| gather(e0 + l));
                            let mut chunks = tr.chunks_mut(np);
                            let trial = std::array::from_fn(|_| chunks.next().expect("4 elements"));
                            if K::evaluate_lanes(
                                material,
                                lane_geo,
                                std::array::from_fn(|l| &ue[l][..nd]),
                                std::array::from_fn(|l| {
                                    &committed[np * (e0 + l)..np * (e0 + l + 1)]
                                }),
                                trial,
                                dt,
                                fbar,
                                part,
                                lane_out,
                                four.each_mut(),
                            ) {
                                return None;
                            }
                        }
                        outs.iter_mut().zip(tr.chunks_mut(np)).enumerate().find_map(
                            |(l, (out, tr))| {
                                let e = e0 + l;
                                let ue = gather(e);
                                K::evaluate(
                                    material,
                                    &geometry[e],
                                    &ue[..nd],
                                    &committed[np * e..np * e + np],
                                    tr,
                                    dt,
                                    fbar,
                                    part,
                                    out,
                                )
                                .err()
                                .map(|f| (e, f))
                            },
                        )
                    })
                    .collect()
            });
            // The first failing element in element order (deterministic).
            if let Some((element, (point, source))) = failures.into_iter().flatten().next() {
                return Err(FemError::Material {
                    element,
                    point,
                    source,
                });
            }
            for e in 0..self.mesh.element_count() {
                let out = &self.element_outs[e];
                let slots = &self.elem_slots[nd * nd * e..nd * nd * (e + 1)];
                scatter::<M, K>(
                    self.mesh.connectivity(e),
                    out,
                    slots,
                    tangent,
                    &mut self.residual,
                    &mut self.system.values,
                    &mut gross,
                );
            }
        } else {
            let ne = self.mesh.element_count();
            let lanes = !self.lane_geometry.is_empty();
            for e0 in (0..ne).step_by(4) {
                let e1 = (e0 + 4).min(ne);
                // Four elements in lanes; on failure (or a short last group)
                // one by one.
                let mut done = false;
                if lanes && e1 == e0 + 4 {
                    let mut ue = [[0.0; 24]; 4];
                    for (l, uel) in ue.iter_mut().enumerate() {
                        let conn = self.mesh.connectivity(e0 + l);
                        for k in 0..nd {
                            uel[k] = self.u[dim * conn[k / dim] + k % dim];
                        }
                    }
                    let (committed, trial) = self.history.split();
                    let committed = &committed[np * e0..np * e1];
                    let mut tr = trial[np * e0..np * e1].chunks_mut(np);
                    let trial = std::array::from_fn(|_| tr.next().expect("4 elements"));
                    done = K::evaluate_lanes(
                        &self.material,
                        &self.lane_geometry[e0 / 4],
                        std::array::from_fn(|l| &ue[l][..nd]),
                        std::array::from_fn(|l| &committed[np * l..np * (l + 1)]),
                        trial,
                        dt,
                        fbar,
                        part,
                        &mut self.lane_out,
                        self.element_out.each_mut(),
                    );
                }
                for e in e0..e1 {
                    let conn = self.mesh.connectivity(e);
                    let out = &mut self.element_out[e - e0];
                    if !done {
                        let mut ue = [0.0; 24];
                        for k in 0..nd {
                            ue[k] = self.u[dim * conn[k / dim] + k % dim];
                        }
                        let (committed, trial) = self.history.element(e);
                        K::evaluate(
                            &self.material,
                            &self.geometry[e],
                            &ue[..nd],
                            committed,
                            trial,
                            dt,
                            fbar,
                            part,
                            out,
                        )
                        .map_err(|(point, source)| FemError::Material {
                            element: e,
                            point,
                            source,
                        })?;
                    }
                    let slots = &self.elem_slots[nd * nd * e..nd * nd * (e + 1)];
                    scatter::<M, K>(
                        conn,
                        out,
                        slots,
                        tangent,
                        &mut self.residual,
                        &mut self.system.values,
                        &mut gross,
                    );
                }
            }
        }
        self.counters.element_seconds += clock.elapsed().as_secs_f64();
        let mut asm = Assembly {
            scale: gross.sqrt(),
            ..Assembly::default()
        };
        let nn = self.mesh.node_count();
        let wdof = dim * nn;
        let w_free = !matches!(ctl.probe, ProbeDrive::Displacement(_));
        if let Some((probe, surface)) = &mut self.probe {
            let sums = surface.assemble(
                &self.positions2,
                &self.u,
                wdof,
                Obstacle::Sphere {
                    centre_z: probe.centre_z + self.u[wdof],
                    radius: probe.radius,
                },
                w_free,
                tangent,
                &mut self.residual,
                &mut self.system.values,
            );
            asm.contact_force = sums.force;
            asm.penetration = sums.penetration;
            asm.active = sums.active;
            asm.scale = asm.scale.max(asm.contact_force.abs());
        }
        for (side, set) in &self.planes {
            // Gap g and its derivative ∂g/∂z: above, g = z_plane − z; below,
            // g = z − z_plane.
            let (z_plane, dg) = match *side {
                PlaneSide::Above => (ctl.plane_z, -1.0),
                PlaneSide::Below(zb) => (zb, 1.0),
            };
            for (k, &a) in set.nodes.iter().enumerate() {
                let z = self.mesh.position(a)[dim - 1] + self.u[dim * a + dim - 1];
                let g = if dg < 0.0 { z_plane - z } else { z - z_plane };
                if g > 0.0 {
                    continue;
                }
                let eps = set.eps[k];
                if dg < 0.0 {
                    self.residual[dim * a + dim - 1] -= eps * g;
                    asm.plane_force -= eps * g;
                } else {
                    self.residual[dim * a + dim - 1] += eps * g;
                    asm.base_force -= eps * g;
                }
                if tangent {
                    let s = set.slots[k][4];
                    if s != NO_SLOT {
                        self.system.values[s] += eps;
                    }
                }
            }
            asm.scale = asm.scale.max(if dg < 0.0 {
                asm.plane_force.abs()
            } else {
                asm.base_force.abs()
            });
        }
        if let Some(cav) = &mut self.cavity {
            let (p, v) = cav.assemble(
                &self.mesh,
                dim,
                &self.u,
                ctl.fluid_injected,
                tangent,
                &mut self.residual,
                &mut self.system.values,
            );
            asm.pressure = p;
            asm.volume = v;
            // The pressure's force on the wall, p V₀^{2/3}.
            asm.scale = asm.scale.max(p.abs() * cav.v0.powf(2.0 / 3.0));
        }
        if self.probe.is_some() {
            let weq = self.dof_eq[wdof];
            let diag = self.system.slot(weq, weq)?;
            match ctl.probe {
                ProbeDrive::Displacement(_) => {
                    if tangent {
                        self.system.values[diag] = self.probe_diag;
                    }
                }
                ProbeDrive::Force(force) => {
                    self.residual[wdof] += force;
                    asm.scale = asm.scale.max(force.abs());
                }
                ProbeDrive::Spring {
                    stiffness,
                    free_end,
                } => {
                    let spring = stiffness * (self.u[wdof] - free_end);
                    self.residual[wdof] += spring;
                    asm.scale = asm.scale.max(spring.abs());
                    if tangent {
                        self.system.values[diag] += stiffness;
                    }
                }
            }
        }
        for (d, &eq) in self.dof_eq.iter().enumerate() {
            if eq != NO_SLOT {
                self.rhs[eq] = -self.residual[d];
            }
        }
        if !w_free && self.probe.is_some() {
            self.rhs[self.dof_eq[wdof]] = 0.0;
        }
        Ok(asm)
    }

    /// Residual norm reported as the tolerance: `rtol` × the gross force
    /// of the assembly, or the round-off floor if that is larger.
    fn tolerance(&self, asm: &Assembly) -> f64 {
        (self.settings.rtol * asm.scale)
            .max(self.settings.atol)
            .max(self.force_floor)
    }

    /// Convergence test of a Newton iterate with residual norm `norm`
    /// (`previous` before the last correction; `corrected`: at least one
    /// correction made): `norm` ≤ `rtol` × the gross force of the assembly
    /// (element forces, contact, spring, applied force); or, when the
    /// forces are so small that this is below round-off (t = 0, first
    /// touch, a probe out of contact, any bulk modulus), `norm` below the
    /// round-off floor 32 ε K L² *and* stagnating (the last correction
    /// gained less than 10×), so a Newton iteration that is still
    /// converging quadratically is never cut short by the floor, and a
    /// predictor is never accepted because its forces are tiny.
    fn converged(&self, norm: f64, previous: f64, asm: &Assembly, corrected: bool) -> bool {
        norm == 0.0
            || norm <= (self.settings.rtol * asm.scale).max(self.settings.atol)
            || (corrected && norm <= self.force_floor && norm > 0.1 * previous)
    }

    fn rhs_norm(&self) -> f64 {
        self.rhs.iter().map(|x| x * x).sum::<f64>().sqrt()
    }

    fn apply_prescribed(&mut self, ctl: &Control) {
        for &(dof, v) in &self.prescribed {
            self.u[dof] = v * ctl.support_scale;
        }
        if let (Some(_), ProbeDrive::Displacement(w)) = (&self.probe, ctl.probe) {
            self.u[K::DIM * self.mesh.node_count()] = w;
        }
    }

    /// A force-driven probe that touches the body at most at a point (first
    /// touch) or not at all has no contact stiffness, and Newton cannot
    /// start there. Predictor: lower the probe to first contact and then by
    /// the Hertz depth of the set force on an incompressible half-space,
    /// δ = (3F / (16 G √R))^{2/3} (eq. 1.1 with E = 3G); Newton then starts
    /// in contact and converges from there.
    ///
    /// Only when the last converged state carries (almost) no contact
    /// force: a probe already pressed in has its contact stiffness, and
    /// lowering it by the Hertz depth of the full set force would indent it
    /// that much deeper at once (the gap test alone misses this: with
    /// segment-integrated contact the penalty penetration of a soft, relaxed
    /// cell is below 1e-3 of the Hertz depth, which inverted the contact
    /// elements of 5 of the 100 setup-1 checking runs).
    fn force_drive_predictor(&mut self, ctl: &Control) {
        let (ProbeDrive::Force(force), Some((probe, surface))) = (ctl.probe, &self.probe) else {
            return;
        };
        if !(force > 0.0) {
            return;
        }
        let carried = self.records.last().map_or(0.0, |r| r.contact_force);
        if carried > 1e-3 * force {
            return;
        }
        let wdof = K::DIM * self.mesh.node_count();
        let obstacle = Obstacle::Sphere {
            centre_z: probe.centre_z + self.u[wdof],
            radius: probe.radius,
        };
        let gap = surface.min_gap(&self.positions2, &self.u, obstacle);
        let depth = (3.0 * force / (16.0 * self.modulus * probe.radius.sqrt())).powf(2.0 / 3.0);
        // Touching (|gap| at round-off) or above: no usable stiffness yet.
        if gap.is_finite() && gap > -1e-3 * depth {
            self.u[wdof] -= gap + depth;
        }
    }

    /// Tangent (Euler) predictor: u = u_c + Δu with K Δu = −(∂R/∂λ) Δλ, K
    /// the last factorised tangent and λ the probe's drive (the prescribed
    /// probe displacement, the spring's free end, or the applied force),
    /// from the loads of the
    /// last converged step to `ctl`. Only for a probe step with the other
    /// loads unchanged; false (u untouched) otherwise.
    fn tangent_predictor(&mut self, ctl: &Control) -> bool {
        let old = self.control;
        if old.plane_z != ctl.plane_z
            || old.support_scale != ctl.support_scale
            || old.fluid_injected != ctl.fluid_injected
            || self.cavity.is_some()
        {
            return false;
        }
        let wdof = K::DIM * self.mesh.node_count();
        let mut b = vec![0.0; self.rhs.len()];
        match (old.probe, ctl.probe, &mut self.probe) {
            (
                ProbeDrive::Spring {
                    stiffness: k0,
                    free_end: z0,
                },
                ProbeDrive::Spring {
                    stiffness: k1,
                    free_end: z1,
                },
                Some(_),
            ) if k0 == k1 && z1 != z0 => {
                // R_w = … + k (w − z): −∂R_w/∂z Δz = k Δz.
                b[self.dof_eq[wdof]] = k1 * (z1 - z0);
            }
            (ProbeDrive::Force(f0), ProbeDrive::Force(f1), Some(_)) if f1 != f0 => {
                // R_w = … + F: −∂R_w/∂F ΔF = −ΔF.
                b[self.dof_eq[wdof]] = -(f1 - f0);
            }
            (
                ProbeDrive::Displacement(w0),
                ProbeDrive::Displacement(w1),
                Some((probe, surface)),
            ) if w1 != w0 => {
                // The w row is the identity and its column is not stored:
                // −(∂R_u/∂w) Δw by central differences of the contact
                // residual at the converged state (contact only, cheap).
                let dw = w1 - w0;
                let h = 1e-6 * dw;
                let mut rp = vec![0.0; self.u.len()];
                let mut rm = vec![0.0; self.u.len()];
                for (r, sign) in [(&mut rp, 1.0), (&mut rm, -1.0)] {
                    surface.assemble(
                        &self.positions2,
                        &self.u_committed,
                        wdof,
                        Obstacle::Sphere {
                            centre_z: probe.centre_z + w0 + sign * h,
                            radius: probe.radius,
                        },
                        false,
                        false,
                        r,
                        &mut [],
                    );
                }
                for (d, &eq) in self.dof_eq.iter().enumerate() {
                    if eq != NO_SLOT && d != wdof {
                        b[eq] = -(rp[d] - rm[d]) / (2.0 * h) * dw;
                    }
                }
                b[self.dof_eq[wdof]] = dw * self.probe_diag;
            }
            _ => return false,
        }
        if !self.system.solve_with_last_factors(&mut b) {
            return false;
        }
        for (d, &eq) in self.dof_eq.iter().enumerate() {
            self.u[d] = self.u_committed[d] + if eq != NO_SLOT { b[eq] } else { 0.0 };
        }
        true
    }

    /// Predictor of the retry of a step rejected by the output control:
    /// the rejected step converged to `u_rejected` at `dt_rejected` after
    /// the committed state, so the retry of length `dt` < `dt_rejected`
    /// lies inside a known interval. u(dt) is interpolated by the quadratic
    /// through the previous committed state (at −`last_dt`), the committed
    /// state (0) and the rejected one (linear before the model's first
    /// committed step).
    /// Extrapolating the last increment instead ignores the rejected state;
    /// the tangent predictor is unavailable (the last factors belong to the
    /// rejected attempt).
    fn rejected_step_predictor(&mut self, dt: f64, dt_rejected: f64) {
        let (h0, h1) = (self.last_dt, dt_rejected);
        // Lagrange weights at t = dt of the nodes −h0, 0, h1.
        let (w_prev, w_committed, w_rejected) = if h0 > 0.0 {
            (
                dt * (dt - h1) / (h0 * (h0 + h1)),
                (dt + h0) * (h1 - dt) / (h0 * h1),
                (dt + h0) * dt / ((h0 + h1) * h1),
            )
        } else {
            (0.0, 1.0 - dt / h1, dt / h1)
        };
        for d in 0..self.u.len() {
            self.u[d] = w_prev * self.u_previous[d]
                + w_committed * self.u_committed[d]
                + w_rejected * self.u_rejected[d];
        }
    }

    fn add_increment(&mut self, du: &[f64], alpha: f64, base: &[f64]) {
        for (d, &eq) in self.dof_eq.iter().enumerate() {
            if eq != NO_SLOT {
                self.u[d] = base[d] + alpha * du[eq];
            }
        }
    }

    /// Newton iterations for one step; Ok((iterations, assembly)) or the
    /// failure (residual, tolerance, iterations, cause).
    fn newton(
        &mut self,
        ctl: &Control,
        dt: f64,
    ) -> std::result::Result<(usize, Assembly), (f64, f64, usize, String)> {
        self.apply_prescribed(ctl);
        self.force_drive_predictor(ctl);
        let mut asm = match self.assemble(ctl, dt, true) {
            Ok(a) => a,
            Err(e) => return Err((f64::NAN, 0.0, 0, e.to_string())),
        };
        let mut norm = self.rhs_norm();
        let mut previous_norm = f64::INFINITY;
        let mut du = vec![0.0; self.rhs.len()];
        let mut base = self.u.clone();
        // −R at `base`, kept for the line search's residual model.
        let mut rhs_base = vec![0.0; self.rhs.len()];
        let growth_limit = self.settings.residual_growth;
        // No tangent at the current point (it was assembled residual-only
        // near convergence): the next correction is a chord step with the
        // last factors.
        let mut chord = false;
        // Chord steps in a row (at most `MAX_CHORD_STEPS`, then a tangent:
        // a chord step converges only linearly).
        let mut chords = 0;
        for it in 0..=self.settings.max_iterations {
            let tol = self.tolerance(&asm);
            if trace() {
                let (mut rmax, mut dmax) = (0.0, 0);
                for (d, &eq) in self.dof_eq.iter().enumerate() {
                    if eq != NO_SLOT && self.rhs[eq].abs() > rmax {
                        rmax = self.rhs[eq].abs();
                        dmax = d;
                    }
                }
                let node = if dmax / K::DIM < self.mesh.node_count() {
                    let x = self.mesh.position(dmax / K::DIM);
                    [x[0], x[x.len() - 1]]
                } else {
                    [f64::NAN; 2]
                };
                eprintln!(
                    "    it {it} |R| {norm:.3e} tol {tol:.3e} active {} F {:.5e} max |R| {rmax:.2e} at dof {dmax} (node at {:.3e}, {:.3e})",
                    asm.active, asm.contact_force, node[0], node[1]
                );
            }
            if self.converged(norm, previous_norm, &asm, it > 0) {
                return Ok((it, asm));
            }
            if !norm.is_finite() {
                return Err((norm, tol, it, "non-finite residual".into()));
            }
            if it == self.settings.max_iterations {
                return Err((norm, tol, it, "iteration limit".into()));
            }
            du.copy_from_slice(&self.rhs);
            let clock = cpu_time::ThreadTime::now();
            let chord_step = chord && self.system.solve_with_last_factors(&mut du);
            let solved = if chord_step {
                Ok(true)
            } else {
                if chord {
                    // No factors to reuse: the tangent here after all.
                    asm = match self.assemble(ctl, dt, true) {
                        Ok(a) => a,
                        Err(e) => return Err((norm, tol, it, e.to_string())),
                    };
                    du.copy_from_slice(&self.rhs);
                }
                self.counters.factorisations += 1;
                self.system.solve(&mut du)
            };
            chords = if chord_step { chords + 1 } else { 0 };
            chord = false;
            self.counters.solve_seconds += clock.elapsed().as_secs_f64();
            match solved {
                Ok(true) => {}
                Ok(false) => self.counters.lu_fallbacks += 1,
                Err(e) => return Err((norm, tol, it, e.to_string())),
            }
            self.counters.iterations += 1;
            // Near-incompressible pressures leave a round-off floor in the
            // residual above rtol·scale when the forces are tiny: a Newton
            // correction below the round-off level of the coordinates means
            // the state cannot be improved and counts as converged — also at
            // the first iteration (a step that starts at equilibrium).
            let du_max = du.iter().fold(0.0, |m: f64, x| m.max(x.abs()));
            if du_max <= 1e-12 * self.length && norm <= 1e-4 * asm.scale {
                return Ok((it, asm));
            }
            base.copy_from_slice(&self.u);
            if std::env::var_os("NLVID_FEM_CHECK_TANGENT").is_some() {
                let rhs0 = self.rhs.clone();
                let h = 1e-5;
                self.add_increment(&du, h, &base);
                let _ = self.assemble(ctl, dt, false);
                let rp = self.rhs.clone();
                self.add_increment(&du, -h, &base);
                let _ = self.assemble(ctl, dt, false);
                let mut err = 0.0;
                let mut den = 0.0;
                let mut worst = (0.0, 0);
                for i in 0..rp.len() {
                    let fd = (rp[i] - self.rhs[i]) / (2.0 * h);
                    let e = (fd + rhs0[i]).abs();
                    err += e * e;
                    den += rhs0[i] * rhs0[i];
                    if e > worst.0 {
                        worst = (e, i);
                    }
                }
                eprintln!(
                    "      tangent check: |fd − K du| / |K du| = {:.3e}, worst eq {} ({:.3e} of {:.3e})",
                    (err / den).sqrt(),
                    worst.1,
                    worst.0,
                    rhs0[worst.1]
                );
                self.u.copy_from_slice(&base);
                let _ = self.assemble(ctl, dt, true);
            }
            let mut alpha = 1.0;
            let mut accepted = false;
            let mut last_err = String::new();
            let lazy = chord_step || norm <= self.settings.lazy_tangent * tol;
            let trials = if chord_step {
                0
            } else {
                self.settings.line_search
            };
            if trials > 0 {
                rhs_base.copy_from_slice(&self.rhs);
            }
            for _ in 0..=trials {
                self.add_increment(&du, alpha, &base);
                let mut next_alpha = 0.5 * alpha;
                match self.assemble(ctl, dt, !lazy) {
                    Ok(a) => {
                        let n = self.rhs_norm();
                        // Monotone residual decrease by default: a full step
                        // that raises it is cut back (measured: fewer
                        // iterations and cut-backs than accepting 10× rises).
                        let limit = if chord_step {
                            // A chord step must contract as the Newton step
                            // it stands in for would.
                            self.settings.chord_contraction * norm
                        } else if alpha == 1.0 {
                            growth_limit * norm
                        } else {
                            norm
                        };
                        if n.is_finite() && n <= limit {
                            asm = a;
                            previous_norm = norm;
                            norm = n;
                            accepted = true;
                            break;
                        }
                        last_err = format!("line search: residual {n:.3e} ≥ {norm:.3e}");
                        if trace() {
                            eprintln!("      line search: α = {alpha} rejected ({last_err})");
                        }
                        if n.is_finite() {
                            next_alpha = backtrack_step(&rhs_base, &self.rhs, alpha);
                        }
                    }
                    Err(e) => last_err = e.to_string(),
                }
                alpha = next_alpha;
            }
            if !accepted && chord_step {
                // The old factors no longer do: a Newton step from the
                // same point with its own tangent (same residual, bitwise).
                self.u.copy_from_slice(&base);
                asm = match self.assemble(ctl, dt, true) {
                    Ok(a) => a,
                    Err(e) => return Err((norm, tol, it + 1, e.to_string())),
                };
                continue;
            }
            if !accepted {
                if norm <= self.force_floor {
                    // No direction improves a residual already at round-off
                    // level: the state cannot be made better; keep it.
                    self.u.copy_from_slice(&base);
                    return match self.assemble(ctl, dt, false) {
                        Ok(a) => Ok((it + 1, a)),
                        Err(e) => Err((norm, tol, it + 1, e.to_string())),
                    };
                }
                return Err((norm, tol, it + 1, last_err));
            }
            if lazy && !self.converged(norm, previous_norm, &asm, true) {
                if norm <= self.settings.chord_contraction * previous_norm
                    && chords < MAX_CHORD_STEPS
                    // Chord steps must not eat the iteration budget of a
                    // step that converges only slowly.
                    && it + 1 + MAX_CHORD_STEPS + 2 <= self.settings.max_iterations
                {
                    // Still contracting fast: the tangent of the last
                    // factorisation is as good as a new one for the rest
                    // (chord steps, residual-only assemblies).
                    chord = true;
                    continue;
                }
                // Predicted convergence did not happen: the next iteration
                // needs the tangent at this point.
                asm = match self.assemble(ctl, dt, true) {
                    Ok(a) => a,
                    Err(e) => return Err((norm, tol, it + 1, e.to_string())),
                };
                norm = self.rhs_norm();
            }
        }
        Err((
            norm,
            0.0,
            self.settings.max_iterations,
            "iteration limit".into(),
        ))
    }

    fn push_record(&mut self, time: f64, ctl: &Control, asm: &Assembly, iterations: usize) {
        let free_end = match ctl.probe {
            ProbeDrive::Spring { free_end, .. } => free_end,
            _ => f64::NAN,
        };
        let has_cavity = self.cavity.is_some();
        self.records.push(StepRecord {
            time,
            probe_w: self.u[K::DIM * self.mesh.node_count()],
            free_end,
            contact_force: asm.contact_force,
            plane_force: asm.plane_force,
            base_force: asm.base_force,
            penetration: asm.penetration,
            cavity_pressure: if has_cavity { asm.pressure } else { f64::NAN },
            cavity_volume: if has_cavity { asm.volume } else { f64::NAN },
            iterations,
            stage: self.stage,
        });
    }

    /// Dense-output error of a candidate step to `t_new` with force
    /// `force` (probe or plane), relative to `output_tolerance` × the
    /// force scale, and the step that would meet the tolerance (from the
    /// third-order error law, ×0.9, between ×0.2 and ×2); (0, ∞) when the
    /// stage has fewer than three earlier points or control is off.
    fn output_error(&self, t_new: f64, force: f64, dt: f64) -> (f64, f64) {
        let tol = self.settings.output_tolerance;
        let n = self.records.len();
        if !(tol > 0.0) || n < 3 {
            return (0.0, f64::INFINITY);
        }
        // The stage's records and its start point.
        let in_stage = self.records[n - 3..]
            .iter()
            .skip(1)
            .all(|r| r.stage == self.stage);
        if !in_stage {
            return (0.0, f64::INFINITY);
        }
        let value = |r: &StepRecord| {
            if self.probe.is_some() {
                r.contact_force
            } else {
                r.plane_force
            }
        };
        let p = &self.records[n - 3..];
        let ts = [p[0].time, p[1].time, p[2].time, t_new];
        let ys = [value(&p[0]), value(&p[1]), value(&p[2]), force];
        let scale = ys[2].abs().max(force.abs()) + self.output_floor;
        let ratio = crate::dense::interpolation_error(ts, ys) / (tol * scale);
        let factor = if ratio > 0.0 {
            (0.9 * ratio.powf(-1.0 / 3.0)).clamp(0.2, 2.0)
        } else {
            2.0
        };
        (ratio, dt * factor)
    }

    /// Advances through `stage` with adaptive steps: a failed attempt is
    /// cut back by `Settings::cutback`, easy steps grow by
    /// `Settings::growth` up to `stage.dt_max`.
    ///
    /// # Errors
    /// [`FemError::NonConvergence`] when the step falls below
    /// `min_step_fraction × stage duration` without converging; the model
    /// keeps the last converged state.
    pub fn run_stage(&mut self, stage: &Stage<'_>) -> Result<()> {
        self.run_stage_observed(stage, &mut |_| Ok(()))
    }

    /// [`Model::run_stage`], calling `observe` after every converged step
    /// (e.g. to record outputs that need the full state).
    ///
    /// # Errors
    /// As [`Model::run_stage`]; an error of `observe` ends the stage.
    pub fn run_stage_observed(
        &mut self,
        stage: &Stage<'_>,
        observe: &mut dyn FnMut(&Self) -> Result<()>,
    ) -> Result<()> {
        let duration = stage.end - self.time;
        if !(duration >= 0.0) || !(stage.dt_max > 0.0) || !(stage.dt_initial > 0.0) {
            return Err(FemError::Setting {
                name: "stage",
                value: duration,
                reason: "stage must end after the current time with positive steps",
            });
        }
        if duration == 0.0 {
            return Ok(());
        }
        let dt_min = self.settings.min_step_fraction * duration;
        let mut dt = stage.dt_initial.min(stage.dt_max);
        let mut first = true;
        // Length of the last step rejected by the output control, while its
        // state (`u_rejected`) is the end of the interval being retried.
        let mut rejected: Option<f64> = None;
        // The last attempt of the current step that met an inadmissible
        // deformation (reported if the step finally fails for another cause).
        let mut inadmissible: Option<String> = None;
        if self.records.is_empty() {
            // The initial state, the start point of the first stage.
            let ctl = (stage.control)(self.time);
            self.u.copy_from_slice(&self.u_committed);
            let asm = self.assemble(&ctl, 0.0, false)?;
            self.push_record(self.time, &ctl, &asm, 0);
        }
        self.stage += 1;
        while self.time < stage.end - 1e-12 * duration {
            let remaining = stage.end - self.time;
            if dt > remaining || remaining - dt < 0.01 * dt {
                dt = remaining;
            }
            let t_new = self.time + dt;
            let ctl = (stage.control)(t_new);
            // Predictor.
            if self.settings.tangent_predictor
                && self.factors_current
                && self.tangent_predictor(&ctl)
            {
                // u set from the converged state and the load increment.
            } else if let Some(dt_rejected) = rejected.filter(|&h| dt < h) {
                self.rejected_step_predictor(dt, dt_rejected);
            } else if self.settings.extrapolate && !first && self.last_dt > 0.0 {
                let s = dt / self.last_dt;
                for d in 0..self.u.len() {
                    self.u[d] =
                        self.u_committed[d] + s * (self.u_committed[d] - self.u_previous[d]);
                }
            } else {
                self.u.copy_from_slice(&self.u_committed);
            }
            match self.newton(&ctl, dt) {
                Ok((iterations, asm)) => {
                    if trace() {
                        eprintln!(
                            "step t={t_new:.5} dt={dt:.3e} its={iterations} F={:.4e}",
                            asm.contact_force
                        );
                    }
                    // Dense-output error of the new interval (module
                    // `dense`): reject and retry smaller if it is too large.
                    let force = if self.probe.is_some() {
                        asm.contact_force
                    } else {
                        asm.plane_force
                    };
                    let (ratio, dt_error) = self.output_error(t_new, force, dt);
                    if ratio > self.settings.output_rejection && dt > dt_min * (1.0 + 1e-9) {
                        if trace() {
                            eprintln!(
                                "reject t={t_new:.5} dt={dt:.3e} output error {ratio:.2} × tolerance"
                            );
                        }
                        self.counters.rejected_steps += 1;
                        self.factors_current = false;
                        // Its converged state predicts the shorter retry.
                        self.u_rejected.copy_from_slice(&self.u);
                        rejected = Some(dt);
                        self.u.copy_from_slice(&self.u_committed);
                        dt = dt_error.max(dt_min);
                        continue;
                    }
                    rejected = None;
                    self.history.commit();
                    self.u_previous.copy_from_slice(&self.u_committed);
                    self.u_committed.copy_from_slice(&self.u);
                    self.time = t_new;
                    self.last_dt = dt;
                    first = false;
                    self.counters.steps += 1;
                    self.control = ctl;
                    self.factors_current = true;
                    self.push_record(t_new, &ctl, &asm, iterations);
                    inadmissible = None;
                    observe(self)?;
                    if iterations <= self.settings.easy_iterations {
                        dt *= self.settings.growth;
                    }
                    dt = dt.min(dt_error).min(stage.dt_max);
                }
                Err((residual, tolerance, iterations, cause)) => {
                    if trace() {
                        eprintln!("cutback t={:.5} dt={dt:.3e} {cause}", self.time);
                    }
                    self.counters.cutbacks += 1;
                    self.factors_current = false;
                    self.u.copy_from_slice(&self.u_committed);
                    if cause.starts_with("material at element") {
                        inadmissible = Some(cause.clone());
                    }
                    if dt <= dt_min * (1.0 + 1e-9) {
                        // Leave the residual vector of the converged state.
                        let _ = self.assemble(&(stage.control)(self.time), 0.0, false);
                        let mut cause = format!("stage `{}`: {cause}", stage.name);
                        if let Some(m) = inadmissible.filter(|m| !cause.ends_with(m.as_str())) {
                            cause.push_str(&format!("; an earlier attempt: {m}"));
                        }
                        if let Some((e, j)) = self.smallest_jacobian().filter(|x| x.1 < 0.1) {
                            cause.push_str(&format!(
                                "; element {e} has det F = {j:.3e} at the last converged state (collapsing)"
                            ));
                        }
                        return Err(FemError::NonConvergence(Box::new(NonConvergence {
                            // + 0.0: a clock started at −0.0 prints as 0.
                            time: self.time + 0.0,
                            dt,
                            residual,
                            tolerance,
                            iterations,
                            cause,
                        })));
                    }
                    // The retry keeps the extrapolation predictor (the last
                    // converged increment scaled to the smaller step): without
                    // it a displacement-driven probe jumps alone into a
                    // surface left where it was and inverts the contact
                    // elements even at 1/16 of the step (the elastic dome:
                    // 7 → 0 cut-back cascades; docs/theory/fem.md).
                    dt = (dt * self.settings.cutback).max(dt_min);
                }
            }
        }
        Ok(())
    }
}

impl CavityModel {
    /// Current positions of a cell's nodes, flattened (`dim` per node).
    fn positions(mesh: &impl Topology, dim: usize, u: &[f64], nodes: &[usize], out: &mut [f64]) {
        for (k, &a) in nodes.iter().enumerate() {
            let x = mesh.position(a);
            for i in 0..dim {
                out[dim * k + i] = x[i] + u[dim * a + i];
            }
        }
    }

    /// Signed volume Σ cells (times `sign`) at displacements `u`.
    fn volume(&self, mesh: &impl Topology, dim: usize, u: &[f64]) -> f64 {
        let mut x = [0.0; 12];
        let mut v = 0.0;
        match &self.cells {
            CavityCells::Segments(cells) => {
                for c in cells {
                    Self::positions(mesh, dim, u, c, &mut x);
                    v += segment_volume(&[[x[0], x[1]], [x[2], x[3]]]).0;
                }
            }
            CavityCells::Quads(cells) => {
                for c in cells {
                    Self::positions(mesh, dim, u, c, &mut x);
                    v += quad_volume(&[
                        [x[0], x[1], x[2]],
                        [x[3], x[4], x[5]],
                        [x[6], x[7], x[8]],
                        [x[9], x[10], x[11]],
                    ])
                    .0;
                }
            }
        }
        self.sign * v
    }

    /// Adds the fluid's terms of the potential (module docs) to the
    /// residual and, if `tangent`, to the matrix; returns (p, V).
    #[allow(clippy::too_many_arguments)]
    fn assemble(
        &mut self,
        mesh: &impl Topology,
        dim: usize,
        u: &[f64],
        injected: f64,
        tangent: bool,
        residual: &mut [f64],
        values: &mut [f64],
    ) -> (f64, f64) {
        let s = u[self.dof];
        let p = self.k * s;
        let sign = self.sign;
        let (dvdu, normals, cell_slots) = (&mut self.dvdu, &mut self.normals, &self.cell_slots);
        dvdu.fill(0.0);
        normals.fill(0.0);
        let mut x = [0.0; 12];
        let mut volume = 0.0;
        let mut cell = 0;
        // One cell's volume v, gradient and Hessian (local dofs, node-major).
        let mut add_cell = |nodes: &[usize],
                            v: f64,
                            grad: &[f64],
                            hess: &dyn Fn(usize, usize) -> f64,
                            normal: &[f64]| {
            volume += v;
            let n = grad.len();
            for (k, (&g, &a)) in grad.iter().zip(normal).enumerate() {
                dvdu[dim * nodes[k / dim] + k % dim] += sign * g;
                normals[dim * nodes[k / dim] + k % dim] += sign * a;
            }
            if tangent {
                let slots = &cell_slots[cell..cell + n * n];
                for r in 0..n {
                    for c in 0..n {
                        let slot = slots[n * r + c];
                        if slot != NO_SLOT {
                            values[slot] -= p * sign * hess(r, c);
                        }
                    }
                }
            }
            cell += n * n;
        };
        match &self.cells {
            CavityCells::Segments(cells) => {
                for c in cells {
                    Self::positions(mesh, dim, u, c, &mut x);
                    let seg = [[x[0], x[1]], [x[2], x[3]]];
                    let (v, g, h) = segment_volume(&seg);
                    add_cell(c, v, &g, &|r, c| h[r][c], &segment_area_normals(&seg));
                }
            }
            CavityCells::Quads(cells) => {
                for c in cells {
                    Self::positions(mesh, dim, u, c, &mut x);
                    let quad = [
                        [x[0], x[1], x[2]],
                        [x[3], x[4], x[5]],
                        [x[6], x[7], x[8]],
                        [x[9], x[10], x[11]],
                    ];
                    let (v, g, h) = quad_volume(&quad);
                    add_cell(c, v, &g, &|r, c| h[r][c], &quad_area_normals(&quad));
                }
            }
        }
        let volume = self.sign * volume;
        for &(d, on_plane) in &self.loaded {
            residual[d] -= p * if on_plane {
                self.normals[d]
            } else {
                self.dvdu[d]
            };
        }
        for &(d, rs, sr) in &self.coupling {
            if tangent {
                values[rs] -= self.k * self.dvdu[d];
                if sr != NO_SLOT {
                    values[sr] -= self.k * self.dvdu[d];
                }
            }
        }
        residual[self.dof] = -self.k * (volume - self.v0 - injected)
            - self.k * self.k * s * self.v0 * self.compliance;
        if tangent {
            values[self.diagonal] -= self.k * self.k * self.v0 * self.compliance;
        }
        (p, volume)
    }
}

/// Adds one element's residual and tangent into the global arrays.
fn scatter<M: Material3, K: ElementKind<M>>(
    conn: &[usize],
    out: &K::Output,
    slots: &[usize],
    tangent: bool,
    residual: &mut [f64],
    values: &mut [f64],
    gross: &mut f64,
) {
    let dim = K::DIM;
    let nd = K::NODES * dim;
    let r = K::residual(out);
    for a in 0..nd {
        residual[dim * conn[a / dim] + a % dim] += r[a];
        *gross += r[a] * r[a];
        if tangent {
            let k = K::tangent_row(out, a);
            for b in 0..nd {
                let s = slots[nd * a + b];
                if s != NO_SLOT {
                    values[s] += k[b];
                }
            }
        }
    }
}

/// Step length of the next line-search trial after the trial at `alpha`
/// was rejected; `r0` and `r_alpha` are the residual vectors (either sign,
/// the same for both) at the start point and at the trial.
///
/// Safeguarded interpolation (Dennis & Schnabel, *Numerical Methods for
/// Unconstrained Optimization and Nonlinear Equations*, 1983, ch. 6), on the
/// residual vector instead of a scalar merit: along a Newton direction
/// (K du = −R₀), R(β) = (1 − β) R₀ + O(β²), so R(β) ≈ (1 − β) R₀ + β² Q with
/// Q fitted to the trial, Q = (R_α − (1 − α) R₀)/α². The next trial
/// minimises |R(β)|² = (1 − β)² a + 2 (1 − β) β² b + β⁴ c (a = |R₀|²,
/// b = R₀·Q, c = |Q|²) over the safeguard [0.1 α, 0.5 α] (on a grid of 41
/// points). Plain halving (session 2) kept the bad direction's second-order
/// term at ¼ of the trial's: where the residual rose 10–30× (the
/// near-incompressible solid under the first contact steps of the elastic
/// dome), it took 3–5 halvings, often to no decrease.
fn backtrack_step(r0: &[f64], r_alpha: &[f64], alpha: f64) -> f64 {
    let (mut a, mut b, mut c) = (0.0, 0.0, 0.0);
    for (&x0, &xa) in r0.iter().zip(r_alpha) {
        let q = (xa - (1.0 - alpha) * x0) / (alpha * alpha);
        a += x0 * x0;
        b += x0 * q;
        c += q * q;
    }
    let phi = |x: f64| {
        let y = 1.0 - x;
        y * y * a + 2.0 * y * x * x * b + x.powi(4) * c
    };
    let (lo, hi) = (0.1 * alpha, 0.5 * alpha);
    let mut best = (hi, phi(hi));
    for k in 0..40 {
        let x = lo + (hi - lo) * f64::from(k) / 40.0;
        let v = phi(x);
        if v < best.1 {
            best = (x, v);
        }
    }
    best.0
}

fn trace() -> bool {
    std::env::var_os("NLVID_FEM_TRACE").is_some()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shell::{ShellPart, ShellSpec, ellipsoidal_shell};

    #[test]
    fn backtrack_step_minimises_the_quadratic_residual_model_within_its_safeguard() {
        // R(β) = (1 − β) R₀ + β² Q with Q ⟂ R₀, |Q| = 9 |R₀|: the trial at
        // α = 1 gives Q; |R(β)|² = (1 − β)² + 81 β⁴ is least at β ≈ 0.1725.
        let r0 = [1.0, 0.0];
        let model = |beta: f64| [1.0 - beta, 9.0 * beta * beta];
        let beta = backtrack_step(&r0, &model(1.0), 1.0);
        assert!((beta - 0.1725).abs() < 0.011, "{beta}");
        // From a trial at α = 0.25 the same model gives the same minimiser
        // when it lies inside [0.025, 0.125]: here it does not (0.1725),
        // so the upper safeguard.
        assert_eq!(backtrack_step(&r0, &model(0.25), 0.25), 0.125);
        // A residual that hardly rises: the minimiser lies beyond α/2, so
        // the safeguard halves as before.
        let mild = |beta: f64| [1.0 - beta, 0.1 * beta * beta];
        assert_eq!(backtrack_step(&r0, &mild(1.0), 1.0), 0.5);
        // A huge rise: never below a tenth of the trial.
        let steep = |beta: f64| [1.0 - beta, 1e6 * beta * beta];
        assert!((backtrack_step(&r0, &steep(0.5), 0.5) - 0.05).abs() < 1e-15);
    }

    /// A coarse eighth of a spherical shell (R = 1 mm, wall 0.2 mm) on
    /// rollers, a plate above and a fluid cavity.
    fn shell_model(fluid: Fluid, symmetric: bool) -> Model<nlvid_material::MooneyRivlin, Solid> {
        let mesh = ellipsoidal_shell(&ShellSpec::sphere(
            1e-3,
            0.2e-3,
            2,
            0.6e-3,
            ShellPart::Eighth,
        ))
        .unwrap();
        let parts = Parts::eighth_capsule(fluid);
        let material = nlvid_material::MooneyRivlin::with_ratio(1e6, 0.3, 1e8).unwrap();
        let settings = Settings {
            symmetric,
            ..Settings::default()
        };
        Model::build(mesh, material, &parts, settings).unwrap()
    }

    /// Central differences of the assembled residual against the assembled
    /// tangent (full storage), over every free equation.
    fn check_tangent(fluid: Fluid) {
        let mut model = shell_model(fluid, false);
        let ctl = Control {
            plane_z: 0.93e-3,
            ..Control::default()
        };
        // A smooth, non-uniform displacement (flattening + bulge), a
        // pressure, supports respected.
        let nn = model.mesh.nodes.len();
        for a in 0..nn {
            let x = model.mesh.nodes[a];
            let w = [
                0.03 * x[0] * (1.0 + 300.0 * x[2]),
                0.02 * x[1] * (1.0 - 200.0 * x[0]),
                -0.05 * x[2] * (1.0 + 400.0 * x[1]),
            ];
            for i in 0..3 {
                model.u[3 * a + i] = w[i];
            }
        }
        model.apply_prescribed(&ctl);
        let sdof = model.cavity.as_ref().unwrap().dof;
        model.u[sdof] = 2e-5;
        model.assemble(&ctl, 0.0, true).unwrap();
        let neq = model.system.dim();
        let free: Vec<usize> = (0..model.u.len())
            .filter(|&d| model.dof_eq[d] != NO_SLOT)
            .collect();
        assert_eq!(free.len(), neq);
        let k = |r: usize, c: usize| {
            model
                .system
                .slot(r, c)
                .map(|s| model.system.values[s])
                .unwrap_or(0.0)
        };
        let kd: Vec<Vec<f64>> = (0..neq)
            .map(|r| (0..neq).map(|c| k(r, c)).collect())
            .collect();
        let kmax = kd.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
        let active = model
            .mesh
            .nodes_in("outer")
            .unwrap()
            .iter()
            .filter(|&&a| model.mesh.nodes[a][2] + model.u[3 * a + 2] > ctl.plane_z)
            .count();
        let u0 = model.u.clone();
        let h = 1e-9;
        for (c, &d) in free.iter().enumerate() {
            model.u.copy_from_slice(&u0);
            model.u[d] += h;
            model.assemble(&ctl, 0.0, false).unwrap();
            let rp = model.rhs.clone();
            model.u[d] -= 2.0 * h;
            model.assemble(&ctl, 0.0, false).unwrap();
            for r in 0..neq {
                let fd = -(rp[r] - model.rhs[r]) / (2.0 * h);
                assert!(
                    (fd - kd[r][c]).abs() < 1e-6 * kmax,
                    "K[{r}][{c}] = {} vs fd {fd} (kmax {kmax})",
                    kd[r][c]
                );
            }
        }
        // The check covered contact and the fluid coupling.
        assert!(kd.iter().all(|row| row.len() == neq));
        assert!(active > 0, "no node in contact");
    }

    /// The element loop in lanes (groups of four, serial or one group per
    /// task on two threads) against the same loop one element at a time:
    /// residual and tangent bitwise equal, for the cell material with a
    /// committed history and a time step, on a mesh whose element count is
    /// not a multiple of four (the short last group goes one by one).
    #[test]
    fn element_loop_in_lanes_is_bitwise_one_element_at_a_time() {
        let shear = nlvid_model::Relaxation::from_named(
            &nlvid_model::names::PRONY2,
            &[1.0, 0.3, 0.3, 0.5, 10.0],
        )
        .unwrap();
        let material = nlvid_material::PronyViscoelastic::cell(&shear, 1000.0).unwrap();
        let build = |threads: usize| {
            let mesh = crate::Mesh::graded_block(1.0, 0.8, 5, 3, 1.3).unwrap();
            let settings = Settings {
                threads,
                ..Settings::default()
            };
            let mut model: Model<_, Axisymmetric> =
                Model::build(mesh, material.clone(), &Parts::default(), settings).unwrap();
            assert_eq!(model.mesh.element_count() % 4, 3);
            assert!(
                !model.lane_geometry.is_empty(),
                "the cell material has lanes"
            );
            let ctl = Control::default();
            // A committed history at half the displacement, then a trial
            // step to the full one.
            for (scale, commit) in [(0.5, true), (1.0, false)] {
                for a in 0..model.mesh.node_count() {
                    let x = model.mesh.position(a);
                    model.u[2 * a] = scale * 0.04 * x[0] * (1.0 + x[1]);
                    model.u[2 * a + 1] = -scale * 0.06 * x[1] * (1.0 + 0.5 * x[0] * x[0]);
                }
                model.assemble(&ctl, 0.2, true).unwrap();
                if commit {
                    model.history.commit();
                }
            }
            model
        };
        let bits = |m: &Model<_, Axisymmetric>| -> Vec<u64> {
            m.residual
                .iter()
                .chain(&m.system.values)
                .map(|x| x.to_bits())
                .collect()
        };
        let ctl = Control::default();
        for threads in [1, 2] {
            let mut model = build(threads);
            let lanes = bits(&model);
            model.lane_geometry.clear();
            model.assemble(&ctl, 0.2, true).unwrap();
            assert!(
                lanes == bits(&model),
                "{threads} thread(s): lanes differ from one element at a time"
            );
        }
    }

    #[test]
    fn tangent_with_plate_and_incompressible_cavity_matches_finite_differences() {
        check_tangent(Fluid::Incompressible);
    }

    #[test]
    fn tangent_with_plate_and_compressible_cavity_matches_finite_differences() {
        check_tangent(Fluid::Compressible { bulk_modulus: 2e7 });
    }
}
