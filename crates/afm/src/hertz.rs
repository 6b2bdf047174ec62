//! Elastic (Hertz–Sneddon) fit of an approach curve for any [`Indenter`] (thesis eq.
//! 1.1–1.3 for the paraboloid).
//!
//! Model: `F(s) = b + E/(1 − ν²)·shape(s_c − s)`, a rigid probe on an elastic half-space.
//! For a fixed contact point s_c the model is linear in E* = E/(1 − ν²) and b, so the fit
//! profiles the residual over s_c: a grid scan over the fitted range followed by Brent's
//! method (argmin `BrentOpt`) in the best grid cell. The residual at each trial is summed
//! directly (not from accumulated moments), so a noise-free curve is fitted to rounding.
//!
//! [`fit_approach`] adds what a user of real curves needs around that: a fit range
//! relative to the contact-point estimate ([`FitRange`]), and [`FitWarning`]s when the
//! indentation exceeds the model's validity, the fitted contact point sits on the edge
//! of its search range, or the fitted force offset exceeds the baseline noise.
//! [`modulus_vs_depth`] refits with growing maximal indentation.

use std::cell::RefCell;
use std::fmt;
use std::ops::Range;

use argmin::core::{CostFunction, Executor, State, TerminationReason, TerminationStatus};
use argmin::solver::brent::BrentOpt;

use crate::curve::{ForceCurve, SegmentKind};
use crate::error::{AfmError, Result};
use crate::indenter::Indenter;
use crate::prepare::{Baseline, ContactMethod, approach_baseline, tip_sample_separation};

/// Settings of an elastic fit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HertzSettings {
    /// Probe geometry.
    pub indenter: Indenter,
    /// Poisson ratio ν of the sample.
    pub poisson: f64,
    /// Fit a constant force offset b together with E and s_c (else b = 0: the force must
    /// already be baseline-corrected).
    pub fit_offset: bool,
    /// Grid points of the contact-point scan before Brent refinement.
    pub grid: usize,
}

impl HertzSettings {
    /// Paraboloid of radius `tip_radius` (eq. 1.1) on a sample of Poisson ratio
    /// `poisson`, offset fitted, 400-point scan.
    pub fn new(tip_radius: f64, poisson: f64) -> Self {
        Self::with_indenter(Indenter::Paraboloid { radius: tip_radius }, poisson)
    }

    /// Any indenter, offset fitted, 400-point scan.
    pub fn with_indenter(indenter: Indenter, poisson: f64) -> Self {
        HertzSettings {
            indenter,
            poisson,
            fit_offset: true,
            grid: 400,
        }
    }

    fn check(&self) -> Result<()> {
        self.indenter.check()?;
        if !(self.poisson > -1.0 && self.poisson <= 0.5) {
            return Err(AfmError::InvalidInput(format!(
                "Poisson ratio must lie in (-1, 0.5], got {}",
                self.poisson
            )));
        }
        if self.grid < 10 {
            return Err(AfmError::InvalidInput(
                "Hertz grid needs ≥ 10 points".into(),
            ));
        }
        Ok(())
    }
}

/// Result of an elastic fit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HertzFit {
    /// Young's modulus E, Pa.
    pub youngs_modulus: f64,
    /// Contact point s_c (tip–sample separation), m.
    pub contact_point: f64,
    /// Fitted force offset b, N (0 if not fitted).
    pub offset: f64,
    /// Root-mean-square residual, N.
    pub rmse: f64,
    /// RMSE divided by the range of the fitted force (eq. 4.4 / 5.2 convention).
    pub range_normalised_rmse: f64,
    /// Samples fitted.
    pub n_points: usize,
    /// Indentation at the last fitted sample, m.
    pub max_indentation: f64,
    /// Interval of separations the contact point was searched in (the fitted samples'
    /// range, extended by a tenth of it beyond the first sample), m.
    pub search: (f64, f64),
    /// Fitted samples on the non-contact side (δ ≤ 0) of the fitted contact point.
    pub n_before_contact: usize,
}

