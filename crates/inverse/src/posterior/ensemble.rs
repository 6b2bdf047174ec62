//! An affine-invariant ensemble sampler (Goodman & Weare 2010, "Ensemble
//! samplers with affine invariance", CAMCoS 5:65; the moves of emcee,
//! Foreman-Mackey et al. 2013) for the per-cell posteriors of issue 17.
//!
//! Written here rather than taken from a crate: the Rust `emcee` crate
//! (0.3 / 1.0.0-alpha) has not been released since 2018 and pins an old
//! `rand`; a NUTS crate would need the log-density's gradient through the
//! bounded, constrained domain (a logit transform and its Jacobian) for a
//! five-parameter problem that an ensemble handles without tuning. The
//! sampler is seeded (ChaCha8, one stream per ensemble) and sequential,
//! so a cell's draws do not depend on threads.
//!
//! *Split form* (Goodman & Weare §3, "parallel" version; emcee's
//! default): each step updates the first half of the walkers against the
//! second half held fixed, then the second half against the (updated)
//! first. Given the other half, each walker of a half makes its own
//! Metropolis–Hastings move that keeps p(x_k) invariant, so the half's
//! joint update keeps the product of the walkers' p. The proposals of a
//! half depend only on positions that do not change during its update,
//! so they are evaluated in one batch ([`LogDensity`]); ensembles stepped
//! together ([`burn_in`], [`sample`]) put their halves in the same batch
//! (the posterior's batches: 4 ensembles × 8 walkers, × 16 for the moves
//! that read only the walker's own position), each with its own random
//! stream.
//!
//! Moves, for walker k of the half being updated:
//! - stretch (GW eq. 7): y = x_j + z (x_k − x_j), j in the other half,
//!   g(z) ∝ 1/√z on [1/a, a], accepted with min(1, z^{d−1} p(y)/p(x_k));
//! - differential evolution (ter Braak 2006): y = x_k + γ (x_i − x_j) + ε,
//!   i ≠ j in the other half, γ = 2.38/√(2d) (1 every 10th step: mode
//!   hopping), ε ~ N(0, 1e-10²), accepted with min(1, p(y)/p(x_k)).
//!
//! - independence (after burn-in only): y ~ t₅(μ̂, 1.2²·Σ̂) with μ̂, Σ̂ the
//!   mean and covariance of the ensemble over the second half of burn-in
//!   (fixed within a call of [`Ensemble::sample`]; refitted only between
//!   calls, see below),
//!   accepted with min(1, p(y) q(x_k) / (p(x_k) q(y))). Where the
//!   posterior is close to Gaussian this cuts the autocorrelation time
//!   from ≈ 25 steps (DE/stretch in 5-D) to a few. Where the positions
//!   form two clusters (BIC of a two-Gaussian EM fit below that of one
//!   Gaussian: a posterior with two arms), q is instead the mixture
//!   Σ_k ŵ_k t₅(μ̂_k, 1.2²·Σ̂_k) of the clusters (module `independence`), so a
//!   walker can change arm in one accepted step (session 14: seed 19's
//!   two slowest cells went from R̂ 1.017–1.020 at 2000 kept steps to
//!   ≤ 1.009 at 450).
//!
//! - axis refresh (for densities supported in the unit box [0, 1]^d, the
//!   posterior's u coordinates; `refresh_fraction`): one coordinate c,
//!   chosen uniformly, is redrawn uniformly on [0, 1], the others kept;
//!   the proposal is symmetric, accepted with min(1, p(y)/p(x_k)). A
//!   Metropolis-within-Gibbs step with the prior as proposal: along a
//!   direction the data do not resolve (τ2 when g2 is small, τ1 below the
//!   time grid) it crosses the whole range in one accepted move, where
//!   stretch/DE moves diffuse along it.
//!
//! - ridge (`ridge_fraction`, with a [`RidgeMove`] given to
//!   [`Ensemble::with_ridge`]): the fast Prony weight g1 is redrawn while
//!   G0·(1 − g1) and G0·g2 are kept, a jump along the posterior's ridge
//!   where τ1 lies below the times the data resolve (module `ridge`).
//!
//! *Pooled proposals* (`pool_proposals`; [`refit_proposals`]): ensembles
//! started in different modes (the fit's other optima,
//! `posterior::sample_posterior`) each hold one mode, and no stretch, DE
//! or own-draws independence move crosses the gap between them, so R̂
//! stays high (on four such cells even the tempered restart had not
//! crossed after 2000 kept steps). With pooling, each rung's proposal
//! is fitted to that rung's positions in every ensemble — the
//! two-cluster mixture below then has a component on each mode — and the
//! same proposal is given to every ensemble: a walker changes mode in one
//! accepted independence step, in proportion to the modes' masses. Each
//! ensemble still moves with its own random stream and its own walkers
//! only; the ensembles interact through the proposal's refits alone (a
//! finite number, at round ends), so each chain keeps its target by the
//! finite-adaptation argument below.
//!
//! The independence proposal can be refitted between calls of
//! [`Ensemble::sample`] to the ensemble's own kept draws
//! ([`Ensemble::refit_proposal`]). Each kernel used keeps the target
//! invariant, and the proposal changes only a finite number of times
//! (once per round of the caller), the "finite adaptation" case of
//! Roberts & Rosenthal (2007, J. Appl. Prob. 44:458, §2), so the chain
//! stays valid; fitted per ensemble, the ensembles stay independent.
//!
//! *Tempering* (parallel tempering, replica exchange: Swendsen & Wang
//! 1986; review Earl & Deem 2005, Phys. Chem. Chem. Phys. 7:3910; with
//! ensemble moves as in emcee's former `PTSampler` and Vousden, Farr &
//! Mandel 2016, MNRAS 455:1919; [`Ensemble::temper`]): the ensemble
//! carries R rungs of W walkers, rung r sampling p^{β_r}, β_0 = 1 > β_1 >
//! … (a geometric ladder β_r = ratio^r, fixed: Vousden et al.'s adaptive
//! ladder is not used, so no kernel changes within a run). For a
//! posterior with a uniform prior p^β is the likelihood tempered. Every
//! move above acts on each rung against its own rung's walkers and
//! target (Metropolis ratio (p(y)/p(x))^β times the move's own factor,
//! which is not tempered); after each step adjacent rungs propose to swap
//! walkers ([`Ensemble::swap_rungs`]). The joint target is Π_r p^{β_r}, so
//! rung 0 keeps p; only its draws are kept. Hot rungs spread along
//! directions the data barely constrain and swaps carry their positions
//! down. Test: `tempering_keeps_a_two_mode_mixture`.
//!
//! *Delayed acceptance* (Christen & Fox 2005, "Markov chain Monte Carlo
//! using an approximation", J. Comput. Graph. Stat. 14:795; with a
//! [`LogDensity::screen_log_densities`]): a proposal is first judged on a
//! cheap approximation p̃ of p, α₁ = min(1, ρ·(p̃(y)/p̃(x))^β) with ρ the
//! move's own factor, and only if it passes is p(y) computed and the
//! second stage α₂ = min(1, ((p(y) p̃(x))/(p(x) p̃(y)))^β) applied. Since
//! α₁(y, x)/α₁(x, y) = 1/(ρ (p̃(y)/p̃(x))^β), the product α₁α₂ satisfies
//! detailed balance with respect to p^β for every move whose one-stage
//! form does, whatever p̃ is (p̃ fixed for the run and finite where p is);
//! a poor p̃ costs acceptance, not correctness. Both stages use the one
//! uniform drawn with the proposal: accepted when ln u < ln α₁ + ln α₂,
//! rejected without p(y) when ln u ≥ ln α₁ (α₂ ≤ 1) — the probability of
//! acceptance is α₁α₂ as with two uniforms, the random stream is that of
//! the one-stage sampler, and with p̃ = p the chain is the one-stage
//! chain draw for draw. Swaps between rungs use p itself (it is known at
//! every walker's position). The screen may change between calls only
//! ([`Ensemble::rescreen`]: finite adaptation, as the proposal's refits).
//!
//! Each step picks the move for the whole ensemble (all its rungs): with probability
//! `refresh_fraction` the axis refresh; otherwise with probability
//! `ridge_fraction` the ridge move (when one is set); otherwise after burn-in the
//! independence move with probability `independence_fraction`; otherwise
//! DE with probability `de_fraction`, else stretch.

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::independence::{Proposal, normal};
pub use super::ridge::{RidgeMove, RidgeTime};
use crate::error::{InverseError, Result};

/// Settings of [`sample_ensemble`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EnsembleSettings {
    /// Walkers (≥ 2·dim + 2).
    pub walkers: usize,
    /// Steps discarded before the kept ones.
    pub burn: usize,
    /// Steps kept (per walker).
    pub steps: usize,
    /// Stretch scale a (> 1; 2 in GW and emcee).
    pub stretch: f64,
    /// Probability that a step uses the DE move (0: stretch only).
    pub de_fraction: f64,
    /// Probability that a kept step uses the independence move (0: none).
    pub independence_fraction: f64,
    /// Probability that a step uses the axis refresh (0: none; only for
    /// densities supported in [0, 1]^d).
    pub refresh_fraction: f64,
    /// Probability that a step uses the ridge move (0: none; only with
    /// [`Ensemble::with_ridge`]).
    pub ridge_fraction: f64,
    /// Fit one independence proposal per rung to the recent positions of
    /// every ensemble stepped together ([`burn_in`], [`refit_proposals`];
    /// module docs, "Pooled proposals"); false: each ensemble its own.
    pub pool_proposals: bool,
    /// Seed.
    pub seed: u64,
}

impl Default for EnsembleSettings {
    fn default() -> Self {
        Self {
            walkers: 32,
            burn: 400,
            steps: 1200,
            stretch: 2.0,
            de_fraction: 0.8,
            independence_fraction: 0.5,
            refresh_fraction: 0.0,
            ridge_fraction: 0.0,
            pool_proposals: false,
            seed: 1,
        }
    }
}

