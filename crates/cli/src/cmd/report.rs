//! `nlvid report <cohort-output-dir>`: the self-contained HTML report (and
//! its SVG figures) of a finished cohort. See docs/cli/report.md.

use std::path::PathBuf;
use std::process::ExitCode;

use nlvid_report::report::{ReportOptions, write_report};
use serde_json::json;

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
        if !self.dir.join("cohort.json").is_file() {
            anyhow::bail!(
                "{}: not an output directory of `nlvid cohort` (no cohort.json)",
                self.dir.display()
            );
        }
        if let Some(o) = &self.out {
            nlvid_study::check_output_dir(o)?;
        }
        if let Some(p) = &self.surrogate_check
            && !p.is_file()
        {
            anyhow::bail!("--surrogate-check {}: no such file", p.display());
        }
        Ok((
            self.dir,
            ReportOptions {
                out: self.out,
                surrogate_check: self.surrogate_check,
                ..ReportOptions::default()
            },
        ))
    }

    fn execute((dir, opts): Self::Config, ctx: &Context) -> anyhow::Result<ExitCode> {
        let files = write_report(&dir, &opts)?;
        if ctx.json {
            crate::output::print_json(&json!({
                "html": files.html.display().to_string(),
                "figures": files.figure_ids,
                "svgs": files.svgs.iter().map(|p| p.display().to_string()).collect::<Vec<_>>(),
            }))?;
        } else {
            say!(
                "report: {} ({} figures)",
                files.html.display(),
                files.figure_ids.len()
            )?;
        }
        Ok(ExitCode::SUCCESS)
    }
}
