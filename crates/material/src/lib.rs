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
//! Models:
//! - [`MooneyRivlin`] (neo-Hookean when `C2 = 0`), eq. 4.1, with the
//!   isochoric/volumetric split and penalty `K J (J − 1)` (eqs. 2.50/D.5);
//! - [`PipkinRogers`], eqs. 2.1–2.2 with coefficients 2.53–2.55 and Prony
//!   `G1`, `G2` (App. D.3–D.4); [`PipkinRogers::qlv`] is the QLV case and
//!   [`PipkinRogers::from_eq_2_56`] ch. II's parametrisation;
//! - [`PronyViscoelastic`], the ABAQUS hereditary integral of §4.3 (capsules:
//!   [`PronyViscoelastic::capsule`], cells: [`PronyViscoelastic::cell`] from
//!   the shear relaxation modulus of eq. 5.1).
//!
//! Each implements [`Material3`], [`MembraneMaterial`] and [`Incompressible`]
//! (the extra stress used by the [`homogeneous`] drivers). Relaxation moduli
//! are the project's one Prony type, [`nlvid_model::Relaxation`] with
//! [`nlvid_model::Prony`] *weights* (eq. 4.2); ch. II's long-term *fractions*
//! (eq. 2.56) live only in [`ThreeParameterSolid`] and [`Eq256`]. Names
//! follow `docs/theory/model.md`: `G0` is a shear modulus, `C1`, `C2` the
//! constants of eq. 4.1 (`G0 = 2(C1 + C2)`), ch. II's G1(0) is `G10`. Study sections are read by
//! [`MaterialSpec`] and [`LoadingSpec`]. The choices made where the thesis is
//! ambiguous are in `docs/theory/material.md`.
//!
//! Cost: one update is O(number of Prony terms) (exact recursive update of
//! the exponential kernels, [`HistoryRule`]) plus ~1.5 k flops for the 9×9
//! tangent: about 0.3 µs per 3D update with tangent on one core. For
//! [`PronyViscoelastic`] the O(terms) part is done once per point and time
//! step: later updates of the same step (Newton iterations) into the same
//! trial state reuse it (a step cache in the state, validated by the
//! committed state's identity, Δt and the material). The
//! axisymmetric path [`Material3::update_axisymmetric`] returns only the
//! 5 components of `P` and the 5×5 block of the tangent an axisymmetric
//! element reads (no 9×9 matrix, no Cauchy stress; tangent optional); for
//! [`PronyViscoelastic`] it also runs four points at once, one per lane of
//! [`F64x4`] (`Material3::update_axisymmetric_lanes`, the same code generic
//! over [`Lane`], bitwise the one-point results). The
//! thesis's O(steps) trapezoidal sum (eq. 2.48) is kept in [`reference`].
//!
//! ```
//! use nlvid_material::{Mat3, Material3, PointState, PronyViscoelastic};
//! use nlvid_model::{Relaxation, names};
//! // The cell model of eq. 5.1: G0 = 1 kPa (so C1 = 500 Pa), g1 = 0.4, g2 = 0.3,
//! // τ1 = 0.5 s, τ2 = 10 s.
//! let g = Relaxation::from_named(&names::PRONY2, &[1000.0, 0.4, 0.3, 0.5, 10.0])?;
//! let cell = PronyViscoelastic::cell(&g, 5.0e5)?;
//! assert_eq!(cell.elastic().c1(), 500.0);
//! let mut state = PointState::initial_state(&cell);
//! let mut trial = state.clone();
//! let f = Mat3::new(1.2, 0.0, 0.0, 0.0, 0.913, 0.0, 0.0, 0.0, 0.913);
//! let r0 = Material3::update(&cell, &state, &f, 0.0, &mut trial)?; // step at t = 0
//! state = trial.clone();
//! let r1 = Material3::update(&cell, &state, &f, 100.0, &mut trial)?; // long after
//! // Relaxed to g∞ = 1 − 0.4 − 0.3 of the instantaneous deviatoric stress.
//! let dev = |s: &Mat3| s[(0, 0)] - s[(1, 1)];
//! assert!((dev(&r1.cauchy) / dev(&r0.cauchy) - 0.3).abs() < 1e-3);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#![warn(missing_docs)]

mod cube_root;
mod curve;
mod error;
mod history;
pub mod homogeneous;
mod hyperelastic;
mod kernel;
mod lane;
pub(crate) mod model;
mod pipkin_rogers;
pub mod point;
mod prony;
mod prony_visco;
pub mod reference;
mod spec;

pub use cube_root::cube_root;
pub use curve::samples_curve;
pub use error::{MaterialError, Result};
pub use history::HistoryRule;
pub use hyperelastic::MooneyRivlin;
pub use lane::{F64x4, Lane};
pub use model::Incompressible;
pub use pipkin_rogers::{Eq256, PipkinRogers, PipkinRogersState};
pub use point::{
    AXISYMMETRIC_COMPONENTS, AxisymmetricResponse, Mat3, Material3, MembraneMaterial,
    MembraneResponse, PointResponse3, PointState, Tangent3,
};
pub use prony::ThreeParameterSolid;
pub use prony_visco::{PronyViscoelastic, PronyViscoelasticState};
pub use spec::{LoadingSpec, MaterialSpec, read_table};
