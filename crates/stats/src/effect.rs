//! Effect sizes for two independent samples (how different, not only
//! whether).
//!
//! - rank-biserial correlation `r = 2·U1/(n1·n2) − 1` (Kerby 2014), from
//!   the rank sum;
//! - Cliff's δ = (#{x > y} − #{x < y})/(n1·n2), from pair counts;
//!   algebraically equal to `r` (a test checks the two computations);
//! - probability of superiority `P(X > Y) + P(X = Y)/2 = U1/(n1·n2)`;
//! - Hodges–Lehmann shift: median of all n1·n2 differences `x_i − y_j`.
//!
//! Positive values mean `x` tends to be larger than `y`.

use crate::ranksum::{Method, rank_sum};
use crate::{Result, StatsError};

/// Effect sizes of `x` relative to `y`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Effect {
    /// Rank-biserial correlation in [−1, 1].
    pub rank_biserial: f64,
    /// Cliff's δ in [−1, 1].
    pub cliffs_delta: f64,
    /// `U1/(n1·n2)` in [0, 1].
    pub superiority: f64,
    /// Median of pairwise differences `x_i − y_j`, in the data's unit.
    pub hodges_lehmann: f64,
}

/// Rank-biserial correlation `2·U1/(n1·n2) − 1`.
///
/// # Errors
/// Empty samples or non-finite values.
pub fn rank_biserial(x: &[f64], y: &[f64]) -> Result<f64> {
    let r = rank_sum(x, y, Method::ASYMPTOTIC)?;
    Ok(2.0 * r.u1 / (r.n1 * r.n2) as f64 - 1.0)
}

fn check(x: &[f64], y: &[f64]) -> Result<()> {
    for (what, v) in [("x", x), ("y", y)] {
        if v.is_empty() {
            return Err(StatsError::TooFew {
                what: what.to_string(),
                needed: 1,
                got: 0,
            });
        }
        if let Some((index, &value)) = v.iter().enumerate().find(|(_, a)| !a.is_finite()) {
            return Err(StatsError::NotFinite { what, index, value });
        }
    }
    Ok(())
}

/// Cliff's δ by counting pairs, O(n1·n2).
///
/// # Errors
/// Empty samples or non-finite values.
pub fn cliffs_delta(x: &[f64], y: &[f64]) -> Result<f64> {
    check(x, y)?;
    let mut s: i64 = 0;
    for &a in x {
        for &b in y {
            s += (a > b) as i64 - (a < b) as i64;
        }
    }
    Ok(s as f64 / (x.len() * y.len()) as f64)
}

/// Hodges–Lehmann estimate of the shift `x − y`: the median of all
/// pairwise differences (mean of the two middle ones for an even count).
///
/// # Errors
/// Empty samples or non-finite values.
pub fn hodges_lehmann(x: &[f64], y: &[f64]) -> Result<f64> {
    check(x, y)?;
    let mut d: Vec<f64> = x
        .iter()
        .flat_map(|&a| y.iter().map(move |&b| a - b))
        .collect();
    d.sort_by(f64::total_cmp);
    let m = d.len();
    Ok(if m % 2 == 1 {
        d[m / 2]
    } else {
        0.5 * (d[m / 2 - 1] + d[m / 2])
    })
}

/// All effect sizes of `x` relative to `y`.
///
/// # Errors
/// Empty samples or non-finite values.
pub fn effect(x: &[f64], y: &[f64]) -> Result<Effect> {
    let r = rank_sum(x, y, Method::ASYMPTOTIC)?;
    let nn = (r.n1 * r.n2) as f64;
    Ok(Effect {
        rank_biserial: 2.0 * r.u1 / nn - 1.0,
        cliffs_delta: cliffs_delta(x, y)?,
        superiority: r.u1 / nn,
        hodges_lehmann: hodges_lehmann(x, y)?,
    })
}
