//! `nlvid sample`: Latin-hypercube training and checking designs.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, bail};
use clap::Args;
use nlvid_surrogate::doe::training_and_checking;
use nlvid_surrogate::{read_domain, write_table};

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
        let (domain, train, check) = if let Some(path) = &self.study {
            let st = nlvid_surrogate::BuildStudy::load(path)?;
            let (train, check) = st.settings.design.designs()?;
            (st.settings.design.domain, train, check)
        } else {
            let (Some(dpath), Some(n)) = (&self.domain, self.n) else {
                bail!("give a study file, or --domain FILE and -n N");
            };
            let domain = read_domain(dpath, &[], &[])?;
            let (train, check) = training_and_checking(
                &domain,
                n,
                self.check.max(1),
                self.seed,
                self.iterations,
                1e-6,
            )?;
            let check = if self.check > 0 { check } else { Vec::new() };
            (domain, train, check)
        };
        nlvid_study::check_output_dir(&self.out)?;
        std::fs::create_dir_all(&self.out)
            .with_context(|| format!("cannot create {}", self.out.display()))?;
        let header = domain.names();
        for (name, rows) in [("train.csv", &train), ("check.csv", &check)] {
            if !rows.is_empty() {
                let mut buf = Vec::new();
                write_table(&mut buf, &header, rows)?;
                crate::output::write_atomic(&self.out.join(name), &buf)?;
            }
        }
        say!(
            "wrote {} training and {} checking points to {}",
            train.len(),
            check.len(),
            self.out.display()
        )?;
        Ok(ExitCode::SUCCESS)
    }
}
