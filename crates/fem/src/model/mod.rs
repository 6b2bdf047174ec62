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

mod assemble;
mod newton;
mod parts;
mod settings;
mod stepping;

pub use parts::{
    Cavity, Component, Control, Fluid, Parts, PlaneSide, ProbeDrive, RigidPlane, SphereProbe,
    Support,
};
pub use settings::Settings;
pub(crate) use stepping::check_output_times;
pub use stepping::{Counters, Stage, StepRecord};

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
    /// Times at which the caller will read the records by dense output
    /// (sorted; empty: every step is under output control). A step with
    /// no sample inside is neither shortened nor redone for its
    /// interpolation error (`Model::set_output_times`).
    output_times: Vec<f64>,
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
            output_times: Vec::new(),
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

    /// Sets [`Settings::easy_iterations`] for the stages run from now on
    /// (e.g. one stage whose Newton iterations do not fall with the step).
    pub fn set_easy_iterations(&mut self, iterations: usize) {
        self.settings.easy_iterations = iterations;
    }

    /// The settings the model was built with (and changed by the setters).
    pub fn settings(&self) -> &Settings {
        &self.settings
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
}

fn trace() -> bool {
    std::env::var_os("NLVID_FEM_TRACE").is_some()
}

#[cfg(test)]
mod tests {
    use super::newton::backtrack_step;
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
