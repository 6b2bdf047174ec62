//! Measured AFM data: JPK instrument files, calibration, contact point, Hertz and
//! Lee–Radok fits (thesis §1.3.2, §5.2, App. B).
//!
//! What it models: an AFM force curve as recorded by the instrument — segments
//! (extend, hold = constant-height pause, creep = constant-force pause, retract), each with
//! its time axis and channels in SI units — and the small-strain analysis of such curves:
//! baseline correction, tip–sample separation, contact point, indentation δ = Z − d
//! (§5.2.2), the Hertz fit of a paraboloidal probe (eq. 1.1) and a linear-viscoelastic
//! Prony fit through the Lee–Radok hereditary integral. App. B.2 cell geometry helpers
//! (cell height, eq. B.1; base diameter √(d1·d2)) live in [`geometry`].
//!
//! Cost: reading a 10 000-point JPK file takes a few milliseconds (ZIP inflate + one pass
//! per channel); a Hertz fit is O(n) per contact-point trial; the Lee–Radok fit is
//! O(n) per objective evaluation (recursive exponential convolution), a few hundred
//! evaluations in all.
//!
//! ```no_run
//! use nlvid_afm::{read_force_curve, SegmentKind};
//! let curve = read_force_curve("fmt-jpk-fd_spot3-0192.jpk-force")?;
//! let extend = curve.segment(SegmentKind::Extend)?;
//! println!("k = {} N/m, {} points, first force {} N",
//!     curve.calibration.spring_constant, extend.len(), extend.force()?[0]);
//! # Ok::<(), nlvid_afm::AfmError>(())
//! ```
#![warn(missing_docs)]

mod curve;
mod error;
pub mod geometry;
mod hertz;
mod jpk;
mod lee_radok;
pub mod plot;
mod prepare;

pub use curve::{Calibration, CalibrationSource, Channel, ForceCurve, Segment, SegmentKind};
pub use error::{AfmError, Result};
pub use hertz::{
    Approach, HertzFit, HertzSettings, fit_hertz, hertz_baseline, hertz_force, prepare_approach,
};
pub use jpk::{
    ReadOptions, read_force_curve, read_force_curve_with, read_force_map, read_jpk_bytes,
};
pub use lee_radok::{
    LeeRadokFit, LeeRadokSettings, Prony, RampHold, fit_lee_radok, lee_radok_force,
    prepare_ramp_hold,
};
pub use prepare::{
    Baseline, ContactMethod, ContactPoint, contact_point, contact_point_from_baseline, indentation,
    tip_sample_separation,
};
