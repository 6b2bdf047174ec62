//! `nlvid report <cohort-output-dir>`: the self-contained HTML report (and
//! its SVG figures) of a finished cohort. See docs/cli/report.md.

use std::path::PathBuf;
use std::process::ExitCode;

use nlvid_report::report::{ReportOptions, write_report};

use super::{Context, Run};

/// Raw arguments of `nlvid report`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Output directory of `nlvid cohort`.
    pub dir: PathBuf,
    /// Where the page and figures go (default: `<dir>/report`).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// CSV of the surrogate's checking errors, shown as a table
    /// (default: `<dir>/surrogate_check.csv` if present).
    #[arg(long)]
    pub surrogate_check: Option<PathBuf>,
}

impl Run for Args {
    type Config = (PathBuf, ReportOptions);

    fn validate(self, _ctx: &Context) -> anyhow::Result<Self::Config> {
        let opts = ReportOptions {
            out: self.out,
            surrogate_check: self.surrogate_check,
            ..ReportOptions::default()
        };
        opts.check(&self.dir)?;
        Ok((self.dir, opts))
    }

    fn execute((dir, opts): Self::Config, ctx: &Context) -> anyhow::Result<ExitCode> {
        let files = write_report(&dir, &opts)?;
        crate::output::emit(ctx.json, &files.to_json(), &files.text())?;
        Ok(ExitCode::SUCCESS)
    }
}