impl HertzFit {
    /// True if the contact point lies on the edge of its search range: fewer than 5 %
    /// of the fitted samples (and at least 10) before it, or fewer than 10 after it.
    /// Without baseline before the contact, offset and contact point are set by the
    /// model's curvature alone; without samples after it there is no indentation to fit.
    pub fn contact_at_edge(&self) -> bool {
        self.n_before_contact < (self.n_points / 20).max(10)
            || self.n_points - self.n_before_contact < 10
    }
}

/// The residual profiled over the contact point. Samples are kept sorted by separation
/// so that a trial contact s_c touches only the samples in contact (s < s_c, a prefix);
/// the baseline samples (s ≥ s_c, a suffix) enter through their count, mean and sum of
/// squared deviations, accumulated from the far end (no cancellation).
struct Profile {
    /// Separations, ascending.
    s: Vec<f64>,
    /// Forces in the same order.
    f: Vec<f64>,
    /// Σ f over the suffix starting at k (length n + 1).
    suffix_sum: Vec<f64>,
    /// Mean and Σ (f − mean)² of the suffix starting at k (Welford, from the end).
    suffix_m2: Vec<(f64, f64)>,
    indenter: Indenter,
    lo: f64,
    span: f64,
    fit_offset: bool,
    /// shape(s_c − s_i) of the current trial, contact samples only.
    scratch: RefCell<Vec<f64>>,
}

impl Profile {
    fn new(
        separation: &[f64],
        force: &[f64],
        settings: &HertzSettings,
        lo: f64,
        span: f64,
    ) -> Self {
        let mut order: Vec<usize> = (0..separation.len()).collect();
        order.sort_by(|&i, &j| separation[i].total_cmp(&separation[j]));
        let s: Vec<f64> = order.iter().map(|&i| separation[i]).collect();
        let f: Vec<f64> = order.iter().map(|&i| force[i]).collect();
        let n = f.len();
        let mut suffix_sum = vec![0.0; n + 1];
        let mut suffix_m2 = vec![(0.0, 0.0); n + 1];
        for k in (0..n).rev() {
            suffix_sum[k] = suffix_sum[k + 1] + f[k];
            let (mean, m2) = suffix_m2[k + 1];
            let count = (n - k) as f64;
            let delta = f[k] - mean;
            let mean_new = mean + delta / count;
            suffix_m2[k] = (mean_new, m2 + delta * (f[k] - mean_new));
        }
        Profile {
            s,
            f,
            suffix_sum,
            suffix_m2,
            indenter: settings.indenter,
            lo,
            span,
            fit_offset: settings.fit_offset,
            scratch: RefCell::new(Vec::with_capacity(n)),
        }
    }

    /// Best (E*, b, sse) for contact point `sc`, with E* ≥ 0.
    fn solve(&self, sc: f64) -> (f64, f64, f64) {
        // One dispatch per trial, then a loop the compiler can specialise.
        match self.indenter {
            Indenter::Paraboloid { radius } => {
                let c = 4.0 / 3.0 * radius.sqrt();
                self.solve_with(sc, |d| c * d * d.sqrt())
            }
            Indenter::Cone { .. } | Indenter::Pyramid { .. } => {
                let c = self.indenter.shape(1.0);
                self.solve_with(sc, |d| c * d * d)
            }
            Indenter::FlatPunch { radius } => self.solve_with(sc, |d| 2.0 * radius * d),
            Indenter::Sphere { .. } => {
                let ind = self.indenter;
                self.solve_with(sc, |d| ind.shape(d))
            }
        }
    }

