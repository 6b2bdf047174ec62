//! Posteriors of the parameters of one curve on a Kriging surrogate
//! (issue 17: uncertainty for every cell, beyond the thesis's point
//! estimates of §5.4.2).
//!
//! - prior: uniform on the surrogate's parameter domain in the domain's own
//!   coordinates u ∈ [0, 1]^d (log-uniform on log axes, as the design was
//!   drawn), restricted to its linear constraints (g1 + g2 ≤ 1 − ε);
//! - likelihood: [`CurveLikelihood`] — Gaussian, measurement noise σ
//!   estimated from the curve ([`noise_sd`]), Kriging MSE with its
//!   cross-time covariance (process covariance estimated by leave-one-out)
//!   folded into the variance;
//! - sampler: independent affine-invariant ensembles ([`ensemble`]) in u,
//!   started over-dispersed around the multistart optimum (Laplace shape)
//!   and — half of them — around the fit's other optima within reach
//!   ([`other_modes`]; the ensembles' independence proposal is then
//!   pooled, the [`ensemble`] module docs, "Pooled proposals"), run in
//!   rounds until the split R̂ across ensembles is ≤ [`RHAT_TARGET`] or
//!   `max_steps` (after the first round R̂ is checked every
//!   `check_every` kept steps, so a posterior stops as soon as it is
//!   converged; refits and the restart stay at round ends); a posterior still above the target after
//!   `temper_after` kept steps — or at the end of a round with R̂ above
//!   `temper_rhat` when set (opt-in), far from converged — is restarted from its walkers' positions
//!   with parallel tempering inside each ensemble (`rungs`; the
//!   [`ensemble`] module docs, "Tempering"), the draws before dropped,
//!   burnt in for `temper_burn` steps and checked from `temper_min_steps`
//!   kept steps;
//! - outputs ([`Posterior`]): equal-tailed credible intervals of every
//!   parameter and of G(0), g1 + g2 and G(t_end) (eq. 5.1 through
//!   `nlvid_model::Relaxation`), a credible band on G(t), split R̂ and
//!   effective sample size per quantity ([`diagnostics`]; R̂ across
//!   ensembles, not walkers: walkers of one ensemble are coupled), and a thinned
//!   set of draws for group summaries.

pub mod diagnostics;
pub mod ensemble;
mod error_scale;
mod independence;
mod likelihood;
mod ridge;
pub mod screen;

use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

pub use ensemble::{
    Chains, Ensemble, EnsembleSettings, LogDensity, burn_in, refit_proposals, sample,
    sample_ensemble, sample_more, temper_from_proposal,
};
pub use likelihood::{CurveLikelihood, noise_sd};
pub use ridge::{RidgeMove, RidgeTime};
use screen::VarianceModel;

use crate::error::{InverseError, Result};
use crate::fixed::FixedInputs;
use crate::model::Model;
use crate::prony::relaxation;
use crate::surrogate::KrigingSurrogate;

