//! Curve preparation: baseline correction, tip–sample separation, contact point,
//! indentation (thesis §5.2.2: δ = Z − d, F = k d).
//!
//! Sign convention (JPK): heights grow *away* from the sample, and a positive force is
//! repulsive (the cantilever is bent away from the sample). The tip therefore sits at
//! `s = h + F/k` (the deflection d = F/k lifts the tip above where the undeflected
//! cantilever would put it), and the indentation is `δ = s_c − s`, positive in contact.
//! This is the thesis's δ = Z − d with Z = s_c' − h the piezo travel past the contact.

use std::ops::Range;

use crate::curve::{ForceCurve, SegmentKind};
use crate::error::{AfmError, Result};

/// A straight baseline `F_b(x) = offset + slope·x` of the non-contact part of a curve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Baseline {
    /// Force offset, N (value at x = 0 when a slope is fitted; the mean otherwise).
    pub offset: f64,
    /// Slope, N per unit of x (0 when fitted without slope).
    pub slope: f64,
    /// Standard deviation of the residual about the baseline, N.
    pub noise: f64,
}

impl Baseline {
    /// Least-squares baseline of `f` against `x` over the samples in `range`
    /// (offset only, or offset + slope when `with_slope`).
    ///
    /// # Errors
    /// [`AfmError::InvalidInput`] if the slices differ in length, the range is out of
    /// bounds or holds fewer than 2 (3 with slope) samples, or x is constant with a slope.
    pub fn fit(x: &[f64], f: &[f64], range: Range<usize>, with_slope: bool) -> Result<Self> {
        if x.len() != f.len() || range.end > f.len() || range.start >= range.end {
            return Err(AfmError::InvalidInput(format!(
                "baseline range {range:?} on {} samples (x has {})",
                f.len(),
                x.len()
            )));
        }
        let n = range.len();
        if n < if with_slope { 3 } else { 2 } {
            return Err(AfmError::InvalidInput(format!(
                "baseline needs more samples than {n}"
            )));
        }
        let xs = &x[range.clone()];
        let fs = &f[range];
        let nf = n as f64;
        let mx = xs.iter().sum::<f64>() / nf;
        let mf = fs.iter().sum::<f64>() / nf;
        let slope = if with_slope {
            let sxx: f64 = xs.iter().map(|v| (v - mx).powi(2)).sum();
            let sxf: f64 = xs.iter().zip(fs).map(|(a, b)| (a - mx) * (b - mf)).sum();
            if sxx <= 0.0 {
                return Err(AfmError::InvalidInput(
                    "baseline with slope over a constant x".into(),
                ));
            }
            sxf / sxx
        } else {
            0.0
        };
        let offset = mf - slope * mx;
        let ss: f64 = xs
            .iter()
            .zip(fs)
            .map(|(a, b)| (b - offset - slope * a).powi(2))
            .sum();
        Ok(Baseline {
            offset,
            slope,
            noise: (ss / (nf - 1.0)).sqrt(),
        })
    }

    /// Baseline value at `x`.
    pub fn at(&self, x: f64) -> f64 {
        self.offset + self.slope * x
    }

    /// `f − F_b(x)` for every sample.
    pub fn subtract(&self, x: &[f64], f: &[f64]) -> Vec<f64> {
        x.iter().zip(f).map(|(a, b)| b - self.at(*a)).collect()
    }
}

/// Tip–sample separation `s = h + F/k` (see the module doc for the sign convention).
///
/// # Errors
/// [`AfmError::InvalidInput`] if lengths differ or k is not positive and finite.
pub fn tip_sample_separation(
    height: &[f64],
    force: &[f64],
    spring_constant: f64,
) -> Result<Vec<f64>> {
    if height.len() != force.len() {
        return Err(AfmError::InvalidInput(format!(
            "height has {} samples, force {}",
            height.len(),
            force.len()
        )));
    }
    if !(spring_constant.is_finite() && spring_constant > 0.0) {
        return Err(AfmError::InvalidInput(format!(
            "spring constant must be positive, got {spring_constant}"
        )));
    }
    Ok(height
        .iter()
        .zip(force)
        .map(|(h, f)| h + f / spring_constant)
        .collect())
}

/// Indentation `δ = s_c − s` (positive in contact, negative before it).
pub fn indentation(separation: &[f64], contact: f64) -> Vec<f64> {
    separation.iter().map(|s| contact - s).collect()
}

