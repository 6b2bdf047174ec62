//! Posteriors of the parameters of one curve on a Kriging surrogate
//! (issue 17: uncertainty for every cell, beyond the thesis's point
//! estimates of §5.4.2).
//!
//! - prior: uniform on the surrogate's parameter domain in the domain's own
//!   coordinates u ∈ [0, 1]^d (log-uniform on log axes, as the design was
//!   drawn), restricted to its linear constraints (g1 + g2 ≤ 1 − ε);
//! - likelihood: [`CurveLikelihood`] — Gaussian, measurement noise σ
//!   estimated from the curve ([`noise_sd`]), Kriging MSE with its
//!   cross-time covariance folded into the variance;
//! - sampler: the affine-invariant ensemble of [`ensemble`], in u, started
//!   around the multistart optimum in a ball shaped by the Gauss–Newton
//!   (Laplace) covariance;
//! - outputs ([`Posterior`]): equal-tailed credible intervals of every
//!   parameter and of G(0), g1 + g2 and G(t_end) (eq. 5.1 through
//!   `nlvid_model::Relaxation`), a credible band on G(t), split R̂ and
//!   effective sample size per quantity ([`diagnostics`]), and a thinned
//!   set of draws for group summaries.

pub mod diagnostics;
pub mod ensemble;
mod likelihood;

use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

pub use ensemble::{Chains, EnsembleSettings, sample_ensemble};
pub use likelihood::{CurveLikelihood, noise_sd};

use crate::error::{InverseError, Result};
use crate::model::Model;
use crate::prony::relaxation;
use crate::surrogate::KrigingSurrogate;

/// Settings of [`sample_posterior`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PosteriorSettings {
    /// The ensemble (walkers, burn-in, kept steps, seed).
    pub walkers: usize,
    /// Burn-in steps.
    pub burn: usize,
    /// Kept steps per walker.
    pub steps: usize,
    /// Seed of the sampler.
    pub seed: u64,
    /// Credible level of the intervals and bands (e.g. 0.9).
    pub level: f64,
    /// Draws kept in [`Posterior::draws`] (thinned evenly).
    pub keep: usize,
    /// Time at which G(t) is summarised (the end of the hold), s.
    pub t_end: f64,
    /// Times of the G(t) band, s.
    pub band_times: Vec<f64>,
}

impl PosteriorSettings {
    /// Defaults for a fitted window ending at `t_end`: 32 walkers, 300
    /// burn-in and 1000 kept steps, 90 % intervals, 200 kept draws, band on
    /// 53 times from 0 to `t_end`.
    pub fn new(t_end: f64) -> Self {
        Self {
            walkers: 32,
            burn: 300,
            steps: 1000,
            seed: 1,
            level: 0.9,
            keep: 200,
            t_end,
            band_times: (0..53).map(|i| t_end * i as f64 / 52.0).collect(),
        }
    }
}

/// An equal-tailed credible interval with its diagnostics.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Interval {
    /// (1 − level)/2 quantile.
    pub lower: f64,
    /// Median.
    pub median: f64,
    /// (1 + level)/2 quantile.
    pub upper: f64,
    /// Split R̂.
    pub rhat: f64,
    /// Effective sample size.
    pub ess: f64,
}

impl Interval {
    /// True when `v` lies inside [lower, upper].
    pub fn covers(&self, v: f64) -> bool {
        self.lower <= v && v <= self.upper
    }
}

/// A pointwise credible band of G(t).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Band {
    /// Times, s.
    pub times: Vec<f64>,
    /// Lower quantile, Pa.
    pub lower: Vec<f64>,
    /// Median, Pa.
    pub median: Vec<f64>,
    /// Upper quantile, Pa.
    pub upper: Vec<f64>,
}

/// The posterior of one curve's parameters (module docs).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Posterior {
    /// Credible level of the intervals and the band.
    pub level: f64,
    /// Measurement noise sd estimated from the curve (units of the curve).
    pub noise_sd: f64,
    /// Per parameter of the domain, in its order: (name, interval).
    pub parameters: Vec<(String, Interval)>,
    /// G(0) = G0, Pa.
    pub g0: Interval,
    /// g1 + g2 (Σ g_k = 1 − g∞).
    pub g_sum: Interval,
    /// G(t_end), Pa.
    pub g_end: Interval,
    /// t_end, s.
    pub t_end: f64,
    /// Pointwise band of G(t).
    pub band: Band,
    /// Largest split R̂ over the parameters and the three summaries.
    pub rhat_max: f64,
    /// Smallest effective sample size over the same.
    pub ess_min: f64,
    /// Acceptance fraction of the sampler.
    pub acceptance: f64,
    /// Thinned draws (physical values, domain order).
    pub draws: Vec<Vec<f64>>,
}

