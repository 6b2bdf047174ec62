//! Piecewise-linear loading histories with exact breakpoints.
//!
//! A [`Program`] is a scalar history `v(t)` (piezo position, plate
//! displacement, set-point force, or a dimensionless D/r0) made of linear
//! [`Segment`]s. Segment ends are stored exactly as built, so a time stepper
//! that asks for [`Program::next_breakpoint`] lands on every kink instead of
//! smearing it over a step. A zero-length segment is a jump (a step load).
//!
//! Conventions:
//! - `value(t)` is right-continuous: at a jump it returns the value after
//!   the jump; `value_left(t)` returns the one before.
//! - `rate(t)` is the right derivative (the rate of the segment that starts
//!   at or contains `t`); `rate_left(t)` the left one.
//! - Outside `[start, end]` the program holds its first / last value
//!   (rate 0); use [`Program::contains`] to test the range.

use std::fmt;

use crate::{ProtocolError, Result};

/// What the program's value measures (sets the unit of its CSV column).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Quantity {
    /// A length in metres (piezo Z, plate displacement).
    Displacement,
    /// A force in newtons (AFM set-point force).
    Force,
    /// A pure number (e.g. D/r0 of ch. II, eq. 2.47).
    Dimensionless,
}

impl Quantity {
    /// SI unit symbol used in CSV headers ("" for dimensionless).
    pub fn si_unit(self) -> &'static str {
        match self {
            Quantity::Displacement => "m",
            Quantity::Force => "N",
            Quantity::Dimensionless => "",
        }
    }
}

/// Direction of one leg of a ramp-reverse (RR) cycle.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Leg {
    /// The loading leg (value increases: piezo moves toward the sample).
    Load,
    /// The reversal leg (value decreases: piezo retracts).
    Unload,
}

/// What a segment is, for output and for users reading a trace.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Label {
    /// A jump (zero-duration segment).
    Step,
    /// A constant-rate ramp.
    Ramp,
    /// A hold at constant value.
    Hold,
    /// Loading leg of a loading–unloading test (Figs. 2.13–2.14).
    Load,
    /// Unloading leg of a loading–unloading test.
    Unload,
    /// Leg of ramp-reverse cycle `cycle` (1-based) of the AFM script.
    RampReverse {
        /// 1-based cycle number.
        cycle: usize,
        /// Which leg of the cycle.
        leg: Leg,
    },
    /// AFM step 1: set-point force ramp that engages the probe.
    Engage,
    /// AFM step 1: hold at the engagement set point.
    EngageHold,
    /// Interval between two rows of a measured table.
    Tabulated,
}

impl fmt::Display for Label {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Label::Step => write!(f, "step"),
            Label::Ramp => write!(f, "ramp"),
            Label::Hold => write!(f, "hold"),
            Label::Load => write!(f, "load"),
            Label::Unload => write!(f, "unload"),
            Label::RampReverse { cycle, leg } => {
                let leg = match leg {
                    Leg::Load => "load",
                    Leg::Unload => "reverse",
                };
                write!(f, "ramp-reverse cycle {cycle} {leg}")
            }
            Label::Engage => write!(f, "engage"),
            Label::EngageHold => write!(f, "engage hold"),
            Label::Tabulated => write!(f, "tabulated"),
        }
    }
}

/// One linear piece `v(t) = v0 (1 − s) + v1 s`, `s = (t − t0)/(t1 − t0)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Segment {
    /// Start time, s.
    pub t0: f64,
    /// End time, s (equal to `t0` for a jump).
    pub t1: f64,
    /// Value at `t0` (after any jump that ends there).
    pub v0: f64,
    /// Value at `t1`.
    pub v1: f64,
    /// What the segment is.
    pub label: Label,
}

impl Segment {
    /// Duration `t1 − t0` (0 for a jump).
    pub fn duration(&self) -> f64 {
        self.t1 - self.t0
    }

    /// Constant rate `(v1 − v0)/(t1 − t0)`; 0 for a jump (its rate is a
    /// Dirac, which no caller can use).
    pub fn rate(&self) -> f64 {
        if self.t1 > self.t0 {
            (self.v1 - self.v0) / (self.t1 - self.t0)
        } else {
            0.0
        }
    }

    /// Whether this segment is a jump.
    pub fn is_jump(&self) -> bool {
        self.t1 == self.t0
    }

    /// Value at `t` in `[t0, t1]`; exact at both ends.
    fn eval(&self, t: f64) -> f64 {
        if self.is_jump() {
            return self.v1;
        }
        let s = (t - self.t0) / (self.t1 - self.t0);
        self.v0 * (1.0 - s) + self.v1 * s
    }
}

/// A piecewise-linear loading history; build it with [`ProgramBuilder`] or
/// one of the named programs in [`crate::programs`].
#[derive(Debug, Clone, PartialEq)]
pub struct Program {
    quantity: Quantity,
    segments: Vec<Segment>,
    /// Segments of positive duration, indices into `segments`, for lookup.
    timed: Vec<usize>,
    /// Sorted distinct segment ends.
    bps: Vec<f64>,
}

