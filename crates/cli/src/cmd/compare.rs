//! `nlvid compare <results.csv>`: group G(t), G(t)/G(0), E(t) = 3G(t)
//! (mean ± sd) on a time grid and the Wilcoxon rank-sum p(t) between two
//! groups, plus G(0), G(t_end) and the relaxation at t_end with effect sizes
//! (thesis §5.4.2; [`nlvid_stats::compare_groups`]). See docs/cli/compare.md.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context as _, bail};
use nlvid_stats::{
    Comparison, Method, Policy, ResultsTable, compare_groups, read_results, write_group_curves,
    write_time_comparisons,
};
use nlvid_study::Dimension;
use serde_json::json;

use super::{Context, Run};
use crate::args::quantity;
use crate::output::{print_json, write_atomic};
use crate::say;

/// Raw arguments of `nlvid compare`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Per-cell results table (format: docs/cli/compare.md).
    pub results: PathBuf,
    /// The two groups to compare, `A,B` (default: the only two groups in the table).
    #[arg(long, value_delimiter = ',')]
    pub groups: Option<Vec<String>>,
    /// End of the uniform time grid, with a unit (the thesis compares up to 52 s).
    #[arg(long, default_value = "52 s", value_parser = |s: &str| quantity(s, Dimension::TIME))]
    pub t_end: f64,
    /// Number of points of the uniform time grid from 0 to --t-end.
    #[arg(long, default_value_t = 53)]
    pub points: usize,
    /// Any increasing time grid instead, e.g. `--times "0 s,0.1 s,1 s,10 s,52 s"`.
    #[arg(long, value_delimiter = ',', conflicts_with_all = ["t_end", "points"],
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

/// `--method` as a rank-sum method.
fn method(name: &str) -> anyhow::Result<Method> {
    Ok(match name {
        "matlab" => Method::Auto(Policy::Matlab),
        "scipy" => Method::Auto(Policy::Scipy),
        "exact" => Method::Exact,
        "asymptotic" => Method::ASYMPTOTIC,
        m => bail!("--method `{m}`: expected one of matlab, scipy, exact, asymptotic"),
    })
}

impl Run for Args {
    type Config = Config;

    fn validate(self, _ctx: &Context) -> anyhow::Result<Config> {
        method(&self.method)?;
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
        compare(
            &c.results, &c.table, c.groups, &c.times, &c.method, &c.out_dir, ctx.json,
        )?;
        Ok(ExitCode::SUCCESS)
    }
}

/// Compares the groups of `table` (read from, or written as, `results`),
/// writes `<stem>.groups.csv` and `<stem>.pvalues.csv` into `out_dir` and
/// prints the summary. `groups`: the pair (default: the only two groups).
///
/// # Errors
/// A bad method or pair, a group with fewer than two cells, unwritable outputs.
pub fn compare(
    results: &Path,
    table: &ResultsTable,
    groups: Option<Vec<String>>,
    times: &[f64],
    method_name: &str,
    out_dir: &Path,
    json_out: bool,
) -> anyhow::Result<()> {
    let names = table.groups();
    let pair = match &groups {
        Some(v) => match v.as_slice() {
            [a, b] => Some((a.as_str(), b.as_str())),
            _ => bail!("--groups: give exactly two names, e.g. --groups MCF-10A,MCF-7"),
        },
        None if names.len() == 2 => Some((names[0].as_str(), names[1].as_str())),
        None => None,
    };
    let cmp = compare_groups(table, pair, times, method(method_name)?)
        .with_context(|| format!("{}", results.display()))?;
    std::fs::create_dir_all(out_dir)
        .with_context(|| format!("--out-dir {}: cannot create", out_dir.display()))?;
    let stem = results
        .file_stem()
        .map_or_else(|| "results".into(), |s| s.to_string_lossy().into_owned());
    let groups_csv = out_dir.join(format!("{stem}.groups.csv"));
    let pvalues_csv = out_dir.join(format!("{stem}.pvalues.csv"));
    let mut buf = Vec::new();
    let curves: Vec<_> = cmp.groups.iter().map(|g| g.curves.clone()).collect();
    write_group_curves(&mut buf, &curves)?;
    write_atomic(&groups_csv, &buf)?;
    if let Some(p) = &cmp.pair {
        let mut buf = Vec::new();
        write_time_comparisons(&mut buf, &p.over_time)?;
        write_atomic(&pvalues_csv, &buf)?;
    }
    let files = (groups_csv, cmp.pair.is_some().then_some(pvalues_csv));
    if json_out {
        print_json(&to_json(results, table, &cmp, method_name, &files))
    } else {
        print_text(results, table, &cmp, method_name, &files)
    }
}

