//! `nlvid compare <results.csv>`: group G(t), G(t)/G(0), E(t) = 3G(t)
//! (mean ± sd) on a time grid and the Wilcoxon rank-sum p(t) between two
//! groups, plus G(0), G(t_end) and the relaxation amount at t_end with
//! effect sizes (thesis §5.4.2, Figs. 5.14–5.21). See docs/cli/compare.md.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::bail;
use nlvid_model::Relaxation;
use nlvid_stats::{
    Effect, Method, Policy, RankSum, ResultsTable, compare_over_time, effect, group_curves,
    mean_sd, rank_sum, read_results, relaxation_amounts, write_group_curves,
    write_time_comparisons,
};
use nlvid_study::Dimension;
use serde_json::{Value, json};

use super::{Context, Run};
use crate::args::quantity;
use crate::output::{print_json, write_atomic};

/// Raw arguments of `nlvid compare`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Per-cell results table (format: docs/cli/compare.md).
    pub results: PathBuf,
    /// The two groups to compare, `A,B` (default: the only two groups in the table).
    #[arg(long, value_delimiter = ',')]
    pub groups: Option<Vec<String>>,
    /// End of the time grid, with a unit (the thesis compares up to 52 s).
    #[arg(long, default_value = "52 s", value_parser = |s: &str| quantity(s, Dimension::TIME))]
    pub t_end: f64,
    /// Number of points of the uniform time grid from 0 to --t-end.
    #[arg(long, default_value_t = 53)]
    pub points: usize,
    /// p-value method: matlab (the thesis's ranksum), scipy (mannwhitneyu
    /// 'auto'), exact, asymptotic (tie + continuity corrected).
    #[arg(long, default_value = "matlab")]
    pub method: String,
    /// Directory for the CSV outputs (default: next to the results table).
    #[arg(long)]
    pub out_dir: Option<PathBuf>,
}

/// Validated configuration.
#[derive(Debug)]
pub struct Config {
    results: PathBuf,
    table: ResultsTable,
    pair: Option<(String, String)>,
    times: Vec<f64>,
    method: Method,
    method_name: String,
    groups_csv: PathBuf,
    pvalues_csv: PathBuf,
}

impl Run for Args {
    type Config = Config;

    /// Check every argument and read the table: unreadable or malformed
    /// table, unknown group or method, a non-positive --t-end, fewer than 2
    /// grid points.
    fn validate(self, _ctx: &Context) -> anyhow::Result<Config> {
        if self.t_end <= 0.0 {
            bail!("--t-end: give a positive time, e.g. `52 s`");
        }
        let times = nlvid_protocol::grid::uniform(0.0, self.t_end, self.points)
            .map_err(|e| anyhow::anyhow!("--points {}: {e}", self.points))?;
        let method = match self.method.as_str() {
            "matlab" => Method::Auto(Policy::Matlab),
            "scipy" => Method::Auto(Policy::Scipy),
            "exact" => Method::Exact,
            "asymptotic" => Method::ASYMPTOTIC,
            m => bail!("--method `{m}`: expected one of matlab, scipy, exact, asymptotic"),
        };
        let table = read_results(&self.results)?;
        let names = table.groups();
        for g in &names {
            let n = table.group(g).len();
            if n < 2 {
                bail!(
                    "{}: group `{g}` has {n} usable cell(s); mean ± sd needs at least 2",
                    self.results.display()
                );
            }
        }
        let pair = match self.groups {
            Some(v) => {
                let [a, b] = v.as_slice() else {
                    bail!("--groups: give exactly two names, e.g. --groups MCF-10A,MCF-7");
                };
                for g in [a, b] {
                    if !names.contains(g) {
                        bail!(
                            "--groups: no usable cells in group `{g}` of {} (groups: {})",
                            self.results.display(),
                            names.join(", ")
                        );
                    }
                }
                if a == b {
                    bail!("--groups: the two groups must differ");
                }
                Some((a.clone(), b.clone()))
            }
            None if names.len() == 2 => Some((names[0].clone(), names[1].clone())),
            None => None,
        };
        let dir = match self.out_dir {
            Some(d) => d,
            None => self
                .results
                .parent()
                .map(Path::to_path_buf)
                .unwrap_or_default(),
        };
        let stem = self
            .results
            .file_stem()
            .map_or_else(|| "results".into(), |s| s.to_string_lossy().into_owned());
        Ok(Config {
            results: self.results,
            table,
            pair,
            times,
            method,
            method_name: self.method,
            groups_csv: dir.join(format!("{stem}.groups.csv")),
            pvalues_csv: dir.join(format!("{stem}.pvalues.csv")),
        })
    }

    fn execute(config: Config, ctx: &Context) -> anyhow::Result<ExitCode> {
        execute(config, ctx.json)
    }
}

fn test_json(r: &RankSum) -> Value {
    json!({ "p": r.p, "u1": r.u1, "z": r.z, "method": r.used.to_string() })
}

fn effect_json(e: &Effect) -> Value {
    json!({
        "rank_biserial": e.rank_biserial,
        "cliffs_delta": e.cliffs_delta,
        "superiority": e.superiority,
        "hodges_lehmann": e.hodges_lehmann,
    })
}

struct Contrast {
    what: String,
    unit: &'static str,
    test: RankSum,
    effect: Effect,
}

fn contrast(
    what: String,
    unit: &'static str,
    a: &[f64],
    b: &[f64],
    m: Method,
) -> anyhow::Result<Contrast> {
    Ok(Contrast {
        what,
        unit,
        test: rank_sum(a, b, m)?,
        effect: effect(a, b)?,
    })
}

