//! Finite-strain implicit finite elements: the cell-indentation model of
//! thesis §5.3 (axisymmetric F-bar solids, frictionless penalty contact with
//! a rigid sphere and a rigid plane, a linear spring — the AFM cantilever —
//! between the sphere and a prescribed point) and, on the same engine, 3D
//! solids for the capsules of ch. IV: 8-node F-bar hexahedra ([`hex`],
//! [`Mesh3`], `Model<M, Solid>`), symmetry rollers, rigid planes above and
//! below that allow separation, and an enclosed fluid cavity whose pressure
//! is an unknown ([`cavity`], [`Cavity`]); axisymmetric membrane elements
//! with the `material` crate's plane-stress update ([`membrane`],
//! `Model<M, Membrane>`, ch. II §2.5.2). Newton with line search and
//! adaptive time stepping with cut-backs (thesis §2.4, §4.3, §5.2.2, §5.3).
//! Capsule runs: plate programs (RH, RR, measured tables; [`plates`]), the
//! capsule's outputs per time (force, pressure, volume, contact area two
//! ways, loss of contact; [`capsule`]) and the deformed mesh as VTU
//! ([`vtu`]).
//!
//! Cost: one Newton iteration is one assembly (4 axisymmetric material
//! updates per element, optionally on several threads; near convergence
//! without the tangent) plus one sparse supernodal LDLᵀ factorisation of
//! the lower triangle, stored in the fill-reducing order so the symbolic
//! analysis is reused for the whole run (LU fallback); the thesis-scale AFM
//! run (912 elements graded to the contact, ≈ 220 steps with curves written
//! to 0.1 % at the samples, ≈ 900 iterations) takes ≈ 1.6–2.1 s of CPU
//! time on one (shared) core; see `docs/theory/fem.md` for the measured
//! breakdown.
//!
//! ```
//! use nlvid_fem::{Component, Control, Mesh, Model, ProbeDrive, Settings, SphereProbe, Stage, Support};
//! use nlvid_fem::reference::NeoHookean;
//!
//! // A 1 kPa block indented 20 nm by a 2.5 µm rigid sphere.
//! let mesh = Mesh::graded_block(20e-6, 20e-6, 12, 12, 20.0)?;
//! let probe = SphereProbe { radius: 2.5e-6, centre_z: 20e-6 + 2.5e-6, surface: "top".into() };
//! let supports = [Support::fixed("axis", Component::R), Support::fixed("base", Component::Z)];
//! let material = NeoHookean { mu: 1e3, kappa: 1e6 };
//! let mut model = Model::new(mesh, material, &supports, Some(probe), None, Settings::default())?;
//! let control = |t: f64| Control { probe: ProbeDrive::Displacement(-20e-9 * t), ..Control::default() };
//! model.run_stage(&Stage { name: "indent", end: 1.0, dt_initial: 0.5, dt_max: 0.5, control: &control })?;
//! let force = model.records().last().map(|r| r.contact_force).unwrap_or(0.0);
//! assert!(force > 0.0);
//! # Ok::<(), nlvid_fem::FemError>(())
//! ```

#![warn(missing_docs)]
// `!(x > 0.0)` is deliberate: it also rejects NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
// Small fixed-size kernels read best with explicit indices.
#![allow(clippy::needless_range_loop)]

pub mod afm;
pub mod capsule;
pub mod cavity;
mod contact;
pub mod dense;
pub mod element;
mod error;
mod fbar;
pub mod hex;
mod history;
mod kind;
mod ldlt;
mod local;
pub mod membrane;
pub mod mesh;
pub mod mesh3;
mod mesh_graded;
mod model;
pub mod plates;
pub mod reference;
mod sets;
pub mod shell;
mod sparse;
pub mod vtu;

pub use capsule::{CapsuleRecord, ContactPatch, Footprint, LiftOff, PatchSpec, Symmetry};
pub use error::{FemError, NonConvergence, Result};
pub use history::History;
pub use kind::{Axisymmetric, ElementKind, Solid, Topology};
pub use membrane::{Membrane, MembraneMesh, MembranePoint};
pub use mesh::Mesh;
pub use mesh_graded::ContactMesh;
pub use mesh3::Mesh3;
pub use model::{
    Cavity, Component, Control, Counters, Fluid, Model, Parts, PlaneSide, ProbeDrive, RigidPlane,
    Settings, SphereProbe, Stage, StepRecord, Support,
};
pub use plates::{PlateProgram, PlateRun, PlateSample, run_plate_program};
