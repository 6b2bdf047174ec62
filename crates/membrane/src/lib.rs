//! Semi-analytical solver for a fluid-filled NLV membrane squeezed between rigid plates (thesis ch. II §2.3, App. C).

#![warn(missing_docs)]

mod error;
pub mod models;
mod shooting;
mod simulate;
mod solver;
pub mod thesis;

pub use error::{MembraneError, Result};
pub use models::{MooneyRivlinMembrane, PipkinRogersMembrane, PipkinRogersParams, PipkinRogersState};
pub use shooting::NodeValue;
pub use solver::{Control, Geometry, MembraneSolver, NewtonSettings, Solution};
pub use simulate::{ControlKind, Loading, MembraneRun, StepRecord, simulate, simulate_with};