/// Kept draws of an ensemble run.
#[derive(Debug, Clone, PartialEq)]
pub struct Chains {
    /// Dimension d.
    pub dim: usize,
    /// Walkers W.
    pub walkers: usize,
    /// Kept steps N.
    pub steps: usize,
    /// Positions, index `(step·W + walker)·d + i`.
    pub samples: Vec<f64>,
    /// Log-density at each kept position, index `step·W + walker`.
    pub log_density: Vec<f64>,
    /// Accepted proposals / proposals over burn-in and kept steps.
    pub acceptance: f64,
}

impl Chains {
    /// Coordinate `i` of walker `w` at kept step `s`.
    pub fn at(&self, s: usize, w: usize, i: usize) -> f64 {
        self.samples[(s * self.walkers + w) * self.dim + i]
    }

    /// The trace of a scalar function of the position, one chain per
    /// walker (W × N), for [`super::diagnostics`].
    pub fn traces(&self, f: impl Fn(&[f64]) -> f64) -> Vec<Vec<f64>> {
        let d = self.dim;
        (0..self.walkers)
            .map(|w| {
                (0..self.steps)
                    .map(|s| {
                        let o = (s * self.walkers + w) * d;
                        f(&self.samples[o..o + d])
                    })
                    .collect()
            })
            .collect()
    }
}

/// A walker index of `from` other than `not`.
fn other(rng: &mut ChaCha8Rng, from: std::ops::Range<usize>, not: Option<usize>) -> usize {
    loop {
        let j = rng.random_range(from.clone());
        if Some(j) != not {
            return j;
        }
    }
}

/// A log-density evaluated at a batch of points at once (module docs:
/// the sampler proposes half an ensemble, of every ensemble stepped
/// together, per batch). Every closure `Fn(&[f64]) -> f64` is one,
/// evaluated point by point.
pub trait LogDensity {
    /// ln p at each point of `xs` in order (−∞ outside the support).
    fn log_densities(&self, xs: &[Vec<f64>]) -> Vec<f64>;

    /// A cheap approximation ln p̃ at each point of `xs`, for delayed
    /// acceptance (module docs), or None: every proposal is then
    /// evaluated by [`LogDensity::log_densities`]. ln p̃ must be finite
    /// wherever ln p is and the same function for the whole run.
    fn screen_log_densities(&self, _xs: &[Vec<f64>]) -> Option<Vec<f64>> {
        None
    }
}

impl<F: Fn(&[f64]) -> f64> LogDensity for F {
    fn log_densities(&self, xs: &[Vec<f64>]) -> Vec<f64> {
        xs.iter().map(|x| self(x)).collect()
    }
}

/// Samples `log_density` (−∞ outside the support) with an ensemble started
/// at `init` (one position per walker, each with a finite log-density):
/// [`Ensemble::new`], `burn` steps of [`burn_in`], then `steps` kept steps
/// of [`sample`].
///
/// Cost: W·(burn + steps) evaluations of `log_density`.
///
/// # Errors
/// [`InverseError::InvalidSetting`] for too few walkers, a stretch scale
/// ≤ 1, no kept steps, or a start with a non-finite log-density.
pub fn sample_ensemble(
    log_density: impl LogDensity,
    init: &[Vec<f64>],
    settings: &EnsembleSettings,
) -> Result<Chains> {
    let mut e = [Ensemble::new(&log_density, init, settings)?];
    burn_in(&mut e, &log_density);
    let mut chains = [e[0].empty_chains()];
    sample(&mut e, &log_density, settings.steps, &mut chains);
    let [chains] = chains;
    Ok(chains)
}

/// The move of one step of an ensemble (module docs).
#[derive(Debug, Clone, Copy)]
enum Move {
    Refresh,
    Ridge,
    Independence,
    DifferentialEvolution { gamma: f64 },
    Stretch,
}

/// A proposal of one walker awaiting the log-density of its point:
/// accepted when ln u < `log_ratio` + ln p(y) − ln p(x).
struct Pending {
    walker: usize,
    log_ratio: f64,
    ln_u: f64,
}

/// An ensemble in flight: positions, log-densities, random stream and the
/// frozen independence proposal (module docs). Stepped by [`burn_in`] and
/// [`sample`], alone or together with other ensembles (each with its own
/// random stream: the draws of one ensemble do not depend on the others);
/// stepping in several calls of [`sample`] gives the same draws as one
/// call.
pub struct Ensemble {
    settings: EnsembleSettings,
    /// Positions of every rung's walkers, index rung·W + walker (rung 0:
    /// β = 1, the draws kept; module docs, "Tempering").
    pos: Vec<Vec<f64>>,
    /// ln p (untempered) at `pos`.
    lp: Vec<f64>,
    /// ln p̃ (the screen of delayed acceptance, untempered) at `pos`;
    /// empty without a screen.
    slp: Vec<f64>,
    /// Inverse temperature of each rung, β_0 = 1 > β_1 > ….
    betas: Vec<f64>,
    rng: ChaCha8Rng,
    /// Each rung's independence proposal.
    proposals: Vec<Option<Proposal>>,
    /// Each rung's positions over the last call of [`sample`], for
    /// [`Ensemble::refit_proposal`].
    recent: Vec<Vec<Vec<f64>>>,
    ridge: Option<RidgeMove>,
    /// The move of the current step, drawn at its start.
    current: Move,
    step: usize,
    /// Accepted and proposed moves of rung 0.
    accepted: usize,
    proposed: usize,
    /// Accepted and proposed swaps between rungs.
    swaps_accepted: usize,
    swaps_proposed: usize,
}

impl Ensemble {
    /// An ensemble at `init` (see [`sample_ensemble`] for the errors);
    /// `log_density` gives the starts' log-densities.
    ///
    /// # Errors
    /// As [`sample_ensemble`].
    pub fn new(
        log_density: &impl LogDensity,
        init: &[Vec<f64>],
        settings: &EnsembleSettings,
    ) -> Result<Self> {
        let w = init.len();
        let d = init.first().map_or(0, Vec::len);
        let bad = |m: String| Err(InverseError::InvalidSetting(m));
        if d == 0 || w < 2 * d + 2 || w != settings.walkers {
            return bad(format!(
                "ensemble: {w} start positions of dimension {d} for {} walkers (need walkers >= 2·dim + 2)",
                settings.walkers
            ));
        }
        let fraction = 0.0..=1.0;
        if !(settings.stretch > 1.0)
            || settings.steps == 0
            || !fraction.contains(&settings.de_fraction)
            || !fraction.contains(&settings.independence_fraction)
            || !fraction.contains(&settings.refresh_fraction)
            || !fraction.contains(&settings.ridge_fraction)
        {
            return bad(format!(
                "ensemble: stretch scale {} (must be > 1), {} kept steps (must be > 0), DE fraction \
                 {}, independence fraction {}, refresh fraction {}, ridge fraction {} (all in [0, 1])",
                settings.stretch,
                settings.steps,
                settings.de_fraction,
                settings.independence_fraction,
                settings.refresh_fraction,
                settings.ridge_fraction
            ));
        }
        let pos: Vec<Vec<f64>> = init.to_vec();
        let lp = log_density.log_densities(&pos);
        if let Some(k) = lp.iter().position(|v| !v.is_finite()) {
            return bad(format!("ensemble: start {k} has log-density {}", lp[k]));
        }
        let slp = log_density.screen_log_densities(&pos).unwrap_or_default();
        if let Some(k) = slp.iter().position(|v| !v.is_finite()) {
            return bad(format!(
                "ensemble: start {k} has screened log-density {}",
                slp[k]
            ));
        }
        Ok(Self {
            settings: *settings,
            pos,
            lp,
            slp,
            betas: vec![1.0],
            rng: ChaCha8Rng::seed_from_u64(settings.seed),
            proposals: vec![None],
            recent: vec![Vec::new()],
            ridge: None,
            current: Move::Stretch,
            step: 0,
            accepted: 0,
            proposed: 0,
            swaps_accepted: 0,
            swaps_proposed: 0,
        })
    }

    /// Adds hot rungs (module docs, "Tempering"): `rungs` in all, rung r
    /// at β_r = `ratio`^r, each started at a copy of the β = 1 walkers
    /// (their independence proposal copied too). A new chain of the
    /// joint target: run [`burn_in`] again before keeping draws.
    ///
    /// # Errors
    /// [`InverseError::InvalidSetting`] for `ratio` outside (0, 1) or a
    /// ladder already set.
    pub fn temper(&mut self, rungs: usize, ratio: f64) -> Result<()> {
        if !(ratio > 0.0 && ratio < 1.0) || self.betas.len() > 1 {
            return Err(InverseError::InvalidSetting(format!(
                "ensemble: rung ratio {ratio} must be in (0, 1), on an ensemble without rungs"
            )));
        }
        let w = self.settings.walkers;
        for r in 1..rungs {
            self.betas.push(ratio.powi(r as i32));
            self.pos.extend_from_within(..w);
            self.lp.extend_from_within(..w);
            if self.screening() {
                self.slp.extend_from_within(..w);
            }
            self.proposals.push(self.proposals[0].clone());
            self.recent.push(Vec::new());
        }
        Ok(())
    }

    /// Sets the probability of a ridge step (`EnsembleSettings::
    /// ridge_fraction`) for the steps to come.
    ///
    /// # Errors
    /// [`InverseError::InvalidSetting`] for a fraction outside [0, 1].
    pub fn set_ridge_fraction(&mut self, fraction: f64) -> Result<()> {
        if !(0.0..=1.0).contains(&fraction) {
            return Err(InverseError::InvalidSetting(format!(
                "ensemble: ridge fraction {fraction} must be in [0, 1]"
            )));
        }
        self.settings.ridge_fraction = fraction;
        Ok(())
    }