    fn solve_with(&self, sc: f64, shape: impl Fn(f64) -> f64) -> (f64, f64, f64) {
        let n = self.s.len();
        let nf = n as f64;
        let k = self.s.partition_point(|&x| x < sc);
        let mut r = self.scratch.borrow_mut();
        r.clear();
        r.extend(self.s[..k].iter().map(|s| shape(sc - s)));
        let y = &self.f[..k];
        // Four partial sums per moment: independent dependency chains (the sums are
        // the hot loop of a batch).
        let (mut sr, mut srr, mut sry) = ([0.0; 4], [0.0; 4], [0.0; 4]);
        let mut gc = r.chunks_exact(4);
        let mut yc = y.chunks_exact(4);
        for (g, y) in gc.by_ref().zip(yc.by_ref()) {
            for l in 0..4 {
                sr[l] += g[l];
                srr[l] += g[l] * g[l];
                sry[l] += g[l] * y[l];
            }
        }
        for (g, y) in gc.remainder().iter().zip(yc.remainder()) {
            sr[0] += g;
            srr[0] += g * g;
            sry[0] += g * y;
        }
        let total = |v: [f64; 4]| (v[0] + v[1]) + (v[2] + v[3]);
        let (sr, srr, sry) = (total(sr), total(srr), total(sry));
        let sy = self.suffix_sum[0];
        let (a, b) = if self.fit_offset {
            let det = nf * srr - sr * sr;
            if det > 0.0 {
                let a = (nf * sry - sr * sy) / det;
                if a > 0.0 {
                    (a, (sy - a * sr) / nf)
                } else {
                    (0.0, sy / nf)
                }
            } else {
                (0.0, sy / nf)
            }
        } else if srr > 0.0 {
            ((sry / srr).max(0.0), 0.0)
        } else {
            (0.0, 0.0)
        };
        let mut sse = [0.0; 4];
        let mut gc = r.chunks_exact(4);
        let mut yc = y.chunks_exact(4);
        for (g, y) in gc.by_ref().zip(yc.by_ref()) {
            for l in 0..4 {
                let e = y[l] - b - a * g[l];
                sse[l] += e * e;
            }
        }
        for (g, y) in gc.remainder().iter().zip(yc.remainder()) {
            let e = y - b - a * g;
            sse[0] += e * e;
        }
        let (mean, m2) = self.suffix_m2[k];
        let baseline = m2 + (n - k) as f64 * (mean - b).powi(2);
        (a, b, total(sse) + baseline)
    }
}

impl CostFunction for Profile {
    type Param = f64;
    type Output = f64;
    fn cost(&self, x: &f64) -> std::result::Result<f64, argmin::core::Error> {
        Ok(self.solve(self.lo + x * self.span).2)
    }
}

