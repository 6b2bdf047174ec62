//! `nlvid cohort <study.toml> <folder or manifest.csv>`: fit every cell
//! (parallel, progress bar, resumable), one row per cell in `results.csv`
//! (format of docs/cli/compare.md). See docs/cli/cohort.md.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use nlvid_report::cell::{CellResult, CellStatus};
use nlvid_report::cohort::{self, CellInput, CohortOutcome, RunOptions};
use nlvid_report::settings::CohortSettings;
use serde_json::json;

use super::{Context, Run};
use crate::say;

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
        print_outcome(&c.settings, &c.out, &run, ctx.json)?;
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

fn count(run: &CohortOutcome, s: CellStatus) -> usize {
    run.cells.iter().filter(|c| c.status == s).count()
}

/// Prints what a cohort run did (text or one JSON document).
///
/// # Errors
/// stdout cannot be written.
pub fn print_outcome(
    settings: &CohortSettings,
    out: &Path,
    run: &CohortOutcome,
    json: bool,
) -> anyhow::Result<()> {
    let listed: Vec<&CellResult> = run
        .cells
        .iter()
        .filter(|c| c.status != CellStatus::Ok)
        .collect();
    let results = run.results_csv.as_ref().map(|p| p.display().to_string());
    if json {
        crate::output::print_json(&json!({
            "study_sha256": settings.study_hash,
            "forward_model": settings.model.describe(),
            "out": out.display().to_string(),
            "cells": run.cells.len(),
            "fitted": run.fitted,
            "reused": run.reused,
            "ok": count(run, CellStatus::Ok),
            "suspicious": count(run, CellStatus::Suspicious),
            "failed": count(run, CellStatus::Failed),
            "listed": listed.iter().map(|c| json!({
                "group": c.group, "file": c.file, "status": c.status.as_str(), "reason": c.reason,
            })).collect::<Vec<_>>(),
            "results_csv": results,
        }))?;
        return Ok(());
    }
    say!("forward model: {}", settings.model.describe())?;
    say!(
        "{} cells: {} fitted now, {} reused from an earlier run; {} ok, {} suspicious, {} failed",
        run.cells.len(),
        run.fitted,
        run.reused,
        count(run, CellStatus::Ok),
        count(run, CellStatus::Suspicious),
        count(run, CellStatus::Failed)
    )?;
    for c in listed {
        say!("  {} {}: {}", c.status.as_str(), c.file, c.reason)?;
    }
    if let Some(r) = results {
        say!("wrote {r}")?;
    }
    Ok(())
}