/// Quantile q ∈ [0, 1] of sorted values (linear interpolation).
pub fn quantile(sorted: &[f64], q: f64) -> f64 {
    let n = sorted.len();
    if n == 0 {
        return f64::NAN;
    }
    let h = q * (n - 1) as f64;
    let lo = h.floor() as usize;
    let hi = (lo + 1).min(n - 1);
    sorted[lo] + (h - lo as f64) * (sorted[hi] - sorted[lo])
}

fn interval(chains: &[Vec<f64>], level: f64) -> Interval {
    let mut all: Vec<f64> = chains.iter().flatten().copied().collect();
    all.sort_by(f64::total_cmp);
    let a = 0.5 * (1.0 - level);
    Interval {
        lower: quantile(&all, a),
        median: quantile(&all, 0.5),
        upper: quantile(&all, 1.0 - a),
        rhat: diagnostics::split_rhat(chains),
        ess: diagnostics::effective_sample_size(chains),
    }
}

fn normal(rng: &mut rand_chacha::ChaCha8Rng) -> f64 {
    use rand::RngExt;
    let u1: f64 = 1.0 - rng.random::<f64>();
    let u2: f64 = rng.random();
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// Start positions in u: û + L ε with L Lᵀ the Gauss–Newton covariance
/// (JᵤᵀJᵤ/σ²)⁻¹ at the optimum (eigenvalues floored so that no direction is
/// wider than the domain), redrawn until inside the prior's support.
fn starts(
    surrogate: &KrigingSurrogate,
    x_hat: &[f64],
    noise_var: f64,
    walkers: usize,
    seed: u64,
    inside: &dyn Fn(&[f64]) -> bool,
) -> Result<Vec<Vec<f64>>> {
    use rand::SeedableRng;
    let domain = Model::domain(surrogate);
    let d = domain.len();
    let u_hat = domain.to_unit(x_hat);
    let (_, jac) = surrogate.response_and_jacobian(x_hat)?;
    let mut ju = jac.clone();
    for (i, p) in domain.params().iter().enumerate() {
        let s = p.dx_du(u_hat[i]);
        for j in 0..ju.nrows() {
            ju[(j, i)] *= s;
        }
    }
    let h: DMatrix<f64> = ju.transpose() * &ju / noise_var;
    let eig = h.symmetric_eigen();
    // Covariance V diag(1/max(λ, 1)) Vᵀ: sd ≤ 1 (the domain's width) per direction.
    let mut l = DMatrix::zeros(d, d);
    for k in 0..d {
        let sd = 1.0 / eig.eigenvalues[k].max(1.0).sqrt();
        for i in 0..d {
            l[(i, k)] = eig.eigenvectors[(i, k)] * sd;
        }
    }
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed ^ 0x5eed_57a7);
    let mut out = Vec::with_capacity(walkers);
    let center_ok = inside(&u_hat);
    for _ in 0..walkers {
        let mut shrink = 1.0;
        let mut placed = None;
        for attempt in 0..200 {
            if attempt % 40 == 39 {
                shrink *= 0.3;
            }
            let e: Vec<f64> = (0..d).map(|_| normal(&mut rng)).collect();
            let u: Vec<f64> = (0..d)
                .map(|i| u_hat[i] + shrink * (0..d).map(|k| l[(i, k)] * e[k]).sum::<f64>())
                .collect();
            if inside(&u) {
                placed = Some(u);
                break;
            }
        }
        match placed {
            Some(u) => out.push(u),
            None if center_ok => out.push(u_hat.clone()),
            None => {
                return Err(InverseError::InvalidSetting(format!(
                    "posterior: no start inside the domain near the optimum {x_hat:?}"
                )));
            }
        }
    }
    Ok(out)
}

