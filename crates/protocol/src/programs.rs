//! Named loading programs of the thesis, all starting at `t = 0` from 0.
//!
//! - step and ramp-hold: relaxation tests (§2.5.1 Fig. 2.6; §4.2 RH tests);
//! - constant-rate loading (§2.5.1);
//! - ramp-reverse / loading–unloading at different rates (§2.5.1
//!   Figs. 2.13–2.14, §4.2 RR tests).
//!
//! Values are in the program's [`Quantity`]: SI for dimensional programs,
//! D/r0 and t0 = t/τ1 for the dimensionless membrane programs (eq. 2.47).

use crate::program::check_positive;
use crate::{Label, Program, ProgramBuilder, Quantity, Result};

/// Step to `amplitude` at `t = 0`, then hold for `hold` seconds.
///
/// # Errors
/// `amplitude` not finite, `hold` not finite and > 0.
pub fn step(quantity: Quantity, amplitude: f64, hold: f64) -> Result<Program> {
    ProgramBuilder::new(quantity, 0.0)
        .jump_to(amplitude)?
        .hold(hold, Label::Hold)?
        .build()
}

/// Constant-rate loading `v(t) = rate · t` for `duration` seconds.
///
/// # Errors
/// `rate` zero or not finite; `duration` not finite and > 0.
pub fn constant_rate(quantity: Quantity, rate: f64, duration: f64) -> Result<Program> {
    check_positive("duration", duration)?;
    check_positive("rate", rate.abs())?;
    ProgramBuilder::new(quantity, 0.0)
        .ramp_over(rate * duration, duration, Label::Ramp)?
        .build()
}

/// Ramp from 0 to `target` at speed `rate`, then hold for `hold` seconds.
///
/// # Errors
/// `target` zero or not finite; `rate`, `hold` not finite and > 0.
pub fn ramp_hold(quantity: Quantity, target: f64, rate: f64, hold: f64) -> Result<Program> {
    ProgramBuilder::new(quantity, 0.0)
        .ramp_to(target, rate, Label::Ramp)?
        .hold(hold, Label::Hold)?
        .build()
}

/// Loading–unloading (Figs. 2.13–2.14): from 0 to `peak` at `load_rate`,
/// then back to `end` at `unload_rate` (the thesis unloads to 0 at
/// s_u = 1 or 1/5 after loading at s_l = 1).
///
/// # Errors
/// `peak` equal to 0 or to `end`, or any rate not finite and > 0.
pub fn load_unload(
    quantity: Quantity,
    peak: f64,
    load_rate: f64,
    unload_rate: f64,
    end: f64,
) -> Result<Program> {
    ProgramBuilder::new(quantity, 0.0)
        .ramp_to(peak, load_rate, Label::Load)?
        .ramp_to(end, unload_rate, Label::Unload)?
        .build()
}

/// One ramp-reverse cycle from 0: up to `peak` at `rate`, back to `end` at
/// the same rate (the RR tests of §4.2).
///
/// # Errors
/// As [`load_unload`].
pub fn ramp_reverse(quantity: Quantity, peak: f64, rate: f64, end: f64) -> Result<Program> {
    ProgramBuilder::new(quantity, 0.0)
        .ramp_to(
            peak,
            rate,
            Label::RampReverse {
                cycle: 1,
                leg: crate::Leg::Load,
            },
        )?
        .ramp_to(
            end,
            rate,
            Label::RampReverse {
                cycle: 1,
                leg: crate::Leg::Unload,
            },
        )?
        .build()
}
