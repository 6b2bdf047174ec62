//! `nlvid fit <study.toml> DATA.csv [DATA2.csv …]`: fit one parameter set
//! to one or several measured curves on Kriging surrogates, then re-check
//! the optimum with the real forward model each experiment names
//! ([`nlvid_report::fit`]). See docs/cli/fit.md.

use std::path::PathBuf;
use std::process::ExitCode;

use nlvid_report::fit::{self, LoadedExperiment};
use nlvid_report::settings::FitSettings;

use super::{Context, Run};

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
        let mut settings = FitSettings::load(&self.study)?;
        settings.starts = self.starts.unwrap_or(settings.starts);
        settings.seed = self.seed.unwrap_or(settings.seed);
        let experiments = fit::load(&settings, &self.data)?;
        Ok(Config {
            settings,
            experiments,
            plot: self.plot,
        })
    }

    fn execute(c: Config, ctx: &Context) -> anyhow::Result<ExitCode> {
        let mut outcome = fit::fit(&c.settings, &c.experiments)?;
        if let Some(dir) = &c.plot {
            outcome = outcome.with_plots(&c.experiments, dir)?;
        }
        crate::output::emit(ctx.json, &outcome.to_json()?, &outcome.text())?;
        Ok(ExitCode::SUCCESS)
    }
}
