//! Output and stepping time grids.
//!
//! - [`uniform`]: `m` equally spaced points on `[t0, t1]`, both ends
//!   included (the thesis samples each response at m = 5095 times, §5.4).
//! - [`Program::stepper_grid`]: every breakpoint, with each segment cut
//!   into equal steps no longer than `max_dt`.
//! - [`Program::refined_grid`]: every breakpoint, steps growing
//!   geometrically from `min_dt` next to each breakpoint up to `max_dt`
//!   mid-segment — where a viscoelastic response changes fastest.

use crate::program::check_positive;
use crate::{Program, ProtocolError, Result};

/// `m` equally spaced times from `t0` to `t1` (both exact).
///
/// # Errors
/// `m < 2`, or `t1 ≤ t0`, or either end not finite.
pub fn uniform(t0: f64, t1: f64, m: usize) -> Result<Vec<f64>> {
    if m < 2 {
        return Err(ProtocolError::Parameter {
            name: "points",
            value: m as f64,
            reason: "a grid needs at least 2 points",
        });
    }
    if !(t0.is_finite() && t1.is_finite() && t1 > t0) {
        return Err(ProtocolError::Parameter {
            name: "end time",
            value: t1,
            reason: "must be finite and after the start time",
        });
    }
    let n = (m - 1) as f64;
    Ok((0..m)
        .map(|i| {
            let s = i as f64 / n;
            t0 * (1.0 - s) + t1 * s
        })
        .collect())
}

/// Offsets in `[0, len]`, symmetric about `len/2`, growing by `growth`
/// from the ends inward and capped at `max_dt`, then scaled by a factor
/// ≤ 1 so that the two halves meet exactly at `len/2`. Every step is
/// therefore ≤ `max_dt` and the first one ≤ `min_dt`; both ends are exact.
fn graded_offsets(len: f64, min_dt: f64, max_dt: f64, growth: f64) -> Vec<f64> {
    let half = 0.5 * len;
    let mut steps = Vec::new();
    let (mut sum, mut h) = (0.0, min_dt);
    while sum < half {
        steps.push(h);
        sum += h;
        h = (h * growth).min(max_dt);
    }
    let c = half / sum;
    let mut left = Vec::with_capacity(steps.len());
    let mut a = 0.0;
    for &h in &steps[..steps.len() - 1] {
        a += c * h;
        left.push(a);
    }
    let mut out = Vec::with_capacity(2 * left.len() + 3);
    out.push(0.0);
    out.extend_from_slice(&left);
    out.push(half);
    out.extend(left.iter().rev().map(|&x| len - x));
    out.push(len);
    out
}

impl Program {
    /// `m` equally spaced times over the whole program.
    ///
    /// # Errors
    /// `m < 2`.
    pub fn uniform_grid(&self, m: usize) -> Result<Vec<f64>> {
        uniform(self.start(), self.end(), m)
    }

    /// Every breakpoint plus equal subdivisions of each segment so that no
    /// step exceeds `max_dt`.
    ///
    /// # Errors
    /// `max_dt` not finite and > 0.
    pub fn stepper_grid(&self, max_dt: f64) -> Result<Vec<f64>> {
        check_positive("max_dt", max_dt)?;
        let bps = self.breakpoints();
        let mut out = vec![bps[0]];
        for w in bps.windows(2) {
            let (a, b) = (w[0], w[1]);
            // The slack keeps round-off in `b − a` (0.3 − 0.2 > 0.1) from
            // adding a step; a step may exceed max_dt by 1e-12 relative.
            let n = ((b - a) / max_dt * (1.0 - 1e-12)).ceil().max(1.0) as usize;
            for i in 1..n {
                let s = i as f64 / n as f64;
                out.push(a * (1.0 - s) + b * s);
            }
            out.push(b);
        }
        Ok(out)
    }

    /// Every breakpoint, with steps of `min_dt` next to each breakpoint
    /// growing by `growth` per step up to `max_dt`.
    ///
    /// # Errors
    /// `min_dt`, `max_dt` not finite and > 0, `max_dt < min_dt`, or
    /// `growth < 1`.
    pub fn refined_grid(&self, min_dt: f64, max_dt: f64, growth: f64) -> Result<Vec<f64>> {
        check_positive("min_dt", min_dt)?;
        check_positive("max_dt", max_dt)?;
        if max_dt < min_dt {
            return Err(ProtocolError::Parameter {
                name: "max_dt",
                value: max_dt,
                reason: "must be ≥ min_dt",
            });
        }
        if !(growth.is_finite() && growth >= 1.0) {
            return Err(ProtocolError::Parameter {
                name: "growth",
                value: growth,
                reason: "must be finite and ≥ 1",
            });
        }
        let bps = self.breakpoints();
        let mut out = vec![bps[0]];
        for w in bps.windows(2) {
            let (a, b) = (w[0], w[1]);
            let offs = graded_offsets(b - a, min_dt, max_dt, growth);
            for &o in &offs[1..offs.len() - 1] {
                out.push(a + o);
            }
            out.push(b);
        }
        Ok(out)
    }
}