/// Fit the elastic model of `settings.indenter` to force `force` (N) against tip–sample
/// separation `separation` (m), all samples used (pass the approach up to the force
/// maximum, or a window of it).
///
/// # Errors
/// [`AfmError::InvalidInput`] for bad settings or fewer than 10 samples;
/// [`AfmError::NotConverged`] if Brent's method stops without converging or the
/// result is not finite/positive.
pub fn fit_hertz(separation: &[f64], force: &[f64], settings: &HertzSettings) -> Result<HertzFit> {
    settings.check()?;
    let n = force.len();
    if separation.len() != n || n < 10 {
        return Err(AfmError::InvalidInput(format!(
            "Hertz fit needs ≥ 10 samples of equal length (separation {}, force {n})",
            separation.len()
        )));
    }
    if force.iter().chain(separation).any(|v| !v.is_finite()) {
        return Err(AfmError::InvalidInput(
            "non-finite sample in the Hertz fit range".into(),
        ));
    }
    let lo = separation.iter().copied().fold(f64::INFINITY, f64::min);
    let s_max = separation.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if s_max <= lo {
        return Err(AfmError::InvalidInput("separation does not vary".into()));
    }
    // The contact may lie before the first fitted sample (a curve that starts in
    // contact): search a tenth of the range beyond it, so that the least-squares optimum
    // is found rather than clipped, and flagged by `contact_at_edge`.
    let hi = s_max + 0.1 * (s_max - lo);
    let span = hi - lo;
    let p = Profile::new(separation, force, settings, lo, span);
    // Grid scan on x = (s_c − lo)/span ∈ [0, 1].
    let g = settings.grid;
    let mut best = (0usize, f64::INFINITY);
    for i in 0..=g {
        let x = i as f64 / g as f64;
        let c = p.solve(lo + x * span).2;
        if c < best.1 {
            best = (i, c);
        }
    }
    let a = best.0.saturating_sub(1) as f64 / g as f64;
    let b = ((best.0 + 1).min(g)) as f64 / g as f64;
    let solver = BrentOpt::new(a, b).set_tolerance(1e-12, 1e-14);
    let res = Executor::new(p, solver)
        .configure(|s| s.max_iters(300))
        .run()
        .map_err(|e| AfmError::NotConverged {
            fit: "Hertz",
            detail: e.to_string(),
            hint: "check the fitted range contains the contact",
        })?;
    let state = res.state();
    if !matches!(
        state.get_termination_status(),
        TerminationStatus::Terminated(TerminationReason::SolverConverged)
    ) {
        return Err(AfmError::NotConverged {
            fit: "Hertz",
            detail: format!(
                "Brent search on the contact point stopped after {} iterations ({:?})",
                state.get_iter(),
                state.get_termination_status()
            ),
            hint: "widen or clean the fitted range",
        });
    }
    let x = state
        .get_best_param()
        .copied()
        .unwrap_or(best.0 as f64 / g as f64);
    let sc = lo + x * span;
    let (e_star, offset, sse) = res
        .problem
        .problem
        .as_ref()
        .map_or_else(|| (0.0, 0.0, f64::NAN), |p| p.solve(sc));
    let e = e_star * (1.0 - settings.poisson.powi(2));
    if !(e.is_finite() && e > 0.0) {
        return Err(AfmError::NotConverged {
            fit: "Hertz",
            detail: format!("modulus {e} Pa at contact point {sc} m"),
            hint: "the curve shows no repulsive contact in the fitted range",
        });
    }
    let fmax = force.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let fmin = force.iter().copied().fold(f64::INFINITY, f64::min);
    let rmse = (sse / n as f64).sqrt();
    Ok(HertzFit {
        youngs_modulus: e,
        contact_point: sc,
        offset,
        rmse,
        range_normalised_rmse: rmse / (fmax - fmin),
        n_points: n,
        max_indentation: sc - lo,
        search: (lo, hi),
        n_before_contact: separation.iter().filter(|&&x| x >= sc).count(),
    })
}

/// Which samples of a prepared approach to fit, relative to the contact-point estimate
/// of [`prepare_approach`] (indentation δ = s_c,est − s, positive in contact).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum FitRange {
    /// Every sample up to the force maximum.
    #[default]
    Full,
    /// Samples whose indentation from the estimated contact lies in [min, max] (m);
    /// a negative `min` keeps that much baseline before the contact, `f64::NEG_INFINITY`
    /// all of it.
    Indentation {
        /// Smallest indentation kept, m.
        min: f64,
        /// Largest indentation kept, m.
        max: f64,
    },
    /// Samples from the start up to the last one before the (baseline-corrected) force
    /// first exceeds `max` (N).
    Force {
        /// Force limit, N.
        max: f64,
    },
}

impl FitRange {
    /// Indices of `approach` inside the range.
    ///
    /// # Errors
    /// [`AfmError::InvalidInput`] for an empty or inverted window, or one holding fewer
    /// than 10 samples.
    pub fn select(&self, approach: &Approach) -> Result<Range<usize>> {
        let n = approach.force.len();
        let range = match *self {
            FitRange::Full => 0..n,
            FitRange::Indentation { min, max } => {
                if min.is_nan() || max.is_nan() || min >= max {
                    return Err(AfmError::InvalidInput(format!(
                        "indentation window [{min}, {max}] m is empty"
                    )));
                }
                let sc = approach.contact.separation;
                let inside: Vec<usize> = (0..n)
                    .filter(|&i| {
                        let d = sc - approach.separation[i];
                        d >= min && d <= max
                    })
                    .collect();
                match (inside.first(), inside.last()) {
                    (Some(&a), Some(&b)) => a..b + 1,
                    _ => 0..0,
                }
            }
            FitRange::Force { max } => {
                if max.is_nan() || max <= 0.0 {
                    return Err(AfmError::InvalidInput(format!(
                        "force window up to {max} N is empty"
                    )));
                }
                let end = approach.force.iter().position(|&f| f > max).unwrap_or(n);
                0..end
            }
        };
        if range.len() < 10 {
            return Err(AfmError::InvalidInput(format!(
                "fit range {self:?} holds {} samples of the approach (need ≥ 10)",
                range.len()
            )));
        }
        Ok(range)
    }
}