/// Settings of [`sample_posterior`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PosteriorSettings {
    /// Walkers of each ensemble.
    pub walkers: usize,
    /// Burn-in steps.
    pub burn: usize,
    /// Kept steps per walker in each round; rounds are added until R̂ ≤
    /// [`RHAT_TARGET`] or `max_steps` is reached.
    pub steps: usize,
    /// Independent ensembles (≥ 2: R̂ compares them).
    #[serde(default = "default_ensembles")]
    pub ensembles: usize,
    /// Most kept steps per walker (a value below `steps`: one round).
    #[serde(default)]
    pub max_steps: usize,
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
    /// Probability of an axis-refresh step (a coordinate redrawn from the
    /// prior, [`ensemble`] module docs).
    #[serde(default = "default_refresh")]
    pub refresh_fraction: f64,
    /// Refit each ensemble's independence proposal to its own last round
    /// before the next round.
    #[serde(default = "default_refit")]
    pub refit_proposal: bool,
    /// Probability of a ridge step (the fastest Prony weight redrawn at
    /// fixed G0·(1 − g1) and G0·g_k, [`ensemble`] module docs; default 0:
    /// off, 0.1 measured in docs/theory/inverse.md).
    #[serde(default = "default_ridge")]
    pub ridge_fraction: f64,
    /// What the ridge steps do with the fast weight's τ ([`RidgeTime`]).
    #[serde(default)]
    pub ridge_time: RidgeTime,
    /// Threads over which each batch of proposals is evaluated (1: the
    /// calling thread). The draws are bitwise the same for any count
    /// ([`CurveLikelihood::with_threads`]); more than 1 is for one
    /// posterior at a time — a cohort already runs one cell per core.
    #[serde(default = "default_threads")]
    pub threads: usize,
    /// Rungs of the temperature ladder of a tempered restart (1: never
    /// tempered; [`ensemble`] module docs, "Tempering").
    #[serde(default = "default_rungs")]
    pub rungs: usize,
    /// Ratio of adjacent rungs' inverse temperatures (β_r = ratio^r).
    #[serde(default = "default_rung_ratio")]
    pub rung_ratio: f64,
    /// Kept steps per walker after which a posterior with R̂ still above
    /// [`RHAT_TARGET`] is restarted with `rungs` rungs (a new burn-in and
    /// rounds of at most `max_steps` kept steps; the draws before are
    /// dropped).
    #[serde(default = "default_temper_after")]
    pub temper_after: usize,
    /// R̂ at the end of a round above which the posterior is restarted
    /// tempered at once, before `temper_after` kept steps (None, the
    /// default: only after `temper_after`). Opt-in: with 1.025, seed 17's
    /// FE cohort tempers the same 9 cells 250 kept steps earlier (2 of
    /// them above 2 s instead of 9, 0.96× the proposals), but seeds 18
    /// and 19 temper more cells or longer (1.02×, 1.08× the proposals)
    /// and seed 19's wide-b-12 ends at R̂ 1.014 after 2000 tempered kept
    /// steps (docs/theory/inverse.md, "Session 21"); 1.05 the same on
    /// wide-b-12, for 0.985× / 0.993× on seeds 17 / 18 ("Session 21b").
    #[serde(default = "default_temper_rhat")]
    pub temper_rhat: Option<f64>,
    /// Burn-in steps of the tempered restart. Its walkers start where the
    /// untempered chain left them, so only the hot rungs have to spread
    /// (seed 19 of docs/theory/inverse.md "Session 16": 100 steps instead
    /// of `burn`, with `temper_min_steps`, cost 0.87× the proposals at the
    /// same coverage; 50 stopped seed 17's wide-a-47 at 100 kept steps
    /// with every ensemble short of the G0 tail, "Session 21").
    #[serde(default = "default_temper_burn")]
    pub temper_burn: usize,
    /// The tempered restart's hot rungs start from draws of the β = 1
    /// walkers' independence proposal (pooled over the ensembles with
    /// `mode_starts`) widened to each rung's temperature, which also
    /// becomes the rung's proposal ([`temper_from_proposal`]); off (the
    /// default): copies of the β = 1 walkers and their proposal. Off by
    /// default: with `temper_rhat` 1.05 the cohorts of seeds 17–19 cost
    /// 1.01–1.03× the proposals, seed 19's wide-b-36 ended at R̂ 1.0104
    /// and its wide-b-12 converged after 100 kept steps on one arm of a
    /// two-armed posterior (docs/theory/inverse.md, "Session 21b").
    #[serde(default)]
    pub hot_starts: bool,
    /// Kept steps of a tempered chain before its first R̂ check (then
    /// every `check_every`; untempered chains wait for a whole round,
    /// `steps`). A tempered step costs `rungs` untempered ones and mixes
    /// faster: the tempered cells of seed 19 had ESS 1500–3000 at 100
    /// kept steps, where untempered cells stop with 150–1000 at 250.
    #[serde(default = "default_temper_min_steps")]
    pub temper_min_steps: usize,
    /// `ridge_fraction` of the tempered restart (the ridge move on every
    /// rung; [`ensemble`] module docs).
    #[serde(default = "default_temper_ridge")]
    pub temper_ridge: f64,
    /// Kept steps between R̂ checks once a chain has one round (`steps`)
    /// of kept steps: the posterior stops at the first check with R̂ ≤
    /// [`RHAT_TARGET`] instead of at the end of its round. The chains are
    /// those of whole rounds cut short (refits and the tempered restart
    /// stay at round ends), so a posterior converged at the end of its
    /// first round is the same draw for draw; `steps` or more: checks at
    /// round ends only (the sampler before session 13).
    #[serde(default = "default_check_every")]
    pub check_every: usize,
    /// Delayed acceptance ([`ensemble`] module docs): each proposal is
    /// first screened with the likelihood's Kriging variance taken from a
    /// model fitted at the starts and after burn-in ([`screen`]: the
    /// surrogate's mean only,
    /// no O(N²) solve), and only the proposals that pass are evaluated in
    /// full. Exact (the same posterior); off: every proposal evaluated in
    /// full.
    #[serde(default = "default_delayed_acceptance")]
    pub delayed_acceptance: bool,
    /// The surrogate error as a Student-t scale mixture with ν fitted to
    /// the meta-model's leave-one-out residuals
    /// (`VarianceCalibration::fit_student`; [`CurveLikelihood`]); off (the
    /// default): Gaussian (`VarianceCalibration::fit`). Off by default:
    /// on seeds 17 and 18 the coverage was the same within 1 point, on
    /// seed 19 worse, and the screen costs 1.46× (docs/theory/inverse.md,
    /// "Session 17").
    #[serde(default = "default_heavy_tails")]
    pub heavy_tails: bool,
    /// The Gaussian surrogate error with a scale per eigen-direction of
    /// the cross-validated output covariance and one exponent β
    /// (`VarianceCalibration::fit_directions`; [`CurveLikelihood`]); off
    /// (the default): one scale over all directions. Not with
    /// `heavy_tails`. A study key (docs/theory/inverse.md, "Session 18").
    #[serde(default)]
    pub direction_scales: bool,
    /// The surrogate's error in the likelihood (on, the default); off: the
    /// noise alone, Σ = σ̂²I — the exact likelihood when the data are the
    /// surrogate's own curve plus noise, for the simulation-based check of
    /// the sampler (example `posterior_sbc` of nlvid-report; not a study
    /// key). Delayed acceptance then has nothing to screen and is off.
    #[serde(default = "default_true")]
    pub surrogate_error: bool,
    /// Half of the ensembles start at the ends of the posterior's weakest
    /// direction ([`ridge_ends`]) where those lie within 6 of the
    /// optimum's ln L; off (the default): every ensemble starts at the
    /// optimum. On cells drawn from the prior with the exact likelihood the
    /// coverage rises from 85 / 84 / 87 % to 89 / 88 / 88 %, with 6 cells
    /// instead of 3 above R̂ 1.01 after 2000 kept steps; on the group
    /// cohort nothing moves but one cell ends at R̂ 1.017
    /// (docs/theory/inverse.md, "Session 19").
    #[serde(default)]
    pub ridge_starts: bool,
    /// Half of the ensembles start at the fit's other local optima
    /// ([`other_modes`]) where those lie within 6 of the optimum's ln L,
    /// and the ensembles share one independence proposal fitted to their
    /// pooled draws (`EnsembleSettings::pool_proposals`); off: session
    /// 19's sampler (every ensemble at the optimum unless `ridge_starts`,
    /// each with its own proposal). docs/theory/inverse.md, "Session 20".
    #[serde(default = "default_true")]
    pub mode_starts: bool,
    /// The surrogate error's calibrated variance held at its value at the
    /// fit, α·v(x̂)^β, over the whole posterior instead of α·v(x)^β at
    /// each point ([`CurveLikelihood::with_variance_held`]); off: v(x).
    #[serde(default)]
    pub variance_at_fit: bool,
}

fn default_true() -> bool {
    true
}

fn default_delayed_acceptance() -> bool {
    true
}

fn default_heavy_tails() -> bool {
    false
}

fn default_check_every() -> usize {
    50
}

fn default_temper_ridge() -> f64 {
    0.1
}

fn default_rungs() -> usize {
    4
}

fn default_rung_ratio() -> f64 {
    0.5
}

fn default_temper_after() -> usize {
    500
}

fn default_temper_rhat() -> Option<f64> {
    None
}

fn default_temper_burn() -> usize {
    100
}

fn default_temper_min_steps() -> usize {
    100
}

fn default_threads() -> usize {
    1
}

fn default_one() -> usize {
    1
}

