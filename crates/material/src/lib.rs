//! Constitutive models of the thesis: the Pipkin–Rogers single-integral
//! non-linear viscoelastic (NLV) model (QLV as its special case, §2.2,
//! eqs. 2.1–2.2, 2.53–2.57) and finite-strain Prony-series viscoelasticity
//! with a Mooney–Rivlin / neo-Hookean elastic part (§4.3, eqs. 4.1–4.3,
//! App. D), as 3D and membrane (plane-stress) point updates that return the
//! stress and its consistent tangent.
//!
//! The contract every forward model codes against is in [`point`]:
//! [`Material3`] for solids and [`MembraneMaterial`] for membranes. History
//! lives in a per-point `State` that the caller owns; an update never
//! mutates the converged state, it writes the trial state, which the caller
//! commits once the global step converges.
//!
//! Cost: one update is O(number of Prony terms) (recursive update of the
//! exponential kernels) plus a fixed ~1.5 k flops for the 9×9 tangent.
//!
//! ```
//! use nlvid_material::{Mat3, Material3, MooneyRivlin};
//! let mr = MooneyRivlin::new(1000.0, 100.0, 1.0e6)?;
//! let state = Material3::initial_state(&mr);
//! let mut trial = state;
//! let f = Mat3::new(1.2, 0.0, 0.0, 0.0, 0.95, 0.0, 0.0, 0.0, 0.88);
//! let r = Material3::update(&mr, &state, &f, 0.0, &mut trial)?;
//! assert!(r.cauchy[(0, 0)] > 0.0);
//! # Ok::<(), nlvid_material::MaterialError>(())
//! ```

#![warn(missing_docs)]

mod error;
mod history;
pub mod homogeneous;
mod hyperelastic;
mod kernel;
pub(crate) mod model;
mod pipkin_rogers;
pub mod point;
mod prony;
mod prony_visco;
pub mod reference;
mod spec;

pub use error::{MaterialError, Result};
pub use history::HistoryRule;
pub use hyperelastic::MooneyRivlin;
pub use model::Incompressible;
pub use pipkin_rogers::{Eq256, PipkinRogers, PipkinRogersState};
pub use point::{Mat3, Material3, MembraneMaterial, MembraneResponse, PointResponse3, Tangent3};
pub use prony::{Prony, PronyTerm, Relaxation, ThreeParameterSolid};
pub use prony_visco::{PronyViscoelastic, PronyViscoelasticState};
pub use spec::{LoadingSpec, MaterialSpec, read_table};
