//! The finite-element model: mesh + material + supports + rigid bodies,
//! global assembly, Newton with line search and adaptive time stepping.
//!
//! Unknowns are the nodal displacements (u_r, u_z) and one vertical
//! displacement `w` of the rigid spherical probe. The probe is driven in one
//! of three ways ([`ProbeDrive`]): its displacement prescribed (rigid
//! cantilever), a force applied to it (force-controlled engagement), or a
//! linear spring between it and a prescribed point (the cantilever whose
//! free end follows the piezo). The total potential is
//!
//! ```text
//! Π = Σ_e ∫ Ψ(F̄) dV₀ + Σ_a ½ ε_a ⟨−g_a⟩² + ½ k (w − z_free)² + F w ,
//! ```
//!
//! g_a the gap between surface node a and the sphere (or plane), so the
//! tangent is the exact Hessian and symmetric for hyperelastic materials.

use crate::contact::{self, ContactSurface, Obstacle};
use crate::element::{ElementOutput, PointGeometry, TangentPart, element_geometry, fbar_element};
use crate::history::History;
use crate::sparse::{NO_SLOT, SparseSystem};
use crate::{FemError, NonConvergence, Result};
use nlvid_material::{Mat3, Material3};

/// Displacement component of a support.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Component {
    /// Radial.
    R,
    /// Axial.
    Z,
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

/// A rigid horizontal plane above the body (facing down), its height given
/// by [`Control::plane_z`], in frictionless penalty contact with a surface.
#[derive(Debug, Clone, PartialEq)]
pub struct RigidPlane {
    /// Ordered surface node set that may touch it.
    pub surface: String,
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
}

impl Default for Control {
    fn default() -> Self {
        Self {
            probe: ProbeDrive::Displacement(0.0),
            plane_z: f64::INFINITY,
            support_scale: 1.0,
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
    /// Newton iterations allowed per attempt.
    pub max_iterations: usize,
    /// Step halvings allowed in the line search.
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
    /// point turns out not converged. 0 disables. Default 1e4 (measured on
    /// the thesis run: 105 tangent assemblies saved, 3 redone).
    pub lazy_tangent: f64,
    /// Dense output: largest estimated interpolation error of the probe
    /// (or plane) force between steps, relative to the force (floor
    /// 1e-7 G L²); steps that exceed 1.5× it are redone smaller, and the
    /// next step is sized for it (module `dense`). 0 disables. Default
    /// 2e-4.
    pub output_tolerance: f64,
    /// Threads for the element loop (material updates); 0 or 1 = serial. The
    /// result is bitwise the same for any number (element outputs are
    /// computed in parallel, then added in element order).
    pub threads: usize,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            fbar: true,
            rtol: 1e-9,
            max_iterations: 14,
            line_search: 6,
            penalty: 100.0,
            growth: 1.5,
            easy_iterations: 4,
            cutback: 0.25,
            min_step_fraction: 1e-6,
            extrapolate: true,
            symmetric: true,
            residual_growth: 1.0,
            lazy_tangent: 1e4,
            output_tolerance: 2e-4,
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
    /// Upward force of the body on the plane (N).
    pub plane_force: f64,
    /// Deepest penetration into the probe (m, ≥ 0).
    pub penetration: f64,
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
    /// Numeric factorisations that fell back from LDLᵀ to LU.
    pub lu_fallbacks: usize,
}

#[derive(Debug, Default, Clone, Copy)]
struct Assembly {
    scale: f64,
    contact_force: f64,
    plane_force: f64,
    penetration: f64,
    active: usize,
}

/// Axisymmetric finite-strain model (see module docs).
pub struct Model<M: Material3> {
    mesh: crate::Mesh,
    material: M,
    settings: Settings,
    geometry: Vec<[PointGeometry; 4]>,
    history: History<M::State>,
    dof_eq: Vec<usize>,
    prescribed: Vec<(usize, f64)>,
    u: Vec<f64>,
    u_committed: Vec<f64>,
    u_previous: Vec<f64>,
    time: f64,
    last_dt: f64,
    elem_slots: Vec<usize>,
    probe: Option<(SphereProbe, ContactSurface)>,
    plane: Option<ContactSurface>,
    system: SparseSystem,
    residual: Vec<f64>,
    rhs: Vec<f64>,
    element_out: ElementOutput,
    /// Per-element outputs for the parallel element loop (empty if serial).
    element_outs: Vec<ElementOutput>,
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
    counters: Counters,
}

impl<M: Material3> std::fmt::Debug for Model<M> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "Model({} nodes, {} elements, {:?})",
            self.mesh.nodes.len(),
            self.mesh.elements.len(),
            self.system
        )
    }
}