fn default_ridge() -> f64 {
    // Off by default: on the 100-cell run it fixed wide-a-47 and wide-b-42
    // but unsettled wide-b-38 and wide-a-05 (docs/theory/inverse.md,
    // "Third round"); 0.1 is the measured setting.
    0.0
}

fn default_ensembles() -> usize {
    4
}

fn default_refresh() -> f64 {
    0.1
}

fn default_refit() -> bool {
    true
}

impl PosteriorSettings {
    /// Defaults for a fitted window ending at `t_end`: 4 ensembles of 16
    /// walkers, 200 burn-in steps, rounds of 250 kept steps up to 1000,
    /// 90 % intervals, 200 kept draws, band on 53 times from 0 to `t_end`.
    pub fn new(t_end: f64) -> Self {
        Self {
            walkers: 16,
            burn: 200,
            steps: 250,
            ensembles: 4,
            max_steps: 1000,
            seed: 1,
            level: 0.9,
            keep: 200,
            t_end,
            band_times: (0..53).map(|i| t_end * i as f64 / 52.0).collect(),
            refresh_fraction: default_refresh(),
            refit_proposal: default_refit(),
            ridge_fraction: default_ridge(),
            ridge_time: RidgeTime::Kept,
            threads: default_threads(),
            rungs: default_rungs(),
            rung_ratio: default_rung_ratio(),
            temper_after: default_temper_after(),
            temper_rhat: default_temper_rhat(),
            temper_burn: default_temper_burn(),
            hot_starts: false,
            temper_min_steps: default_temper_min_steps(),
            temper_ridge: default_temper_ridge(),
            check_every: default_check_every(),
            delayed_acceptance: default_delayed_acceptance(),
            heavy_tails: default_heavy_tails(),
            direction_scales: false,
            surrogate_error: true,
            ridge_starts: false,
            mode_starts: true,
            variance_at_fit: false,
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
    /// Acceptance fraction of the sampler (the β = 1 walkers).
    pub acceptance: f64,
    /// Kept steps per walker behind the intervals.
    #[serde(default)]
    pub kept_steps: usize,
    /// Rungs of the temperature ladder (1: untempered).
    #[serde(default = "default_one")]
    pub rungs: usize,
    /// Accepted fraction of the swaps between rungs (0 when untempered).
    #[serde(default)]
    pub swap_acceptance: f64,
    /// Points proposed (the starts, and per step one per walker and rung,
    /// every phase included): the sampler's cost in log-density calls,
    /// an upper bound on likelihood evaluations (a point outside the
    /// prior's support costs none).
    #[serde(default)]
    pub proposals: usize,
    /// Points whose full likelihood (or Kriging variance, for the screen's
    /// fits) was computed: the starts and the proposals, less those delayed
    /// acceptance rejected on its screen and those outside the prior's
    /// support.
    #[serde(default)]
    pub evaluations: usize,
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

fn normal(rng: &mut rand_chacha::ChaCha8Rng) -> f64 {
    use rand::RngExt;
    let u1: f64 = 1.0 - rng.random::<f64>();
    let u2: f64 = rng.random();
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// Over-dispersion of the starts: the start ball is this many Laplace sd
/// wide, so that R̂ compares ensembles that began apart (BDA3 §11.4).
const OVERDISPERSION: f64 = 2.0;

/// Largest start sd along any direction in u (before the
/// over-dispersion): a quarter of the domain's width, so that a direction
/// the data do not resolve starts spread over the middle half of the
/// domain.
const MAX_START_SD: f64 = 0.25;

/// ln L below the optimum's down to which another start centre (one of
/// the fit's other optima, [`other_modes`], or a ridge end,
/// [`ridge_ends`]) gets ensembles of its own: about the 95 % point of
/// χ²₅/2, so that a centre the posterior could hold mass around is kept
/// and one far out in the tail is not.
const OTHER_CENTRE_LN_L: f64 = 6.0;

/// The fit's other local optima (`others`, free parameters) whose ln L
/// lies within [`OTHER_CENTRE_LN_L`] of the optimum's (`best`), highest
/// first. A multistart clusters its local runs into distinct optima and
/// reports the lowest misfit; where two basins fit within a few units of
/// ln L — a fast Prony term at τ1 ≈ 0.02–0.1 s against a term near 1.5 s
/// of lower weight — the posterior mass may sit mostly in the one that is
/// not the optimum (the longer basin along the fast-term ridge has the
/// larger prior volume), and ensembles all started at the optimum agree
/// with each other there and never see it (docs/theory/inverse.md,
/// "Session 20"). Started in both, the ensembles share one independence
/// proposal fitted to their pooled draws, which carries walkers between
/// the modes in proportion to their masses (and R̂ stays high until it
/// has).
fn other_modes(
    lik: &CurveLikelihood,
    fixed: &FixedInputs,
    best: f64,
    others: &[Vec<f64>],
) -> Result<Vec<Vec<f64>>> {
    let mut near = Vec::new();
    for x in others {
        let l = lik.value(&fixed.expand(x))?;
        if l >= best - OTHER_CENTRE_LN_L {
            near.push((l, x.clone()));
        }
    }
    near.sort_by(|a, b| b.0.total_cmp(&a.0));
    Ok(near.into_iter().map(|(_, x)| x).collect())
}

/// The ends of the posterior's weakest direction: the parameter with the
/// largest share of the least-determined eigenvector of the Laplace
/// information in u (`information`, [`laplace_information`]) is held at 0.02 and at 0.98 of its range and the
/// others refitted (`SurrogateFitter::fit_fixed`); an end whose ln L lies
/// within [`OTHER_CENTRE_LN_L`] of the optimum's ln L (`best`) is returned (free
/// parameters), so that the sampler also starts there: a ridge that runs
/// to a bound (a fast term at its lower time bound) is otherwise not
/// reached by ensembles started at the optimum (docs/theory/inverse.md,
/// "Session 19").
fn ridge_ends(
    surrogate: &KrigingSurrogate,
    fixed: &FixedInputs,
    data: &[f64],
    x_hat: &[f64],
    (lik, best): (&CurveLikelihood, f64),
    information: &DMatrix<f64>,
) -> Result<Vec<Vec<f64>>> {
    let domain = fixed.free_domain();
    let u_hat = domain.to_unit(x_hat);
    let eig = information.clone().symmetric_eigen();
    let weakest = eig.eigenvalues.imin();
    let v = eig.eigenvectors.column(weakest);
    let i = v.iamax();
    let fitter = crate::SurrogateFitter::new(surrogate.clone(), None)?;
    let multistart = crate::MultiStart::new().with_starts(8)?.with_seed(1);
    let mut ends = Vec::new();
    for u_i in [0.02, 0.98] {
        if (u_i - u_hat[i]).abs() < 0.1 {
            continue;
        }
        let mut u = u_hat.clone();
        u[i] = u_i;
        let held = domain.from_unit(&u)[i];
        let mut pairs: Vec<(&str, f64)> = fixed
            .fixed()
            .iter()
            .map(|(n, x)| (n.as_str(), *x))
            .collect();
        pairs.push((domain.params()[i].name.as_str(), held));
        let end_inputs = FixedInputs::new(fixed.full_domain(), &pairs)?;
        let Ok(fit) = fitter.fit_fixed(&[("ridge end", data)], &multistart, &end_inputs) else {
            continue;
        };
        let full = end_inputs.expand(&fit.fit.best.x);
        if lik.value(&full)? >= best - OTHER_CENTRE_LN_L {
            ends.push(fixed.restrict(&full));
        }
    }
    Ok(ends)
}

/// The Gauss–Newton (Laplace) information JᵤᵀJᵤ/σ² of the free parameters
/// in u at `x_hat`.
fn laplace_information(
    surrogate: &KrigingSurrogate,
    fixed: &FixedInputs,
    x_hat: &[f64],
    noise_var: f64,
) -> Result<DMatrix<f64>> {
    let domain = fixed.free_domain();
    let u_hat = domain.to_unit(x_hat);
    let (_, jac) = surrogate.response_and_jacobian(&fixed.expand(x_hat))?;
    let mut ju = fixed.columns(&jac);
    for (i, p) in domain.params().iter().enumerate() {
        let s = p.dx_du(u_hat[i]);
        for j in 0..ju.nrows() {
            ju[(j, i)] *= s;
        }
    }
    Ok(ju.transpose() * &ju / noise_var)
}

/// Start positions in u for `ensembles` ensembles of `walkers`: u_c + k·L ε
/// with the centre u_c the multistart optimum û (the first half of the
/// ensembles, all of them without other centres) or another centre (the
/// fit's other optima, [`other_modes`], then the ridge ends,
/// [`ridge_ends`]: the other half in turn), k = [`OVERDISPERSION`] and L Lᵀ
/// the Gauss–Newton (Laplace) covariance H⁻¹ at û (`information` = H =
/// JᵤᵀJᵤ/σ², [`laplace_information`]), its sd capped at [`MAX_START_SD`];
/// each start redrawn (shrinking the ball every 40 tries) until inside the
/// prior's support.
fn starts(
    domain: &nlvid_model::Domain,
    (x_hat, centres): (&[f64], &[Vec<f64>]),
    information: &DMatrix<f64>,
    (walkers, ensembles): (usize, usize),
    seed: u64,
    inside: &dyn Fn(&[f64]) -> bool,
) -> Result<Vec<Vec<Vec<f64>>>> {
    use rand::SeedableRng;
    let d = domain.len();
    let eig = information.clone().symmetric_eigen();
    let floor = 1.0 / (MAX_START_SD * MAX_START_SD);
    let mut l = DMatrix::zeros(d, d);
    for k in 0..d {
        let sd = OVERDISPERSION / eig.eigenvalues[k].max(floor).sqrt();
        for i in 0..d {
            l[(i, k)] = eig.eigenvectors[(i, k)] * sd;
        }
    }
    let u_opt = domain.to_unit(x_hat);
    let mut all = Vec::with_capacity(ensembles);
    for e in 0..ensembles {
        let half = ensembles / 2;
        let u_hat = if centres.is_empty() || e < half {
            u_opt.clone()
        } else {
            domain.to_unit(&centres[(e - half) % centres.len()])
        };
        let center_ok = inside(&u_hat);
        let mut rng =
            rand_chacha::ChaCha8Rng::seed_from_u64(seed ^ 0x5eed_57a7 ^ ((e as u64) << 32));
        let mut out = Vec::with_capacity(walkers);
        for _ in 0..walkers {
            let mut shrink = 1.0;
            let mut placed = None;
            for attempt in 0..200 {
                if attempt % 40 == 39 {
                    shrink *= 0.3;
                }
                let eps: Vec<f64> = (0..d).map(|_| normal(&mut rng)).collect();
                let u: Vec<f64> = (0..d)
                    .map(|i| u_hat[i] + shrink * (0..d).map(|k| l[(i, k)] * eps[k]).sum::<f64>())
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
        all.push(out);
    }
    Ok(all)
}

/// Samples the posterior of the parameters of `data` (on the surrogate's
/// grid) given the optimum `x_hat` of a fit (module docs): `ensembles`
/// independent ensembles in the domain's unit coordinates u, each burnt
/// in and then run `steps` kept steps at a time until the split R̂ across
/// ensembles of every reported quantity is ≤ [`RHAT_TARGET`] or
/// `max_steps` kept steps are reached. Not converged after
/// `temper_after` kept steps, or with R̂ above `temper_rhat` at the end of
/// an earlier round ([`temper_now`]): every ensemble gets `rungs` rungs
/// ([`Ensemble::temper`]), is burnt in again (`temper_burn` steps) and run
/// in rounds as before (kept steps counted from 0, R̂ checked from
/// `temper_min_steps`), only its β = 1 rung kept. Validity: the
/// restart is a new chain of the tempered joint target from the current
/// positions; within it the kernel changes only at the finitely many
/// refits of the independence proposal (finite adaptation, Roberts &
/// Rosenthal 2007), and each ensemble is tempered on its own (own rungs,
/// own random stream), so the ensembles stay independent for R̂.
///
/// Cost: ensembles·walkers·(burn + kept steps) likelihood evaluations
/// (times `rungs` for the tempered restart's burn-in and steps),
/// each one reduced prediction O(N·q·d) and one Kriging variance O(N²)
/// (N training runs); the ensembles are stepped together so that each
/// step's proposals of all ensembles are evaluated in batches of 32–64
/// points, the O(N²) triangular solve done for the batch at once
/// ([`CurveLikelihood::values`]).
///
/// # Errors
/// Bad settings, a curve without measurable noise, surrogate failures.
pub fn sample_posterior(
    surrogate: &KrigingSurrogate,
    data: &[f64],
    (x_hat, other_optima): (&[f64], &[Vec<f64>]),
    settings: &PosteriorSettings,
) -> Result<Posterior> {
    let none = FixedInputs::none(Model::domain(surrogate));
    sample_posterior_fixed(surrogate, &none, data, (x_hat, other_optima), settings)
}

/// As [`sample_posterior`] with the inputs of `fixed` held at their values
/// (known, not sampled: e.g. a cell's measured height and diameter): the
/// prior is uniform on the free parameters' domain, `x_hat` and the draws
/// are free parameters.
///
/// # Errors
/// As [`sample_posterior`].
pub fn sample_posterior_fixed(
    surrogate: &KrigingSurrogate,
    fixed: &FixedInputs,
    data: &[f64],
    (x_hat, other_optima): (&[f64], &[Vec<f64>]),
    settings: &PosteriorSettings,
) -> Result<Posterior> {
    if !(settings.level > 0.0 && settings.level < 1.0)
        || settings.keep == 0
        || settings.ensembles < 2
        || settings.steps < 4
    {
        return Err(InverseError::InvalidSetting(format!(
            "posterior: level {} must be in (0, 1), keep {} > 0, ensembles {} >= 2 and steps \
             {} >= 4",
            settings.level, settings.keep, settings.ensembles, settings.steps
        )));
    }
    if fixed.full_domain() != Model::domain(surrogate) {
        return Err(InverseError::InvalidSetting(
            "posterior: the fixed inputs were made for another surrogate's domain".into(),
        ));
    }
    let domain = fixed.free_domain().clone();
    let noise = noise_sd(Model::times(surrogate), data)?;
    let lik = CurveLikelihood::new(
        surrogate,
        data,
        noise,
        settings.heavy_tails,
        settings.direction_scales,
    )?
    .with_threads(settings.threads)
    .with_surrogate_error(settings.surrogate_error);
    let lik = if settings.variance_at_fit {
        let v = lik.calibrated_variances(&[fixed.expand(x_hat)])?[0];
        lik.with_variance_held(Some(v))
    } else {
        lik
    };
    let inside = |u: &[f64]| {
        u.iter().all(|v| (0.0..=1.0).contains(v)) && domain.feasible(&domain.from_unit(u), 0.0)
    };
    let information = laplace_information(surrogate, fixed, x_hat, lik.noise_var())?;
    let best = lik.value(&fixed.expand(x_hat))?;
    let mut centres = Vec::new();
    if settings.mode_starts {
        centres = other_modes(&lik, fixed, best, other_optima)?;
    }
    if settings.ridge_starts {
        centres.extend(ridge_ends(
            surrogate,
            fixed,
            data,
            x_hat,
            (&lik, best),
            &information,
        )?);
    }
    let init = starts(
        &domain,
        (x_hat, &centres),
        &information,
        (settings.walkers, settings.ensembles),
        settings.seed,
        &inside,
    )?;
    let mut log_density = UnitDensity {
        lik: &lik,
        fixed,
        domain: &domain,
        inside: &inside,
        screen: None,
        screen_points: (Vec::new(), Vec::new()),
        evaluations: std::cell::Cell::new(0),
    };
    if settings.delayed_acceptance && !lik.variance_held() {
        log_density.add_screen_points(init.iter().flatten())?;
    }
    let mut ensembles = Vec::with_capacity(init.len());
    let mut chains = Vec::with_capacity(init.len());
    for (e, start) in init.iter().enumerate() {
        let es = EnsembleSettings {
            walkers: settings.walkers,
            burn: settings.burn,
            steps: settings.steps,
            seed: settings
                .seed
                .wrapping_add(0x9e37_79b9_7f4a_7c15u64.wrapping_mul(e as u64)),
            refresh_fraction: settings.refresh_fraction,
            ridge_fraction: settings.ridge_fraction,
            pool_proposals: settings.mode_starts,
            ..EnsembleSettings::default()
        };
        let mut ens = Ensemble::new(&log_density, start, &es)?;
        if let Some(mut ridge) = ridge_move(&domain) {
            ridge.time_move = settings.ridge_time;
            ens = ens.with_ridge(ridge);
        }
        chains.push(ens.empty_chains());
        ensembles.push(ens);
    }
    burn_in(&mut ensembles, &log_density);
    refit_screen_after_burn_in(&mut log_density, &mut ensembles)?;
    let max_steps = settings.max_steps.max(settings.steps);
    let per_step = settings.ensembles * settings.walkers;
    let mut proposals = per_step * (1 + settings.burn);
    let check = settings.check_every.clamp(1, settings.steps);
    loop {
        // One round in parts of `check` kept steps; R̂ is checked after
        // each part once the chain has `first_check` kept steps (a whole
        // round, or `temper_min_steps` when tempered), else at the round's
        // end (the stopping rule, `PosteriorSettings::check_every`).
        let rungs = ensembles[0].rungs();
        let first_check = if rungs > 1 {
            settings.temper_min_steps.min(settings.steps)
        } else {
            settings.steps
        };
        let mut done = 0;
        let (kept, post) = loop {
            let part = check.min(settings.steps - done);
            if done == 0 {
                sample(&mut ensembles, &log_density, part, &mut chains);
            } else {
                sample_more(&mut ensembles, &log_density, part, &mut chains);
            }
            done += part;
            proposals += per_step * rungs * part;
            let kept = chains[0].steps;
            if done < settings.steps && kept < first_check {
                continue;
            }
            let draws = to_draws(&domain, chains.iter());
            let mut post = summarise(&draws, noise, settings)?;
            (post.kept_steps, post.rungs, post.proposals) = (kept, rungs, proposals);
            post.evaluations = log_density.evaluations.get();
            post.swap_acceptance = ensembles.iter().map(Ensemble::swap_acceptance).sum::<f64>()
                / ensembles.len() as f64;
            if post.rhat_max <= RHAT_TARGET {
                return Ok(post);
            }
            if done == settings.steps {
                break (kept, post);
            }
        };
        if kept + settings.steps > max_steps {
            return Ok(post);
        }
        if rungs == 1 && settings.rungs > 1 && temper_now(settings, kept, post.rhat_max) {
            // A tempered restart from the current positions: a new chain
            // of the tempered joint target, burnt in, its rounds counted
            // from 0 ([`ensemble`] module docs, "Tempering").
            if settings.hot_starts {
                proposals += temper_from_proposal(
                    &mut ensembles,
                    &log_density,
                    settings.rungs,
                    settings.rung_ratio,
                )?;
            }
            for (ens, ch) in ensembles.iter_mut().zip(chains.iter_mut()) {
                if !settings.hot_starts {
                    ens.temper(settings.rungs, settings.rung_ratio)?;
                }
                ens.set_ridge_fraction(settings.temper_ridge)?;
                ens.set_burn(settings.temper_burn);
                *ch = ens.empty_chains();
            }
            burn_in(&mut ensembles, &log_density);
            refit_screen_after_burn_in(&mut log_density, &mut ensembles)?;
            proposals += per_step * settings.rungs * settings.temper_burn;
        } else if settings.refit_proposal {
            refit_proposals(&mut ensembles);
        }
    }
}

/// True when an untempered posterior with `kept` kept steps and R̂
/// `rhat` at the end of a round (above [`RHAT_TARGET`]) is restarted
/// tempered: after `temper_after` kept steps, or earlier when R̂ is above
/// `temper_rhat`.
fn temper_now(settings: &PosteriorSettings, kept: usize, rhat: f64) -> bool {
    kept >= settings.temper_after || settings.temper_rhat.is_some_and(|t| !(rhat <= t))
}

/// The posterior's log-density in the unit coordinates u of the free
/// parameters: −∞ outside the prior's support, else ln L at the expanded
/// physical point, the points of a batch evaluated together
/// ([`CurveLikelihood::values`]); with a `screen`, the screen of delayed
/// acceptance is ln L with the Kriging variance of that model
/// ([`CurveLikelihood::screen_values`]).
struct UnitDensity<'a> {
    lik: &'a CurveLikelihood<'a>,
    fixed: &'a FixedInputs,
    domain: &'a nlvid_model::Domain,
    inside: &'a dyn Fn(&[f64]) -> bool,
    screen: Option<VarianceModel>,
    /// The points (u) and calibrated Kriging variances the screen was
    /// fitted to.
    screen_points: (Vec<Vec<f64>>, Vec<f64>),
    /// Points inside the support whose full ln L (or Kriging variance)
    /// was computed.
    evaluations: std::cell::Cell<usize>,
}

/// After a burn-in: the screen of delayed acceptance refitted with the
/// variances at every ensemble's current positions added to its points,
/// and the walkers' screened values recomputed (module docs of
/// [`screen`]; nothing without delayed acceptance).
fn refit_screen_after_burn_in(density: &mut UnitDensity, ensembles: &mut [Ensemble]) -> Result<()> {
    if density.screen.is_none() {
        return Ok(());
    }
    density.add_screen_points(ensembles.iter().flat_map(Ensemble::positions))?;
    ensembles.iter_mut().for_each(|e| e.rescreen(&*density));
    Ok(())
}

impl UnitDensity<'_> {
    /// Adds the calibrated Kriging variances at `us` (those inside the
    /// support) to the screen's points and refits it ([`VarianceModel::fit`]).
    fn add_screen_points<'u>(&mut self, us: impl Iterator<Item = &'u Vec<f64>>) -> Result<()> {
        let us: Vec<Vec<f64>> = us.cloned().collect();
        let (idx, xs) = self.inside_points(&us);
        let vs = self.lik.calibrated_variances(&xs)?;
        self.evaluations.set(self.evaluations.get() + xs.len());
        self.screen_points
            .0
            .extend(idx.iter().map(|&i| us[i].clone()));
        self.screen_points.1.extend(vs);
        self.screen = VarianceModel::fit(&self.screen_points.0, &self.screen_points.1);
        Ok(())
    }

    /// The indices of the points of `us` inside the prior's support and
    /// their physical points.
    fn inside_points(&self, us: &[Vec<f64>]) -> (Vec<usize>, Vec<Vec<f64>>) {
        let idx: Vec<usize> = (0..us.len()).filter(|&i| (self.inside)(&us[i])).collect();
        let xs = idx
            .iter()
            .map(|&i| self.fixed.expand(&self.domain.from_unit(&us[i])))
            .collect();
        (idx, xs)
    }
}

impl LogDensity for UnitDensity<'_> {
    fn screen_log_densities(&self, us: &[Vec<f64>]) -> Option<Vec<f64>> {
        let model = self.screen.as_ref()?;
        let mut out = vec![f64::NEG_INFINITY; us.len()];
        let (idx, xs) = self.inside_points(us);
        let variances: Vec<f64> = idx.iter().map(|&i| model.variance(&us[i])).collect();
        match self.lik.screen_values(&xs, &variances) {
            Ok(Some(v)) => idx.iter().zip(v).for_each(|(&i, l)| out[i] = l),
            Ok(None) => return None,
            // A point the surrogate refuses: one by one, so that only it
            // gets −∞ (and so is rejected on the screen).
            Err(_) => {
                for ((&i, x), v) in idx.iter().zip(&xs).zip(&variances) {
                    let one = self.lik.screen_values(std::slice::from_ref(x), &[*v]);
                    if let Ok(Some(l)) = one {
                        out[i] = l[0];
                    }
                }
            }
        }
        Some(out)
    }

    fn log_densities(&self, us: &[Vec<f64>]) -> Vec<f64> {
        let mut out = vec![f64::NEG_INFINITY; us.len()];
        let (idx, xs) = self.inside_points(us);
        self.evaluations.set(self.evaluations.get() + xs.len());
        match self.lik.values(&xs) {
            Ok(v) => idx.iter().zip(v).for_each(|(&i, l)| out[i] = l),
            // A point the surrogate refuses: evaluate one by one so that
            // only it gets −∞.
            Err(_) => {
                for (&i, x) in idx.iter().zip(&xs) {
                    out[i] = self.lik.value(x).unwrap_or(f64::NEG_INFINITY);
                }
            }
        }
        out
    }
}

/// The ridge move of a Prony domain (eq. 5.1): scale `G0` (or `C1`, which
/// scales G0 in proportion), the weight whose relaxation time has the
/// lowest bound redrawn (g1 of Table 5.3, τ1 ∈ [0.01, 2] s), the other
/// weights carried, its time redrawn on half the moves. None when the domain has no modulus or fewer than one
/// weight/time pair.
pub fn ridge_move(domain: &nlvid_model::Domain) -> Option<RidgeMove> {
    use nlvid_model::names;
    let axis = |i: usize| (i, domain.params()[i].clone());
    let scale = domain
        .index_of(names::G0)
        .or_else(|| domain.index_of(names::C1))?;
    let pairs: Vec<(usize, usize)> = (1..)
        .map_while(|k| {
            Some((
                domain.index_of(&names::weight(k))?,
                domain.index_of(&names::time(k))?,
            ))
        })
        .collect();
    let lower = |t: usize| domain.params()[t].lower;
    let (fast, fast_time) = *pairs
        .iter()
        .min_by(|a, b| lower(a.1).total_cmp(&lower(b.1)))?;
    Some(RidgeMove {
        scale: axis(scale),
        fast: axis(fast),
        carried: pairs
            .iter()
            .filter(|p| p.0 != fast)
            .map(|p| axis(p.0))
            .collect(),
        fast_time: Some(axis(fast_time)),
        time_move: RidgeTime::Kept,
    })
}

/// R̂ at or below which a posterior counts as converged (Vehtari et al.
/// 2021, "Rank-normalization, folding, and localization", §4: 1.01).
pub const RHAT_TARGET: f64 = 1.01;

/// Kept draws of every ensemble in physical coordinates.
struct Draws<'a> {
    domain: &'a nlvid_model::Domain,
    /// Per ensemble: walkers, steps, and x at index step·walkers + walker.
    ensembles: Vec<(usize, usize, Vec<Vec<f64>>)>,
    acceptance: f64,
}

fn to_draws<'a, 'c>(
    domain: &'a nlvid_model::Domain,
    chains: impl Iterator<Item = &'c Chains>,
) -> Draws<'a> {
    let mut ensembles = Vec::new();
    let mut acc = Vec::new();
    for c in chains {
        let xs = c
            .samples
            .chunks(c.dim)
            .map(|u| domain.from_unit(u))
            .collect();
        ensembles.push((c.walkers, c.steps, xs));
        acc.push(c.acceptance);
    }
    Draws {
        domain,
        ensembles,
        acceptance: acc.iter().sum::<f64>() / acc.len().max(1) as f64,
    }
}

