//! `model = "hertz-prony"`: the analytic Lee–Radok ramp-hold model of the
//! surrogate crate ([`HertzProny`]) with every setting from the study.

use nlvid_study::{Bounds, Dimension, Section};
use nlvid_surrogate::HertzProny;

use crate::error::Result;

/// Settings of the analytic linear-viscoelastic Hertz ramp-hold model.
#[derive(Debug, Clone, PartialEq)]
pub struct HertzPronySpec {
    /// Probe (sphere) radius R [m].
    pub probe_radius: f64,
    /// Indentation rate during the ramp [m/s].
    pub rate: f64,
    /// Ramp duration [s].
    pub ramp: f64,
    /// Hold duration after the ramp [s].
    pub hold: f64,
    /// Output points m, equally spaced in (0, ramp + hold].
    pub points: usize,
}

impl HertzPronySpec {
    /// The settings `nlvid build --model hertz-prony` uses without a study:
    /// R = 5 µm, 1 µm/s for 1 s, 9 s hold, `points` output points.
    pub fn flag_defaults(points: usize) -> Self {
        Self {
            probe_radius: 5e-6,
            rate: 1e-6,
            ramp: 1.0,
            hold: 9.0,
            points,
        }
    }

    /// Reads `probe_radius`, `rate`, `ramp`, `hold`, `points` from `[forward]`.
    ///
    /// # Errors
    /// Missing key, wrong unit or out-of-range value (file, line, key).
    pub fn from_section(s: &mut Section) -> Result<Self> {
        let pos = Bounds::positive();
        Ok(Self {
            probe_radius: s.req_quantity("probe_radius", Dimension::LENGTH, pos)?,
            rate: s.req_quantity("rate", Dimension::VELOCITY, pos)?,
            ramp: s.req_quantity("ramp", Dimension::TIME, pos)?,
            hold: s.req_quantity("hold", Dimension::TIME, Bounds::non_negative())?,
            points: s.req_usize("points", Bounds::closed(2.0, 1e7))?,
        })
    }

    /// The model.
    pub fn build(&self) -> HertzProny {
        HertzProny::new(
            self.probe_radius,
            self.rate,
            self.ramp,
            self.ramp + self.hold,
            self.points,
        )
    }
}
