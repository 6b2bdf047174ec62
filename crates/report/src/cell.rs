//! One cell: read its AFM curve, fit the five Prony parameters (G0, g1,
//! τ1, g2, τ2; eq. 5.1, Table 5.3 domain) with the misfit of eq. 5.3, and
//! keep everything the results table and the report need.
//!
//! A cell never makes the cohort fail: unreadable data, a curve that does
//! not cover the fitted window, or a fit that does not converge give a
//! [`CellResult`] with status `failed` and the reason.

use std::path::Path;

use nlvid_inverse::{
    AfmColumns, BoundSide, Calibration, Domain, Experiment, LeeRadokHertz, Misfit, Model,
    MultiStart, ramp_hold_grid,
};
use serde::{Deserialize, Serialize};

use crate::settings::{CohortSettings, ForwardModel};

/// Outcome class of a cell.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum CellStatus {
    /// Fitted; flags may still carry warnings.
    Ok,
    /// Fitted, but the fit is poor (misfit above `fit.suspicious_misfit`):
    /// listed, excluded from group statistics.
    Suspicious,
    /// Not fitted (bad data or no convergence): listed with the reason.
    Failed,
}

impl CellStatus {
    /// The word written in the `status` column.
    pub fn as_str(&self) -> &'static str {
        match self {
            CellStatus::Ok => "ok",
            CellStatus::Suspicious => "suspicious",
            CellStatus::Failed => "failed",
        }
    }
}

/// A fitted parameter with its SI unit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ParamValue {
    /// Name (`G0`, `g1`, `tau1`, …).
    pub name: String,
    /// SI unit (`Pa`, `s`, or empty).
    pub unit: String,
    /// Value in SI.
    pub value: f64,
}

/// Everything known about one cell after its fit (also the per-cell result
/// file of a cohort run, as JSON).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CellResult {
    /// Group name.
    pub group: String,
    /// Data file, relative to the cohort input (folder or manifest).
    pub file: String,
    /// Cell identifier (the file stem).
    pub cell: String,
    /// Hash of the study the cell was fitted with.
    pub study_hash: String,
    /// Outcome.
    pub status: CellStatus,
    /// Why the cell is suspicious or failed (empty when ok).
    pub reason: String,
    /// Warnings: parameters on a bound, alternative optima, failed starts.
    pub flags: Vec<String>,
    /// Best parameters (empty when failed).
    pub parameters: Vec<ParamValue>,
    /// Misfit of eq. 5.3 at the best parameters.
    pub misfit: Option<f64>,
    /// Distinct optima within the misfit tolerance besides the best.
    pub alternatives: usize,
    /// Peak measured force in the fitted window, N.
    pub peak_force: Option<f64>,
    /// Relaxation at the end of the hold of the peak-normalised measured
    /// curve, 1 − F(t_end)/F_peak (fraction; Figs. 5.6–5.8).
    pub relaxation: Option<f64>,
    /// Model time grid, s (empty if the data could not be read).
    pub times: Vec<f64>,
    /// Measured force resampled on the grid, N.
    pub data: Vec<f64>,
    /// Fitted force on the grid, N (empty when failed).
    pub fit: Vec<f64>,
}

impl CellResult {
    fn failed(group: &str, file: &str, cell: &str, hash: &str, reason: String) -> Self {
        Self {
            group: group.into(),
            file: file.into(),
            cell: cell.into(),
            study_hash: hash.into(),
            status: CellStatus::Failed,
            reason,
            flags: Vec::new(),
            parameters: Vec::new(),
            misfit: None,
            alternatives: 0,
            peak_force: None,
            relaxation: None,
            times: Vec::new(),
            data: Vec::new(),
            fit: Vec::new(),
        }
    }

    /// Value of a named parameter.
    pub fn parameter(&self, name: &str) -> Option<f64> {
        self.parameters
            .iter()
            .find(|p| p.name == name)
            .map(|p| p.value)
    }
}

/// The parameter domain used for every cell (Table 5.3).
///
/// # Errors
/// An ε outside [0, 0.98).
pub fn domain(settings: &CohortSettings) -> nlvid_inverse::Result<Domain> {
    Domain::prony2_table_5_3(settings.constraint_epsilon)
}

/// The model time grid: the ramp in `ramp_points` uniform steps, then the
/// hold log-spaced (dense where fast relaxation shows).
///
/// # Errors
/// Inconsistent durations (checked when the settings are read).
pub fn model_grid(settings: &CohortSettings) -> nlvid_inverse::Result<Vec<f64>> {
    ramp_hold_grid(
        settings.ramp,
        settings.ramp_points,
        settings.hold_end,
        settings.hold_points,
        settings.first_hold_step,
    )
}