/// Something about a fit the user should know before trusting E.
#[derive(Debug, Clone, PartialEq)]
pub enum FitWarning {
    /// The maximal indentation exceeds the depth range the model holds in.
    BeyondValidity {
        /// Indenter name.
        indenter: &'static str,
        /// δ_max / R of the fit.
        ratio: f64,
        /// Largest δ/R inside the validity.
        max_ratio: f64,
        /// What breaks.
        reason: &'static str,
    },
    /// The fitted contact point lies on the edge of its search range
    /// ([`HertzFit::contact_at_edge`]).
    ContactAtEdge {
        /// Fitted contact point, m.
        contact: f64,
        /// Search range, m.
        search: (f64, f64),
        /// Fitted samples before the contact.
        before: usize,
        /// Fitted samples.
        total: usize,
    },
    /// The fitted force offset exceeds 3 standard deviations of the baseline noise.
    OffsetBeyondNoise {
        /// Fitted offset, N.
        offset: f64,
        /// Baseline noise (standard deviation), N.
        noise: f64,
    },
}

impl fmt::Display for FitWarning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            FitWarning::BeyondValidity {
                indenter,
                ratio,
                max_ratio,
                reason,
            } => write!(
                f,
                "indentation δ/R = {ratio:.3} exceeds the {indenter} model's validity (δ/R ≤ {max_ratio}): {reason}"
            ),
            FitWarning::ContactAtEdge {
                contact,
                search,
                before,
                total,
            } => write!(
                f,
                "contact point {contact:.6e} m lies on the edge of its search range [{:.6e}, {:.6e}] m ({before} of {total} fitted samples before it): widen the fit range to hold baseline before the contact and indentation after it",
                search.0, search.1
            ),
            FitWarning::OffsetBeyondNoise { offset, noise } => write!(
                f,
                "fitted force offset {offset:.3e} N exceeds 3× the baseline noise ({noise:.3e} N): the model does not describe the curve near the contact"
            ),
        }
    }
}

/// The warnings that apply to `fit` made with `settings`; `noise` is the baseline's
/// noise standard deviation (N), if known.
pub fn fit_warnings(
    fit: &HertzFit,
    settings: &HertzSettings,
    noise: Option<f64>,
) -> Vec<FitWarning> {
    let mut w = Vec::new();
    if let Some(v) = settings.indenter.validity() {
        let ratio = fit.max_indentation / v.length;
        if ratio > v.max_ratio {
            w.push(FitWarning::BeyondValidity {
                indenter: settings.indenter.name(),
                ratio,
                max_ratio: v.max_ratio,
                reason: v.reason,
            });
        }
    }
    if fit.contact_at_edge() {
        w.push(FitWarning::ContactAtEdge {
            contact: fit.contact_point,
            search: fit.search,
            before: fit.n_before_contact,
            total: fit.n_points,
        });
    }
    if let Some(noise) = noise
        && settings.fit_offset
        && fit.offset.abs() > 3.0 * noise
    {
        w.push(FitWarning::OffsetBeyondNoise {
            offset: fit.offset,
            noise,
        });
    }
    w
}

/// An elastic fit of a prepared approach: the fit, the samples it used and its warnings.
#[derive(Debug, Clone, PartialEq)]
pub struct ApproachFit {
    /// The fit.
    pub fit: HertzFit,
    /// Indices of the approach samples fitted.
    pub fitted: Range<usize>,
    /// Contact-point estimate the range was taken relative to, m.
    pub contact_estimate: f64,
    /// What to check before trusting E.
    pub warnings: Vec<FitWarning>,
}

