//! The in-memory force curve: segments, per-segment time axes, channels in SI units.

use std::io::Write;

use crate::error::{AfmError, Result};

/// What the piezo does during a segment.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SegmentKind {
    /// Approach: the probe moves towards the sample (JPK style `extend`).
    Extend,
    /// Withdrawal (JPK style `retract`).
    Retract,
    /// Constant-height pause: stress relaxation (JPK `constant-height-pause`).
    Hold,
    /// Constant-force pause: creep (JPK `constant-force-pause`, force feedback on).
    Creep,
}

impl SegmentKind {
    /// Short lower-case name, as used in CSV output.
    pub fn as_str(self) -> &'static str {
        match self {
            SegmentKind::Extend => "extend",
            SegmentKind::Retract => "retract",
            SegmentKind::Hold => "hold",
            SegmentKind::Creep => "creep",
        }
    }
}

impl std::fmt::Display for SegmentKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// One recorded channel of one segment, converted to its physical unit.
#[derive(Debug, Clone, PartialEq)]
pub struct Channel {
    /// JPK channel name (`vDeflection`, `height`, `strainGaugeHeight`, ...).
    pub name: String,
    /// Unit of `values` (`N`, `m`, `V`, ...).
    pub unit: String,
    /// Conversion slot that produced `values` (`force`, `nominal`, `calibrated`, `volts`).
    pub conversion: String,
    /// The samples.
    pub values: Vec<f64>,
}

/// One segment of a force curve (extend, hold, retract...).
#[derive(Debug, Clone, PartialEq)]
pub struct Segment {
    /// Position in the file (0-based).
    pub index: usize,
    /// Piezo program of the segment.
    pub kind: SegmentKind,
    /// Instrument's segment name (`extend-spm`, `pause-spm`, ...).
    pub name: String,
    /// Duration of the recorded part, s.
    pub duration: f64,
    /// Sample times, s, counted from the start of the first segment.
    pub time: Vec<f64>,
    /// The channels, in file order.
    pub channels: Vec<Channel>,
}

/// Channel names JPK uses for the measured (closed-loop sensor) height, in order of preference.
const MEASURED_HEIGHT: [&str; 3] = [
    "strainGaugeHeight",
    "capacitiveSensorHeight",
    "measuredHeight",
];

impl Segment {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.time.len()
    }

    /// True if the segment holds no samples.
    pub fn is_empty(&self) -> bool {
        self.time.is_empty()
    }

    /// The channel called `name`.
    ///
    /// # Errors
    /// [`AfmError::MissingChannel`] if absent.
    pub fn channel(&self, name: &str) -> Result<&Channel> {
        self.channels
            .iter()
            .find(|c| c.name == name)
            .ok_or_else(|| AfmError::MissingChannel {
                segment: self.index,
                channel: name.to_string(),
                available: self
                    .channels
                    .iter()
                    .map(|c| c.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", "),
            })
    }

    /// Force on the probe, N (channel `vDeflection` through its force conversion;
    /// positive = repulsive, cantilever bent away from the sample).
    ///
    /// # Errors
    /// [`AfmError::MissingChannel`] if there is no `vDeflection`.
    pub fn force(&self) -> Result<&[f64]> {
        Ok(&self.channel("vDeflection")?.values)
    }

    /// Cantilever deflection d = F/k, m (positive = bent away from the sample), with k
    /// from `calibration` (thesis §5.2.2, F = k d).
    ///
    /// # Errors
    /// [`AfmError::MissingChannel`] if there is no `vDeflection`.
    pub fn deflection(&self, calibration: &Calibration) -> Result<Vec<f64>> {
        let k = calibration.spring_constant;
        Ok(self.force()?.iter().map(|f| f / k).collect())
    }

    /// Piezo height, m (channel `height`, open-loop actuator signal; `head-height` on
    /// instruments that move the head).
    ///
    /// # Errors
    /// [`AfmError::MissingChannel`] if neither is present.
    pub fn height_piezo(&self) -> Result<&[f64]> {
        match self.channel("height") {
            Ok(c) => Ok(&c.values),
            Err(e) => self
                .channel("head-height")
                .map(|c| c.values.as_slice())
                .map_err(|_| e),
        }
    }

    /// Measured height, m (`strainGaugeHeight` or `capacitiveSensorHeight`), falling back
    /// to the piezo `height` when the file has no sensor channel. JPK heights grow away
    /// from the sample.
    ///
    /// # Errors
    /// [`AfmError::MissingChannel`] if no height channel exists.
    pub fn height(&self) -> Result<&[f64]> {
        for name in MEASURED_HEIGHT {
            if let Ok(c) = self.channel(name) {
                return Ok(&c.values);
            }
        }
        self.height_piezo()
    }
}

