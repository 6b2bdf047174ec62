//! `nlvid cohort <study.toml> <folder or manifest.csv>`: fit every cell
//! (parallel, progress bar, resumable), one row per cell in `results.csv`
//! (format of docs/cli/compare.md). See docs/cli/cohort.md.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use nlvid_report::cell::CellResult;
use nlvid_report::cohort::{self, CellInput, CohortOutcome, RunOptions};
use nlvid_report::settings::CohortSettings;

use super::{Context, Run};

/// Raw arguments of `nlvid cohort`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Study file (probe, afm, protocol, fit sections; docs/cli/cohort.md).
    pub study: PathBuf,
    /// A folder with one sub-folder per group (each *.csv a cell), or a
    /// manifest CSV with columns group,file.
    pub input: PathBuf,
    /// Output directory (per-cell results, results.csv, cohort.json);
    /// default: `<study stem>-cohort` in the current directory. Re-running
    /// into the same directory fits only the cells not yet done.
    #[arg(long)]
    pub out: Option<PathBuf>,
}

/// Validated configuration.
#[derive(Debug)]
pub struct Config {
    study: PathBuf,
    input: PathBuf,
    settings: CohortSettings,
    cells: Vec<CellInput>,
    out: PathBuf,
}

impl Run for Args {
    type Config = Config;

    fn validate(self, _ctx: &Context) -> anyhow::Result<Config> {
        let settings = CohortSettings::load(&self.study)?;
        let cells = cohort::discover(&self.input)?;
        let out = self.out.unwrap_or_else(|| {
            let stem = self
                .study
                .file_stem()
                .map_or_else(|| "study".into(), |s| s.to_string_lossy().into_owned());
            PathBuf::from(format!("{stem}-cohort"))
        });
        Ok(Config {
            study: self.study,
            input: self.input,
            settings,
            cells,
            out,
        })
    }

    fn execute(c: Config, ctx: &Context) -> anyhow::Result<ExitCode> {
        let run = run_with_progress(&c.settings, &c.study, &c.input, &c.cells, &c.out)?;
        if ctx.json {
            crate::output::print_json(&run.to_json(&c.out))?;
        } else {
            crate::output::print_text(&run.text())?;
        }
        Ok(ExitCode::SUCCESS)
    }
}

/// Runs a cohort with a progress bar on stderr.
///
/// # Errors
/// The output directory cannot be written.
pub fn run_with_progress(
    settings: &CohortSettings,
    study: &Path,
    input: &Path,
    cells: &[CellInput],
    out: &Path,
) -> anyhow::Result<CohortOutcome> {
    let bar = crate::progress::bar(cells.len() as u64, "cells");
    let tick = |_: &CellResult| bar.inc(1);
    let run = cohort::run_cohort(
        settings,
        study,
        input,
        cells,
        out,
        &RunOptions {
            max_new_fits: None,
            on_cell: Some(&tick),
        },
    )?;
    bar.finish_and_clear();
    Ok(run)
}
