//! Wilcoxon rank-sum (Mann–Whitney U) test between two independent samples,
//! two-sided, as used in §5.4.2 (MATLAB `ranksum`) to compare cell groups.
//!
//! Statistics: pool `x` (size n1) and `y` (size n2), N = n1 + n2, mid-rank
//! ties; `W` = rank sum of `x`, `U1 = W − n1(n1+1)/2` (scipy's `statistic`),
//! `U2 = n1·n2 − U1`.
//!
//! p-values:
//! - **Exact** — the permutation distribution of `W` over all C(N, n1)
//!   assignments of the observed mid-ranks to `x`, p = min(1, 2·min(P(W ≤
//!   w), P(W ≥ w))). Without ties this is the classical Mann–Whitney
//!   distribution (scipy `mannwhitneyu(method='exact')`); with ties it is
//!   the conditional distribution MATLAB's `ranksum(..., 'method','exact')`
//!   enumerates. (scipy's 'exact' ignores ties and truncates U; we do not
//!   reproduce that.) Cost O(n_min · N · N(N+1)) operations.
//! - **Asymptotic** — normal approximation
//!   `z = (|U1 − n1n2/2| − c)/σ`, `σ² = n1n2/12 · (N + 1 − Σ(t³ − t)/(N(N − 1)))`
//!   (tie correction, t = size of each tie group), `c = 1/2` with the
//!   continuity correction, p = min(1, 2·P(Z > z)). With both corrections
//!   this is scipy `mannwhitneyu(method='asymptotic', use_continuity=True)`
//!   and MATLAB's `'approximate'` method; with neither it is scipy
//!   `ranksums`. If every value is tied, σ = 0 and p = 1 (no evidence).
//!
//! Which one [`Method::Auto`] picks is set by a [`Policy`]:
//! - [`Policy::Matlab`] (default, the thesis's tool): exact when
//!   min(n1, n2) < 10 and N < 20 (MATLAB documentation for `ranksum`),
//!   otherwise asymptotic with both corrections;
//! - [`Policy::Scipy`]: exact when min(n1, n2) ≤ 8 and there are no ties,
//!   otherwise asymptotic with both corrections (`mannwhitneyu` 'auto').

use crate::normal::normal_sf;
use crate::rank::midranks;
use crate::{Result, StatsError};

/// Rule that chooses exact or asymptotic under [`Method::Auto`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Policy {
    /// MATLAB `ranksum`: exact iff min(n1, n2) < 10 and n1 + n2 < 20.
    #[default]
    Matlab,
    /// scipy `mannwhitneyu(method='auto')`: exact iff min(n1, n2) ≤ 8 and
    /// no ties.
    Scipy,
}

/// How the p-value is computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Method {
    /// Let a [`Policy`] choose between the two below.
    Auto(Policy),
    /// Permutation distribution of the rank sum (conditional on ties).
    Exact,
    /// Normal approximation.
    Asymptotic {
        /// Subtract 1/2 from |U − n1n2/2| (continuity correction).
        continuity: bool,
        /// Use the tie-corrected variance.
        tie_correction: bool,
    },
}

impl Default for Method {
    fn default() -> Self {
        Method::Auto(Policy::Matlab)
    }
}

impl Method {
    /// scipy `mannwhitneyu(x, y)` defaults (method 'auto', continuity on).
    pub const SCIPY_MANNWHITNEYU: Method = Method::Auto(Policy::Scipy);
    /// scipy `ranksums(x, y)`: normal approximation, no tie or continuity
    /// correction.
    pub const SCIPY_RANKSUMS: Method = Method::Asymptotic {
        continuity: false,
        tie_correction: false,
    };
    /// MATLAB `ranksum(x, y)` defaults.
    pub const MATLAB_RANKSUM: Method = Method::Auto(Policy::Matlab);
    /// Normal approximation with tie and continuity corrections.
    pub const ASYMPTOTIC: Method = Method::Asymptotic {
        continuity: true,
        tie_correction: true,
    };
}

/// Which computation produced a p-value.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Used {
    /// Exact permutation distribution.
    Exact,
    /// Normal approximation (with the corrections named).
    Asymptotic {
        /// Continuity correction applied.
        continuity: bool,
        /// Tie-corrected variance used.
        tie_correction: bool,
    },
}

impl std::fmt::Display for Used {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Used::Exact => write!(f, "exact"),
            Used::Asymptotic {
                continuity,
                tie_correction,
            } => {
                write!(f, "asymptotic")?;
                if *tie_correction {
                    write!(f, "+ties")?;
                }
                if *continuity {
                    write!(f, "+continuity")?;
                }
                Ok(())
            }
        }
    }
}

/// Outcome of a two-sided rank-sum test.
#[derive(Debug, Clone, PartialEq)]
pub struct RankSum {
    /// Size of `x`.
    pub n1: usize,
    /// Size of `y`.
    pub n2: usize,
    /// Rank sum of `x` (mid-ranks).
    pub w: f64,
    /// Mann–Whitney U of `x`: number of pairs with x > y, ties counting 1/2.
    pub u1: f64,
    /// Standardised statistic of the normal approximation (signed like
    /// `U1 − n1n2/2`); `None` for the exact method.
    pub z: Option<f64>,
    /// Two-sided p-value.
    pub p: f64,
    /// Whether the pooled sample has ties.
    pub ties: bool,
    /// Which computation produced `p`.
    pub used: Used,
}

fn check_sample(what: &'static str, v: &[f64]) -> Result<()> {
    if v.is_empty() {
        return Err(StatsError::TooFew {
            what: what.to_string(),
            needed: 1,
            got: 0,
        });
    }
    if let Some((index, &value)) = v.iter().enumerate().find(|(_, x)| !x.is_finite()) {
        return Err(StatsError::NotFinite { what, index, value });
    }
    Ok(())
}