    /// Sets the burn-in steps of the next [`burn_in`] (e.g. of a tempered
    /// restart).
    pub fn set_burn(&mut self, burn: usize) {
        self.settings.burn = burn;
    }

    /// Number of rungs (1: untempered).
    pub fn rungs(&self) -> usize {
        self.betas.len()
    }

    /// Accepted / proposed swaps between adjacent rungs (0 without
    /// rungs).
    pub fn swap_acceptance(&self) -> f64 {
        self.swaps_accepted as f64 / self.swaps_proposed.max(1) as f64
    }

    /// The ensemble with the ridge move (module docs) used with
    /// probability `ridge_fraction`; the log-density must be a density on
    /// the unit coordinates of the ridge's axes.
    pub fn with_ridge(mut self, ridge: RidgeMove) -> Self {
        self.ridge = Some(ridge);
        self
    }

    /// The positions of every rung's walkers, index rung·W + walker.
    pub fn positions(&self) -> &[Vec<f64>] {
        &self.pos
    }

    /// Recomputes the screened log-densities at the walkers' positions
    /// after the screen of `log_density` changed (module docs, "Delayed
    /// acceptance": the screen must stay fixed while moves use it, so it
    /// may change only between calls, as the independence proposal's
    /// refits).
    pub fn rescreen(&mut self, log_density: &impl LogDensity) {
        self.slp = log_density
            .screen_log_densities(&self.pos)
            .unwrap_or_default();
    }

    /// Kept draws with nothing in them yet, for [`sample`].
    pub fn empty_chains(&self) -> Chains {
        Chains {
            dim: self.pos[0].len(),
            walkers: self.settings.walkers,
            steps: 0,
            samples: Vec::new(),
            log_density: Vec::new(),
            acceptance: 0.0,
        }
    }

    /// Refits each rung's independence proposal to that rung's positions
    /// over the last call of [`sample`] (for rung 0 its kept draws;
    /// module docs: finite adaptation between rounds). Keeps the old
    /// proposal when the draws' covariance is not positive definite or
    /// independence moves are off.
    pub fn refit_proposal(&mut self) {
        if self.settings.independence_fraction <= 0.0 {
            return;
        }
        for (q, points) in self.proposals.iter_mut().zip(&self.recent) {
            if let Some(fit) = Proposal::fit(points, 1.2) {
                *q = Some(fit);
            }
        }
    }

    /// Draws the move of the next step (`kept` allows the independence
    /// move): refresh, else ridge, else independence, else DE or stretch.
    fn choose_move(&mut self, kept: bool) {
        let s = &self.settings;
        let rng = &mut self.rng;
        self.current = if s.refresh_fraction > 0.0 && rng.random::<f64>() < s.refresh_fraction {
            Move::Refresh
        } else if self.ridge.is_some() && rng.random::<f64>() < s.ridge_fraction {
            Move::Ridge
        } else if self.proposals[0].is_some()
            && kept
            && rng.random::<f64>() < s.independence_fraction
        {
            Move::Independence
        } else if rng.random::<f64>() < s.de_fraction {
            let d = self.pos[0].len();
            let gamma = if self.step % 10 == 9 {
                1.0
            } else {
                2.38 / (2.0 * d as f64).sqrt()
            };
            Move::DifferentialEvolution { gamma }
        } else {
            Move::Stretch
        };
    }

    /// The walkers (indices into `pos`) of half `h` of rung `r` (0: the
    /// first ⌊W/2⌋, 1: the rest) and of the complementary half.
    fn halves(&self, r: usize, h: usize) -> (std::ops::Range<usize>, std::ops::Range<usize>) {
        let w = self.settings.walkers;
        let (o, mid) = (r * w, r * w + w / 2);
        if h == 0 {
            (o..mid, mid..o + w)
        } else {
            (mid..o + w, o..mid)
        }
    }

    /// Proposals of the current move for the walkers of half `h` of every
    /// rung, their points appended to `ys`. Stretch and DE draw their
    /// partners from the complementary half of the same rung only (the
    /// split form, module docs).
    fn propose(&mut self, h: usize, ys: &mut Vec<Vec<f64>>) -> Vec<Pending> {
        let mut out = Vec::new();
        for r in 0..self.betas.len() {
            self.propose_rung(r, h, ys, &mut out);
        }
        out
    }

    /// [`Ensemble::propose`] for rung `r`.
    fn propose_rung(&mut self, r: usize, h: usize, ys: &mut Vec<Vec<f64>>, out: &mut Vec<Pending>) {
        let (own, rest) = self.halves(r, h);
        let d = self.pos[0].len();
        let a = self.settings.stretch;
        let rng = &mut self.rng;
        for k in own {
            let x = &self.pos[k];
            if r == 0 {
                self.proposed += 1;
            }
            let (y, log_ratio) = match self.current {
                Move::Refresh => {
                    let c = rng.random_range(0..d);
                    let mut y = x.clone();
                    y[c] = rng.random::<f64>();
                    (y, 0.0)
                }
                Move::Ridge => {
                    let Some(ridge) = self.ridge.as_ref() else {
                        continue;
                    };
                    let v: f64 = rng.random();
                    let proposed = match ridge.time_move {
                        RidgeTime::Kept => ridge.propose(x, v, None),
                        RidgeTime::Redrawn => {
                            let time = (rng.random::<f64>() < 0.5).then(|| rng.random::<f64>());
                            ridge.propose(x, v, time)
                        }
                        RidgeTime::Viscous if rng.random::<f64>() < 0.5 => {
                            ridge.propose_viscous(x, v)
                        }
                        RidgeTime::Viscous => ridge.propose(x, v, None),
                    };
                    match proposed {
                        Some(p) => p,
                        None => {
                            // Rejected; the acceptance uniform is drawn as for any walker.
                            let _: f64 = rng.random();
                            continue;
                        }
                    }
                }
                Move::Independence => {
                    let Some(q) = self.proposals[r].as_ref() else {
                        continue;
                    };
                    let (y, lqy) = q.draw(rng);
                    let lqx = q.log_density(x);
                    (y, lqx - lqy)
                }
                Move::DifferentialEvolution { gamma } => {
                    let i = other(rng, rest.clone(), None);
                    let j = other(rng, rest.clone(), Some(i));
                    let (xi, xj) = (&self.pos[i], &self.pos[j]);
                    let y = (0..d)
                        .map(|c| x[c] + gamma * (xi[c] - xj[c]) + 1e-10 * normal(rng))
                        .collect();
                    (y, 0.0)
                }
                Move::Stretch => {
                    let j = other(rng, rest.clone(), None);
                    let u: f64 = rng.random();
                    let z = ((a - 1.0) * u + 1.0).powi(2) / a;
                    let xj = &self.pos[j];
                    let y = (0..d).map(|c| xj[c] + z * (x[c] - xj[c])).collect();
                    (y, (d as f64 - 1.0) * z.ln())
                }
            };
            let u: f64 = rng.random();
            ys.push(y);
            out.push(Pending {
                walker: k,
                log_ratio,
                ln_u: u.ln(),
            });
        }
    }

    /// ln α₁ = min(0, ln ρ + β(ln p̃(y) − ln p̃(x))), the first stage's
    /// acceptance probability, of proposal `p` with screened log-density
    /// `sy` at its point (module docs, "Delayed acceptance").
    fn screen_log_alpha(&self, p: &Pending, sy: f64) -> f64 {
        let beta = self.betas[p.walker / self.settings.walkers];
        (p.log_ratio + beta * (sy - self.slp[p.walker])).min(0.0)
    }

    /// True when proposal `p` passes the screen: its point's full
    /// log-density is needed.
    fn passes_screen(&self, p: &Pending, sy: f64) -> bool {
        sy.is_finite() && p.ln_u < self.screen_log_alpha(p, sy)
    }

    /// True when the ensemble holds screened log-densities of its walkers
    /// (made, or [`Ensemble::rescreen`]ed, with a density that has a
    /// screen); an ensemble without them takes the one-stage test even
    /// when the density offers a screen.
    fn screening(&self) -> bool {
        !self.slp.is_empty()
    }

    /// Accepts or rejects the proposals `pending` at points `ys` with
    /// log-densities `lps` (Metropolis–Hastings on each walker's rung's
    /// target p^β: the density ratio raised to β, the proposal's own
    /// ratio not). With screened log-densities `slps`, delayed acceptance
    /// (module docs): accepted when ln u < ln α₁ + ln α₂, the same uniform
    /// as the screen's, so a proposal the screen rejected (its `lps` entry
    /// −∞) stays rejected.
    fn accept(
        &mut self,
        pending: &[Pending],
        ys: Vec<Vec<f64>>,
        lps: &[f64],
        slps: Option<&[f64]>,
    ) {
        let w = self.settings.walkers;
        for (i, ((p, y), &lpy)) in pending.iter().zip(ys).zip(lps).enumerate() {
            let beta = self.betas[p.walker / w];
            let lpx = self.lp[p.walker];
            let accepted = lpy.is_finite()
                && match slps {
                    // β·lpy − β·lpx: with β = 1 the same operations as untempered.
                    None => p.ln_u < p.log_ratio + beta * lpy - beta * lpx,
                    Some(s) => {
                        let (sy, sx) = (s[i], self.slp[p.walker]);
                        let ln_alpha2 = (beta * ((lpy - lpx) - (sy - sx))).min(0.0);
                        p.ln_u < self.screen_log_alpha(p, sy) + ln_alpha2
                    }
                };
            if accepted {
                self.pos[p.walker] = y;
                self.lp[p.walker] = lpy;
                if let Some(s) = slps {
                    self.slp[p.walker] = s[i];
                }
                if p.walker < w {
                    self.accepted += 1;
                }
            }
        }
    }