impl Program {
    /// What the value measures.
    pub fn quantity(&self) -> Quantity {
        self.quantity
    }

    /// All segments in time order (jumps included).
    pub fn segments(&self) -> &[Segment] {
        &self.segments
    }

    /// Start time, s.
    pub fn start(&self) -> f64 {
        self.segments[0].t0
    }

    /// End time, s.
    pub fn end(&self) -> f64 {
        self.segments[self.segments.len() - 1].t1
    }

    /// Total duration `end − start`, s.
    pub fn duration(&self) -> f64 {
        self.end() - self.start()
    }

    /// Whether `t` lies in `[start, end]`.
    pub fn contains(&self, t: f64) -> bool {
        t >= self.start() && t <= self.end()
    }

    /// Index into `segments` of the timed segment that governs `t` from the
    /// right: the last one with `t0 ≤ t` (clamped to the first / last).
    fn right_segment(&self, t: f64) -> &Segment {
        let k = self
            .timed
            .partition_point(|&i| self.segments[i].t0 <= t)
            .saturating_sub(1);
        &self.segments[self.timed[k]]
    }

    /// Timed segment that governs `t` from the left: the first with `t1 ≥ t`.
    fn left_segment(&self, t: f64) -> &Segment {
        let k = self
            .timed
            .partition_point(|&i| self.segments[i].t1 < t)
            .min(self.timed.len() - 1);
        &self.segments[self.timed[k]]
    }

    /// Value at `t` (right-continuous at jumps; held constant outside the
    /// program's range).
    pub fn value(&self, t: f64) -> f64 {
        if t < self.start() {
            return self.segments[0].v0;
        }
        if t >= self.end() {
            return self.segments[self.segments.len() - 1].v1;
        }
        let seg = self.right_segment(t);
        seg.eval(t.min(seg.t1))
    }

    /// Value just before `t` (differs from [`Program::value`] only at jumps).
    pub fn value_left(&self, t: f64) -> f64 {
        if t <= self.start() {
            return self.segments[0].v0;
        }
        if t > self.end() {
            return self.segments[self.segments.len() - 1].v1;
        }
        let seg = self.left_segment(t);
        seg.eval(t.max(seg.t0))
    }

    /// Rate dv/dt at `t`, from the right (0 outside the program).
    pub fn rate(&self, t: f64) -> f64 {
        if t < self.start() || t >= self.end() {
            return 0.0;
        }
        self.right_segment(t).rate()
    }

    /// Rate dv/dt just before `t` (0 outside the program).
    pub fn rate_left(&self, t: f64) -> f64 {
        if t <= self.start() || t > self.end() {
            return 0.0;
        }
        self.left_segment(t).rate()
    }

    /// Label of the segment that governs `t` from the right.
    pub fn label(&self, t: f64) -> Label {
        self.right_segment(t).label
    }

    /// Every time where the rate or the value may change: segment ends,
    /// sorted, without duplicates (a jump contributes one time).
    pub fn breakpoints(&self) -> &[f64] {
        &self.bps
    }

    /// The first breakpoint strictly after `t`, if any. Time steppers take
    /// `dt = dt.min(bp − t)` so they never step over a kink.
    pub fn next_breakpoint(&self, t: f64) -> Option<f64> {
        let k = self.bps.partition_point(|&b| b <= t);
        self.bps.get(k).copied()
    }

    /// Times of the jumps (zero-length segments).
    pub fn jumps(&self) -> Vec<f64> {
        self.segments
            .iter()
            .filter(|s| s.is_jump())
            .map(|s| s.t0)
            .collect()
    }

    /// Largest and smallest value reached.
    pub fn value_range(&self) -> (f64, f64) {
        let mut lo = f64::INFINITY;
        let mut hi = f64::NEG_INFINITY;
        for s in &self.segments {
            lo = lo.min(s.v0).min(s.v1);
            hi = hi.max(s.v0).max(s.v1);
        }
        (lo, hi)
    }

    /// Evaluate the program on `times`.
    pub fn sample(&self, times: &[f64]) -> Vec<f64> {
        times.iter().map(|&t| self.value(t)).collect()
    }
}

/// Builds a [`Program`] one segment at a time, starting at `(t0, v0)`.
///
/// ```
/// use nlvid_protocol::{Label, ProgramBuilder, Quantity};
/// // 0 → 2 µm at 10 µm/s, then hold 5 s.
/// let p = ProgramBuilder::new(Quantity::Displacement, 0.0)
///     .ramp_to(2e-6, 10e-6, Label::Ramp)?
///     .hold(5.0, Label::Hold)?
///     .build()?;
/// let bps = p.breakpoints();
/// assert_eq!(bps.len(), 3);
/// assert!((bps[1] - 0.2).abs() < 1e-15 && (bps[2] - 5.2).abs() < 1e-14);
/// assert!((p.value(0.1) - 1e-6).abs() < 1e-18);
/// # Ok::<(), nlvid_protocol::ProtocolError>(())
/// ```
#[derive(Debug, Clone)]
pub struct ProgramBuilder {
    quantity: Quantity,
    t: f64,
    v: f64,
    segments: Vec<Segment>,
}

