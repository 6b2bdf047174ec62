//! Group summaries that carry each cell's uncertainty (issue 17), beside
//! the thesis's point-estimate statistics of §5.4.2.
//!
//! Every cell with a posterior keeps K thinned draws of its parameters
//! (`nlvid_inverse::Posterior::draws`). Cells are independent, so draw s
//! of every cell together is one draw of the whole cohort's parameters:
//! - [`group_bands`]: for each s, the group's mean G(t) over its cells;
//!   the pointwise quantiles over s are a credible band of the group mean
//!   *given these cells* — the measurement (and surrogate) uncertainty of
//!   the mean, not the cell-to-cell spread (that is the ±sd band of the
//!   thesis's Fig. 5.15);
//! - [`p_over_draws`]: for each s, the thesis's Wilcoxon rank-sum p(t)
//!   between two groups on the cells' G(t) of draw s; the quantiles of
//!   p_s(t) over s and the fraction of draws with p < 0.05 show whether the
//!   point-estimate p(t) survives the cells' uncertainty.
//!
//! G(t) is eq. 5.1 through `nlvid_model::Relaxation` (via
//! `nlvid_inverse::relaxation`).

use nlvid_inverse::posterior::quantile;
use nlvid_model::Domain;
use nlvid_stats::{Method, Policy, rank_sum};
use serde::Serialize;

use crate::cell::{CellResult, CellStatus};
use crate::error::{ReportError, Result};

/// A credible band of a group's mean G(t).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GroupBand {
    /// Group.
    pub group: String,
    /// Cells with a posterior (status ok).
    pub cells: usize,
    /// Times, s.
    pub times: Vec<f64>,
    /// Lower quantile, Pa.
    pub lower: Vec<f64>,
    /// Median, Pa.
    pub median: Vec<f64>,
    /// Upper quantile, Pa.
    pub upper: Vec<f64>,
    /// Credible level.
    pub level: f64,
}

/// The distribution over posterior draws of the rank-sum p(t) of a pair.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct POverDraws {
    /// First group.
    pub a: String,
    /// Second group.
    pub b: String,
    /// Times, s.
    pub times: Vec<f64>,
    /// 5 % quantile of p_s(t).
    pub p05: Vec<f64>,
    /// Median of p_s(t).
    pub p50: Vec<f64>,
    /// 95 % quantile of p_s(t).
    pub p95: Vec<f64>,
    /// Fraction of draws with p_s(t) < 0.05.
    pub frac_below_005: Vec<f64>,
    /// Draws used.
    pub draws: usize,
}

/// Per group: the cells (status ok, with a posterior) as K × G(t) curves.
struct GroupDraws {
    name: String,
    /// curves[cell][s][time]
    curves: Vec<Vec<Vec<f64>>>,
}

fn group_draws(cells: &[CellResult], domain: &Domain, times: &[f64]) -> Result<Vec<GroupDraws>> {
    let mut groups: Vec<GroupDraws> = Vec::new();
    for c in cells {
        let Some(p) = c.posterior.as_ref().filter(|_| c.status == CellStatus::Ok) else {
            continue;
        };
        let mut curves = Vec::with_capacity(p.draws.len());
        for x in &p.draws {
            let g = nlvid_inverse::relaxation(domain, x).map_err(|e| {
                ReportError::InvalidSetting(format!("cell {} posterior draw: {e}", c.cell))
            })?;
            curves.push(times.iter().map(|&t| g.value(t)).collect());
        }
        match groups.iter_mut().find(|g| g.name == c.group) {
            Some(g) => g.curves.push(curves),
            None => groups.push(GroupDraws {
                name: c.group.clone(),
                curves: vec![curves],
            }),
        }
    }
    Ok(groups)
}

/// The common number of draws of a group's cells (the smallest).
fn n_draws(g: &GroupDraws) -> usize {
    g.curves.iter().map(Vec::len).min().unwrap_or(0)
}

