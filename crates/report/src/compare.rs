//! `nlvid compare`: the group comparison of a results table
//! ([`nlvid_stats::compare_groups`]) written as CSV (`<stem>.groups.csv`,
//! `<stem>.pvalues.csv`) and reported as text or JSON (thesis §5.4.2).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use nlvid_stats::{
    Comparison, Method, Policy, ResultsTable, compare_groups, write_group_curves,
    write_time_comparisons,
};
use serde_json::json;

use crate::cohort::write_atomic;
use crate::error::{ReportError, Result};

/// The rank-sum method named `name`: `matlab` (the thesis's ranksum),
/// `scipy` (mannwhitneyu 'auto'), `exact`, `asymptotic`.
///
/// # Errors
/// Any other name.
pub fn method(name: &str) -> Result<Method> {
    Ok(match name {
        "matlab" => Method::Auto(Policy::Matlab),
        "scipy" => Method::Auto(Policy::Scipy),
        "exact" => Method::Exact,
        "asymptotic" => Method::ASYMPTOTIC,
        m => {
            return Err(ReportError::InvalidSetting(format!(
                "--method `{m}`: expected one of matlab, scipy, exact, asymptotic"
            )));
        }
    })
}

/// A finished comparison and the files it wrote.
#[derive(Debug, Clone)]
pub struct CompareOutcome {
    /// The results table compared (file or, for a cohort, its results.csv).
    pub results: PathBuf,
    /// Cells used and excluded.
    pub table: ResultsTable,
    /// Group curves, p(t) and tests.
    pub comparison: Comparison,
    /// Method name as given.
    pub method: String,
    /// `<stem>.groups.csv`.
    pub groups_csv: PathBuf,
    /// `<stem>.pvalues.csv`, when two groups were compared.
    pub pvalues_csv: Option<PathBuf>,
}

/// Compares the groups of `table` (read from, or written as, `results`)
/// and writes `<stem>.groups.csv` and `<stem>.pvalues.csv` into `out_dir`
/// (created if missing). `groups`: the pair (default: the only two groups).
///
/// # Errors
/// A bad method or pair, a group with fewer than two cells, unwritable outputs.
pub fn compare(
    results: &Path,
    table: ResultsTable,
    groups: Option<&[String]>,
    times: &[f64],
    method_name: &str,
    out_dir: &Path,
) -> Result<CompareOutcome> {
    let names = table.groups();
    let pair = match groups {
        Some([a, b]) => Some((a.as_str(), b.as_str())),
        Some(_) => {
            return Err(ReportError::InvalidSetting(
                "--groups: give exactly two names, e.g. --groups MCF-10A,MCF-7".into(),
            ));
        }
        None if names.len() == 2 => Some((names[0].as_str(), names[1].as_str())),
        None => None,
    };
    let comparison = compare_groups(&table, pair, times, method(method_name)?)
        .map_err(|e| ReportError::InvalidSetting(format!("{}: {e}", results.display())))?;
    std::fs::create_dir_all(out_dir).map_err(|e| ReportError::io(out_dir, e))?;
    let stem = results
        .file_stem()
        .map_or_else(|| "results".into(), |s| s.to_string_lossy().into_owned());
    let groups_csv = out_dir.join(format!("{stem}.groups.csv"));
    let mut buf = Vec::new();
    let curves: Vec<_> = comparison.groups.iter().map(|g| g.curves.clone()).collect();
    write_group_curves(&mut buf, &curves)?;
    write_atomic(&groups_csv, &buf)?;
    let pvalues_csv = match &comparison.pair {
        Some(p) => {
            let path = out_dir.join(format!("{stem}.pvalues.csv"));
            let mut buf = Vec::new();
            write_time_comparisons(&mut buf, &p.over_time)?;
            write_atomic(&path, &buf)?;
            Some(path)
        }
        None => None,
    };
    Ok(CompareOutcome {
        results: results.to_path_buf(),
        table,
        comparison,
        method: method_name.to_string(),
        groups_csv,
        pvalues_csv,
    })
}

impl CompareOutcome {
    /// The `--json` document: groups, tests with effect sizes, p(t) at
    /// every grid time, exclusions, files.
    pub fn to_json(&self) -> serde_json::Value {
        let (results, table, c, method) =
            (&self.results, &self.table, &self.comparison, &self.method);
        let (groups_csv, pvalues_csv) = (&self.groups_csv, &self.pvalues_csv);
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

    /// The text summary: groups (G(0), G(t_end), relaxation), tests, files.
    pub fn text(&self) -> String {
        let (results, table, c, method) =
            (&self.results, &self.table, &self.comparison, &self.method);
        let (groups_csv, pvalues_csv) = (&self.groups_csv, &self.pvalues_csv);
        let mut s = String::new();
        let t_end = c.t_end();
        let _ = writeln!(
            s,
            "{}: {} group(s), {} cell(s) used, {} excluded",
            results.display(),
            c.groups.len(),
            table.cells.len(),
            table.excluded.len()
        );
        for e in &table.excluded {
            let _ = writeln!(
                s,
                "  excluded {} ({}, line {}): {}",
                e.cell, e.group, e.line, e.reason
            );
        }
        let g_end = format!("G({t_end} s) kPa");
        let _ = writeln!(
            s,
            "{:<16} {:>4}  {:>18}  {g_end:>18}  {:>16}",
            "group", "n", "G(0) kPa", "relaxation %"
        );
        for g in &c.groups {
            let (cur, last, r) = (&g.curves, g.curves.times.len() - 1, &g.relaxation_end);
            let _ = writeln!(
                s,
                "{:<16} {:>4}  {:>8.3} ± {:<7.3}  {:>8.3} ± {:<7.3}  {:>6.1} ± {:<6.1}",
                cur.name,
                cur.n,
                cur.shear[0].mean / 1e3,
                cur.shear[0].sd / 1e3,
                cur.shear[last].mean / 1e3,
                cur.shear[last].sd / 1e3,
                100.0 * r.mean,
                100.0 * r.sd
            );
        }
        match &c.pair {
            Some(p) => {
                let _ = writeln!(
                    s,
                    "{} vs {} (Wilcoxon rank-sum, two-sided, --method {method}):",
                    p.a, p.b
                );
                for k in &p.contrasts {
                    let hl = k.effect.hodges_lehmann;
                    let hl = if k.unit == "Pa" {
                        format!("{:.3} kPa", hl / 1e3)
                    } else {
                        format!("{hl:.3}")
                    };
                    let _ = writeln!(
                        s,
                        "  {:<28} p = {:<10.3e} ({}), rank-biserial = {:+.3}, Hodges–Lehmann shift = {hl}",
                        k.quantity, k.test.p, k.test.used, k.effect.rank_biserial
                    );
                }
                let _ = writeln!(
                    s,
                    "  G(t): p < 0.05 at {} of {} times",
                    p.times_below(0.05),
                    c.times.len()
                );
            }
            None => drop(writeln!(
                s,
                "{} groups: choose two with --groups A,B for p-values",
                c.groups.len()
            )),
        };
        for f in std::iter::once(groups_csv).chain(pvalues_csv) {
            let _ = writeln!(s, "wrote {}", f.display());
        }
        s
    }
}
