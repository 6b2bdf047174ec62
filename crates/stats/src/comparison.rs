//! The group comparison of §5.4.2 (Figs. 5.14–5.21) as one call: per group
//! mean ± sd of G(t), G(t)/G(0), E(t) = 3G(t) on a time grid and of the
//! relaxation amount at the grid's end; between two groups the rank-sum
//! p(t) at every time and the tests and effect sizes of G(0), G(t_end) and
//! the relaxation 1 − G(t_end)/G(0). `nlvid compare`, the HTML report and
//! the demo all call [`compare_groups`].

use crate::effect::{Effect, effect};
use crate::groups::{
    GroupCurves, MeanSd, TimeComparison, compare_over_time, group_curves, mean_sd,
    relaxation_amounts,
};
use crate::ranksum::{Method, RankSum, rank_sum};
use crate::results::ResultsTable;
use crate::{Result, StatsError};
use nlvid_model::Relaxation;

/// One group summarised on the grid.
#[derive(Debug, Clone, PartialEq)]
pub struct GroupSummary {
    /// G(t), G(t)/G(0), E(t): mean ± sd at every grid time.
    pub curves: GroupCurves,
    /// Relaxation 1 − G(t_end)/G(0) at the grid's last time: mean ± sd.
    pub relaxation_end: MeanSd,
}

/// A scalar quantity compared between the two groups.
#[derive(Debug, Clone, PartialEq)]
pub struct Contrast {
    /// What is compared, e.g. `G(0)` or `G(52 s)`.
    pub quantity: String,
    /// Its SI unit (`Pa`), or `""` for a fraction.
    pub unit: &'static str,
    /// Mean ± sd in group a.
    pub a: MeanSd,
    /// Mean ± sd in group b.
    pub b: MeanSd,
    /// Two-sided rank-sum test.
    pub test: RankSum,
    /// Effect sizes of a relative to b.
    pub effect: Effect,
}

/// Two groups compared.
#[derive(Debug, Clone, PartialEq)]
pub struct PairComparison {
    /// First group.
    pub a: String,
    /// Second group.
    pub b: String,
    /// Rank-sum tests at every grid time (p(t) on G and on G/G(0)).
    pub over_time: Vec<TimeComparison>,
    /// G(0), G(t_end) and the relaxation at t_end.
    pub contrasts: Vec<Contrast>,
}

impl PairComparison {
    /// Number of grid times where the test on G(t) gives p < `alpha`.
    pub fn times_below(&self, alpha: f64) -> usize {
        self.over_time.iter().filter(|r| r.shear.p < alpha).count()
    }
}

/// Everything a group comparison reports.
#[derive(Debug, Clone, PartialEq)]
pub struct Comparison {
    /// The time grid, s.
    pub times: Vec<f64>,
    /// Every group of the table, in table order.
    pub groups: Vec<GroupSummary>,
    /// The two groups compared, when a pair was given.
    pub pair: Option<PairComparison>,
}

impl Comparison {
    /// The last grid time (t_end), s.
    pub fn t_end(&self) -> f64 {
        self.times.last().copied().unwrap_or(0.0)
    }
}

fn contrast(
    quantity: String,
    unit: &'static str,
    (a, b): (&[f64], &[f64]),
    method: Method,
) -> Result<Contrast> {
    Ok(Contrast {
        quantity,
        unit,
        a: mean_sd("group a", a)?,
        b: mean_sd("group b", b)?,
        test: rank_sum(a, b, method)?,
        effect: effect(a, b)?,
    })
}