/// Credible bands of each group's mean G(t) at `times` (module docs).
/// Groups without a posterior cell are left out.
///
/// # Errors
/// A draw that is not an admissible Prony series (names from `domain`).
pub fn group_bands(
    cells: &[CellResult],
    domain: &Domain,
    times: &[f64],
    level: f64,
) -> Result<Vec<GroupBand>> {
    let a = 0.5 * (1.0 - level);
    let mut out = Vec::new();
    for g in group_draws(cells, domain, times)? {
        let k = n_draws(&g);
        if k == 0 {
            continue;
        }
        let n = g.curves.len() as f64;
        let mut band = GroupBand {
            group: g.name.clone(),
            cells: g.curves.len(),
            times: times.to_vec(),
            lower: Vec::new(),
            median: Vec::new(),
            upper: Vec::new(),
            level,
        };
        for ti in 0..times.len() {
            let mut means: Vec<f64> = (0..k)
                .map(|s| g.curves.iter().map(|c| c[s][ti]).sum::<f64>() / n)
                .collect();
            means.sort_by(f64::total_cmp);
            band.lower.push(quantile(&means, a));
            band.median.push(quantile(&means, 0.5));
            band.upper.push(quantile(&means, 1.0 - a));
        }
        out.push(band);
    }
    Ok(out)
}

/// The rank-sum p(t) (MATLAB `ranksum` rule, as the thesis) of groups `a`
/// and `b` for every posterior draw, summarised over draws (module docs).
/// `None` when either group has fewer than two cells with a posterior.
///
/// # Errors
/// A draw that is not an admissible Prony series; rank-sum failures.
pub fn p_over_draws(
    cells: &[CellResult],
    domain: &Domain,
    times: &[f64],
    a: &str,
    b: &str,
) -> Result<Option<POverDraws>> {
    let groups = group_draws(cells, domain, times)?;
    let (Some(ga), Some(gb)) = (
        groups.iter().find(|g| g.name == a),
        groups.iter().find(|g| g.name == b),
    ) else {
        return Ok(None);
    };
    if ga.curves.len() < 2 || gb.curves.len() < 2 {
        return Ok(None);
    }
    let k = n_draws(ga).min(n_draws(gb));
    let mut out = POverDraws {
        a: a.into(),
        b: b.into(),
        times: times.to_vec(),
        p05: Vec::new(),
        p50: Vec::new(),
        p95: Vec::new(),
        frac_below_005: Vec::new(),
        draws: k,
    };
    let method = Method::Auto(Policy::Matlab);
    for ti in 0..times.len() {
        let mut ps = Vec::with_capacity(k);
        for s in 0..k {
            let x: Vec<f64> = ga.curves.iter().map(|c| c[s][ti]).collect();
            let y: Vec<f64> = gb.curves.iter().map(|c| c[s][ti]).collect();
            let r = rank_sum(&x, &y, method)
                .map_err(|e| ReportError::InvalidSetting(format!("rank sum over draws: {e}")))?;
            ps.push(r.p);
        }
        let below = ps.iter().filter(|p| **p < 0.05).count() as f64 / k as f64;
        ps.sort_by(f64::total_cmp);
        out.p05.push(quantile(&ps, 0.05));
        out.p50.push(quantile(&ps, 0.5));
        out.p95.push(quantile(&ps, 0.95));
        out.frac_below_005.push(below);
    }
    Ok(Some(out))
}

#[cfg(test)]
mod tests {
    use super::*;
    use nlvid_inverse::Posterior;
    use nlvid_inverse::posterior::{Band, Interval};

