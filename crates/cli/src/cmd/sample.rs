//! `nlvid sample`: Latin-hypercube training and checking designs.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context;
use clap::Args;
use nlvid_surrogate::doe::{Domain, training_and_checking};

use super::surrogate::write_table;

/// Arguments of `sample`.
#[derive(Debug, Args)]
pub struct SampleArgs {
    /// Domain file (TOML: `[[axes]]` name, unit, lower, upper, log; `[[constraints]]` coeffs, bound).
    #[arg(long)]
    pub domain: PathBuf,
    /// Training points.
    #[arg(long, short)]
    pub n: usize,
    /// Checking points (a separate, non-overlapping design).
    #[arg(long, default_value_t = 0)]
    pub check: usize,
    /// Seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// ESE optimisation iterations (0: random Latin hypercube).
    #[arg(long, default_value_t = 30)]
    pub iterations: usize,
    /// Output directory (train.csv, check.csv).
    #[arg(long, short)]
    pub out: PathBuf,
}

impl SampleArgs {
    /// Run.
    pub fn run(self) -> anyhow::Result<ExitCode> {
        let text = std::fs::read_to_string(&self.domain)
            .with_context(|| format!("cannot read {}", self.domain.display()))?;
        let domain: Domain =
            toml::from_str(&text).with_context(|| format!("{}", self.domain.display()))?;
        domain
            .validate()
            .with_context(|| format!("{}", self.domain.display()))?;
        let (train, check) = training_and_checking(
            &domain,
            self.n,
            self.check.max(1),
            self.seed,
            self.iterations,
            1e-6,
        )?;
        std::fs::create_dir_all(&self.out)
            .with_context(|| format!("cannot create {}", self.out.display()))?;
        let header: Vec<String> = domain.axes.iter().map(|a| a.name.clone()).collect();
        write_table(Some(&self.out.join("train.csv")), &header, &train)?;
        if self.check > 0 {
            write_table(Some(&self.out.join("check.csv")), &header, &check)?;
        }
        println!(
            "wrote {} training and {} checking points to {}",
            train.len(),
            self.check,
            self.out.display()
        );
        Ok(ExitCode::SUCCESS)
    }
}