fn to_json(
    results: &Path,
    table: &ResultsTable,
    c: &Comparison,
    method: &str,
    (groups_csv, pvalues_csv): &(PathBuf, Option<PathBuf>),
) -> serde_json::Value {
    let ms = |m: &nlvid_stats::MeanSd| json!({ "mean": m.mean, "sd": m.sd });
    let groups: Vec<_> = c
        .groups
        .iter()
        .map(|g| {
            let (cur, last) = (&g.curves, g.curves.times.len() - 1);
            json!({ "group": cur.name, "n": cur.n, "G0_Pa": ms(&cur.shear[0]),
                "G_end_Pa": ms(&cur.shear[last]), "relaxation_end": ms(&g.relaxation_end) })
        })
        .collect();
    let comparison = c.pair.as_ref().map(|p| json!({
        "a": p.a, "b": p.b, "method": method,
        "times_with_p_below_0.05": p.times_below(0.05),
        "tests": p.contrasts.iter().map(|k| json!({
            "quantity": k.quantity, "unit": k.unit, "a": ms(&k.a), "b": ms(&k.b),
            "test": { "p": k.test.p, "u1": k.test.u1, "z": k.test.z, "method": k.test.used.to_string() },
            "effect_a_minus_b": { "rank_biserial": k.effect.rank_biserial,
                "cliffs_delta": k.effect.cliffs_delta, "superiority": k.effect.superiority,
                "hodges_lehmann": k.effect.hodges_lehmann },
        })).collect::<Vec<_>>(),
        "p_of_t": p.over_time.iter().map(|r| json!({
            "time_s": r.t, "p_G": r.shear.p, "method_G": r.shear.used.to_string(),
            "p_G_norm": r.normalised.p, "rank_biserial_G": r.shear_effect.rank_biserial,
        })).collect::<Vec<_>>(),
        "pvalues_csv": pvalues_csv,
    }));
    json!({
        "results": results, "cells_used": table.cells.len(),
        "excluded": table.excluded.iter().map(|e| json!({
            "cell": e.cell, "group": e.group, "line": e.line, "reason": e.reason,
        })).collect::<Vec<_>>(),
        "t_end_s": c.t_end(), "points": c.times.len(), "times_s": c.times,
        "groups": groups, "comparison": comparison, "groups_csv": groups_csv,
    })
}

fn print_text(
    results: &Path,
    table: &ResultsTable,
    c: &Comparison,
    method: &str,
    (groups_csv, pvalues_csv): &(PathBuf, Option<PathBuf>),
) -> anyhow::Result<()> {
    let t_end = c.t_end();
    say!(
        "{}: {} group(s), {} cell(s) used, {} excluded",
        results.display(),
        c.groups.len(),
        table.cells.len(),
        table.excluded.len()
    )?;
    for e in &table.excluded {
        say!(
            "  excluded {} ({}, line {}): {}",
            e.cell,
            e.group,
            e.line,
            e.reason
        )?;
    }
    let g_end = format!("G({t_end} s) kPa");
    say!(
        "{:<16} {:>4}  {:>18}  {g_end:>18}  {:>16}",
        "group",
        "n",
        "G(0) kPa",
        "relaxation %"
    )?;
    for g in &c.groups {
        let (cur, last, r) = (&g.curves, g.curves.times.len() - 1, &g.relaxation_end);
        say!(
            "{:<16} {:>4}  {:>8.3} ± {:<7.3}  {:>8.3} ± {:<7.3}  {:>6.1} ± {:<6.1}",
            cur.name,
            cur.n,
            cur.shear[0].mean / 1e3,
            cur.shear[0].sd / 1e3,
            cur.shear[last].mean / 1e3,
            cur.shear[last].sd / 1e3,
            100.0 * r.mean,
            100.0 * r.sd
        )?;
    }
    match &c.pair {
        Some(p) => {
            say!(
                "{} vs {} (Wilcoxon rank-sum, two-sided, --method {method}):",
                p.a,
                p.b
            )?;
            for k in &p.contrasts {
                let hl = k.effect.hodges_lehmann;
                let hl = if k.unit == "Pa" {
                    format!("{:.3} kPa", hl / 1e3)
                } else {
                    format!("{hl:.3}")
                };
                say!(
                    "  {:<28} p = {:<10.3e} ({}), rank-biserial = {:+.3}, Hodges–Lehmann shift = {hl}",
                    k.quantity,
                    k.test.p,
                    k.test.used,
                    k.effect.rank_biserial
                )?;
            }
            say!(
                "  G(t): p < 0.05 at {} of {} times",
                p.times_below(0.05),
                c.times.len()
            )?;
        }
        None => say!(
            "{} groups: choose two with --groups A,B for p-values",
            c.groups.len()
        )?,
    }
    for f in std::iter::once(groups_csv).chain(pvalues_csv) {
        say!("wrote {}", f.display())?;
    }
    Ok(())
}
