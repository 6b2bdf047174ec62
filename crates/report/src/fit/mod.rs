//! `nlvid fit`: one parameter set fitted to one or several measured curves
//! on Kriging surrogates (thesis §4.4.1 step 5, §4.4.2, §5.4.1, eq. 5.3),
//! then the optimum re-checked with the real forward model each experiment
//! names.
//!
//! Read top to bottom: [`crate::settings::FitSettings`] (the study's
//! `[fit]`) → [`load`] (surrogates, data files, protocol checks,
//! resampling) → [`fit`] (multistart on the summed eq. 5.3 misfit, re-check
//! in `recheck`) → [`Outcome`] (text, JSON, SVG figures).
//!
//! ```no_run
//! use std::path::{Path, PathBuf};
//! use nlvid_report::{fit, settings::FitSettings};
//! # fn main() -> nlvid_report::Result<()> {
//! let settings = FitSettings::load(Path::new("examples/fit/study.toml"))?;
//! let curves = fit::load(&settings, &[PathBuf::from("examples/fit/data.csv")])?;
//! let outcome = fit::fit(&settings, &curves)?;
//! print!("{}", outcome.text());
//! # Ok(())
//! # }
//! ```

mod data;
pub mod domain;
mod outcome;
mod recheck;

use nlvid_inverse::{MultiStart, Precomputed, SurrogateCurve, SurrogateMisfit};

pub use data::{LoadedExperiment, RealModel, Surrogate, check_protocol, load, load_curves};
pub use outcome::{Agreement, ExperimentOutcome, Outcome};

use crate::error::Result;
use crate::settings::FitSettings;

/// Fits `experiments` (loaded by [`load`]) together, re-runs each real
/// model at the optimum and scores everything.
///
/// # Errors
/// Surrogate or optimiser failures. A failed re-run is reported in the
/// outcome, not an error.
pub fn fit(settings: &FitSettings, experiments: &[LoadedExperiment]) -> Result<Outcome> {
    let t0 = std::time::Instant::now();
    // Reduced (PCA) form for PCA-reduced surrogates, else the Gram form;
    // both depend on the surrogate and the weights only.
    let pre = experiments
        .iter()
        .map(|e| Precomputed::new(&e.surrogate.model, e.weights.as_deref()))
        .collect::<std::result::Result<Vec<_>, _>>()?;
    let curves: Vec<SurrogateCurve<'_>> = experiments
        .iter()
        .zip(&pre)
        .map(|(e, p)| SurrogateCurve {
            label: &e.label,
            surrogate: &e.surrogate.model,
            precomputed: p,
            data: &e.force,
            weights: e.weights.as_deref(),
        })
        .collect();
    let misfit = SurrogateMisfit::new(&curves)?;
    let fit = MultiStart::new()
        .with_starts(settings.starts)?
        .with_seed(settings.seed)
        .fit(&misfit)?;
    let seconds = t0.elapsed().as_secs_f64();
    let reruns = experiments
        .iter()
        .map(|e| recheck::recheck(e, &fit.domain, &fit.best.x).map_err(|err| err.to_string()))
        .collect();
    Outcome::new(settings, experiments, fit, reruns, seconds)
}
