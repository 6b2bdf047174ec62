//! The real forward model at the optimum (§4.4.1 step 5, §5.4.1): any
//! `nlvid_surrogate::ForwardModel` is run once and scored with eq. 5.3
//! ([`nlvid_inverse::rerun`]); this module only picks the model an
//! experiment names.

use anyhow::{Context as _, bail};
use nlvid_inverse::{Domain, ForwardFromModel, LeeRadokHertz, Model as _, Rerun, rerun};
use nlvid_surrogate::ForwardModel;

use super::config::RealModelSpec;
use super::data::LoadedExperiment;

/// The forward model that re-checks `exp`.
///
/// # Errors
/// A model that cannot be set up for this curve (e.g. Lee–Radok without an
/// indentation history).
pub fn real_model(
    spec: &RealModelSpec,
    exp: &LoadedExperiment,
    domain: &Domain,
) -> anyhow::Result<Box<dyn ForwardModel>> {
    match spec {
        RealModelSpec::LeeRadok { radius, poisson } => {
            let Some(delta) = &exp.curve.indentation else {
                bail!(
                    "{}: the Lee-Radok re-check needs an indentation history (AFM data)",
                    exp.curve.path.display()
                );
            };
            // The hereditary integral starts from rest at t = 0: run on
            // 0 ∪ grid (rerun interpolates back onto the grid, exactly).
            let times = exp.surrogate.model.times();
            let grid: Vec<f64> = (times[0] > 0.0)
                .then_some(0.0)
                .into_iter()
                .chain(times.iter().copied())
                .collect();
            let delta = exp.curve.resample(delta, &grid)?;
            let model = LeeRadokHertz::new(domain.clone(), grid, &delta, *radius, *poisson)?;
            Ok(Box::new(ForwardFromModel {
                model,
                identity: format!("lee-radok R={radius:e} m nu={poisson}"),
            }))
        }
    }
}

/// Re-runs the real model of `exp` (if it names one) at `x`.
///
/// # Errors
/// Set-up or run failures, naming the curve.
pub fn recheck(
    exp: &LoadedExperiment,
    domain: &Domain,
    x: &[f64],
) -> anyhow::Result<Option<Rerun>> {
    let Some(spec) = &exp.real else {
        return Ok(None);
    };
    let model = real_model(spec, exp, domain)?;
    let r = rerun(
        model.as_ref(),
        domain,
        x,
        exp.surrogate.model.times(),
        &exp.force,
        exp.weights.as_deref(),
    )
    .with_context(|| format!("{}: re-check with the real model", exp.label))?;
    Ok(Some(r))
}