/// Compute the group curves and the comparison, write the CSVs, print.
fn execute(c: Config, json_out: bool) -> anyhow::Result<ExitCode> {
    let t_end = c.times[c.times.len() - 1];
    let names = c.table.groups();
    let mut curves = Vec::with_capacity(names.len());
    let mut group_json = Vec::new();
    for g in &names {
        let cells: Vec<Relaxation> = c.table.group(g);
        let cur = group_curves(g, &cells, &c.times)?;
        let relax = mean_sd(g, &relaxation_amounts(&cells, t_end))?;
        let last = cur.times.len() - 1;
        group_json.push(json!({
            "group": g, "n": cur.n,
            "G0_Pa": { "mean": cur.shear[0].mean, "sd": cur.shear[0].sd },
            "G_end_Pa": { "mean": cur.shear[last].mean, "sd": cur.shear[last].sd },
            "relaxation_end": { "mean": relax.mean, "sd": relax.sd },
        }));
        curves.push((cur, relax));
    }
    let mut buf = Vec::new();
    write_group_curves(
        &mut buf,
        &curves.iter().map(|(g, _)| g.clone()).collect::<Vec<_>>(),
    )?;
    write_atomic(&c.groups_csv, &buf)?;

    let mut contrasts = Vec::new();
    let mut significant = 0;
    if let Some((a, b)) = &c.pair {
        let (ca, cb) = (c.table.group(a), c.table.group(b));
        let rows = compare_over_time(&ca, &cb, &c.times, c.method)?;
        significant = rows.iter().filter(|r| r.shear.p < 0.05).count();
        let mut buf = Vec::new();
        write_time_comparisons(&mut buf, &rows)?;
        write_atomic(&c.pvalues_csv, &buf)?;
        let g = |cells: &[Relaxation], t: f64| cells.iter().map(|p| p.value(t)).collect::<Vec<_>>();
        contrasts.push(contrast(
            "G(0)".into(),
            "Pa",
            &g(&ca, 0.0),
            &g(&cb, 0.0),
            c.method,
        )?);
        contrasts.push(contrast(
            format!("G({t_end} s)"),
            "Pa",
            &g(&ca, t_end),
            &g(&cb, t_end),
            c.method,
        )?);
        contrasts.push(contrast(
            format!("relaxation at {t_end} s"),
            "",
            &relaxation_amounts(&ca, t_end),
            &relaxation_amounts(&cb, t_end),
            c.method,
        )?);
    }

    if json_out {
        let comparison = c.pair.as_ref().map(|(a, b)| {
            json!({
                "a": a, "b": b, "method": c.method_name,
                "times_with_p_below_0.05": significant,
                "tests": contrasts.iter().map(|k| json!({
                    "quantity": k.what, "unit": k.unit,
                    "test": test_json(&k.test), "effect_a_minus_b": effect_json(&k.effect),
                })).collect::<Vec<_>>(),
                "pvalues_csv": c.pvalues_csv.display().to_string(),
            })
        });
        let doc = json!({
            "results": c.results.display().to_string(),
            "cells_used": c.table.cells.len(),
            "excluded": c.table.excluded.iter().map(|e| json!({
                "cell": e.cell, "group": e.group, "line": e.line, "reason": e.reason,
            })).collect::<Vec<_>>(),
            "t_end_s": t_end,
            "points": c.times.len(),
            "groups": group_json,
            "comparison": comparison,
            "groups_csv": c.groups_csv.display().to_string(),
        });
        print_json(&doc)?;
        return Ok(ExitCode::SUCCESS);
    }

    println!(
        "{}: {} group(s), {} cell(s) used, {} excluded",
        c.results.display(),
        names.len(),
        c.table.cells.len(),
        c.table.excluded.len()
    );
    for e in &c.table.excluded {
        println!(
            "  excluded {} ({}, line {}): {}",
            e.cell, e.group, e.line, e.reason
        );
    }
    println!(
        "{:<16} {:>4}  {:>18}  {:>18}  {:>16}",
        "group",
        "n",
        "G(0) kPa",
        format!("G({t_end} s) kPa"),
        "relaxation %"
    );
    for (g, relax) in &curves {
        let last = g.times.len() - 1;
        println!(
            "{:<16} {:>4}  {:>8.3} ± {:<7.3}  {:>8.3} ± {:<7.3}  {:>6.1} ± {:<6.1}",
            g.name,
            g.n,
            g.shear[0].mean / 1e3,
            g.shear[0].sd / 1e3,
            g.shear[last].mean / 1e3,
            g.shear[last].sd / 1e3,
            100.0 * relax.mean,
            100.0 * relax.sd
        );
    }
    match &c.pair {
        Some((a, b)) => {
            println!(
                "{a} vs {b} (Wilcoxon rank-sum, two-sided, --method {}):",
                c.method_name
            );
            for k in &contrasts {
                let hl = if k.unit == "Pa" {
                    format!("{:.3} kPa", k.effect.hodges_lehmann / 1e3)
                } else {
                    format!("{:.3}", k.effect.hodges_lehmann)
                };
                println!(
                    "  {:<24} p = {:<10.3e} ({}), rank-biserial = {:+.3}, Hodges–Lehmann shift = {hl}",
                    k.what, k.test.p, k.test.used, k.effect.rank_biserial
                );
            }
            println!(
                "  G(t): p < 0.05 at {significant} of {} times",
                c.times.len()
            );
            println!("wrote {}", c.pvalues_csv.display());
        }
        None => println!(
            "{} groups: choose two with --groups A,B for p-values",
            names.len()
        ),
    }
    println!("wrote {}", c.groups_csv.display());
    Ok(ExitCode::SUCCESS)
}