/// Samples the posterior of the parameters of `data` (on the surrogate's
/// grid) given the optimum `x_hat` of a fit (module docs).
///
/// Cost: walkers·(burn + steps) likelihood evaluations, each one reduced
/// prediction O(N·q·d) and one Kriging variance O(N²) (N training runs).
///
/// # Errors
/// Bad settings, a curve without measurable noise, surrogate failures.
pub fn sample_posterior(
    surrogate: &KrigingSurrogate,
    data: &[f64],
    x_hat: &[f64],
    settings: &PosteriorSettings,
) -> Result<Posterior> {
    if !(settings.level > 0.0 && settings.level < 1.0) || settings.keep == 0 {
        return Err(InverseError::InvalidSetting(format!(
            "posterior: level {} must be in (0, 1) and keep {} > 0",
            settings.level, settings.keep
        )));
    }
    let domain = Model::domain(surrogate).clone();
    let noise = noise_sd(Model::times(surrogate), data)?;
    let lik = CurveLikelihood::new(surrogate, data, noise)?;
    let inside = |u: &[f64]| {
        u.iter().all(|v| (0.0..=1.0).contains(v)) && domain.feasible(&domain.from_unit(u), 0.0)
    };
    let log_density = |u: &[f64]| {
        if !inside(u) {
            return f64::NEG_INFINITY;
        }
        lik.value(&domain.from_unit(u)).unwrap_or(f64::NEG_INFINITY)
    };
    let init = starts(
        surrogate,
        x_hat,
        lik.noise_var(),
        settings.walkers,
        settings.seed,
        &inside,
    )?;
    let es = EnsembleSettings {
        walkers: settings.walkers,
        burn: settings.burn,
        steps: settings.steps,
        seed: settings.seed,
        ..EnsembleSettings::default()
    };
    let chains = sample_ensemble(log_density, &init, &es)?;
    summarise(&domain, &chains, noise, settings)
}

/// Intervals, band, diagnostics and thinned draws of chains in u.
fn summarise(
    domain: &nlvid_model::Domain,
    chains: &Chains,
    noise: f64,
    settings: &PosteriorSettings,
) -> Result<Posterior> {
    let d = domain.len();
    let params = domain.params();
    let mut parameters = Vec::with_capacity(d);
    for (i, p) in params.iter().enumerate() {
        let tr = chains.traces(|u| p.from_unit(u[i]));
        parameters.push((p.name.clone(), interval(&tr, settings.level)));
    }
    let g = |u: &[f64]| relaxation(domain, &domain.from_unit(u));
    // Validate once (names G0, g_k, tau_k) before mapping every draw.
    let first: Vec<f64> = (0..d).map(|i| chains.at(0, 0, i)).collect();
    g(&first)?;
    let rel = |u: &[f64]| g(u).ok();
    let t_end = settings.t_end;
    let g0 = interval(
        &chains.traces(|u| rel(u).map_or(f64::NAN, |r| r.g0())),
        settings.level,
    );
    let g_sum = interval(
        &chains.traces(|u| rel(u).map_or(f64::NAN, |r| 1.0 - r.prony().long_term_weight())),
        settings.level,
    );
    let g_end = interval(
        &chains.traces(|u| rel(u).map_or(f64::NAN, |r| r.value(t_end))),
        settings.level,
    );
    let mut rhat_max = g0.rhat.max(g_sum.rhat).max(g_end.rhat);
    let mut ess_min = g0.ess.min(g_sum.ess).min(g_end.ess);
    for (_, iv) in &parameters {
        rhat_max = rhat_max.max(iv.rhat);
        ess_min = ess_min.min(iv.ess);
    }
    // Draws in step-major order, thinned evenly.
    let total = chains.steps * chains.walkers;
    let pick = |n: usize| -> Vec<Vec<f64>> {
        let n = n.min(total);
        (0..n)
            .map(|k| {
                let idx = k * total / n;
                let u = &chains.samples[idx * d..(idx + 1) * d];
                domain.from_unit(u)
            })
            .collect()
    };
    let band_draws = pick(2000);
    let a = 0.5 * (1.0 - settings.level);
    let mut band = Band {
        times: settings.band_times.clone(),
        lower: Vec::new(),
        median: Vec::new(),
        upper: Vec::new(),
    };
    let curves: Vec<nlvid_model::Relaxation> = band_draws
        .iter()
        .map(|x| relaxation(domain, x))
        .collect::<Result<_>>()?;
    for &t in &settings.band_times {
        let mut v: Vec<f64> = curves.iter().map(|r| r.value(t)).collect();
        v.sort_by(f64::total_cmp);
        band.lower.push(quantile(&v, a));
        band.median.push(quantile(&v, 0.5));
        band.upper.push(quantile(&v, 1.0 - a));
    }
    Ok(Posterior {
        level: settings.level,
        noise_sd: noise,
        parameters,
        g0,
        g_sum,
        g_end,
        t_end,
        band,
        rhat_max,
        ess_min,
        acceptance: chains.acceptance,
        draws: pick(settings.keep),
    })
}
