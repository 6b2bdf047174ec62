//! Semi-analytical solver for a fluid-filled NLV membrane squeezed between
//! two smooth rigid plates (thesis ch. II §2.3, §2.5, App. C).
//!
//! A spherical membrane (radius r0, thickness h0 ≪ r0) filled with an
//! incompressible fluid is inflated to r_s and pressed by two frictionless
//! parallel plates. By symmetry only 0 ≤ ψ ≤ π/2 is solved: a flat contact
//! region 0 ≤ ψ ≤ ψc and a free region ψc ≤ ψ ≤ π/2 (eqs. 2.33–2.39), with
//! the crown conditions 2.40–2.41, the equator condition 2.42, constant
//! volume (2.45–2.46) and displacement (2.43) or force (2.44) control. At each
//! time the equations are integrated from the crown by RK4 on a fixed grid of
//! material nodes and Newton finds (λ0, ψc, p); histories are stored at the
//! nodes and advanced by the material's recursive update (eq. 2.48).
//!
//! Any [`nlvid_material::MembraneMaterial`] can be used; [`models`] holds an
//! incompressible Mooney–Rivlin membrane and the ch. II Pipkin–Rogers
//! membrane (eqs. 2.53–2.56, a thin adapter over
//! [`nlvid_material::PipkinRogers`]); [`thesis`] regenerates the data of
//! Figs. 2.3–2.14 and Table 2.1 and [`plot`] draws them as SVG. Everything is dimensionless (eq. 2.47):
//! F̄ = F/(G10 h0 r0), p̄ = p r0/(G10 h0), t0 = t/τ1.
//!
//! Cost: one shot is O(nodes) material updates (×2 for blended histories);
//! a time step takes 3–8 shots; the Fig. 2.6 relaxation run (101 steps,
//! 64 intervals) takes ≈ 0.35 s of CPU on one core (see
//! `benches/relaxation.rs`).
//!
//! ```
//! use nlvid_membrane::{Control, Geometry, MembraneSolver, MooneyRivlinMembrane};
//! // Mooney–Rivlin membrane, γ = 0.1, inflated to r_s = 1.03, squeezed to D/r0 = 0.78.
//! let m = MooneyRivlinMembrane::new(1.0, 0.1)?;
//! let mut solver = MembraneSolver::new(m, Geometry::default(), 1.0)?;
//! let sol = solver.equilibrium(0.0, Control::Displacement(0.78))?.record;
//! assert!((sol.psi_c - 1.2917).abs() < 2e-3); // §2.5.1
//! // The flat frictionless contact carries exactly the fluid pressure.
//! let f = std::f64::consts::PI * sol.contact_radius.powi(2) * sol.pressure;
//! assert!((sol.force - f).abs() < 1e-12 * f);
//! # Ok::<(), nlvid_membrane::MembraneError>(())
//! ```
//!
//! For time-dependent runs use [`simulate`] (parameters, geometry and a
//! [`Loading`] in, F(t), ψc(t), p(t), H1(t) and profiles out).

#![warn(missing_docs)]
// `!(x > 0.0)` is used on purpose: it rejects NaN as well as non-positive values.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
// Small fixed-size numeric kernels read better with explicit indices.
#![allow(clippy::needless_range_loop)]

mod error;
pub mod models;
pub mod plot;
mod shooting;
mod simulate;
mod solver;
mod tables;
pub mod thesis;
pub use tables::{reproduction_files, table2_1_csv, table2_1_text};

pub use error::{MembraneError, Result};
pub use models::{
    MooneyRivlinMembrane, PipkinRogersMembrane, PipkinRogersParams, PipkinRogersState,
};
pub use shooting::NodeValue;
pub use simulate::{ControlKind, Loading, MembraneRun, run_loading, simulate, simulate_with};
pub use solver::{Control, Geometry, MembraneSolver, NewtonSettings, Solution, StepRecord};
