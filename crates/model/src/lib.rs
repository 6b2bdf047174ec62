//! The shared vocabulary of nlvid: what every pipeline stage means by a
//! parameter name, a relaxation modulus, a parameter domain, a forward
//! model and a curve. Every other crate speaks these types; none defines
//! its own copy.
//!
//! # One convention for the moduli
//!
//! | name | quantity | thesis |
//! |---|---|---|
//! | `G0` | instantaneous **shear** modulus G(0) (Pa) of eq. 5.1 | §5.4.1, Table 5.3 |
//! | `C1`, `C2` | Mooney–Rivlin constants of eq. 4.1, W = C1(Ī1 − 3) + C2(Ī2 − 3) (ABAQUS's C10, C01) | eq. 4.1, Table 4.1 |
//! | `alpha` | C2 / C1 (eq. 4.1) | Table 4.1 |
//! | `G10` | ch. II's instantaneous Pipkin–Rogers modulus G1(0) (§2.5's "C1 = G1(0)") | eqs. 2.53–2.56 |
//! | `gk`, `tauk` | Prony weights g_k and relaxation times τ_k (eqs. 4.2, 5.1) | — |
//!
//! For a Mooney–Rivlin solid the small-strain shear modulus is
//! G0 = 2(C1 + C2); a neo-Hookean cell of shear modulus G0 has C1 = G0/2.
//! Ch. II writes the same material with σ = −qI + (C1 + I1C2)B − C2B²
//! (eq. 2.4), whose "C1" is twice the C1 of eq. 4.1 and equals the shear
//! modulus of a neo-Hookean membrane. Ch. II's G1(0) (eqs. 2.53–2.56,
//! which keep eq. 4.1's factor 2) is `G10` here: the eq. 4.1 C1 of the
//! instantaneous response, half of eq. 2.4's "C1". The
//! argument for reading Table 5.3's numbers as G0 is in
//! `docs/theory/model.md`; [`names`] holds the names and their units.
//!
//! # Contents
//! - [`Relaxation`] and [`Prony`]: G(t) = G0 [g∞ + Σ g_k e^{−t/τ_k}]
//!   (eqs. 4.2–4.3, 5.1), the one Prony type.
//! - [`Domain`]: named, bounded, scaled parameters with linear constraints
//!   such as g1 + g2 < 1, in one order; every meta-model stores it.
//! - [`ForwardModel`]: parameters → response on a fixed time grid.
//! - [`Curve`]: time plus named channels with units.
#![warn(missing_docs)]

mod conditions;
mod curve;
mod domain;
mod error;
mod forward;
pub mod names;
mod prony;

pub use conditions::BuildConditions;
pub use curve::{Channel, Curve, parameters_json, unit_suffixed};
pub use domain::{BoundHit, BoundSide, Domain, LinearConstraint, Parameter, Scale};
pub use error::{ModelError, Result};
pub use forward::{FailureKind, ForwardModel, RunFailure};
pub use prony::{ModulusPoint, Prony, PronyTerm, Relaxation};
