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

#![warn(missing_docs)]

mod error;
pub mod point;

pub use error::{MaterialError, Result};
pub use point::{Mat3, Material3, MembraneMaterial, MembraneResponse, PointResponse3, Tangent3};