/// How to find the contact point on an approach curve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ContactMethod {
    /// Last sample before the force maximum at which the baseline-corrected force is
    /// still within `n_sigma` noise standard deviations of the baseline; the baseline
    /// is fitted (offset only) over the first `baseline_fraction` of the samples.
    Deviation {
        /// Fraction of the curve (from its start) taken as baseline, in (0, 1).
        baseline_fraction: f64,
        /// Threshold in baseline noise standard deviations.
        n_sigma: f64,
    },
    /// Least-squares fit of a continuous piecewise model, constant before the contact
    /// and linear in separation after it, `F = b + m·max(0, s_c − s)`; the contact is
    /// the break point minimising the residual (exhaustive over samples, O(n)).
    PiecewiseLinear,
}

impl ContactMethod {
    /// The method by its name in the CLI and Python: `deviation` (the
    /// default) or `piecewise`.
    ///
    /// # Errors
    /// Any other name, quoted, with the two that exist.
    pub fn from_name(name: &str) -> std::result::Result<Self, String> {
        match name {
            "deviation" => Ok(ContactMethod::default()),
            "piecewise" => Ok(ContactMethod::PiecewiseLinear),
            other => Err(format!(
                "`{other}`: expected \"deviation\" or \"piecewise\""
            )),
        }
    }
}

impl Default for ContactMethod {
    fn default() -> Self {
        ContactMethod::Deviation {
            baseline_fraction: 0.5,
            n_sigma: 5.0,
        }
    }
}

/// A contact point on a curve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactPoint {
    /// Sample index of the contact.
    pub index: usize,
    /// Tip–sample separation at contact, m.
    pub separation: f64,
}

/// Contact point of an approach curve (force against separation), searched before the
/// force maximum.
///
/// # Errors
/// [`AfmError::InvalidInput`] for mismatched or too short input or bad method settings;
/// [`AfmError::NoContact`] if the force never leaves the baseline.
pub fn contact_point(
    separation: &[f64],
    force: &[f64],
    method: ContactMethod,
) -> Result<ContactPoint> {
    let n = force.len();
    if separation.len() != n || n < 8 {
        return Err(AfmError::InvalidInput(format!(
            "contact point needs ≥ 8 samples of equal length (separation {}, force {n})",
            separation.len()
        )));
    }
    if force.iter().chain(separation).any(|v| !v.is_finite()) {
        return Err(AfmError::InvalidInput(
            "non-finite sample in the approach curve".into(),
        ));
    }
    let imax = argmax(force);
    match method {
        ContactMethod::Deviation {
            baseline_fraction,
            n_sigma,
        } => {
            if !(baseline_fraction > 0.0 && baseline_fraction < 1.0 && n_sigma > 0.0) {
                return Err(AfmError::InvalidInput(format!(
                    "deviation method needs 0 < baseline_fraction < 1 and n_sigma > 0 (got {baseline_fraction}, {n_sigma})"
                )));
            }
            let nb = ((n as f64 * baseline_fraction) as usize).max(2);
            let base = Baseline::fit(separation, force, 0..nb, false)?;
            let thr = n_sigma * base.noise;
            if imax < nb || force[imax] - base.offset <= thr {
                return Err(AfmError::NoContact(format!(
                    "force maximum {:.3e} N is within {n_sigma} σ ({thr:.3e} N) of the baseline or inside the baseline window",
                    force[imax] - base.offset
                )));
            }
            let mut i = imax;
            while i > 0 && force[i] - base.offset > thr {
                i -= 1;
            }
            Ok(ContactPoint {
                index: i,
                separation: separation[i],
            })
        }
        ContactMethod::PiecewiseLinear => {
            let (index, _) = piecewise_break(&separation[..=imax], &force[..=imax])?;
            Ok(ContactPoint {
                index,
                separation: separation[index],
            })
        }
    }
}

/// Deviation-from-baseline contact point with a baseline measured elsewhere (e.g. the
/// pause before the approach): the last sample before the force maximum whose force
/// lies within `n_sigma`·noise of `baseline` (evaluated at the sample's separation).
///
/// # Errors
/// [`AfmError::InvalidInput`] for mismatched input or n_sigma ≤ 0; [`AfmError::NoContact`]
/// if the maximum does not exceed the threshold.
pub fn contact_point_from_baseline(
    separation: &[f64],
    force: &[f64],
    baseline: &Baseline,
    n_sigma: f64,
) -> Result<ContactPoint> {
    let n = force.len();
    if separation.len() != n || n < 2 || n_sigma.is_nan() || n_sigma <= 0.0 {
        return Err(AfmError::InvalidInput(format!(
            "contact point needs equal-length input and n_sigma > 0 (separation {}, force {n}, n_sigma {n_sigma})",
            separation.len()
        )));
    }
    let thr = n_sigma * baseline.noise;
    let imax = argmax(force);
    let above = |i: usize| force[i] - baseline.at(separation[i]) > thr;
    if !above(imax) {
        return Err(AfmError::NoContact(format!(
            "force maximum is within {n_sigma} σ ({thr:.3e} N) of the baseline"
        )));
    }
    let mut i = imax;
    while i > 0 && above(i) {
        i -= 1;
    }
    Ok(ContactPoint {
        index: i,
        separation: separation[i],
    })
}