/// Fit `settings`' model to the samples of `approach` inside `range`, with warnings.
///
/// # Errors
/// As [`FitRange::select`] and [`fit_hertz`].
pub fn fit_approach(
    approach: &Approach,
    settings: &HertzSettings,
    range: FitRange,
) -> Result<ApproachFit> {
    let r = range.select(approach)?;
    let fit = fit_hertz(
        &approach.separation[r.clone()],
        &approach.force[r.clone()],
        settings,
    )?;
    let warnings = fit_warnings(&fit, settings, Some(approach.baseline.noise));
    Ok(ApproachFit {
        fit,
        fitted: r,
        contact_estimate: approach.contact.separation,
        warnings,
    })
}

/// Read–prepare–fit of one curve: [`prepare_approach`] with `method`, then
/// [`fit_approach`] (what a batch runs on every curve).
///
/// # Errors
/// As [`prepare_approach`] and [`fit_approach`].
pub fn fit_curve(
    curve: &ForceCurve,
    settings: &HertzSettings,
    range: FitRange,
    method: ContactMethod,
) -> Result<ApproachFit> {
    fit_approach(&prepare_approach(curve, method)?, settings, range)
}

/// Young's modulus against indentation depth: one fit per entry of `depths` (m), each
/// over all samples up to that indentation from the estimated contact
/// (`FitRange::Indentation { min: −∞, max: depth }`). A depth whose fit fails keeps its
/// error; the others are unaffected.
pub fn modulus_vs_depth(
    approach: &Approach,
    settings: &HertzSettings,
    depths: &[f64],
) -> Vec<(f64, Result<ApproachFit>)> {
    depths
        .iter()
        .map(|&d| {
            let range = FitRange::Indentation {
                min: f64::NEG_INFINITY,
                max: d,
            };
            (d, fit_approach(approach, settings, range))
        })
        .collect()
}

/// The approach part of a curve ready for fitting: separation and baseline-corrected
/// force on the extend segment up to the force maximum.
#[derive(Debug, Clone, PartialEq)]
pub struct Approach {
    /// Tip–sample separation s = h + F/k, m.
    pub separation: Vec<f64>,
    /// Force minus the baseline, N.
    pub force: Vec<f64>,
    /// Baseline that was subtracted (fitted against separation).
    pub baseline: Baseline,
    /// Contact point estimate.
    pub contact: crate::prepare::ContactPoint,
}

/// Prepare the extend segment of `curve`: separation from the measured height, cut at the
/// force maximum; contact estimate and baseline from [`approach_baseline`] (the pause
/// before the extend, if the curve has one, else the extend before the contact).
///
/// # Errors
/// Missing extend segment or channels, or no contact found.
pub fn prepare_approach(curve: &ForceCurve, method: ContactMethod) -> Result<Approach> {
    let ext = curve
        .segments
        .iter()
        .position(|s| s.kind == SegmentKind::Extend)
        .ok_or_else(|| AfmError::MissingSegment {
            kind: SegmentKind::Extend.to_string(),
        })?;
    let seg = &curve.segments[ext];
    let f = seg.force()?;
    let s = tip_sample_separation(seg.height()?, f, curve.calibration.spring_constant)?;
    let imax = f
        .iter()
        .enumerate()
        .fold(
            (0, f64::NEG_INFINITY),
            |b, (i, v)| if *v > b.1 { (i, *v) } else { b },
        )
        .0;
    if imax < 8 {
        return Err(AfmError::NoContact(format!(
            "the extend force is largest at sample {imax} of {}: the probe never pushes on the sample",
            f.len()
        )));
    }
    let s = s[..=imax].to_vec();
    let f = &f[..=imax];
    let (contact, baseline) = approach_baseline(curve, ext, &s, f, method)?;
    let force = baseline.subtract(&s, f);
    Ok(Approach {
        separation: s,
        force,
        baseline,
        contact,
    })
}

/// Hertz baseline for one cell (issue 7 results column): prepare the approach and fit
/// E and the contact point on it, up to the force maximum.
///
/// # Errors
/// As [`prepare_approach`] and [`fit_hertz`].
pub fn hertz_baseline(curve: &ForceCurve, settings: &HertzSettings) -> Result<HertzFit> {
    let a = prepare_approach(curve, ContactMethod::default())?;
    fit_hertz(&a.separation, &a.force, settings)
}