/// Two-sided Wilcoxon rank-sum test of `x` against `y`.
///
/// ```
/// use nlvid_stats::{rank_sum, Method};
/// // scipy's documentation example: mannwhitneyu(males, females, method="exact")
/// let males = [19.0, 22.0, 16.0, 29.0, 24.0];
/// let females = [20.0, 11.0, 17.0, 12.0];
/// let r = rank_sum(&males, &females, Method::Exact)?;
/// assert_eq!(r.u1, 17.0);
/// assert!((r.p - 0.1111111111111111).abs() < 1e-15);
/// # Ok::<(), nlvid_stats::StatsError>(())
/// ```
///
/// # Errors
/// An empty sample or a non-finite value; [`StatsError::ExactTooLarge`] if
/// the exact method is requested for samples too large to enumerate.
pub fn rank_sum(x: &[f64], y: &[f64], method: Method) -> Result<RankSum> {
    check_sample("x", x)?;
    check_sample("y", y)?;
    let (n1, n2) = (x.len(), y.len());
    let n = n1 + n2;
    let pooled: Vec<f64> = x.iter().chain(y).copied().collect();
    let (ranks, tie_sizes) = midranks(&pooled);
    let ties = !tie_sizes.is_empty();
    let w: f64 = ranks[..n1].iter().sum();
    let u1 = w - (n1 * (n1 + 1)) as f64 / 2.0;

    let exact = match method {
        Method::Exact => true,
        Method::Asymptotic { .. } => false,
        Method::Auto(Policy::Matlab) => n1.min(n2) < 10 && n < 20,
        Method::Auto(Policy::Scipy) => n1.min(n2) <= 8 && !ties,
    };
    if exact {
        let p = exact_p(&ranks, n1, w)?;
        return Ok(RankSum {
            n1,
            n2,
            w,
            u1,
            z: None,
            p,
            ties,
            used: Used::Exact,
        });
    }
    let (continuity, tie_correction) = match method {
        Method::Asymptotic {
            continuity,
            tie_correction,
        } => (continuity, tie_correction),
        _ => (true, true),
    };
    let (nf1, nf2, nf) = (n1 as f64, n2 as f64, n as f64);
    let tie_term: f64 = if tie_correction && n > 1 {
        tie_sizes
            .iter()
            .map(|&t| {
                let t = t as f64;
                t * t * t - t
            })
            .sum::<f64>()
            / (nf * (nf - 1.0))
    } else {
        0.0
    };
    let var = nf1 * nf2 / 12.0 * ((nf + 1.0) - tie_term);
    let d = u1 - nf1 * nf2 / 2.0;
    let (z, p) = if var <= 0.0 {
        (0.0, 1.0)
    } else {
        let num = d.abs() - if continuity { 0.5 } else { 0.0 };
        let z_abs = num / var.sqrt();
        (
            z_abs.max(0.0) * d.signum(),
            (2.0 * normal_sf(z_abs)).min(1.0),
        )
    };
    Ok(RankSum {
        n1,
        n2,
        w,
        u1,
        z: Some(if d == 0.0 { 0.0 } else { z }),
        p,
        ties,
        used: Used::Asymptotic {
            continuity,
            tie_correction,
        },
    })
}

/// Exact two-sided p of the rank sum `w` of the first `n1` of `ranks`
/// under all C(N, n1) equally likely assignments of the ranks.
fn exact_p(ranks: &[f64], n1: usize, w: f64) -> Result<f64> {
    let n = ranks.len();
    let n2 = n - n1;
    // Work with the smaller group (the distribution of the other group's
    // rank sum is its mirror: W_other = total − W).
    let total2: u64 = ranks.iter().map(|r| (2.0 * r).round() as u64).sum();
    let w2 = (2.0 * w).round() as u64;
    let (k, target) = if n1 <= n2 {
        (n1, w2)
    } else {
        (n2, total2 - w2)
    };
    let flip = n1 > n2;
    let smax = (n * (n + 1)) as u64; // 2 × the largest possible rank sum
    let ops = (k as f64) * (n as f64) * (smax as f64);
    if ops > 4e9 {
        return Err(StatsError::ExactTooLarge { n1, n2, ops });
    }
    let doubled: Vec<usize> = ranks.iter().map(|r| (2.0 * r).round() as usize).collect();
    let smax = smax as usize;
    // counts[j][s]: number of j-subsets of the items seen so far with
    // doubled-rank sum s. Counts reach C(N, k) < 1e308 for any N this
    // guard admits; f64 keeps ~1e-16 relative error per addition.
    let width = smax + 1;
    let mut counts = vec![0.0f64; (k + 1) * width];
    counts[0] = 1.0;
    for (i, &a) in doubled.iter().enumerate() {
        for j in (1..=k.min(i + 1)).rev() {
            let (lo, hi) = counts.split_at_mut(j * width);
            let prev = &lo[(j - 1) * width..];
            let cur = &mut hi[..width];
            for s in (a..width).rev() {
                cur[s] += prev[s - a];
            }
        }
    }
    let dist = &counts[k * width..];
    let all: f64 = dist.iter().sum();
    let target = target as usize;
    let below: f64 = dist[..=target.min(smax)].iter().sum();
    let above: f64 = dist[target.min(width)..].iter().sum();
    let (p_le, p_ge) = (below / all, above / all);
    // P(W_x ≤ w) = P(W_small ≥ total − w) when the small group is y.
    let (lo, hi) = if flip { (p_ge, p_le) } else { (p_le, p_ge) };
    Ok((2.0 * lo.min(hi)).min(1.0))
}
