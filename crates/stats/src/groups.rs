//! Group summaries and group comparison over time (§5.4.2, Figs.
//! 5.14–5.21): per group mean ± sd of G(t), G(t)/G(0) and E(t) = 3G(t) on
//! a time grid, and the rank-sum p-value between two groups at every time.
//!
//! The standard deviation is the sample one (divisor n − 1, as MATLAB's
//! `std`), so every group needs at least two cells. The rank-sum test of
//! E(t) is that of G(t) (a common factor 3 does not change ranks), and the
//! test of the relaxation amount 1 − G(t)/G(0) is that of G(t)/G(0).
//! At t = 0 every G(t)/G(0) is 1: all tied, p = 1 by construction.

use crate::effect::{Effect, effect};
use crate::ranksum::{Method, RankSum, rank_sum};
use crate::{Result, StatsError};
use nlvid_model::Relaxation;

/// Mean and sample standard deviation (n − 1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeanSd {
    /// Arithmetic mean.
    pub mean: f64,
    /// Sample standard deviation.
    pub sd: f64,
}

/// Mean and sample standard deviation of `v`.
///
/// # Errors
/// Fewer than two values.
pub fn mean_sd(what: &str, v: &[f64]) -> Result<MeanSd> {
    if v.len() < 2 {
        return Err(StatsError::TooFew {
            what: what.to_string(),
            needed: 2,
            got: v.len(),
        });
    }
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let ss: f64 = v.iter().map(|x| (x - mean) * (x - mean)).sum();
    Ok(MeanSd {
        mean,
        sd: (ss / (n - 1.0)).sqrt(),
    })
}

/// One group's curves on a time grid.
#[derive(Debug, Clone, PartialEq)]
pub struct GroupCurves {
    /// Group name.
    pub name: String,
    /// Number of cells.
    pub n: usize,
    /// Time grid, s.
    pub times: Vec<f64>,
    /// G(t), Pa.
    pub shear: Vec<MeanSd>,
    /// G(t)/G(0).
    pub normalised: Vec<MeanSd>,
    /// E(t) = 3G(t), Pa.
    pub young: Vec<MeanSd>,
}

/// Mean ± sd of G(t), G(t)/G(0) and E(t) over `cells` at each of `times`.
///
/// # Errors
/// Fewer than two cells.
pub fn group_curves(name: &str, cells: &[Relaxation], times: &[f64]) -> Result<GroupCurves> {
    let what = format!("group `{name}`");
    let mut shear = Vec::with_capacity(times.len());
    let mut normalised = Vec::with_capacity(times.len());
    let mut young = Vec::with_capacity(times.len());
    for &t in times {
        let g: Vec<f64> = cells.iter().map(|c| c.value(t)).collect();
        let gn: Vec<f64> = cells.iter().map(|c| c.prony().value(t)).collect();
        let e: Vec<f64> = cells.iter().map(|c| c.young(t)).collect();
        shear.push(mean_sd(&what, &g)?);
        normalised.push(mean_sd(&what, &gn)?);
        young.push(mean_sd(&what, &e)?);
    }
    if times.is_empty() {
        mean_sd(&what, &cells.iter().map(Relaxation::g0).collect::<Vec<_>>())?;
    }
    Ok(GroupCurves {
        name: name.to_string(),
        n: cells.len(),
        times: times.to_vec(),
        shear,
        normalised,
        young,
    })
}

/// Comparison of two groups at one time.
#[derive(Debug, Clone, PartialEq)]
pub struct TimeComparison {
    /// Time, s.
    pub t: f64,
    /// Rank-sum test on G(t) (equivalently E(t)).
    pub shear: RankSum,
    /// Rank-sum test on G(t)/G(0) (equivalently the relaxation amount).
    pub normalised: RankSum,
    /// Effect sizes of group a relative to b on G(t).
    pub shear_effect: Effect,
}

/// Rank-sum tests between groups `a` and `b` at each of `times`.
///
/// # Errors
/// An empty group, or the exact method on groups too large to enumerate.
pub fn compare_over_time(
    a: &[Relaxation],
    b: &[Relaxation],
    times: &[f64],
    method: Method,
) -> Result<Vec<TimeComparison>> {
    times
        .iter()
        .map(|&t| {
            let ga: Vec<f64> = a.iter().map(|c| c.value(t)).collect();
            let gb: Vec<f64> = b.iter().map(|c| c.value(t)).collect();
            let na: Vec<f64> = a.iter().map(|c| c.prony().value(t)).collect();
            let nb: Vec<f64> = b.iter().map(|c| c.prony().value(t)).collect();
            Ok(TimeComparison {
                t,
                shear: rank_sum(&ga, &gb, method)?,
                normalised: rank_sum(&na, &nb, method)?,
                shear_effect: effect(&ga, &gb)?,
            })
        })
        .collect()
}

/// Relaxation amounts 1 − G(t)/G(0) of each cell at `t`.
pub fn relaxation_amounts(cells: &[Relaxation], t: f64) -> Vec<f64> {
    cells.iter().map(|c| 1.0 - c.prony().value(t)).collect()
}