    /// Swaps between adjacent rungs (module docs, "Tempering"), from the
    /// hottest pair down: walker k of rung r and walker π(k) of rung r + 1
    /// (π a random permutation) exchange positions with probability
    /// min(1, exp((β_r − β_{r+1})(ln p(x_{r+1}) − ln p(x_r)))), the
    /// Metropolis ratio of the swap under Π_r p^{β_r} (Earl & Deem 2005,
    /// eq. 3). No random numbers are drawn without rungs.
    fn swap_rungs(&mut self) {
        let w = self.settings.walkers;
        for r in (0..self.betas.len().saturating_sub(1)).rev() {
            let d_beta = self.betas[r] - self.betas[r + 1];
            let mut perm: Vec<usize> = (0..w).collect();
            for i in (1..w).rev() {
                perm.swap(i, self.rng.random_range(0..=i));
            }
            for (k, &j) in perm.iter().enumerate() {
                let (cold, hot) = (r * w + k, (r + 1) * w + j);
                let ln_u = self.rng.random::<f64>().ln();
                self.swaps_proposed += 1;
                if ln_u < d_beta * (self.lp[hot] - self.lp[cold]) {
                    self.pos.swap(cold, hot);
                    self.lp.swap(cold, hot);
                    if self.screening() {
                        self.slp.swap(cold, hot);
                    }
                    self.swaps_accepted += 1;
                }
            }
        }
    }
}

/// One step of every ensemble in `ensembles`: each draws its move, then
/// each half of every ensemble's walkers is proposed and the proposals of
/// all ensembles are evaluated in one batch (two calls of `log_density`
/// per step). A move whose proposal depends only on the walker's own
/// position (refresh, ridge, independence) proposes both halves in the
/// first batch: the positions it reads do not change in between, so the
/// draws are the same, and larger batches cost less per point.
/// Then each ensemble's rungs swap ([`Ensemble::swap_rungs`]). `kept`
/// allows the independence move.
fn step_all(ensembles: &mut [Ensemble], log_density: &impl LogDensity, kept: bool) {
    for e in ensembles.iter_mut() {
        e.choose_move(kept);
    }
    for h in 0..2 {
        let mut ys = Vec::new();
        let mut batches = Vec::with_capacity(ensembles.len());
        for e in ensembles.iter_mut() {
            let own_only = !matches!(
                e.current,
                Move::Stretch | Move::DifferentialEvolution { .. }
            );
            let from = ys.len();
            let pending = match (h, own_only) {
                (0, true) => {
                    let mut p = e.propose(0, &mut ys);
                    p.extend(e.propose(1, &mut ys));
                    p
                }
                (_, true) => Vec::new(),
                _ => e.propose(h, &mut ys),
            };
            batches.push((from, pending));
        }
        let screens = log_density.screen_log_densities(&ys);
        let lps = match &screens {
            None => log_density.log_densities(&ys),
            Some(s) => {
                // Delayed acceptance: only the proposals that pass the
                // screen are evaluated, in one batch.
                let mut passed = Vec::new();
                for (e, (from, pending)) in ensembles.iter().zip(&batches) {
                    passed.extend(
                        pending
                            .iter()
                            .enumerate()
                            .filter(|(i, p)| !e.screening() || e.passes_screen(p, s[from + i]))
                            .map(|(i, _)| from + i),
                    );
                }
                let points: Vec<Vec<f64>> = passed.iter().map(|&i| ys[i].clone()).collect();
                let mut lps = vec![f64::NEG_INFINITY; ys.len()];
                for (&i, v) in passed.iter().zip(log_density.log_densities(&points)) {
                    lps[i] = v;
                }
                lps
            }
        };
        let mut ys = ys.into_iter();
        for (e, (from, pending)) in ensembles.iter_mut().zip(batches) {
            let n = pending.len();
            let mine: Vec<Vec<f64>> = ys.by_ref().take(n).collect();
            let slps = screens
                .as_ref()
                .filter(|_| e.screening())
                .map(|s| &s[from..from + n]);
            e.accept(&pending, mine, &lps[from..from + n], slps);
        }
    }
    for e in ensembles.iter_mut() {
        e.swap_rungs();
        e.step += 1;
    }
}

/// `burn` steps (the first ensemble's setting) of every ensemble,
/// stepped together (without the independence move); at their end stray
/// walkers of each rung are moved onto that rung's bulk
/// ([`prune_strays`]) and each rung's independence proposal is fitted to
/// its second half of burn-in.
pub fn burn_in(ensembles: &mut [Ensemble], log_density: &impl LogDensity) {
    let Some(burn) = ensembles.first().map(|e| e.settings.burn) else {
        return;
    };
    for e in ensembles.iter_mut() {
        e.recent.iter_mut().for_each(Vec::clear);
    }
    for s in 0..burn {
        if s >= burn / 2 {
            ensembles.iter_mut().for_each(Ensemble::record_recent);
        }
        step_all(ensembles, log_density, false);
    }
    for e in ensembles.iter_mut() {
        let (w, d) = (e.settings.walkers, e.pos[0].len());
        for r in 0..e.betas.len() {
            let at = r * w..(r + 1) * w;
            if burn > 0 {
                for (k, j) in prune_strays(&e.lp[at.clone()], d, e.betas[r], &mut e.rng) {
                    let (k, j) = (at.start + k, at.start + j);
                    e.pos[k] = e.pos[j].clone();
                    e.lp[k] = e.lp[j];
                    if e.screening() {
                        e.slp[k] = e.slp[j];
                    }
                }
            }
        }
        e.record_recent();
    }
    if pooled(ensembles) {
        refit_proposals(ensembles);
    } else {
        for e in ensembles.iter_mut() {
            if e.settings.independence_fraction > 0.0 {
                e.proposals = e.recent.iter().map(|p| Proposal::fit(p, 1.2)).collect();
            }
        }
    }
    for e in ensembles.iter_mut() {
        e.recent.iter_mut().for_each(Vec::clear);
    }
}

/// True when `ensembles` fit one pooled independence proposal per rung
/// (`EnsembleSettings::pool_proposals`, independence moves on).
fn pooled(ensembles: &[Ensemble]) -> bool {
    ensembles
        .first()
        .is_some_and(|e| e.settings.pool_proposals && e.settings.independence_fraction > 0.0)
}

/// Refits the independence proposals of ensembles stepped together to
/// their positions over the last call of [`sample`]: each ensemble's own
/// ([`Ensemble::refit_proposal`]), or with `pool_proposals` one proposal
/// per rung fitted to that rung's positions in every ensemble and given
/// to all (module docs, "Pooled proposals"). A fit that fails keeps the
/// old proposals.
pub fn refit_proposals(ensembles: &mut [Ensemble]) {
    if !pooled(ensembles) {
        ensembles.iter_mut().for_each(Ensemble::refit_proposal);
        return;
    }
    for r in 0..ensembles[0].betas.len() {
        let points: Vec<Vec<f64>> = ensembles
            .iter()
            .flat_map(|e| e.recent[r].iter().cloned())
            .collect();
        if let Some(q) = Proposal::fit(&points, 1.2) {
            for e in ensembles.iter_mut() {
                e.proposals[r] = Some(q.clone());
            }
        }
    }
}

/// Tempers ensembles stepped together ([`Ensemble::temper`]) with their
/// hot rungs started from draws of an independence proposal instead of
/// copies of the β = 1 walkers (module docs, "Tempering"): rung r's
/// walkers are drawn from [`Proposal::fit`] of the β = 1 positions over
/// the current round (pooled over the ensembles with `pool_proposals`,
/// else each ensemble's own; its current walkers when the round is
/// empty) with the scale 1.2/√β_r — a Gaussian posterior's spread at
/// inverse temperature β — and that proposal becomes the rung's
/// independence proposal. A draw outside the support is redrawn (at most
/// `HOT_TRIES` times, then the copy stays). Each ensemble draws with its
/// own random stream. A new chain of the joint target from other
/// starting positions: run [`burn_in`] before keeping draws.
///
/// Cost: the draws' log-densities, at most `HOT_TRIES` batches of the
/// hot rungs' walkers per ensemble (points outside the unit box are −∞
/// without a likelihood evaluation in the posterior's density).
///
/// Returns the number of points drawn (log-densities asked for).
///
/// # Errors
/// As [`Ensemble::temper`].
pub fn temper_from_proposal(
    ensembles: &mut [Ensemble],
    log_density: &impl LogDensity,
    rungs: usize,
    ratio: f64,
) -> Result<usize> {
    const HOT_TRIES: usize = 20;
    let pool = pooled(ensembles);
    let points_of = |e: &Ensemble| -> Vec<Vec<f64>> {
        if e.recent[0].is_empty() {
            e.pos[..e.settings.walkers].to_vec()
        } else {
            e.recent[0].clone()
        }
    };
    let pooled_points: Vec<Vec<f64>> = if pool {
        ensembles.iter().flat_map(points_of).collect()
    } else {
        Vec::new()
    };
    let mut drawn = 0;
    for e in ensembles.iter_mut() {
        e.temper(rungs, ratio)?;
        let own;
        let points = if pool {
            &pooled_points
        } else {
            own = points_of(e);
            &own
        };
        let w = e.settings.walkers;
        for r in 1..e.betas.len() {
            let Some(q) = Proposal::fit(points, 1.2 / e.betas[r].sqrt()) else {
                continue;
            };
            let mut todo: Vec<usize> = (0..w).collect();
            for _ in 0..HOT_TRIES {
                if todo.is_empty() {
                    break;
                }
                let ys: Vec<Vec<f64>> = todo.iter().map(|_| q.draw(&mut e.rng).0).collect();
                drawn += ys.len();
                let lp = log_density.log_densities(&ys);
                let ok: Vec<usize> = (0..ys.len()).filter(|&i| lp[i].is_finite()).collect();
                let slp = if e.screening() {
                    let good: Vec<Vec<f64>> = ok.iter().map(|&i| ys[i].clone()).collect();
                    log_density.screen_log_densities(&good).unwrap_or_default()
                } else {
                    Vec::new()
                };
                for (j, &i) in ok.iter().enumerate() {
                    if e.screening() && !slp.get(j).is_some_and(|v| v.is_finite()) {
                        continue;
                    }
                    let k = r * w + todo[i];
                    e.pos[k].clone_from(&ys[i]);
                    e.lp[k] = lp[i];
                    if e.screening() {
                        e.slp[k] = slp[j];
                    }
                    todo[i] = usize::MAX;
                }
                todo.retain(|&k| k != usize::MAX);
            }
            e.proposals[r] = Some(q);
        }
    }
    Ok(drawn)
}