impl Draws<'_> {
    /// The interval of a scalar f(x): quantiles over all draws, split R̂
    /// over the ensembles (each ensemble's walkers pooled step by step into
    /// one chain: walkers of one ensemble are not independent chains), ESS
    /// over the walkers' own chains (the autocorrelation averaged over
    /// walkers, as emcee's estimator does).
    fn interval(&self, f: &dyn Fn(&[f64]) -> f64, level: f64) -> Interval {
        let mut pooled = Vec::with_capacity(self.ensembles.len());
        let mut walkers = Vec::new();
        for (w, n, xs) in &self.ensembles {
            let v: Vec<f64> = xs.iter().map(|x| f(x)).collect();
            for k in 0..*w {
                walkers.push((0..*n).map(|s| v[s * w + k]).collect::<Vec<f64>>());
            }
            pooled.push(v);
        }
        let mut all: Vec<f64> = pooled.iter().flatten().copied().collect();
        all.sort_by(f64::total_cmp);
        let a = 0.5 * (1.0 - level);
        Interval {
            lower: quantile(&all, a),
            median: quantile(&all, 0.5),
            upper: quantile(&all, 1.0 - a),
            rhat: diagnostics::split_rhat(&pooled),
            ess: diagnostics::effective_sample_size(&walkers),
        }
    }

    /// `n` draws spread evenly over the ensembles and steps.
    fn pick(&self, n: usize) -> Vec<Vec<f64>> {
        let all: Vec<&Vec<f64>> = self.ensembles.iter().flat_map(|e| e.2.iter()).collect();
        let n = n.min(all.len());
        (0..n).map(|k| all[k * all.len() / n].clone()).collect()
    }
}

