//! Measured AFM data: JPK instrument files (single curves, force maps, QI) and Asylum
//! Research `.ibw` curves, calibration, contact point, elastic (Hertz–Sneddon) fits for
//! five indenters, Lee–Radok relaxation and creep fits, batches over folders (thesis
//! §1.3.2, §5.2, App. B).
//!
//! What it models: an AFM force curve as recorded by the instrument — segments
//! (extend, hold = constant-height pause, creep = constant-force pause, retract), each with
//! its time axis and channels in SI units — and the small-strain analysis of such curves:
//! baseline correction, tip–sample separation, contact point, indentation δ = Z − d
//! (§5.2.2), elastic fits (paraboloid, eq. 1.1; exact sphere, cone, pyramid, flat punch:
//! [`Indenter`]) with fit ranges relative to the contact and warnings, and
//! linear-viscoelastic Prony fits through the Lee–Radok hereditary integral (the kernel
//! of `nlvid-forward`, the relaxation modulus of `nlvid-model`), in
//! displacement control (relaxation) and in force control (creep, [`fit_creep`]).
//! [`batch::for_each_curve`] runs any per-curve analysis over files, maps and folders in
//! parallel and lists every curve that failed with its reason. App. B.2 cell geometry
//! helpers (cell height, eq. B.1; base diameter √(d1·d2)) live in [`geometry`].
//!
//! Cost: reading a 10 000-point JPK file takes a few milliseconds (ZIP inflate + one pass
//! per channel); an elastic fit is O(samples in contact) per contact-point trial, ~450
//! trials; the Lee–Radok and creep fits are O(n) per objective evaluation (recursive
//! exponential convolution). A batch of 1000 public curves costs ~2.4 s of CPU.
//!
//! ```
//! use nlvid_afm::{ContactMethod, HertzSettings, SegmentKind, fit_hertz, prepare_approach, read_force_curve};
//! let path = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/fmt-jpk-fd_spot3-0192.jpk-force");
//! let curve = read_force_curve(path)?;
//! let extend = curve.segment(SegmentKind::Extend)?;
//! assert_eq!(extend.len(), 2000);
//! assert_eq!(extend.force()?[0], -5.145579192349918e-10); // N
//!
//! // paraboloidal Hertz fit, R = 40 nm, ν = 0.5 (eq. 1.1)
//! let approach = prepare_approach(&curve, ContactMethod::default())?;
//! let fit = fit_hertz(&approach.separation, &approach.force, &HertzSettings::new(40e-9, 0.5))?;
//! assert!((fit.youngs_modulus / 233.1e3 - 1.0).abs() < 0.01);
//! # Ok::<(), nlvid_afm::AfmError>(())
//! ```
#![warn(missing_docs)]

pub mod batch;
mod creep;
mod curve;
mod error;
pub mod geometry;
mod hertz;
mod ibw;
mod indenter;
mod inspect;
mod jpk;
mod lee_radok;
pub mod plot;
mod prepare;
mod ramp_hold;
mod varpro;

pub use batch::{
    Batch, BatchRow, CurveFailure, NoProgress, Progress, expand_inputs, for_each_curve,
    for_each_curve_with,
};
pub use creep::{
    Compliance, Creep, CreepFit, CreepSettings, creep_indentation, creep_objective, fit_creep,
    prepare_creep,
};
pub use curve::{Calibration, CalibrationSource, Channel, ForceCurve, Segment, SegmentKind};
pub use error::{AfmError, Result};
pub use hertz::{
    Approach, ApproachFit, FitRange, FitWarning, HertzFit, HertzSettings, fit_approach, fit_curve,
    fit_hertz, fit_warnings, hertz_baseline, modulus_vs_depth, prepare_approach,
};
pub use ibw::read_ibw_bytes;
pub use indenter::{Indenter, Validity, hertz_force};
pub use inspect::{
    InspectRow, Inspection, QuickFit, QuickFitKind, batch_csv, batch_json, batch_warnings,
    inspect_batch, inspect_row, quick_fit, range, summary_json, summary_text, write_plot,
};
pub use jpk::{
    JpkArchive, ReadOptions, read_force_curve, read_force_curve_with, read_force_map,
    read_jpk_bytes, read_jpk_each,
};
pub use lee_radok::{
    LeeRadokFit, LeeRadokSettings, RampHold, fit_lee_radok, fit_lee_radok_from, prepare_ramp_hold,
};
pub use prepare::{
    Baseline, ContactMethod, ContactPoint, approach_baseline, contact_point,
    contact_point_from_baseline, indentation, tip_sample_separation,
};
pub use ramp_hold::{read_ramp_hold, read_ramp_hold_curve};
pub use varpro::Multistart;