fn check_finite(name: &'static str, value: f64) -> Result<()> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(ProtocolError::Parameter {
            name,
            value,
            reason: "must be a finite number",
        })
    }
}

pub(crate) fn check_positive(name: &'static str, value: f64) -> Result<()> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(ProtocolError::Parameter {
            name,
            value,
            reason: "must be finite and > 0",
        })
    }
}

impl ProgramBuilder {
    /// Start at time 0 with value `v0`.
    pub fn new(quantity: Quantity, v0: f64) -> Self {
        Self::starting_at(quantity, 0.0, v0)
    }

    /// Start at time `t0` with value `v0`.
    pub fn starting_at(quantity: Quantity, t0: f64, v0: f64) -> Self {
        Self {
            quantity,
            t: t0,
            v: v0,
            segments: Vec::new(),
        }
    }

    /// Current end time of the program being built.
    pub fn time(&self) -> f64 {
        self.t
    }

    /// Current end value of the program being built.
    pub fn value(&self) -> f64 {
        self.v
    }

    fn push(mut self, t1: f64, v1: f64, label: Label) -> Self {
        self.segments.push(Segment {
            t0: self.t,
            t1,
            v0: self.v,
            v1,
            label,
        });
        self.t = t1;
        self.v = v1;
        self
    }

    /// Ramp to `target` at speed `|rate|` (the sign is taken from the
    /// direction of travel).
    ///
    /// # Errors
    /// `rate` not finite and > 0 in magnitude, `target` not finite, or
    /// `target` equal to the current value (a ramp of zero duration).
    pub fn ramp_to(self, target: f64, rate: f64, label: Label) -> Result<Self> {
        check_finite("target", target)?;
        check_positive("rate", rate.abs())?;
        let dv = target - self.v;
        if dv == 0.0 {
            return Err(ProtocolError::Parameter {
                name: "target",
                value: target,
                reason: "equals the current value: a ramp to it has zero duration",
            });
        }
        let t1 = self.t + dv.abs() / rate.abs();
        Ok(self.push(t1, target, label))
    }

    /// Ramp by `delta` (signed) at speed `|rate|`.
    ///
    /// # Errors
    /// As [`ProgramBuilder::ramp_to`].
    pub fn ramp_by(self, delta: f64, rate: f64, label: Label) -> Result<Self> {
        let target = self.v + delta;
        self.ramp_to(target, rate, label)
    }

    /// Ramp linearly to `target` over `duration` seconds.
    ///
    /// # Errors
    /// `duration` not finite and > 0, `target` not finite.
    pub fn ramp_over(self, target: f64, duration: f64, label: Label) -> Result<Self> {
        check_finite("target", target)?;
        check_positive("duration", duration)?;
        let t1 = self.t + duration;
        Ok(self.push(t1, target, label))
    }

    /// Straight line to `(t1, target)`, with `t1` stored exactly (for
    /// tabulated histories whose rows are the breakpoints).
    ///
    /// # Errors
    /// `target` or `t1` not finite, or `t1` not after the current time.
    pub fn line_to(self, t1: f64, target: f64, label: Label) -> Result<Self> {
        check_finite("target", target)?;
        check_finite("time", t1)?;
        if t1 <= self.t {
            return Err(ProtocolError::Parameter {
                name: "time",
                value: t1,
                reason: "must be after the end of the previous segment",
            });
        }
        Ok(self.push(t1, target, label))
    }

    /// Hold the current value for `duration` seconds.
    ///
    /// # Errors
    /// `duration` not finite and > 0.
    pub fn hold(self, duration: f64, label: Label) -> Result<Self> {
        check_positive("duration", duration)?;
        let (t1, v) = (self.t + duration, self.v);
        Ok(self.push(t1, v, label))
    }

    /// Jump to `target` at the current time (a step).
    ///
    /// # Errors
    /// `target` not finite.
    pub fn jump_to(self, target: f64) -> Result<Self> {
        check_finite("target", target)?;
        let t = self.t;
        Ok(self.push(t, target, Label::Step))
    }

    /// Finish the program.
    ///
    /// # Errors
    /// [`ProtocolError::Empty`] if no segment has positive duration.
    pub fn build(self) -> Result<Program> {
        let timed: Vec<usize> = self
            .segments
            .iter()
            .enumerate()
            .filter(|(_, s)| !s.is_jump())
            .map(|(i, _)| i)
            .collect();
        if timed.is_empty() {
            return Err(ProtocolError::Empty);
        }
        let mut bps = Vec::with_capacity(timed.len() + 1);
        bps.push(self.segments[0].t0);
        for s in &self.segments {
            if s.t1 > bps[bps.len() - 1] {
                bps.push(s.t1);
            }
        }
        Ok(Program {
            quantity: self.quantity,
            segments: self.segments,
            timed,
            bps,
        })
    }
}
