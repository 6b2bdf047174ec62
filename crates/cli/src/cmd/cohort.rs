//! `nlvid cohort <study.toml> <folder or manifest.csv>`: fit every cell
//! (parallel, progress bar, resumable), one row per cell in `results.csv`
//! (format of docs/cli/compare.md). See docs/cli/cohort.md.

use std::path::PathBuf;
use std::process::ExitCode;

use nlvid_report::cell::CellResult;
use nlvid_report::cohort::{self, CellInput, RunOptions};
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
        let out = self.out.unwrap_or_else(|| cohort::default_out(&self.study));
        nlvid_study::check_output_dir(&out)?;
        Ok(Config {
            study: self.study,
            input: self.input,
            settings,
            cells,
            out,
        })
    }

    fn execute(c: Config, ctx: &Context) -> anyhow::Result<ExitCode> {
        let bar = crate::progress::bar(c.cells.len() as u64, "cells");
        let tick = |_: &CellResult| bar.inc(1);
        let opts = RunOptions {
            max_new_fits: None,
            on_cell: Some(&tick),
        };
        let run = cohort::run_cohort(&c.settings, &c.study, &c.input, &c.cells, &c.out, &opts)?;
        bar.finish_and_clear();
        crate::output::emit(ctx.json, &run.to_json(&c.out), &run.text())?;
        // Exit status CELLS_FAILED with a summary on stderr when any cell
        // failed (the table and report list them).
        match run.failures_text() {
            None => Ok(ExitCode::SUCCESS),
            Some(t) => {
                eprint!("{t}");
                Ok(ExitCode::from(CELLS_FAILED))
            }
        }
    }
}

/// Exit status of a cohort run that finished with failed cells
/// (docs/cli/README.md).
pub const CELLS_FAILED: u8 = 3;