/// `steps` more steps of every ensemble, stepped together, appended to
/// `out` (one [`Ensemble::empty_chains`] per ensemble, same order; the
/// β = 1 rung only). Starts a round: the points the next
/// [`Ensemble::refit_proposal`] fits are these steps' only.
pub fn sample(
    ensembles: &mut [Ensemble],
    log_density: &impl LogDensity,
    steps: usize,
    out: &mut [Chains],
) {
    for e in ensembles.iter_mut() {
        e.recent.iter_mut().for_each(Vec::clear);
    }
    sample_more(ensembles, log_density, steps, out);
}

/// [`sample`] continuing the current round: its steps join the points of
/// the next refit, so a round sampled in parts gives the same chains as in
/// one call (the stopping rule's checks within a round, [`super`] docs).
pub fn sample_more(
    ensembles: &mut [Ensemble],
    log_density: &impl LogDensity,
    steps: usize,
    out: &mut [Chains],
) {
    for _ in 0..steps {
        step_all(ensembles, log_density, true);
        for (e, c) in ensembles.iter_mut().zip(out.iter_mut()) {
            for k in 0..e.settings.walkers {
                c.samples.extend_from_slice(&e.pos[k]);
                c.log_density.push(e.lp[k]);
            }
            e.record_recent();
        }
    }
    for (e, c) in ensembles.iter().zip(out.iter_mut()) {
        c.steps += steps;
        c.acceptance = e.accepted as f64 / e.proposed.max(1) as f64;
    }
}

impl Ensemble {
    /// Appends every rung's current positions to its `recent` points
    /// (nothing when independence moves are off: no proposal to fit).
    fn record_recent(&mut self) {
        if self.settings.independence_fraction <= 0.0 {
            return;
        }
        let w = self.settings.walkers;
        for (r, points) in self.recent.iter_mut().enumerate() {
            points.extend(self.pos[r * w..(r + 1) * w].iter().cloned());
        }
    }
}