    fn cell(group: &str, name: &str, draws: Vec<Vec<f64>>) -> CellResult {
        let iv = Interval {
            lower: 0.0,
            median: 0.0,
            upper: 0.0,
            rhat: 1.0,
            ess: 1.0,
        };
        let json = serde_json::json!({
            "group": group, "file": name, "cell": name, "study_hash": "h", "status": "ok",
            "reason": "", "flags": [], "parameters": [], "misfit": null, "alternatives": 0,
            "peak_force": null, "relaxation": null, "times": [], "data": [], "fit": []
        });
        let mut c: CellResult = serde_json::from_value(json).expect("cell");
        c.posterior = Some(Posterior {
            level: 0.9,
            noise_sd: 1.0,
            parameters: Vec::new(),
            g0: iv,
            g_sum: iv,
            g_end: iv,
            t_end: 52.0,
            band: Band {
                times: vec![],
                lower: vec![],
                median: vec![],
                upper: vec![],
            },
            rhat_max: 1.0,
            ess_min: 1.0,
            acceptance: 0.3,
            kept_steps: 1,
            rungs: 1,
            swap_acceptance: 0.0,
            proposals: 1,
            evaluations: 1,
            draws,
        });
        c
    }

    /// Elastic cells (g = 0: G(t) = G0) with draws G0 ∈ {c, c + 1, …}:
    /// the group mean of draw s is the mean of the cells' s-th values,
    /// computed here by hand.
    #[test]
    fn group_band_is_the_quantile_of_draw_wise_means() {
        let d = Domain::table_5_3(0.01).unwrap();
        let el = |g0: f64| vec![g0, 0.01, 0.01, 0.1, 10.0];
        // Two cells, 5 draws each: means (100+300)/2 + s·(1+3)/2 = 200 + 2s.
        let cells = vec![
            cell("A", "a1", (0..5).map(|s| el(100.0 + s as f64)).collect()),
            cell(
                "A",
                "a2",
                (0..5).map(|s| el(300.0 + 3.0 * s as f64)).collect(),
            ),
        ];
        let b = group_bands(&cells, &d, &[0.0], 0.5).unwrap();
        assert_eq!(b.len(), 1);
        assert_eq!(b[0].cells, 2);
        // Means 200, 202, 204, 206, 208: median 204, quartiles 202 and 206.
        assert!((b[0].median[0] - 204.0).abs() < 1e-9);
        assert!((b[0].lower[0] - 202.0).abs() < 1e-9);
        assert!((b[0].upper[0] - 206.0).abs() < 1e-9);
    }

    /// Groups separated in every draw: 3 vs 3 cells, all of A below all of
    /// B, exact rank-sum p = 2/C(6,3) = 0.1 in every draw; interleaved in
    /// every draw: ranks 1, 4, 5 vs 2, 3, 6, W = 10 next to the mean 10.5, p = 1.
    #[test]
    fn p_over_draws_reproduces_the_exact_rank_sum_of_each_draw() {
        let d = Domain::table_5_3(0.01).unwrap();
        let el = |g0: f64| vec![g0, 0.01, 0.01, 0.1, 10.0];
        let mk = |g: &str, n: &str, v: f64| cell(g, n, (0..4).map(|s| el(v + s as f64)).collect());
        let sep = vec![
            mk("A", "a1", 100.0),
            mk("A", "a2", 110.0),
            mk("A", "a3", 120.0),
            mk("B", "b1", 200.0),
            mk("B", "b2", 210.0),
            mk("B", "b3", 220.0),
        ];
        let p = p_over_draws(&sep, &d, &[0.0, 10.0], "A", "B")
            .unwrap()
            .unwrap();
        assert_eq!(p.draws, 4);
        for v in p.p50.iter().chain(&p.p05).chain(&p.p95) {
            assert!((v - 0.1).abs() < 1e-12, "{v}");
        }
        assert_eq!(p.frac_below_005, vec![0.0, 0.0]);
        let mixed = vec![
            mk("A", "a1", 100.0),
            mk("A", "a2", 400.0),
            mk("A", "a3", 500.0),
            mk("B", "b1", 200.0),
            mk("B", "b2", 300.0),
            mk("B", "b3", 600.0),
        ];
        let p = p_over_draws(&mixed, &d, &[0.0], "A", "B").unwrap().unwrap();
        assert!((p.p50[0] - 1.0).abs() < 1e-12, "{}", p.p50[0]);
        assert!(
            p_over_draws(&mixed, &d, &[0.0], "A", "C")
                .unwrap()
                .is_none()
        );
    }
}