/// Summarises every group of `table` on `times` and, when `pair` names two
/// of its groups, compares them with `method`.
///
/// # Errors
/// An empty or non-increasing grid; a group with fewer than two usable
/// cells; a pair naming a group the table does not have, or the same group
/// twice.
pub fn compare_groups(
    table: &ResultsTable,
    pair: Option<(&str, &str)>,
    times: &[f64],
    method: Method,
) -> Result<Comparison> {
    let grid_ok = !times.is_empty()
        && times.iter().all(|t| t.is_finite() && *t >= 0.0)
        && times.windows(2).all(|w| w[1] > w[0]);
    if !grid_ok {
        return Err(StatsError::Comparison(
            "the time grid must be non-empty, finite, >= 0 and increasing".into(),
        ));
    }
    let t_end = times[times.len() - 1];
    let names = table.groups();
    let mut groups = Vec::with_capacity(names.len());
    for g in &names {
        let cells = table.group(g);
        groups.push(GroupSummary {
            curves: group_curves(g, &cells, times)?,
            relaxation_end: mean_sd(&format!("group `{g}`"), &relaxation_amounts(&cells, t_end))?,
        });
    }
    let pair = match pair {
        None => None,
        Some((a, b)) => {
            for g in [a, b] {
                if !names.iter().any(|n| n == g) {
                    return Err(StatsError::Comparison(format!(
                        "no usable cells in group `{g}` (groups: {})",
                        names.join(", ")
                    )));
                }
            }
            if a == b {
                return Err(StatsError::Comparison(format!(
                    "compare two different groups, not `{a}` with itself"
                )));
            }
            let (ca, cb) = (table.group(a), table.group(b));
            let g =
                |cells: &[Relaxation], t: f64| cells.iter().map(|p| p.value(t)).collect::<Vec<_>>();
            let contrasts = vec![
                contrast("G(0)".into(), "Pa", (&g(&ca, 0.0), &g(&cb, 0.0)), method)?,
                contrast(
                    format!("G({t_end} s)"),
                    "Pa",
                    (&g(&ca, t_end), &g(&cb, t_end)),
                    method,
                )?,
                contrast(
                    format!("relaxation 1 − G({t_end} s)/G(0)"),
                    "",
                    (
                        &relaxation_amounts(&ca, t_end),
                        &relaxation_amounts(&cb, t_end),
                    ),
                    method,
                )?,
            ];
            Some(PairComparison {
                a: a.to_string(),
                b: b.to_string(),
                over_time: compare_over_time(&ca, &cb, times, method)?,
                contrasts,
            })
        }
    };
    Ok(Comparison {
        times: times.to_vec(),
        groups,
        pair,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::results::CellRow;
    use nlvid_model::Prony;

    fn table(rows: &[(&str, f64)]) -> ResultsTable {
        let cells = rows
            .iter()
            .enumerate()
            .map(|(i, (group, g0))| CellRow {
                cell: format!("c{i}"),
                group: group.to_string(),
                line: i as u64 + 2,
                relaxation: Relaxation::new(
                    "G0",
                    *g0,
                    Prony::new("G", &[(0.5, 1.0)]).expect("prony"),
                )
                .expect("relaxation"),
            })
            .collect();
        ResultsTable {
            cells,
            excluded: Vec::new(),
            terms: 1,
        }
    }

    /// Three cells per group, complete separation: the exact two-sided
    /// rank-sum p is 2/C(6,3) = 0.1 at every time (G(t) ∝ G0 within a
    /// group of equal g, τ), and the relaxation (the same in every cell) is
    /// all ties: p = 1.
    #[test]
    fn separated_groups_give_the_exact_p_at_every_time_and_tied_relaxation_p_one() {
        let t = table(&[
            ("a", 3.0e3),
            ("a", 3.2e3),
            ("a", 2.9e3),
            ("b", 1.0e3),
            ("b", 1.1e3),
            ("b", 1.2e3),
        ]);
        let c =
            compare_groups(&t, Some(("a", "b")), &[0.0, 0.5, 4.0], Method::Exact).expect("compare");
        let p = c.pair.as_ref().expect("pair");
        for r in &p.over_time {
            assert!(
                (r.shear.p - 0.1).abs() < 1e-15,
                "t = {}: {}",
                r.t,
                r.shear.p
            );
        }
        assert_eq!(p.times_below(0.05), 0);
        assert_eq!(p.contrasts.len(), 3);
        assert!((p.contrasts[0].a.mean - (3.0e3 + 3.2e3 + 2.9e3) / 3.0).abs() < 1e-9);
        // G(4 s)/G(0) = 0.5 + 0.5 e^{-4} in every cell: relaxation all tied.
        assert_eq!(p.contrasts[2].test.p, 1.0);
        let expected = 0.5 - 0.5 * (-4.0f64).exp();
        assert!((c.groups[0].relaxation_end.mean - expected).abs() < 1e-15);
        assert_eq!(c.t_end(), 4.0);
    }

    #[test]
    fn bad_grids_and_unknown_groups_are_errors_that_say_why() {
        let t = table(&[("a", 1.0), ("a", 2.0), ("b", 3.0), ("b", 4.0)]);
        let e = compare_groups(&t, None, &[0.0, 2.0, 1.0], Method::Exact).expect_err("grid");
        assert!(e.to_string().contains("increasing"), "{e}");
        let e = compare_groups(&t, Some(("a", "c")), &[0.0], Method::Exact).expect_err("c");
        assert!(e.to_string().contains("group `c`"), "{e}");
        let e = compare_groups(&t, Some(("a", "a")), &[0.0], Method::Exact).expect_err("same");
        assert!(e.to_string().contains("itself"), "{e}");
    }
}
