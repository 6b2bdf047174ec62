//! `nlvid compare <results.csv>`: group G(t), G(t)/G(0), E(t) = 3G(t)
//! (mean ± sd) on a time grid and the Wilcoxon rank-sum p(t) between two
//! groups, plus G(0), G(t_end) and the relaxation at t_end with effect sizes
//! (thesis §5.4.2; [`nlvid_report::compare`]). See docs/cli/compare.md.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::bail;
use nlvid_report::compare::compare;
use nlvid_stats::{ResultsTable, read_results};
use nlvid_study::Dimension;

use super::{Context, Run};
use crate::args::quantity;
use crate::output::emit;

/// Raw arguments of `nlvid compare`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Per-cell results table (format: docs/cli/compare.md).
    pub results: PathBuf,
    /// The two groups to compare, `A,B` (default: the only two groups in the table).
    #[arg(long, value_delimiter = ',')]
    pub groups: Option<Vec<String>>,
    /// End of the uniform time grid, with a unit (the thesis compares up to 52 s).
    #[arg(long, default_value = "52 s", allow_hyphen_values = true, value_parser = |s: &str| quantity(s, Dimension::TIME))]
    pub t_end: f64,
    /// Number of points of the uniform time grid from 0 to --t-end.
    #[arg(long, default_value_t = 53)]
    pub points: usize,
    /// Any increasing time grid instead, e.g. `--times "0 s,0.1 s,1 s,10 s,52 s"`.
    #[arg(long, value_delimiter = ',', conflicts_with_all = ["t_end", "points"], allow_hyphen_values = true,
          value_parser = |s: &str| quantity(s.trim(), Dimension::TIME))]
    pub times: Option<Vec<f64>>,
    /// p-value method: matlab (the thesis's ranksum), scipy (mannwhitneyu
    /// 'auto'), exact, asymptotic (tie + continuity corrected).
    #[arg(long, default_value = "matlab")]
    pub method: String,
    /// Directory for the CSV outputs, created if missing (default: next to the results table).
    #[arg(long)]
    pub out_dir: Option<PathBuf>,
}

/// Validated configuration.
#[derive(Debug)]
pub struct Config {
    results: PathBuf,
    table: ResultsTable,
    groups: Option<Vec<String>>,
    times: Vec<f64>,
    method: String,
    out_dir: PathBuf,
}

impl Run for Args {
    type Config = Config;

    fn validate(self, _ctx: &Context) -> anyhow::Result<Config> {
        nlvid_report::compare::method(&self.method)?;
        let times = match self.times {
            Some(t) => t,
            None if self.t_end <= 0.0 => bail!("--t-end: give a positive time, e.g. `52 s`"),
            None => nlvid_protocol::grid::uniform(0.0, self.t_end, self.points)
                .map_err(|e| anyhow::anyhow!("--points {}: {e}", self.points))?,
        };
        let out_dir = self.out_dir.unwrap_or_else(|| {
            self.results
                .parent()
                .map(Path::to_path_buf)
                .unwrap_or_default()
        });
        nlvid_study::check_output_dir(&out_dir)?;
        Ok(Config {
            table: read_results(&self.results)?,
            results: self.results,
            groups: self.groups,
            times,
            method: self.method,
            out_dir,
        })
    }

    fn execute(c: Config, ctx: &Context) -> anyhow::Result<ExitCode> {
        let groups = c.groups.as_deref();
        let out = compare(&c.results, c.table, groups, &c.times, &c.method, &c.out_dir)?;
        emit(ctx.json, &out.to_json(), &out.text())?;
        Ok(ExitCode::SUCCESS)
    }
}