/// Where the deflection calibration came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CalibrationSource {
    /// Read from the file's conversion set.
    File,
    /// Given by the user (study file or command line), replacing the file's value.
    Override,
}

/// Cantilever calibration used to turn photodiode volts into force.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Calibration {
    /// Spring constant k, N/m.
    pub spring_constant: f64,
    /// Deflection sensitivity, m/V.
    pub sensitivity: f64,
    /// Origin of `spring_constant`.
    pub spring_constant_source: CalibrationSource,
    /// Origin of `sensitivity`.
    pub sensitivity_source: CalibrationSource,
}

/// A force curve read from an instrument file.
#[derive(Debug, Clone, PartialEq)]
pub struct ForceCurve {
    /// File (and, for maps, curve index) the curve came from.
    pub source: String,
    /// JPK `file-format-version` (`0.12`, `2.0`, ...).
    pub format_version: String,
    /// Instrument name from the header, if given.
    pub instrument: Option<String>,
    /// Lateral position (x, y) of the curve, m, if given.
    pub position: Option<(f64, f64)>,
    /// Calibration of the vertical deflection.
    pub calibration: Calibration,
    /// The segments, in recording order.
    pub segments: Vec<Segment>,
}

impl ForceCurve {
    /// The first extend segment's index and the segment right after it,
    /// which must be of `kind` (`what` names it in the error).
    ///
    /// # Errors
    /// [`AfmError::MissingSegment`] without an extend, or when the next
    /// segment is not of `kind`.
    pub fn extend_then(&self, kind: SegmentKind, what: &str) -> Result<(usize, &Segment)> {
        let ext_i = (self.segments.iter())
            .position(|s| s.kind == SegmentKind::Extend)
            .ok_or_else(|| AfmError::MissingSegment {
                kind: "extend".into(),
            })?;
        let next = self.segments[ext_i + 1..]
            .first()
            .filter(|s| s.kind == kind)
            .ok_or_else(|| AfmError::MissingSegment { kind: what.into() })?;
        Ok((ext_i, next))
    }

    /// First segment of the given kind.
    ///
    /// # Errors
    /// [`AfmError::MissingSegment`] if none.
    pub fn segment(&self, kind: SegmentKind) -> Result<&Segment> {
        self.segments
            .iter()
            .find(|s| s.kind == kind)
            .ok_or_else(|| AfmError::MissingSegment {
                kind: kind.to_string(),
            })
    }

    /// Total number of samples over all segments.
    pub fn len(&self) -> usize {
        self.segments.iter().map(Segment::len).sum()
    }

    /// True if no segment holds samples.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Write all segments as CSV with unit-suffixed headers:
    /// `segment,kind,time_s,<channel>_<unit>,...`, one row per sample. Channels that a
    /// segment lacks are left empty. Values use Rust's shortest round-trip scientific format (`2.878322343068329e-5`).
    ///
    /// # Errors
    /// [`AfmError::Io`] if writing fails.
    pub fn write_csv<W: Write>(&self, mut out: W) -> Result<()> {
        let mut columns: Vec<(String, String)> = Vec::new();
        for seg in &self.segments {
            for c in &seg.channels {
                if !columns.iter().any(|(n, _)| *n == c.name) {
                    columns.push((c.name.clone(), c.unit.clone()));
                }
            }
        }
        let io = |source| AfmError::Io {
            path: "<csv output>".into(),
            source,
        };
        let mut line = String::from("segment,kind,time_s");
        for (name, unit) in &columns {
            line.push(',');
            line.push_str(name);
            line.push('_');
            line.push_str(&unit.replace('/', "_per_"));
        }
        writeln!(out, "{line}").map_err(io)?;
        for seg in &self.segments {
            let cols: Vec<Option<&Channel>> = columns
                .iter()
                .map(|(n, _)| seg.channels.iter().find(|c| c.name == *n))
                .collect();
            for (i, t) in seg.time.iter().enumerate() {
                line.clear();
                line.push_str(&format!("{},{},{t}", seg.index, seg.kind));
                for c in &cols {
                    line.push(',');
                    if let Some(v) = c.and_then(|c| c.values.get(i)) {
                        line.push_str(&format!("{v:e}"));
                    }
                }
                writeln!(out, "{line}").map_err(io)?;
            }
        }
        Ok(())
    }
}