/// Intervals, band, diagnostics and thinned draws.
fn summarise(draws: &Draws, noise: f64, settings: &PosteriorSettings) -> Result<Posterior> {
    let domain = draws.domain;
    let mut parameters = Vec::with_capacity(domain.len());
    for (i, p) in domain.params().iter().enumerate() {
        parameters.push((p.name.clone(), draws.interval(&|x| x[i], settings.level)));
    }
    // Validate once (names G0, g_k, tau_k) before mapping every draw.
    relaxation(domain, &draws.ensembles[0].2[0])?;
    let rel = |x: &[f64]| relaxation(domain, x).ok();
    let t_end = settings.t_end;
    let g0 = draws.interval(&|x| rel(x).map_or(f64::NAN, |r| r.g0()), settings.level);
    let g_sum = draws.interval(
        &|x| rel(x).map_or(f64::NAN, |r| 1.0 - r.prony().long_term_weight()),
        settings.level,
    );
    let g_end = draws.interval(
        &|x| rel(x).map_or(f64::NAN, |r| r.value(t_end)),
        settings.level,
    );
    let mut rhat_max = g0.rhat.max(g_sum.rhat).max(g_end.rhat);
    let mut ess_min = g0.ess.min(g_sum.ess).min(g_end.ess);
    for (_, iv) in &parameters {
        rhat_max = rhat_max.max(iv.rhat);
        ess_min = ess_min.min(iv.ess);
    }
    let a = 0.5 * (1.0 - settings.level);
    let mut band = Band {
        times: settings.band_times.clone(),
        lower: Vec::new(),
        median: Vec::new(),
        upper: Vec::new(),
    };
    let curves: Vec<nlvid_model::Relaxation> = draws
        .pick(2000)
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
        acceptance: draws.acceptance,
        kept_steps: 0,
        rungs: 1,
        swap_acceptance: 0.0,
        proposals: 0,
        evaluations: 0,
        draws: draws.pick(settings.keep),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A cell whose fast term sits near its lower time bound (τ1 = 0.021 s
    /// on the demo meta-model's 0.1-s grid; session 19's cell where the
    /// sampler missed the ridge's far end): the weakest direction is held
    /// at an end of its range and refitted, and an end within
    /// [`OTHER_CENTRE_LN_L`] of the optimum's ln L is returned; a curve that
    /// determines every parameter has no end within reach.
    #[test]
    fn ridge_ends_reach_the_bound_of_a_fast_term() {
        let s = likelihood::tests::demo_surrogate();
        let none = FixedInputs::none(Model::domain(&s));
        let domain = Model::domain(&s).clone();
        let ends_of = |x: &[f64]| {
            let (data, sd) = likelihood::tests::pseudo_noisy_curve(&s, x);
            let lik = CurveLikelihood::new(&s, &data, sd, false, false)
                .unwrap()
                .with_surrogate_error(false);
            let fitter = crate::SurrogateFitter::new(s.clone(), None).unwrap();
            let ms = crate::MultiStart::new().with_seed(1);
            let fit = fitter.fit_fixed(&[("cell", &data)], &ms, &none).unwrap();
            let x_hat = fit.fit.best.x;
            let best = lik.value(&x_hat).unwrap();
            let h = laplace_information(&s, &none, &x_hat, lik.noise_var()).unwrap();
            let ends = ridge_ends(&s, &none, &data, &x_hat, (&lik, best), &h).unwrap();
            for e in &ends {
                assert!(lik.value(e).unwrap() >= best - OTHER_CENTRE_LN_L);
                let u = domain.to_unit(e);
                assert!(
                    u.iter()
                        .any(|v| (v - 0.02).abs() < 1e-9 || (v - 0.98).abs() < 1e-9),
                    "an end holds one parameter at 2 % or 98 % of its range: {u:?}"
                );
            }
            ends
        };
        let fast = ends_of(&[215.6, 0.1535, 0.2913, 0.0211, 33.74]);
        assert!(
            fast.iter()
                .any(|e| (domain.to_unit(e)[3] - 0.02).abs() < 1e-9),
            "the fast term's time held at its lower end: {fast:?}"
        );
        assert!(ends_of(&[1500.0, 0.3, 0.25, 0.5, 10.0]).is_empty());
    }

    /// The fit's other optima that become start centres: exactly those
    /// within [`OTHER_CENTRE_LN_L`] of the optimum's ln L, highest first.
    /// On the fast-term cell of [`ridge_ends_reach_the_bound_of_a_fast_term`]
    /// (the session-19 cell whose posterior the sampler missed) the
    /// 64-start fit has a second basin with a τ1 at least 3× apart from
    /// the optimum's within reach: the mode the ensembles never visited.
    /// The restart rule: after `temper_after` kept steps whatever R̂, and
    /// before it only when R̂ at the round's end is above `temper_rhat`
    /// (NaN counts as above); with `temper_rhat` None, the default, only
    /// after `temper_after` (the sampler before session 21).
    #[test]
    fn a_far_unconverged_round_is_tempered_before_temper_after() {
        let default = PosteriorSettings::new(52.0);
        assert_eq!((default.temper_after, default.temper_rhat), (500, None));
        let s = PosteriorSettings {
            temper_rhat: Some(1.025),
            ..default
        };
        assert!(!temper_now(&s, 250, 1.024));
        assert!(temper_now(&s, 250, 1.026));
        assert!(temper_now(&s, 250, f64::NAN));
        assert!(temper_now(&s, 500, 1.011));
        let off = PosteriorSettings {
            temper_rhat: None,
            ..s
        };
        assert!(!temper_now(&off, 250, 1.5));
        assert!(!temper_now(&off, 450, f64::NAN));
        assert!(temper_now(&off, 500, 1.011));
    }

    #[test]
    fn other_modes_are_the_optima_within_reach_of_the_best() {
        let s = likelihood::tests::demo_surrogate();
        let none = FixedInputs::none(Model::domain(&s));
        let x = [215.6, 0.1535, 0.2913, 0.0211, 33.74];
        let (data, sd) = likelihood::tests::pseudo_noisy_curve(&s, &x);
        let lik = CurveLikelihood::new(&s, &data, sd, false, false)
            .unwrap()
            .with_surrogate_error(false);
        let fitter = crate::SurrogateFitter::new(s.clone(), None).unwrap();
        let ms = crate::MultiStart::new().with_seed(1);
        let fit = fitter
            .fit_fixed(&[("cell", &data)], &ms, &none)
            .unwrap()
            .fit;
        let best = lik.value(&fit.best.x).unwrap();
        let others = fit.other_optima();
        let modes = other_modes(&lik, &none, best, &others).unwrap();
        let ln_l = |x: &[f64]| lik.value(x).unwrap();
        for pair in modes.windows(2) {
            assert!(ln_l(&pair[0]) >= ln_l(&pair[1]), "highest first");
        }
        for o in &others {
            let kept = modes.contains(o);
            assert_eq!(kept, ln_l(o) >= best - OTHER_CENTRE_LN_L, "{o:?}");
        }
        let tau = fit.best.x[3];
        assert!(
            modes.iter().any(|m| (m[3] / tau).ln().abs() >= 3f64.ln()),
            "a second basin along τ1: best τ1 {tau}, modes {modes:?}, all {:?}",
            others
                .iter()
                .map(|o| (ln_l(o) - best, o[3]))
                .collect::<Vec<_>>()
        );
    }

    /// Table 5.3: scale G0 (index 0), fast weight g1 (τ1 ≥ 0.01 s, below
    /// τ2 ≥ 2 s), g2 carried; a domain without weights has no ridge.
    #[test]
    fn the_ridge_of_table_5_3_redraws_g1_and_carries_g2() {
        let d = nlvid_model::Domain::table_5_3(0.01).expect("domain");
        let r = ridge_move(&d).expect("ridge");
        assert_eq!((r.scale.0, r.fast.0), (0, 1));
        assert_eq!(r.fast_time.map(|t| t.0), Some(3));
        assert_eq!(r.carried.iter().map(|c| c.0).collect::<Vec<_>>(), vec![2]);
        let g = nlvid_model::Parameter::new("G0", "Pa", 1.0, 2.0, nlvid_model::Scale::Log);
        let only = nlvid_model::Domain::new(vec![g]).expect("1-d");
        assert!(ridge_move(&only).is_none());
    }
}