fn argmax(x: &[f64]) -> usize {
    let mut best = 0;
    for (i, v) in x.iter().enumerate() {
        if *v > x[best] {
            best = i;
        }
    }
    best
}

/// Break index c minimising Σ (F_i − b − m·max(0, s_c − s_i))² with b, m free, m ≥ 0.
/// Suffix sums make each candidate O(1). Returns (c, sse).
fn piecewise_break(s: &[f64], f: &[f64]) -> Result<(usize, f64)> {
    let n = s.len();
    if n < 4 {
        return Err(AfmError::NoContact(
            "force maximum too close to the start of the curve".into(),
        ));
    }
    // Centre the data to keep the sums well conditioned.
    let s0 = s[0];
    let fm = f.iter().sum::<f64>() / n as f64;
    let fc: Vec<f64> = f.iter().map(|v| v - fm).collect();
    let sc: Vec<f64> = s.iter().map(|v| v - s0).collect();
    // suffix sums over i ≥ c: count, Σs, Σs², Σf, Σs·f
    let mut suf = vec![[0.0; 5]; n + 1];
    for i in (0..n).rev() {
        let (x, y) = (sc[i], fc[i]);
        suf[i] = [
            suf[i + 1][0] + 1.0,
            suf[i + 1][1] + x,
            suf[i + 1][2] + x * x,
            suf[i + 1][3] + y,
            suf[i + 1][4] + x * y,
        ];
    }
    let nf = n as f64;
    let syy: f64 = fc.iter().map(|v| v * v).sum();
    let sy: f64 = 0.0; // centred
    let mut best = (usize::MAX, f64::INFINITY);
    for c in 1..n - 1 {
        let xc = sc[c];
        let [k, sx, sxx, sfy, sxy] = suf[c];
        // r_i = xc − x_i for i ≥ c (tip moves to smaller s in contact), 0 before.
        let sr = k * xc - sx;
        let srr = k * xc * xc - 2.0 * xc * sx + sxx;
        let sry = xc * sfy - sxy;
        let det = nf * srr - sr * sr;
        let (b, m) = if det > 0.0 {
            let m = (nf * sry - sr * sy) / det;
            if m > 0.0 {
                ((sy - m * sr) / nf, m)
            } else {
                (sy / nf, 0.0)
            }
        } else {
            (sy / nf, 0.0)
        };
        // SSE = Σ(y − b − m r)²
        let sse = syy - 2.0 * b * sy - 2.0 * m * sry + nf * b * b + 2.0 * b * m * sr + m * m * srr;
        if sse < best.1 {
            best = (c, sse);
        }
    }
    if best.0 == usize::MAX {
        return Err(AfmError::NoContact("piecewise fit found no break".into()));
    }
    Ok(best)
}

/// Baseline and contact point of the extend segment `curve.segments[extend]`, whose
/// separation and force are `separation`, `force`.
///
/// A pause recorded just before the approach (the probe still free, ≥ 16 samples) is the
/// better baseline, since the force may rise from the very first extend sample (ramp-hold
/// files, docs/theory/afm.md choice 5): with the deviation method its mean and noise give
/// the baseline and [`contact_point_from_baseline`] the contact. Otherwise the contact is
/// found on the extend with `method` and the baseline fitted (offset only) to the samples
/// before it.
///
/// # Errors
/// As [`contact_point`], [`contact_point_from_baseline`] and [`Baseline::fit`]; missing
/// channels of the pause.
pub fn approach_baseline(
    curve: &ForceCurve,
    extend: usize,
    separation: &[f64],
    force: &[f64],
    method: ContactMethod,
) -> Result<(ContactPoint, Baseline)> {
    let pre = extend
        .checked_sub(1)
        .and_then(|i| curve.segments.get(i))
        .filter(|s| s.kind == SegmentKind::Hold && s.len() >= 16);
    match (method, pre) {
        (ContactMethod::Deviation { n_sigma, .. }, Some(pre)) => {
            let fp = pre.force()?;
            let sp = tip_sample_separation(pre.height()?, fp, curve.calibration.spring_constant)?;
            let base = Baseline::fit(&sp, fp, 0..fp.len(), false)?;
            Ok((
                contact_point_from_baseline(separation, force, &base, n_sigma)?,
                base,
            ))
        }
        _ => {
            let contact = contact_point(separation, force, method)?;
            let base = Baseline::fit(separation, force, 0..contact.index.max(2), false)?;
            Ok((contact, base))
        }
    }
}