impl<M: Material3> Model<M> {
    /// Builds the model: dof numbering, sparse pattern, symbolic LDLᵀ and LU,
    /// contact penalties.
    ///
    /// # Errors
    /// [`FemError::Mesh`] for a missing node set; [`FemError::Material`] if
    /// the material cannot be evaluated at F = I; [`FemError::Solver`] if
    /// the symbolic factorisation fails.
    pub fn new(
        mesh: crate::Mesh,
        material: M,
        supports: &[Support],
        probe: Option<SphereProbe>,
        plane: Option<RigidPlane>,
        settings: Settings,
    ) -> Result<Self> {
        let nn = mesh.nodes.len();
        let ndof = 2 * nn + 1;
        let wdof = 2 * nn;
        let mut constrained = vec![false; ndof];
        let mut prescribed = Vec::new();
        for s in supports {
            for &a in mesh.nodes_in(&s.set)? {
                let dof = 2 * a + usize::from(s.component == Component::Z);
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
        let elem_eqs = |conn: &[usize; 4]| -> Vec<usize> {
            (0..8).map(|k| dof_eq[2 * conn[k / 2] + k % 2]).collect()
        };
        let mut blocks: Vec<Vec<usize>> = Vec::with_capacity(mesh.elements.len() + 1);
        for conn in &mesh.elements {
            blocks.push(
                elem_eqs(conn)
                    .into_iter()
                    .filter(|&e| e != NO_SLOT)
                    .collect(),
            );
        }
        let probe_nodes = match &probe {
            Some(p) => mesh.nodes_in(&p.surface)?.to_vec(),
            None => Vec::new(),
        };
        let plane_nodes = match &plane {
            Some(p) => mesh.nodes_in(&p.surface)?.to_vec(),
            None => Vec::new(),
        };
        if probe.is_some() {
            // The probe couples with each surface segment's two nodes.
            blocks.extend(contact::blocks(&probe_nodes, &dof_eq, Some(dof_eq[wdof])));
            blocks.push(vec![dof_eq[wdof]]);
        }
        blocks.extend(contact::blocks(&plane_nodes, &dof_eq, None));
        let system = SparseSystem::new(neq, &blocks, settings.symmetric)?;
        let mut elem_slots = Vec::with_capacity(64 * mesh.elements.len());
        let mut tmp = Vec::with_capacity(64);
        for conn in &mesh.elements {
            system.block_slots(&elem_eqs(conn), &mut tmp)?;
            if settings.symmetric {
                // The element computes its lower triangle only
                // (`TangentPart::Lower`): entry (a, b), b ≤ a, goes to the
                // stored slot of the pair, whichever orientation is stored.
                for a in 0..8 {
                    for b in 0..8 {
                        elem_slots.push(if b > a {
                            NO_SLOT
                        } else if tmp[8 * a + b] != NO_SLOT {
                            tmp[8 * a + b]
                        } else {
                            tmp[8 * b + a]
                        });
                    }
                }
            } else {
                elem_slots.extend_from_slice(&tmp);
            }
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
        let probe = match probe {
            Some(p) => {
                let surface = ContactSurface::new(
                    &mesh.nodes,
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
        let plane = match plane {
            Some(_) => Some(ContactSurface::new(
                &mesh.nodes,
                &plane_nodes,
                &dof_eq,
                None,
                settings.penalty,
                g0,
                &system,
            )?),
            None => None,
        };
        let probe_diag = probe
            .as_ref()
            .map(|(_, s)| s.stiffness_scale())
            .unwrap_or(1.0)
            .max(f64::MIN_POSITIVE);
        let length = mesh
            .nodes
            .iter()
            .fold(0.0, |m: f64, p| m.max(p[0].abs()).max(p[1].abs()));
        let geometry = mesh
            .elements
            .iter()
            .map(|conn| element_geometry(&conn.map(|a| mesh.nodes[a])))
            .collect();
        let history = History::new(&material, 4 * mesh.elements.len());
        Ok(Self {
            geometry,
            history,
            dof_eq,
            prescribed,
            u: vec![0.0; ndof],
            u_committed: vec![0.0; ndof],
            u_previous: vec![0.0; ndof],
            time: 0.0,
            last_dt: 0.0,
            elem_slots,
            probe,
            plane,
            residual: vec![0.0; ndof],
            rhs: vec![0.0; neq],
            element_out: ElementOutput::zero(),
            element_outs: if settings.threads > 1 {
                vec![ElementOutput::zero(); mesh.elements.len()]
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
            records: Vec::new(),
            counters: Counters::default(),
            system,
            mesh,
            material,
            settings,
        })
    }

    /// The mesh.
    pub fn mesh(&self) -> &crate::Mesh {
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
        let wdof = 2 * self.mesh.nodes.len();
        self.u[wdof] = w;
        self.u_committed[wdof] = w;
        self.u_previous[wdof] = w;
    }

    /// Converged nodal displacements, (u_r, u_z) per node.
    pub fn displacements(&self) -> impl Iterator<Item = [f64; 2]> + '_ {
        self.u_committed[..2 * self.mesh.nodes.len()]
            .chunks_exact(2)
            .map(|c| [c[0], c[1]])
    }

    /// Converged probe displacement w (m).
    pub fn probe_displacement(&self) -> f64 {
        self.u_committed[2 * self.mesh.nodes.len()]
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
    /// [`FemError::Mesh`] for a missing set.
    pub fn reaction(&self, set: &str, component: Component) -> Result<f64> {
        let c = usize::from(component == Component::Z);
        Ok(self
            .mesh
            .nodes_in(set)?
            .iter()
            .map(|&a| self.residual[2 * a + c])
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
        if let Some(pool) = &self.pool {
            let (committed, trial) = self.history.split();
            let (mesh, material, geometry, u) =
                (&self.mesh, &self.material, &self.geometry, &self.u);
            let failures: Vec<Option<(usize, crate::element::PointFailure)>> = pool.install(|| {
                use rayon::prelude::*;
                self.element_outs
                    .par_iter_mut()
                    .zip(trial.par_chunks_mut(4))
                    .enumerate()
                    .map(|(e, (out, tr))| {
                        let conn = &mesh.elements[e];
                        let mut ue = [0.0; 8];
                        for k in 0..8 {
                            ue[k] = u[2 * conn[k / 2] + k % 2];
                        }
                        fbar_element(
                            material,
                            &geometry[e],
                            &ue,
                            &committed[4 * e..4 * e + 4],
                            tr,
                            dt,
                            fbar,
                            part,
                            out,
                        )
                        .err()
                        .map(|f| (e, f))
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
            for (e, conn) in self.mesh.elements.iter().enumerate() {
                let out = &self.element_outs[e];
                let slots = &self.elem_slots[64 * e..64 * e + 64];
                scatter(
                    conn,
                    out,
                    slots,
                    tangent,
                    &mut self.residual,
                    &mut self.system.values,
                    &mut gross,
                );
            }
        } else {
            for (e, conn) in self.mesh.elements.iter().enumerate() {
                let mut ue = [0.0; 8];
                for k in 0..8 {
                    ue[k] = self.u[2 * conn[k / 2] + k % 2];
                }
                let (committed, trial) = self.history.element(e);
                fbar_element(
                    &self.material,
                    &self.geometry[e],
                    &ue,
                    committed,
                    trial,
                    dt,
                    fbar,
                    part,
                    &mut self.element_out,
                )
                .map_err(|(point, source)| FemError::Material {
                    element: e,
                    point,
                    source,
                })?;
                let slots = &self.elem_slots[64 * e..64 * e + 64];
                scatter(
                    conn,
                    &self.element_out,
                    slots,
                    tangent,
                    &mut self.residual,
                    &mut self.system.values,
                    &mut gross,
                );
            }
        }
        self.counters.element_seconds += clock.elapsed().as_secs_f64();
        let mut asm = Assembly {
            scale: gross.sqrt(),
            ..Assembly::default()
        };
        let nn = self.mesh.nodes.len();
        let wdof = 2 * nn;
        let w_free = !matches!(ctl.probe, ProbeDrive::Displacement(_));
        if let Some((probe, surface)) = &mut self.probe {
            let sums = surface.assemble(
                &self.mesh.nodes,
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
        if let Some(surface) = &mut self.plane {
            let sums = surface.assemble(
                &self.mesh.nodes,
                &self.u,
                wdof,
                Obstacle::Plane { z: ctl.plane_z },
                false,
                tangent,
                &mut self.residual,
                &mut self.system.values,
            );
            asm.plane_force = sums.force;
            asm.scale = asm.scale.max(asm.plane_force.abs());
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
        (self.settings.rtol * asm.scale).max(self.force_floor)
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
            || norm <= self.settings.rtol * asm.scale
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
            self.u[2 * self.mesh.nodes.len()] = w;
        }
    }

    /// A force-driven probe that touches the body at most at a point (first
    /// touch) or not at all has no contact stiffness, and Newton cannot
    /// start there. Predictor: lower the probe to first contact and then by
    /// the Hertz depth of the set force on an incompressible half-space,
    /// δ = (3F / (16 G √R))^{2/3} (eq. 1.1 with E = 3G); Newton then starts
    /// in contact and converges from there.
    fn force_drive_predictor(&mut self, ctl: &Control) {
        let (ProbeDrive::Force(force), Some((probe, surface))) = (ctl.probe, &self.probe) else {
            return;
        };
        if !(force > 0.0) {
            return;
        }
        let wdof = 2 * self.mesh.nodes.len();
        let obstacle = Obstacle::Sphere {
            centre_z: probe.centre_z + self.u[wdof],
            radius: probe.radius,
        };
        let gap = surface.min_gap(&self.mesh.nodes, &self.u, obstacle);
        let depth = (3.0 * force / (16.0 * self.modulus * probe.radius.sqrt())).powf(2.0 / 3.0);
        // Touching (|gap| at round-off) or above: no usable stiffness yet.
        if gap.is_finite() && gap > -1e-3 * depth {
            self.u[wdof] -= gap + depth;
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
        let growth_limit = self.settings.residual_growth;
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
                let node = self
                    .mesh
                    .nodes
                    .get(dmax / 2)
                    .copied()
                    .unwrap_or([f64::NAN; 2]);
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
            let solved = self.system.solve(&mut du);
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
            let lazy = norm <= self.settings.lazy_tangent * tol;
            for _ in 0..=self.settings.line_search {
                self.add_increment(&du, alpha, &base);
                match self.assemble(ctl, dt, !lazy) {
                    Ok(a) => {
                        let n = self.rhs_norm();
                        // Monotone residual decrease by default: a full step
                        // that raises it is halved (measured: fewer
                        // iterations and cut-backs than accepting 10× rises).
                        let limit = if alpha == 1.0 {
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
                    }
                    Err(e) => last_err = e.to_string(),
                }
                alpha *= 0.5;
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
        self.records.push(StepRecord {
            time,
            probe_w: self.u[2 * self.mesh.nodes.len()],
            free_end,
            contact_force: asm.contact_force,
            plane_force: asm.plane_force,
            penetration: asm.penetration,
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
            if self.settings.extrapolate && !first && self.last_dt > 0.0 {
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
                    if ratio > 1.5 && dt > dt_min * (1.0 + 1e-9) {
                        if trace() {
                            eprintln!(
                                "reject t={t_new:.5} dt={dt:.3e} output error {ratio:.2} × tolerance"
                            );
                        }
                        self.counters.rejected_steps += 1;
                        self.u.copy_from_slice(&self.u_committed);
                        dt = dt_error.max(dt_min);
                        continue;
                    }
                    self.history.commit();
                    self.u_previous.copy_from_slice(&self.u_committed);
                    self.u_committed.copy_from_slice(&self.u);
                    self.time = t_new;
                    self.last_dt = dt;
                    first = false;
                    self.counters.steps += 1;
                    self.push_record(t_new, &ctl, &asm, iterations);
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
                    self.u.copy_from_slice(&self.u_committed);
                    if dt <= dt_min * (1.0 + 1e-9) {
                        // Leave the residual vector of the converged state.
                        let _ = self.assemble(&(stage.control)(self.time), 0.0, false);
                        return Err(FemError::NonConvergence(Box::new(NonConvergence {
                            // + 0.0: a clock started at −0.0 prints as 0.
                            time: self.time + 0.0,
                            dt,
                            residual,
                            tolerance,
                            iterations,
                            cause: format!("stage `{}`: {cause}", stage.name),
                        })));
                    }
                    dt = (dt * self.settings.cutback).max(dt_min);
                    first = true;
                }
            }
        }
        Ok(())
    }
}

/// Adds one element's residual and tangent into the global arrays.
fn scatter(
    conn: &[usize; 4],
    out: &ElementOutput,
    slots: &[usize],
    tangent: bool,
    residual: &mut [f64],
    values: &mut [f64],
    gross: &mut f64,
) {
    for a in 0..8 {
        residual[2 * conn[a / 2] + a % 2] += out.r[a];
        *gross += out.r[a] * out.r[a];
        if tangent {
            for b in 0..8 {
                let s = slots[8 * a + b];
                if s != NO_SLOT {
                    values[s] += out.k[a][b];
                }
            }
        }
    }
}

fn trace() -> bool {
    std::env::var_os("NLVID_FEM_TRACE").is_some()
}
