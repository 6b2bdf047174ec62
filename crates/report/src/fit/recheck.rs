//! The real forward model at the optimum (§4.4.1 step 5, §5.4.1): any
//! `nlvid_model::ForwardModel` is run once and scored with eq. 5.3
//! ([`nlvid_inverse::rerun`]); this module only sets up the model an
//! experiment names.

use nlvid_inverse::{ForwardFromModel, LeeRadokHertz, Model as _, Rerun, rerun};
use nlvid_model::{Domain, ForwardModel};

use super::data::{LoadedExperiment, RealModel};
use crate::error::{ReportError, Result};

/// Lee–Radok Hertz driven by the curve's own measured indentation, on
/// 0 ∪ the surrogate grid (the hereditary integral starts from rest at
/// t = 0; [`rerun`] interpolates back onto the grid, exactly).
fn lee_radok(
    exp: &LoadedExperiment,
    domain: &Domain,
    radius: f64,
    poisson: f64,
) -> Result<Box<dyn ForwardModel>> {
    let Some(delta) = exp.curve.indentation() else {
        return Err(ReportError::InvalidSetting(format!(
            "{}: the Lee-Radok re-check needs an indentation history (AFM data)",
            exp.curve.path.display()
        )));
    };
    let times = exp.surrogate.model.times();
    let grid: Vec<f64> = (times[0] > 0.0)
        .then_some(0.0)
        .into_iter()
        .chain(times.iter().copied())
        .collect();
    let delta = exp.curve.resample(delta, &grid)?;
    let model = LeeRadokHertz::new(domain.clone(), grid, &delta, radius, poisson)?;
    Ok(Box::new(ForwardFromModel {
        model,
        identity: format!("lee-radok R={radius:e} m nu={poisson}"),
    }))
}

/// Re-runs the real model of `exp` (if it names one) at `x`.
///
/// # Errors
/// Set-up or run failures, naming the curve.
pub fn recheck(exp: &LoadedExperiment, domain: &Domain, x: &[f64]) -> Result<Option<Rerun>> {
    let built;
    let model: &dyn ForwardModel = match &exp.real {
        None => return Ok(None),
        Some(RealModel::LeeRadok { radius, poisson }) => {
            built = lee_radok(exp, domain, *radius, *poisson)?;
            built.as_ref()
        }
        Some(RealModel::Forward(m)) => m.as_ref(),
    };
    let r = rerun(
        model,
        domain,
        x,
        exp.surrogate.model.times(),
        &exp.force,
        exp.weights.as_deref(),
    )
    .map_err(|e| {
        ReportError::InvalidSetting(format!("{}: re-check with the real model: {e}", exp.label))
    })?;
    Ok(Some(r))
}
