//! `nlvid sample`: Latin-hypercube training and checking designs.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::bail;
use clap::Args;
use nlvid_surrogate::doe::DesignSettings;
use nlvid_surrogate::read_domain;

/// Arguments of `sample`.
#[derive(Debug, Args)]
pub struct SampleArgs {
    /// Study file with `[forward]` and `[design]` sections (docs/study-format.md).
    pub study: Option<PathBuf>,
    /// Domain file (TOML: `[[parameters]]` name, unit, lower, upper, scale = "linear"/"log"; `[[constraints]]` coefficients, rhs, label); flag-only use.
    #[arg(long, conflicts_with = "study")]
    pub domain: Option<PathBuf>,
    /// Training points (flag-only use).
    #[arg(long, short, conflicts_with = "study")]
    pub n: Option<usize>,
    /// Checking points, a separate non-overlapping design (flag-only use).
    #[arg(long, default_value_t = 0, conflicts_with = "study")]
    pub check: usize,
    /// Seed (flag-only use).
    #[arg(long, default_value_t = 1, conflicts_with = "study")]
    pub seed: u64,
    /// ESE optimisation iterations, 0: random Latin hypercube (flag-only use).
    #[arg(long, default_value_t = 30, conflicts_with = "study")]
    pub iterations: usize,
    /// Output directory (train.csv, check.csv).
    #[arg(long, short)]
    pub out: PathBuf,
}

impl SampleArgs {
    /// Run.
    pub fn run(self) -> anyhow::Result<ExitCode> {
        let design = if let Some(path) = &self.study {
            nlvid_surrogate::BuildStudy::load(path)?.settings.design
        } else {
            let (Some(dpath), Some(n_train)) = (&self.domain, self.n) else {
                bail!("give a study file, or --domain FILE and -n N");
            };
            DesignSettings {
                domain: read_domain(dpath, &[], &[])?,
                n_train,
                n_check: self.check,
                seed: self.seed,
                ese_iterations: self.iterations,
                infill: None,
            }
        };
        nlvid_study::check_output_dir(&self.out)?;
        let (train, check) = design.write_designs(&self.out)?;
        let out = self.out.display();
        say!("wrote {train} training and {check} checking points to {out}")?;
        Ok(ExitCode::SUCCESS)
    }
}
