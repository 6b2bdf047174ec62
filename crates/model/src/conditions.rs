//! What a meta-model was built for: the protocol (ramp time, hold, depth), time span and
//! geometry (probe radius, cell size) of the forward model behind it, stored in the
//! build's `meta.json` so that a fit can compare measured data with it before fitting
//! (issue 14; thesis §4.4.1: a meta-model is valid for one protocol and geometry).

use serde::{Deserialize, Serialize};

/// The build conditions of a forward model; `None` where the model has no such quantity.
/// Each quantity names the study key that sets it (`[forward] probe_radius`, …) so that
/// a mismatch can say what to change.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct BuildConditions {
    /// Forward model name (`hertz-prony`, `afm-fe`, …).
    pub model: String,
    /// Probe radius R, m.
    pub probe_radius_m: Option<f64>,
    /// Ramp (loading) time, s.
    pub ramp_time_s: Option<f64>,
    /// Hold after the ramp up to the grid's end, s.
    pub hold_time_s: Option<f64>,
    /// Travel of the ramp (indentation depth), m.
    pub depth_m: Option<f64>,
    /// Last time of the output grid, s.
    pub end_time_s: f64,
    /// Cell height, m.
    pub cell_height_m: Option<f64>,
    /// Cell diameter, m.
    pub cell_diameter_m: Option<f64>,
    /// `(quantity, study key)`: e.g. `("probe_radius_m", "[forward] probe_radius")`.
    pub keys: Vec<(String, String)>,
}

impl BuildConditions {
    /// The study key that sets `quantity` (a field name), or a generic hint.
    pub fn key(&self, quantity: &str) -> String {
        self.keys.iter().find(|(q, _)| q == quantity).map_or_else(
            || format!("the {} study's settings", self.model),
            |(_, k)| k.clone(),
        )
    }
}
