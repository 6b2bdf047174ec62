//! `nlvid fit <study.toml> DATA.csv [DATA2.csv …]`: fit one parameter set
//! to one or several measured curves on Kriging surrogates (thesis §4.4.1
//! step 5, §4.4.2, §5.4.1, eq. 5.3), then re-check the optimum with the
//! real forward model each experiment names.
//!
//! Read top to bottom: `config` (the study's `[fit]` section) → `data`
//! (surrogates, data files, protocol checks, resampling) → [`Run::execute`]
//! (multistart fit on the summed eq. 5.3 misfit, re-check in `recheck`) →
//! `report` (text, `--json`, SVG figures). See docs/cli/fit.md.

mod config;
mod data;
mod recheck;
mod report;

use std::path::PathBuf;
use std::process::ExitCode;

use nlvid_inverse::{MultiStart, Precomputed, SurrogateCurve, SurrogateMisfit};

use super::{Context, Run};
use config::FitSettings;
use data::LoadedExperiment;

/// Raw arguments of `nlvid fit`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The study file (TOML) with a `[fit]` section.
    pub study: PathBuf,
    /// Measured curves (CSV with the columns of `[fit.columns]`, or
    /// `.jpk-force`), fitted together with one parameter set; with
    /// `[[fit.experiment]]` tables, one file per table in the same order.
    #[arg(required = true)]
    pub data: Vec<PathBuf>,
    /// Directory for SVG figures of data vs fitted curve (one per data file).
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Override `[fit] starts`.
    #[arg(long)]
    pub starts: Option<usize>,
    /// Override `[fit] seed`.
    #[arg(long)]
    pub seed: Option<u64>,
}

/// Validated settings with every surrogate and data file loaded.
pub struct Config {
    settings: FitSettings,
    experiments: Vec<LoadedExperiment>,
    plot: Option<PathBuf>,
}

impl Run for Args {
    type Config = Config;

    fn validate(self, _ctx: &Context) -> anyhow::Result<Config> {
        let settings = config::read(&self.study, self.starts, self.seed)?;
        let experiments = data::load(&settings, &self.data)?;
        Ok(Config {
            settings,
            experiments,
            plot: self.plot,
        })
    }

    fn execute(c: Config, ctx: &Context) -> anyhow::Result<ExitCode> {
        let t0 = std::time::Instant::now();
        // Reduced (PCA) form for PCA-reduced surrogates, else the Gram form;
        // both depend on the surrogate and the weights only.
        let pre = c
            .experiments
            .iter()
            .map(|e| Precomputed::new(&e.surrogate.model, e.weights.as_deref()))
            .collect::<Result<Vec<_>, _>>()?;
        let curves: Vec<SurrogateCurve<'_>> = c
            .experiments
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
            .with_starts(c.settings.starts)?
            .with_seed(c.settings.seed)
            .fit(&misfit)?;
        let seconds = t0.elapsed().as_secs_f64();
        let x = fit.best.x.clone();
        let mut reruns = Vec::with_capacity(c.experiments.len());
        for e in &c.experiments {
            reruns.push(recheck::recheck(e, &fit.domain, &x).map_err(|err| format!("{err:#}")));
        }
        let outcome = report::Outcome::new(&c.settings, &c.experiments, fit, reruns, seconds)?;
        let outcome = match &c.plot {
            Some(dir) => outcome.with_plots(&c.experiments, dir)?,
            None => outcome,
        };
        if ctx.json {
            crate::output::print_json(&outcome.to_json()?)?;
        } else {
            print!("{}", outcome.text());
        }
        Ok(ExitCode::SUCCESS)
    }
}