/// At the end of burn-in, walkers stranded far below the bulk (β·ln p
/// more than d/2 + 6√(d/2) + 10 below the median of the rung's target
/// p^β, far beyond the spread of ln p of a d-dimensional Gaussian, ½χ²_d)
/// are moved onto randomly chosen walkers of the bulk: a stray walker
/// would otherwise take thousands of steps to return and dominate R̂
/// (emcee FAQ, "walkers stuck"). Burn-in only, so the kept chain is
/// unaffected in law. Returns (stray, bulk walker it takes the place of)
/// for the rung's walkers with log-densities `lp`.
fn prune_strays(lp: &[f64], d: usize, beta: f64, rng: &mut ChaCha8Rng) -> Vec<(usize, usize)> {
    let mut sorted: Vec<f64> = lp.to_vec();
    sorted.sort_by(f64::total_cmp);
    let median = sorted[sorted.len() / 2];
    let half = d as f64 / 2.0;
    let cut = median - (half + 6.0 * half.sqrt() + 10.0) / beta;
    let good: Vec<usize> = (0..lp.len()).filter(|&k| lp[k] >= cut).collect();
    if good.is_empty() {
        return Vec::new();
    }
    (0..lp.len())
        .filter(|&k| lp[k] < cut)
        .map(|k| (k, good[rng.random_range(0..good.len())]))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Mean and variance (1/n) of coordinate `i` over every kept draw.
    fn moments(ch: &Chains, i: usize) -> (f64, f64) {
        let n = ch.steps * ch.walkers;
        let dim = ch.samples.len() / n;
        let xs = || ch.samples.iter().skip(i).step_by(dim);
        let mean = xs().sum::<f64>() / n as f64;
        let var = xs().map(|v| (v - mean).powi(2)).sum::<f64>() / n as f64;
        (mean, var)
    }

    /// A 3-D Gaussian with correlation 0.9 between the first two axes and
    /// very different scales: mean and covariance of the draws match the
    /// closed form within a few Monte-Carlo standard errors.
    #[test]
    fn draws_match_a_correlated_gaussian() {
        let (init, s) = correlated_gaussian_run();
        let ch = sample_ensemble(correlated_gaussian, &init, &s).expect("run");
        assert_correlated_gaussian(&ch);
        assert!(
            ch.acceptance > 0.2 && ch.acceptance < 0.9,
            "acceptance {}",
            ch.acceptance
        );
    }

    /// Per-axis sd of [`correlated_gaussian`].
    const GAUSS_SD: [f64; 3] = [1.0, 100.0, 0.01];
    /// Correlation of its first two axes.
    const GAUSS_RHO: f64 = 0.9;

    /// A 3-D Gaussian with sd [`GAUSS_SD`] and correlation [`GAUSS_RHO`]
    /// between the first two axes.
    fn correlated_gaussian(x: &[f64]) -> f64 {
        let (sd, rho) = (GAUSS_SD, GAUSS_RHO);
        let (a, b, c) = (x[0] / sd[0], x[1] / sd[1], x[2] / sd[2]);
        -0.5 * ((a * a - 2.0 * rho * a * b + b * b) / (1.0 - rho * rho) + c * c)
    }

    /// Starts (24 walkers near the mode) and settings (500 burn-in, 3000
    /// kept steps) of the runs on [`correlated_gaussian`].
    fn correlated_gaussian_run() -> (Vec<Vec<f64>>, EnsembleSettings) {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let init = (0..24)
            .map(|_| {
                (0..3)
                    .map(|i| GAUSS_SD[i] * 0.1 * normal(&mut rng))
                    .collect()
            })
            .collect();
        let s = EnsembleSettings {
            walkers: 24,
            burn: 500,
            steps: 3000,
            seed: 9,
            ..EnsembleSettings::default()
        };
        (init, s)
    }

    /// Mean and covariance of the draws of [`correlated_gaussian`] match
    /// the closed form within a few Monte-Carlo standard errors (24
    /// walkers × 3000 steps: ESS ≈ 72000/τ with τ ≲ 30, so the standard
    /// error of a mean is ≲ sd/40).
    fn assert_correlated_gaussian(ch: &Chains) {
        let (sd, rho) = (GAUSS_SD, GAUSS_RHO);
        let n = (ch.steps * ch.walkers) as f64;
        let mean = |i: usize| ch.samples.iter().skip(i).step_by(3).sum::<f64>() / n;
        let cov = |i: usize, j: usize| {
            let (mi, mj) = (mean(i), mean(j));
            (0..ch.steps * ch.walkers)
                .map(|k| (ch.samples[k * 3 + i] - mi) * (ch.samples[k * 3 + j] - mj))
                .sum::<f64>()
                / n
        };
        for i in 0..3 {
            assert!(mean(i).abs() < 0.1 * sd[i], "mean {i} = {}", mean(i));
            let v = cov(i, i) / (sd[i] * sd[i]);
            assert!((v - 1.0).abs() < 0.12, "var {i} ratio {v}");
        }
        let r = cov(0, 1) / (cov(0, 0) * cov(1, 1)).sqrt();
        assert!((r - rho).abs() < 0.03, "correlation {r}");
    }

    /// Two Gaussian modes in 2-D, weights 0.25 at x = −5 and 0.75 at
    /// x = 5, sd ½ in each axis, separated by ≈ 20 sd.
    fn two_modes(x: &[f64]) -> f64 {
        let mode = |c: f64, w: f64| w.ln() - 2.0 * ((x[0] - c).powi(2) + x[1] * x[1]);
        let (a, b) = (mode(-5.0, 0.25), mode(5.0, 0.75));
        a.max(b) + (-(a - b).abs()).exp().ln_1p()
    }

    /// Starts (16 walkers all in the left mode) and settings of the runs
    /// on [`two_modes`].
    fn two_modes_run() -> (Vec<Vec<f64>>, EnsembleSettings) {
        let init = (0..16)
            .map(|k| vec![-5.0 + 0.05 * k as f64, 0.1 - 0.01 * k as f64])
            .collect();
        let s = EnsembleSettings {
            walkers: 16,
            burn: 200,
            steps: 500,
            seed: 13,
            ..EnsembleSettings::default()
        };
        (init, s)
    }

    /// Two ensembles on [`two_modes`] with settings `s` (the second with
    /// seed 14), started at `a` and `b`.
    fn two_ensembles(a: &[Vec<f64>], b: &[Vec<f64>], s: EnsembleSettings) -> [Ensemble; 2] {
        let s2 = EnsembleSettings { seed: 14, ..s };
        [
            Ensemble::new(&two_modes, a, &s).expect("first"),
            Ensemble::new(&two_modes, b, &s2).expect("second"),
        ]
    }

    /// Pooled proposals carry walkers between modes that separate
    /// ensembles were started in: on [`two_modes`], one ensemble started in
    /// each mode, no tempering, eight rounds with refits. Pooled, each
    /// ensemble's draws have the mixture's moments; each fitted to its own
    /// draws, every ensemble stays in the mode it started in (measured:
    /// P(x > 0) = 0 and 1).
    #[test]
    fn pooled_proposals_carry_walkers_between_modes() {
        let logp = two_modes;
        let (left, s) = two_modes_run();
        let right: Vec<Vec<f64>> = left.iter().map(|p| vec![-p[0], p[1]]).collect();
        let run = |pool: bool| {
            let s = EnsembleSettings {
                pool_proposals: pool,
                ..s
            };
            let mut e = two_ensembles(&left, &right, s);
            burn_in(&mut e, &logp);
            let mut ch = [e[0].empty_chains(), e[1].empty_chains()];
            for _ in 0..8 {
                sample(&mut e, &logp, 500, &mut ch);
                refit_proposals(&mut e);
            }
            ch
        };
        for ch in &run(true) {
            assert_two_modes(ch);
        }
        let right_share = |ch: &Chains| {
            ch.samples.iter().step_by(2).filter(|&&v| v > 0.0).count() as f64
                / (ch.steps * ch.walkers) as f64
        };
        let alone = run(false);
        assert_eq!((right_share(&alone[0]), right_share(&alone[1])), (0.0, 1.0));
    }

    /// The draws of [`two_modes`] put 75 % of the mass at x > 0, with
    /// E[x] = 2.5, Var[x] = 19, E[y] = 0, Var[y] = ¼.
    fn assert_two_modes(ch: &Chains) {
        let right = ch.samples.iter().step_by(2).filter(|&&v| v > 0.0).count() as f64
            / (ch.steps * ch.walkers) as f64;
        let (mean, var) = (|i| moments(ch, i).0, |i| moments(ch, i).1);
        assert!((right - 0.75).abs() < 0.03, "P(x > 0) {right}");
        assert!((mean(0) - 2.5).abs() < 0.3, "E[x] {}", mean(0));
        assert!((var(0) - 19.0).abs() < 1.2, "Var[x] {}", var(0));
        assert!(mean(1).abs() < 0.02, "E[y] {}", mean(1));
        assert!((var(1) - 0.25).abs() < 0.02, "Var[y] {}", var(1));
    }

    /// A log-density with a screen for delayed acceptance, counting the
    /// points whose full log-density is computed.
    struct Screened<F, G> {
        exact: F,
        screen: G,
        evaluated: std::cell::Cell<usize>,
    }

    impl<F: Fn(&[f64]) -> f64, G: Fn(&[f64]) -> f64> Screened<F, G> {
        fn new(exact: F, screen: G) -> Self {
            Self {
                exact,
                screen,
                evaluated: std::cell::Cell::new(0),
            }
        }
    }

    impl<F: Fn(&[f64]) -> f64, G: Fn(&[f64]) -> f64> LogDensity for Screened<F, G> {
        fn log_densities(&self, xs: &[Vec<f64>]) -> Vec<f64> {
            self.evaluated.set(self.evaluated.get() + xs.len());
            xs.iter().map(|x| (self.exact)(x)).collect()
        }

        fn screen_log_densities(&self, xs: &[Vec<f64>]) -> Option<Vec<f64>> {
            Some(xs.iter().map(|x| (self.screen)(x)).collect())
        }
    }

    /// Delayed acceptance with the density itself as screen is the
    /// one-stage sampler draw for draw (same uniforms, α₂ = 1), with every
    /// move, the independence proposal's refits and tempering; only the
    /// proposals that pass the screen are evaluated (here: the accepted
    /// ones).
    #[test]
    fn delayed_acceptance_with_an_exact_screen_is_the_one_stage_chain() {
        let logp = |x: &[f64]| -0.5 * (x[0] * x[0] + 4.0 * (x[1] - 0.3 * x[0]).powi(2));
        let init: Vec<Vec<f64>> = (0..12)
            .map(|k| vec![0.1 * k as f64 - 0.5, 0.05 * (k % 5) as f64])
            .collect();
        let s = EnsembleSettings {
            walkers: 12,
            burn: 100,
            steps: 200,
            seed: 21,
            ..EnsembleSettings::default()
        };
        let run = |density: &dyn Fn(&mut [Ensemble], &mut [Chains])| {
            let mut e = [Ensemble::new(&logp, &init, &s).expect("ensemble")];
            let mut ch = [e[0].empty_chains()];
            density(&mut e, &mut ch);
            let [ch] = ch;
            ch
        };
        let plain = run(&|e, ch| {
            burn_in(e, &logp);
            sample(e, &logp, 200, ch);
            e[0].refit_proposal();
            e[0].temper(3, 0.5).expect("ladder");
            sample(e, &logp, 200, ch);
        });
        let screened = Screened::new(logp, logp);
        let delayed = run(&|e, ch| {
            // The ensemble made with the plain density has no screened
            // values; start it again with the screened one.
            e[0] = Ensemble::new(&screened, &init, &s).expect("ensemble");
            burn_in(e, &screened);
            sample(e, &screened, 200, ch);
            e[0].refit_proposal();
            e[0].temper(3, 0.5).expect("ladder");
            sample(e, &screened, 200, ch);
        });
        assert_eq!(plain.samples, delayed.samples);
        assert_eq!(plain.acceptance, delayed.acceptance);
        // Untempered, every proposal that passes an exact screen is
        // accepted: the full log-density is computed for exactly those.
        let screened = Screened::new(logp, logp);
        let mut e = [Ensemble::new(&screened, &init, &s).expect("ensemble")];
        let mut ch = [e[0].empty_chains()];
        burn_in(&mut e, &screened);
        sample(&mut e, &screened, 200, &mut ch);
        let proposals = 12 * (100 + 200);
        let evaluated = screened.evaluated.get() - 12;
        let accepted = (ch[0].acceptance * proposals as f64).round() as usize;
        assert_eq!(evaluated, accepted, "of {proposals} proposals");
        assert!(evaluated < proposals * 3 / 4, "{evaluated} of {proposals}");
    }

    /// Delayed acceptance with a poor screen (a Gaussian with the wrong
    /// mean, scales and no correlation) still samples the correlated
    /// Gaussian of `draws_match_a_correlated_gaussian`, within the same
    /// Monte-Carlo tolerances, and with tempering the two-mode mixture of
    /// `tempering_keeps_a_two_mode_mixture` (screen: one broad mode in the
    /// middle).
    #[test]
    fn delayed_acceptance_with_a_poor_screen_keeps_the_target() {
        let sd = GAUSS_SD;
        let screen = |x: &[f64]| {
            let (a, b, c) = (
                (x[0] - 0.5 * sd[0]) / (2.0 * sd[0]),
                (x[1] + 0.3 * sd[1]) / (0.7 * sd[1]),
                x[2] / (1.5 * sd[2]),
            );
            -0.5 * (a * a + b * b + c * c)
        };
        let density = Screened::new(correlated_gaussian, screen);
        let (init, s) = correlated_gaussian_run();
        let mut e = [Ensemble::new(&density, &init, &s).expect("ensemble")];
        burn_in(&mut e, &density);
        let mut ch = [e[0].empty_chains()];
        sample(&mut e, &density, s.steps, &mut ch);
        let [ch] = ch;
        assert_correlated_gaussian(&ch);
        let proposals = 24 * (500 + 3000);
        assert!(density.evaluated.get() - 24 < proposals);

        let broad = |x: &[f64]| -0.5 * (x[0] * x[0] / 36.0 + x[1] * x[1]);
        let density = Screened::new(two_modes, broad);
        let (init, s) = two_modes_run();
        let mut e = [Ensemble::new(&density, &init, &s).expect("ensemble")];
        e[0].temper(5, 0.4).expect("ladder");
        burn_in(&mut e, &density);
        let mut ch = [e[0].empty_chains()];
        for _ in 0..8 {
            sample(&mut e, &density, 500, &mut ch);
            e[0].refit_proposal();
        }
        let [ch] = ch;
        assert_two_modes(&ch);
    }

    /// A uniform density on the triangle x, y ≥ 0, x + y ≤ 1 (the shape of
    /// the g1 + g2 < 1 prior): E[x] = 1/3, Var[x] = 1/18.
    #[test]
    fn a_uniform_triangle_is_sampled_uniformly() {
        let logp = |x: &[f64]| {
            if x[0] >= 0.0 && x[1] >= 0.0 && x[0] + x[1] <= 1.0 {
                0.0
            } else {
                f64::NEG_INFINITY
            }
        };
        let init: Vec<Vec<f64>> = (0..16)
            .map(|k| vec![0.05 + 0.02 * k as f64, 0.05 + 0.03 * (k % 5) as f64])
            .collect();
        let s = EnsembleSettings {
            walkers: 16,
            burn: 300,
            steps: 4000,
            seed: 3,
            ..EnsembleSettings::default()
        };
        let ch = sample_ensemble(logp, &init, &s).expect("run");
        let (m, v) = moments(&ch, 0);
        assert!((m - 1.0 / 3.0).abs() < 0.01, "mean {m}");
        assert!((v - 1.0 / 18.0).abs() < 0.004, "var {v}");
    }

    /// The axis refresh and refits of the independence proposal between
    /// rounds keep the target: a funnel in the unit box (as τ2 given a
    /// small g2), x uniform on (0, 1] and y | x = x·b with b ~ Beta(2, 5),
    /// p(x, y) = (1/x)·30 (y/x)(1 − y/x)⁴ on 0 < y < x. Closed forms:
    /// E[x] = 1/2, Var[x] = 1/12, E[y] = 1/7, Var[y] = E[x²]E[b²] −
    /// (E[x]E[b])² = (1/3)(3/28) − 1/49 = 3/196. Run in 8 rounds with a
    /// refit after each.
    #[test]
    fn refresh_and_refits_keep_a_funnel_in_the_unit_box() {
        let logp = |x: &[f64]| {
            let (a, y) = (x[0], x[1]);
            if a > 0.0 && a <= 1.0 && y > 0.0 && y < a {
                let b = y / a;
                -a.ln() + b.ln() + 4.0 * (1.0 - b).ln()
            } else {
                f64::NEG_INFINITY
            }
        };
        let init: Vec<Vec<f64>> = (0..16)
            .map(|k| vec![0.4 + 0.01 * k as f64, 0.1 + 0.005 * k as f64])
            .collect();
        let s = EnsembleSettings {
            walkers: 16,
            burn: 200,
            steps: 500,
            refresh_fraction: 0.2,
            seed: 11,
            ..EnsembleSettings::default()
        };
        let mut e = [Ensemble::new(&logp, &init, &s).expect("ensemble")];
        burn_in(&mut e, &logp);
        let mut ch = [e[0].empty_chains()];
        for _ in 0..8 {
            sample(&mut e, &logp, 500, &mut ch);
            e[0].refit_proposal();
        }
        let [ch] = ch;
        let mean = |i: usize| moments(&ch, i).0;
        let var = |i: usize| moments(&ch, i).1;
        assert!((mean(0) - 0.5).abs() < 0.02, "E[x] {}", mean(0));
        assert!((var(0) - 1.0 / 12.0).abs() < 0.006, "Var[x] {}", var(0));
        assert!((mean(1) - 1.0 / 7.0).abs() < 0.01, "E[y] {}", mean(1));
        assert!((var(1) - 3.0 / 196.0).abs() < 0.0015, "Var[y] {}", var(1));
    }

    /// The ridge of a Prony domain: G0 on a log axis [1, 10], g1 and g2
    /// linear on [0, 1] (u = g).
    fn ridge_3d() -> RidgeMove {
        use nlvid_model::{Parameter, Scale};
        RidgeMove {
            scale: (0, Parameter::new("G0", "Pa", 1.0, 10.0, Scale::Log)),
            fast: (1, Parameter::new("g1", "1", 0.0, 1.0, Scale::Linear)),
            carried: vec![(2, Parameter::new("g2", "1", 0.0, 1.0, Scale::Linear))],
            fast_time: Some((3, Parameter::new("tau1", "s", 0.01, 2.0, Scale::Log))),
            time_move: RidgeTime::Kept,
        }
    }

    /// The viscous map keeps G0·(1 − g1), G0·g1·τ1 and G0·g2, is an
    /// involution (τ1's u and the auxiliary v swap), and its ln |J| is the
    /// log-determinant of ∂(u_G0', u_g1', u_g2')/∂(u_G0, u_g1, u_g2) by
    /// central differences (the swapped pair adds |det| 1).
    #[test]
    fn viscous_map_is_an_involution_with_its_jacobian() {
        let m = ridge_3d();
        let tau = &m.fast_time.as_ref().expect("time").1;
        let x = [0.3, 0.4, 0.2, 0.6];
        let v = 0.35;
        let (y, lj) = m.propose_viscous(&x, v).expect("move");
        let phys = |u: &[f64]| (10f64.powf(u[0]), u[1], u[2], tau.from_unit(u[3]));
        let (g, g1, g2, t) = phys(&x);
        let (h, h1, h2, s) = phys(&y);
        assert!(s < t, "a shorter τ1: {s} vs {t}");
        let close = |a: f64, b: f64| (a - b).abs() < 1e-12 * a.abs().max(1.0);
        assert!(close(g * (1.0 - g1), h * (1.0 - h1)), "G0 (1 − g1)");
        assert!(close(g * g1 * t, h * h1 * s), "G0 g1 τ1");
        assert!(close(g * g2, h * h2), "G0 g2");
        let (back, lj_back) = m.propose_viscous(&y, x[3]).expect("back");
        for i in 0..4 {
            assert!((back[i] - x[i]).abs() < 1e-12, "{back:?}");
        }
        assert!((lj + lj_back).abs() < 1e-12);
        let e = 1e-6;
        let mut jac = nalgebra::Matrix3::zeros();
        for (c, &k) in [0, 1, 2].iter().enumerate() {
            let (mut p, mut q) = (x, x);
            p[k] += e;
            q[k] -= e;
            let (yp, yq) = (
                m.propose_viscous(&p, v).expect("fd").0,
                m.propose_viscous(&q, v).expect("fd").0,
            );
            for r in 0..3 {
                jac[(r, c)] = (yp[r] - yq[r]) / (2.0 * e);
            }
        }
        let det = jac.determinant();
        assert!((det.ln() - lj).abs() < 1e-6, "ln det {} vs {lj}", det.ln());
    }

    /// The ridge map keeps G0·(1 − g1) and G0·g2, is an involution (v and
    /// u_g1 swap), and its ln |J| is the log-determinant of ∂(u_G0', u_g2')
    /// /∂(u_G0, u_g2) by central differences (the other two coordinates
    /// swap, |det| 1), here ln(1/r) = ln((1 − g1')/(1 − g1)).
    #[test]
    fn ridge_map_is_an_involution_with_its_jacobian() {
        let m = ridge_3d();
        let x = [0.3, 0.4, 0.2];
        let v = 0.7;
        let (y, lj) = m.propose(&x, v, None).expect("move");
        let phys = |u: &[f64]| (10f64.powf(u[0]), u[1], u[2]);
        let (g, g1, g2) = phys(&x);
        let (h, h1, h2) = phys(&y);
        assert!((g * (1.0 - g1) - h * (1.0 - h1)).abs() < 1e-12);
        assert!((g * g2 - h * h2).abs() < 1e-12);
        let (back, lj_back) = m.propose(&y, x[1], None).expect("back");
        for i in 0..3 {
            assert!((back[i] - x[i]).abs() < 1e-12, "{back:?}");
        }
        assert!((lj + lj_back).abs() < 1e-12);
        let e = 1e-6;
        let at = |a: f64, b: f64| m.propose(&[a, x[1], b], v, None).expect("fd").0;
        let (p0, m0) = (at(x[0] + e, x[2]), at(x[0] - e, x[2]));
        let (p2, m2) = (at(x[0], x[2] + e), at(x[0], x[2] - e));
        let j = [
            [(p0[0] - m0[0]) / (2.0 * e), (p2[0] - m2[0]) / (2.0 * e)],
            [(p0[2] - m0[2]) / (2.0 * e), (p2[2] - m2[2]) / (2.0 * e)],
        ];
        let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
        assert!((det.ln() - lj).abs() < 1e-6, "ln det {} vs {lj}", det.ln());
        assert!((lj - ((1.0 - 0.7) / (1.0 - 0.4f64)).ln()).abs() < 1e-12);
    }

    /// The ridge move keeps a known density: uniform in u on the prism
    /// u ∈ [0, 1]⁴, u_g1 + u_g2 ≤ 1 (the Table 5.3 prior's shape; the 4th
    /// axis is τ1, redrawn on half the ridge moves, or moved by the
    /// viscous map on half of them), run with the ridge move on 60 % of
    /// the steps. Closed forms: E[u_G0] = E[u_τ1] = 1/2, Var = 1/12;
    /// E[u_g1] = E[u_g2] = 1/3, Var = 1/18. Without the Jacobian 1/r in
    /// the acceptance this fails (measured: E[u_G0] = 0.562).
    #[test]
    fn ridge_move_keeps_a_uniform_prism() {
        ridge_keeps_a_uniform_prism(RidgeTime::Redrawn);
    }

    /// As [`ridge_move_keeps_a_uniform_prism`] with the viscous map on
    /// half the ridge steps. Without its Jacobian in the acceptance this
    /// fails (measured: E[u_τ1] = 0.562).
    #[test]
    fn viscous_ridge_keeps_a_uniform_prism() {
        ridge_keeps_a_uniform_prism(RidgeTime::Viscous);
    }

    fn ridge_keeps_a_uniform_prism(time_move: RidgeTime) {
        let logp = |x: &[f64]| {
            if x.iter().all(|v| (0.0..=1.0).contains(v)) && x[1] + x[2] <= 1.0 {
                0.0
            } else {
                f64::NEG_INFINITY
            }
        };
        let init: Vec<Vec<f64>> = (0..16)
            .map(|k| {
                let t = k as f64 / 16.0;
                vec![0.2 + 0.5 * t, 0.1 + 0.3 * t, 0.3 - 0.2 * t, 0.4 + 0.1 * t]
            })
            .collect();
        let s = EnsembleSettings {
            walkers: 16,
            burn: 200,
            steps: 6000,
            ridge_fraction: 0.6,
            seed: 21,
            ..EnsembleSettings::default()
        };
        let ridge = RidgeMove {
            time_move,
            ..ridge_3d()
        };
        let mut e = [Ensemble::new(&logp, &init, &s)
            .expect("ensemble")
            .with_ridge(ridge)];
        burn_in(&mut e, &logp);
        let mut ch = [e[0].empty_chains()];
        sample(&mut e, &logp, s.steps, &mut ch);
        let [ch] = ch;
        let mean = |i: usize| moments(&ch, i).0;
        let var = |i: usize| moments(&ch, i).1;
        for i in [0, 3] {
            assert!((mean(i) - 0.5).abs() < 0.015, "E[u_{i}] {}", mean(i));
            assert!((var(i) - 1.0 / 12.0).abs() < 0.005, "Var[u_{i}] {}", var(i));
        }
        for i in 1..3 {
            assert!((mean(i) - 1.0 / 3.0).abs() < 0.01, "E[u_g{i}] {}", mean(i));
            assert!(
                (var(i) - 1.0 / 18.0).abs() < 0.004,
                "Var[u_g{i}] {}",
                var(i)
            );
        }
    }

    /// Tempering keeps the target of the β = 1 rung: a mixture of two
    /// Gaussians, 0.25·N((−5, 0), 0.5²I) + 0.75·N((5, 0), 0.5²I), every
    /// walker started in the left (lighter) mode, run one round untempered
    /// and then restarted with 5 rungs (β down to 0.4⁴ ≈ 0.026) as
    /// `sample_posterior` does, with refits between rounds. Closed forms:
    /// P(x > 0) = 0.75, E[x] = 2.5, Var[x] = 0.25 + 25 − 2.5² = 19, E[y] = 0,
    /// Var[y] = 0.25. Untempered, no walker reaches the right mode (the
    /// same run without the restart: P(x > 0) = 0). Over seeds 1–20 the
    /// tempered P(x > 0) was 0.736–0.760 (mean 0.751).
    #[test]
    fn tempering_keeps_a_two_mode_mixture() {
        let logp = two_modes;
        let (init, s) = two_modes_run();
        let run = |tempered: bool| {
            let mut e = [Ensemble::new(&logp, &init, &s).expect("ensemble")];
            burn_in(&mut e, &logp);
            let mut ch = [e[0].empty_chains()];
            sample(&mut e, &logp, 500, &mut ch);
            if tempered {
                e[0].temper(5, 0.4).expect("ladder");
                assert!(e[0].temper(3, 0.5).is_err(), "a second ladder");
                ch = [e[0].empty_chains()];
                burn_in(&mut e, &logp);
            }
            for _ in 0..8 {
                sample(&mut e, &logp, 500, &mut ch);
                e[0].refit_proposal();
            }
            let [ch] = ch;
            (ch, e[0].swap_acceptance())
        };
        let (ch, swaps) = run(true);
        assert_two_modes(&ch);
        assert!(swaps > 0.2 && swaps < 0.95, "swap acceptance {swaps}");
        let (cold, none) = run(false);
        let right = cold.samples.iter().step_by(2).filter(|&&v| v > 0.0).count();
        assert_eq!((right, none), (0, 0.0));
    }

    /// The tempered restart as `sample_posterior` makes it early with
    /// `temper_rhat` set (session 21): two pooled ensembles started in the light mode of
    /// [`two_modes`], restarted after one untempered round of 250 kept
    /// steps (the early restart, `temper_rhat`) with a burn-in of 50
    /// steps (half `temper_burn`), then rounds with pooled refits. Each
    /// ensemble's β = 1 draws have the mixture's moments (the tolerances of
    /// [`assert_two_modes`]); without the restart no walker leaves the
    /// light mode.
    #[test]
    fn an_early_restart_keeps_a_two_mode_mixture() {
        let logp = two_modes;
        let (init, s) = two_modes_run();
        let s = EnsembleSettings {
            pool_proposals: true,
            ..s
        };
        let run = |tempered: bool| {
            let mut e = two_ensembles(&init, &init, s);
            burn_in(&mut e, &logp);
            let mut ch = [e[0].empty_chains(), e[1].empty_chains()];
            sample(&mut e, &logp, 250, &mut ch);
            if tempered {
                for (e, c) in e.iter_mut().zip(ch.iter_mut()) {
                    e.temper(5, 0.4).expect("ladder");
                    e.set_burn(50);
                    *c = e.empty_chains();
                }
                burn_in(&mut e, &logp);
            } else {
                refit_proposals(&mut e);
            }
            for _ in 0..8 {
                sample(&mut e, &logp, 500, &mut ch);
                refit_proposals(&mut e);
            }
            ch
        };
        for ch in &run(true) {
            assert_two_modes(ch);
        }
        for ch in &run(false) {
            let right = ch.samples.iter().step_by(2).filter(|&&v| v > 0.0).count();
            assert_eq!(right, 0);
        }
    }

    /// Hot starts ([`temper_from_proposal`]): on [`two_modes`], two pooled
    /// ensembles all in the light mode, one round, then the hot rungs
    /// drawn from the pooled proposal widened to their temperature. Every
    /// walker's stored ln p is the density at its position; the hottest
    /// rung (β = 0.4⁴) is spread ≈ 1.2/√β × t₅ times wider along the
    /// second coordinate than the β = 1 walkers (copies: the same
    /// spread); after a 50-step burn-in and eight pooled rounds each
    /// ensemble has the mixture's moments ([`assert_two_modes`]).
    #[test]
    fn hot_starts_spread_the_hot_rungs_and_keep_a_two_mode_mixture() {
        let logp = two_modes;
        let (init, s) = two_modes_run();
        let s = EnsembleSettings {
            pool_proposals: true,
            ..s
        };
        let mut e = two_ensembles(&init, &init, s);
        burn_in(&mut e, &logp);
        let mut ch = [e[0].empty_chains(), e[1].empty_chains()];
        sample(&mut e, &logp, 250, &mut ch);
        let drawn = temper_from_proposal(&mut e, &logp, 5, 0.4).expect("ladder");
        assert!(drawn >= 2 * 4 * 16, "{drawn} draws");
        let sd = |xs: &[Vec<f64>]| {
            let m = xs.iter().map(|p| p[1]).sum::<f64>() / xs.len() as f64;
            (xs.iter().map(|p| (p[1] - m).powi(2)).sum::<f64>() / (xs.len() - 1) as f64).sqrt()
        };
        for ens in &e {
            assert_eq!(ens.rungs(), 5);
            for (x, lp) in ens.pos.iter().zip(&ens.lp) {
                assert_eq!(*lp, logp(x));
            }
            let ratio = sd(&ens.pos[4 * 16..]) / sd(&ens.pos[..16]);
            assert!(ratio > 3.0 && ratio < 30.0, "hottest / cold spread {ratio}");
            assert!(ens.proposals.iter().all(Option::is_some));
        }
        for (ens, c) in e.iter_mut().zip(ch.iter_mut()) {
            ens.set_burn(50);
            *c = ens.empty_chains();
        }
        burn_in(&mut e, &logp);
        for _ in 0..8 {
            sample(&mut e, &logp, 500, &mut ch);
            refit_proposals(&mut e);
        }
        for c in &ch {
            assert_two_modes(c);
        }
    }

    /// Ensembles stepped together (their proposals evaluated in shared
    /// batches) give exactly the chains each gives alone: own random
    /// streams, nothing shared but the batch, so they stay independent
    /// for R̂.
    #[test]
    fn ensembles_stepped_together_equal_ensembles_run_alone() {
        let logp = |x: &[f64]| -0.5 * (x[0] * x[0] + 4.0 * (x[1] - x[0]).powi(2));
        let init: Vec<Vec<f64>> = (0..8).map(|k| vec![k as f64 * 0.1, -0.2]).collect();
        let settings = |seed| EnsembleSettings {
            walkers: 8,
            burn: 20,
            steps: 60,
            refresh_fraction: 0.1,
            seed,
            ..EnsembleSettings::default()
        };
        let mut together: Vec<Ensemble> = [3, 4]
            .map(|seed| Ensemble::new(&logp, &init, &settings(seed)).expect("e"))
            .into();
        burn_in(&mut together, &logp);
        let mut chains: Vec<Chains> = together.iter().map(Ensemble::empty_chains).collect();
        sample(&mut together, &logp, 30, &mut chains);
        sample(&mut together, &logp, 30, &mut chains);
        for (seed, ch) in [3, 4].into_iter().zip(&chains) {
            let alone = sample_ensemble(logp, &init, &settings(seed)).expect("alone");
            assert_eq!(&alone, ch);
        }
        assert_ne!(chains[0].samples, chains[1].samples);
    }

    /// A round sampled in parts ([`sample`] then [`sample_more`], as the
    /// stopping rule's checks within a round do) gives the chains of the
    /// round in one call, the refit after it included; restarting the
    /// round at the part (`sample` twice) changes the refit and the chains.
    #[test]
    fn a_round_in_parts_equals_the_round_in_one_call() {
        let logp = |x: &[f64]| -0.5 * (x[0] * x[0] + 4.0 * (x[1] - x[0]).powi(2));
        let init: Vec<Vec<f64>> = (0..8).map(|k| vec![k as f64 * 0.1, -0.2]).collect();
        let settings = EnsembleSettings {
            walkers: 8,
            burn: 20,
            steps: 60,
            refresh_fraction: 0.1,
            seed: 5,
            ..EnsembleSettings::default()
        };
        assert!(settings.independence_fraction > 0.0);
        let run = |parts: &[(usize, bool)]| {
            let mut e = vec![Ensemble::new(&logp, &init, &settings).expect("e")];
            burn_in(&mut e, &logp);
            let mut chains = vec![e[0].empty_chains()];
            for &(steps, more) in parts {
                if steps == 0 {
                    e[0].refit_proposal();
                } else if more {
                    sample_more(&mut e, &logp, steps, &mut chains);
                } else {
                    sample(&mut e, &logp, steps, &mut chains);
                }
            }
            chains.remove(0)
        };
        let whole = run(&[(60, false), (0, false), (60, false)]);
        let parts = run(&[(20, false), (40, true), (0, false), (25, false), (35, true)]);
        assert_eq!(whole, parts);
        let restarted = run(&[(20, false), (40, false), (0, false), (60, false)]);
        assert_eq!(restarted.steps, whole.steps);
        assert_ne!(restarted.samples, whole.samples);
    }

    #[test]
    fn same_seed_same_chains_and_bad_settings_are_refused() {
        let logp = |x: &[f64]| -0.5 * x.iter().map(|v| v * v).sum::<f64>();
        let init: Vec<Vec<f64>> = (0..8).map(|k| vec![k as f64 * 0.1, -0.2]).collect();
        let s = EnsembleSettings {
            walkers: 8,
            burn: 10,
            steps: 50,
            ..EnsembleSettings::default()
        };
        let a = sample_ensemble(logp, &init, &s).expect("a");
        let b = sample_ensemble(logp, &init, &s).expect("b");
        assert_eq!(a, b);
        let c = sample_ensemble(logp, &init, &EnsembleSettings { seed: 2, ..s }).expect("c");
        assert_ne!(a.samples, c.samples);
        assert!(sample_ensemble(logp, &init[..5], &EnsembleSettings { walkers: 5, ..s }).is_err());
        let mut bad = init.clone();
        bad[0] = vec![f64::NAN, 0.0];
        assert!(sample_ensemble(logp, &bad, &s).is_err());
    }
}