/// Reads and fits one cell. Never fails: problems become a `failed` cell.
pub fn fit_cell(settings: &CohortSettings, group: &str, file: &str, path: &Path) -> CellResult {
    let cell = Path::new(file)
        .file_stem()
        .map_or_else(|| file.to_string(), |s| s.to_string_lossy().into_owned());
    let hash = settings.study_hash.as_str();
    let fail = |reason: String| CellResult::failed(group, file, &cell, hash, reason);

    let cols = AfmColumns {
        time: settings.time_column.clone(),
        piezo: settings.piezo_column.clone(),
        deflection: settings.deflection_column.clone(),
    };
    let cal = Calibration {
        deflection_sensitivity: settings.deflection_sensitivity,
        spring_constant: settings.spring_constant,
    };
    let curve = match nlvid_inverse::read_afm_csv(path, &cols, &cal) {
        Ok(c) => c,
        Err(e) => return fail(format!("cannot read the curve: {e}")),
    };
    let Some(indentation) = curve.indentation.clone() else {
        return fail("no indentation in the curve".into());
    };
    let (Some(&t_first), Some(&t_last)) = (curve.time.first(), curve.time.last()) else {
        return fail("the curve has no samples".into());
    };
    if t_last - t_first < settings.hold_end * (1.0 - 1e-9) {
        return fail(format!(
            "the curve covers {:.4} s but protocol.hold_end is {} s",
            t_last - t_first,
            settings.hold_end
        ));
    }
    let grid = match model_grid(settings) {
        Ok(g) => g,
        Err(e) => return fail(format!("model grid: {e}")),
    };
    let (force, delta) = match (
        curve.resample(&curve.force, &grid),
        curve.resample(&indentation, &grid),
    ) {
        (Ok(f), Ok(d)) => (f, d),
        (Err(e), _) | (_, Err(e)) => return fail(format!("resampling: {e}")),
    };
    // Peak of the measured samples inside the fitted window.
    let peak = curve
        .time
        .iter()
        .zip(&curve.force)
        .filter(|(t, _)| **t - t_first <= settings.hold_end * (1.0 + 1e-12))
        .map(|(_, f)| *f)
        .fold(f64::NEG_INFINITY, f64::max);
    let end_force = force[force.len() - 1];
    let mut base = fail(String::new());
    base.times = grid.clone();
    base.data = force.clone();
    if peak.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        base.reason = "no positive force in the fitted window".into();
        return base;
    }
    base.peak_force = Some(peak);
    base.relaxation = Some(1.0 - end_force / peak);

    let model = match (settings.model, domain(settings)) {
        (ForwardModel::LeeRadok, Ok(d)) => {
            match LeeRadokHertz::new(d, grid, &delta, settings.radius, settings.poisson) {
                Ok(m) => m,
                Err(e) => {
                    base.reason = format!("model: {e}");
                    return base;
                }
            }
        }
        (_, Err(e)) => {
            base.reason = format!("domain: {e}");
            return base;
        }
    };
    let fitted = Experiment::new(&cell, model, force, None)
        .and_then(|e| Misfit::new(vec![e]))
        .and_then(|misfit| {
            let fit = MultiStart::new()
                .with_starts(settings.starts)?
                .with_seed(settings.seed)
                .fit(&misfit)?;
            let y = misfit.experiments()[0].model.response(&fit.best.x)?;
            Ok((fit, y))
        });
    let (fit, y) = match fitted {
        Ok(v) => v,
        Err(e) => {
            base.reason = format!("fit: {e}");
            return base;
        }
    };
    base.parameters = fit
        .domain
        .params()
        .iter()
        .zip(&fit.best.x)
        .map(|(p, &value)| ParamValue {
            name: p.name.clone(),
            unit: p.unit.clone(),
            value,
        })
        .collect();
    base.fit = y;
    base.misfit = Some(fit.best.misfit);
    base.alternatives = fit.alternatives.len();
    for hit in &fit.best.on_bounds {
        let side = match hit.side {
            BoundSide::Lower => "lower",
            BoundSide::Upper => "upper",
        };
        base.flags.push(format!(
            "{} at its {side} bound (widen the domain)",
            hit.name
        ));
    }
    if !fit.alternatives.is_empty() {
        base.flags.push(format!(
            "{} alternative optimum/optima within the misfit tolerance",
            fit.alternatives.len()
        ));
    }
    if !fit.failed_starts.is_empty() {
        base.flags.push(format!(
            "{} of {} starts failed",
            fit.failed_starts.len(),
            fit.starts
        ));
    }
    if fit.best.misfit > settings.suspicious_misfit {
        base.status = CellStatus::Suspicious;
        base.reason = format!(
            "misfit {:.4} above fit.suspicious_misfit = {}",
            fit.best.misfit, settings.suspicious_misfit
        );
    } else {
        base.status = CellStatus::Ok;
        base.reason.clear();
    }
    base
}
