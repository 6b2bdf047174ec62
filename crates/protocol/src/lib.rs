//! Loading programs and time grids (thesis §4.2, §5.2.2, Fig. 5.2, App.
//! A.1.2; membrane programs of §2.5.1, Figs. 2.13–2.14).
//!
//! A loading program is a piecewise-linear scalar history — piezo position
//! Z(t), plate displacement D(t), a set-point force, or a dimensionless
//! D/r0 — whose breakpoints are stored exactly, so forward models can step
//! onto every kink ([`Program::next_breakpoint`]) and label their output
//! by segment ([`Label`]: ramp-reverse cycle k, ramp, hold, ...).
//!
//! What is here:
//! - [`Program`] / [`ProgramBuilder`]: value(t), rate(t), breakpoints,
//!   labels, duration;
//! - [`programs`]: step, constant-rate, ramp-hold, ramp-reverse,
//!   loading–unloading at different rates;
//! - [`AfmScript`]: the AFM two-step script (force-controlled engagement,
//!   then three ramp-reverse cycles, a ramp and a hold), with
//!   [`Cantilever`] for F = k·d and [`indentation`] δ = Z − d;
//! - [`read_table`]: measured Z(t) (or F(t)) histories from CSV with
//!   unit-suffixed headers;
//! - [`ProtocolSettings`]: the study file's `[protocol]` section;
//! - grids: [`grid::uniform`] (e.g. the thesis's m = 5095 points),
//!   [`Program::stepper_grid`], [`Program::refined_grid`].
//!
//! Cost: evaluation is a binary search over segments, O(log n); grids are
//! O(points). Nothing here allocates per evaluation.
//!
//! ```
//! use nlvid_protocol::{AfmScript, Label, Leg};
//! let script = AfmScript::thesis_ch5(0.12)?;
//! let z = script.piezo()?;
//! // 0.2 + 0.1 s (10 µm/s), 0.2 + 0.2 s (5 µm/s), 1 + 1 s (1 µm/s),
//! // 0.1 s ramp back to 2 µm, 50 s hold.
//! assert!((z.duration() - 52.8).abs() < 1e-12);
//! assert_eq!(z.label(1.0), Label::RampReverse { cycle: 3, leg: Leg::Load });
//! assert!((z.value(0.2) - 2e-6).abs() < 1e-18);
//! assert!((script.engage.setpoint_force - 0.48e-9).abs() < 1e-20);
//! # Ok::<(), nlvid_protocol::ProtocolError>(())
//! ```

#![warn(missing_docs)]

mod afm;
mod error;
pub mod grid;
mod program;
pub mod programs;
mod section;
mod table;
pub mod units;

pub use afm::{AfmScript, Cantilever, Engage, indentation};
pub use error::{ProtocolError, Result};
pub use program::{Label, Leg, Program, ProgramBuilder, Quantity, Segment};
pub use section::{Loading, ProtocolSettings};
pub use table::{parse_table, read_table};
