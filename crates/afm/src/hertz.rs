//! Hertz fit of a spherical (paraboloidal) probe on an approach curve (thesis eq. 1.1–1.3).
//!
//! Model: `F(s) = b + (4/3)·E/(1 − ν²)·√R·max(0, s_c − s)^{3/2}`, a rigid probe on an
//! elastic half-space (E* ≈ E/(1 − ν²), eq. 1.3). For a fixed contact point s_c the
//! model is linear in `a = (4/3)E√R/(1 − ν²)` and `b`, so the fit profiles the residual
//! over s_c: a grid scan over the fitted range followed by Brent's method (argmin
//! `BrentOpt`) in the best grid cell.

use argmin::core::{CostFunction, Executor, State, TerminationReason, TerminationStatus};
use argmin::solver::brent::BrentOpt;

use crate::curve::{ForceCurve, SegmentKind};
use crate::error::{AfmError, Result};
use crate::prepare::{Baseline, ContactMethod, contact_point, tip_sample_separation};

/// Force of a paraboloidal probe of radius `r` indenting by `delta` a half-space of
/// Young's modulus `e` and Poisson ratio `nu` (eq. 1.1 with eq. 1.3); zero for δ ≤ 0.
pub fn hertz_force(delta: f64, e: f64, r: f64, nu: f64) -> f64 {
    if delta <= 0.0 {
        return 0.0;
    }
    4.0 / 3.0 * e / (1.0 - nu * nu) * r.sqrt() * delta.powf(1.5)
}

/// Settings of a Hertz fit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HertzSettings {
    /// Probe radius R, m.
    pub tip_radius: f64,
    /// Poisson ratio ν of the sample.
    pub poisson: f64,
    /// Fit a constant force offset b together with E and s_c (else b = 0: the force must
    /// already be baseline-corrected).
    pub fit_offset: bool,
    /// Grid points of the contact-point scan before Brent refinement.
    pub grid: usize,
}

impl HertzSettings {
    /// Settings for a probe of radius `tip_radius` and a sample of Poisson ratio `poisson`,
    /// offset fitted, 400-point scan.
    pub fn new(tip_radius: f64, poisson: f64) -> Self {
        HertzSettings {
            tip_radius,
            poisson,
            fit_offset: true,
            grid: 400,
        }
    }

    fn check(&self) -> Result<()> {
        if !(self.tip_radius.is_finite() && self.tip_radius > 0.0) {
            return Err(AfmError::InvalidInput(format!(
                "tip radius must be positive, got {} m",
                self.tip_radius
            )));
        }
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

/// Result of a Hertz fit.
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
}

struct Profile<'a> {
    s: &'a [f64],
    f: &'a [f64],
    lo: f64,
    span: f64,
    fit_offset: bool,
}

impl Profile<'_> {
    /// Best (a, b, sse) for contact point `sc`, with a ≥ 0.
    fn solve(&self, sc: f64) -> (f64, f64, f64) {
        let n = self.s.len() as f64;
        let (mut sr, mut srr, mut sy, mut sry, mut syy) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for (s, y) in self.s.iter().zip(self.f) {
            let d = sc - s;
            let r = if d > 0.0 { d * d.sqrt() } else { 0.0 };
            sr += r;
            srr += r * r;
            sy += y;
            sry += r * y;
            syy += y * y;
        }
        let (a, b) = if self.fit_offset {
            let det = n * srr - sr * sr;
            if det > 0.0 {
                let a = (n * sry - sr * sy) / det;
                if a > 0.0 {
                    (a, (sy - a * sr) / n)
                } else {
                    (0.0, sy / n)
                }
            } else {
                (0.0, sy / n)
            }
        } else if srr > 0.0 {
            ((sry / srr).max(0.0), 0.0)
        } else {
            (0.0, 0.0)
        };
        let sse = syy - 2.0 * b * sy - 2.0 * a * sry + n * b * b + 2.0 * a * b * sr + a * a * srr;
        (a, b, sse.max(0.0))
    }
}

impl CostFunction for Profile<'_> {
    type Param = f64;
    type Output = f64;
    fn cost(&self, x: &f64) -> std::result::Result<f64, argmin::core::Error> {
        Ok(self.solve(self.lo + x * self.span).2)
    }
}

/// Fit the Hertz model to force `force` (N) against tip–sample separation `separation`
/// (m), all samples used (pass the approach up to the force maximum).
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
    let hi = separation.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let span = hi - lo;
    if span <= 0.0 {
        return Err(AfmError::InvalidInput("separation does not vary".into()));
    }
    let p = Profile {
        s: separation,
        f: force,
        lo,
        span,
        fit_offset: settings.fit_offset,
    };
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
    let solver = BrentOpt::new(a, b).set_tolerance(f64::EPSILON.sqrt(), 1e-10);
    let res = Executor::new(p, solver)
        .configure(|s| s.max_iters(200))
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
    let prof = Profile {
        s: separation,
        f: force,
        lo,
        span,
        fit_offset: settings.fit_offset,
    };
    let (a_coef, offset, sse) = prof.solve(sc);
    let e = a_coef * 3.0 / 4.0 * (1.0 - settings.poisson.powi(2)) / settings.tip_radius.sqrt();
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
    })
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

/// Prepare the extend segment of `curve`: separation from the measured height, baseline
/// (offset only) from the samples before the contact estimate, cut at the force maximum.
///
/// # Errors
/// Missing extend segment or channels, or no contact found.
pub fn prepare_approach(curve: &ForceCurve, method: ContactMethod) -> Result<Approach> {
    let seg = curve.segment(SegmentKind::Extend)?;
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
    let contact = contact_point(&s, f, method)?;
    let baseline = Baseline::fit(&s, f, 0..contact.index.max(2), false)?;
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
