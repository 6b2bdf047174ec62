//! Adaptive infill of a meta-model design (issue 17; the thesis, §4.4.1
//! and §5.4.1, runs one Latin hypercube of N = 970): start from a small
//! Latin hypercube, fit the Kriging model, add the batch of runs where the
//! predicted range-normalised error is largest, refit, and stop when the
//! checking error (eq. 4.4 on the separate checking set) reaches a target
//! or the run budget `n_train` is spent.
//!
//! * Criterion: e(x)² = φ(x)·a(x), the Kriging MSE averaged over the
//!   outputs divided by the squared range of the predicted curve
//!   ([`KrigingModel::error_weight`]) — eq. 4.4 with the MSE in place of
//!   the squared error, so it is in the units of the stopping target.
//! * Batch: greedy; after each pick s the MSE factor of every candidate is
//!   updated exactly for s as a new site at the same θ,
//!   φ(x) ← φ(x) − k(x, s)²/k(s, s) (a pivoted Cholesky over the
//!   candidates), so a batch spreads out instead of clustering.
//! * Candidates: seeded uniform points of the feasible domain. A candidate
//!   whose predicted curve the admissibility filters would remove (peak
//!   below `min_peak_force`, a force ≤ 0 after contact) is skipped — the
//!   Kriging model has no data there (removed runs are not fitted) and
//!   would otherwise keep asking for runs that are thrown away; with the
//!   output scale F ∝ G0 the predicted peak is accurate at low G0. So is
//!   a candidate whose nearest training run (unit cube) failed, and one
//!   within 1e-6 of a run or checking point.
//! * Resumable: the design so far lives in the store's `meta.json`
//!   ([`RunStore::open_growing`]); a re-run takes it as it is, runs what
//!   is missing and continues. Every choice depends only on the stored
//!   runs and the seed, so an interrupted build ends with the same design
//!   as an uninterrupted one.

use std::path::Path;

use faer::Mat;
use nlvid_model::{Domain, ForwardModel};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use crate::build::{Admissibility, BuildOptions, MetaModel, build_into, load};
/// Read with the rest of `[design]` ([`crate::doe::DesignSettings`]).
pub use crate::doe::InfillSettings;

use crate::doe::Design;
use crate::error::{Result, SurrogateError};
use crate::kriging::{KrigingModel, KrigingSettings, OutputScale, VariancePoint};
use crate::store::{RunStore, StoreMeta};
use crate::{Correlation, Regression};

impl InfillSettings {
    /// The Kriging fit of every round: gauss/poly1 (the best of the
    /// measured choices, docs/theory/surrogate.md), log-axis parameters
    /// kriged in ln x, the output scale and PCA of these settings.
    pub fn kriging_settings(&self, domain: &Domain) -> KrigingSettings {
        let d = domain.len();
        let mut s = KrigingSettings::new(Regression::Poly1, Correlation::Gauss, d);
        s.log_inputs = domain.params().iter().map(|p| p.is_log()).collect();
        s.output_scale = self
            .proportional_to
            .map(|input| OutputScale::Linear { input });
        s.pca_energy = self.pca_energy;
        s
    }
}

/// A batch chosen by [`select_batch`].
#[derive(Debug, Clone)]
pub struct Selection {
    /// New design points (parameters).
    pub points: Vec<Vec<f64>>,
    /// Max predicted error e(x) over the usable candidates before the batch.
    pub predicted_max: f64,
    /// Usable candidates.
    pub candidates: usize,
}

/// Chooses up to `batch` new points of `domain` for `model` (module
/// docs): `runs` are the training runs so far (parameters, whether the
/// run failed), `filters` the admissibility filters the predicted curve
/// must pass, `avoid` further points to keep away from (the checking set).
///
/// # Errors
/// Prediction errors at a candidate.
#[allow(clippy::too_many_arguments)]
pub fn select_batch(
    model: &KrigingModel,
    domain: &Domain,
    runs: &[(Vec<f64>, bool)],
    filters: &Admissibility,
    avoid: &[Vec<f64>],
    batch: usize,
    n_candidates: usize,
    seed: u64,
) -> Result<Selection> {
    let d = domain.len();
    let unit_runs: Vec<(Vec<f64>, bool)> = runs
        .iter()
        .map(|(x, ok)| (domain.to_unit(x), *ok))
        .collect();
    let unit_avoid: Vec<Vec<f64>> = avoid.iter().map(|x| domain.to_unit(x)).collect();
    let dist2 =
        |a: &[f64], b: &[f64]| -> f64 { a.iter().zip(b).map(|(p, q)| (p - q).powi(2)).sum() };
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut cands: Vec<Vec<f64>> = Vec::with_capacity(n_candidates);
    for _ in 0..n_candidates.saturating_mul(50) {
        if cands.len() == n_candidates {
            break;
        }
        let u: Vec<f64> = (0..d).map(|_| rng.random::<f64>()).collect();
        let x = domain.from_unit(&u);
        if !domain.feasible(&x, 0.0) {
            continue;
        }
        let nearest = unit_runs
            .iter()
            .min_by(|a, b| dist2(&a.0, &u).total_cmp(&dist2(&b.0, &u)));
        if nearest.is_some_and(|(r, failed)| *failed || dist2(r, &u) < 1e-12) {
            continue;
        }
        if unit_avoid.iter().any(|a| dist2(a, &u) < 1e-12) {
            continue;
        }
        cands.push(x);
    }
    let pv = model.process_variance();
    let scored: Vec<Option<(f64, VariancePoint)>> = cands
        .par_iter()
        .map(|x| {
            let y = model.predict(x)?;
            if !admissible(&y, filters) {
                return Ok(None);
            }
            Ok(Some((
                model.error_weight(x, &y, &pv)?,
                model.variance_point(x)?,
            )))
        })
        .collect::<Result<_>>()?;
    let (cands, scored): (Vec<Vec<f64>>, Vec<(f64, VariancePoint)>) = cands
        .into_iter()
        .zip(scored)
        .filter_map(|(x, s)| s.map(|s| (x, s)))
        .unzip();
    let weight: Vec<f64> = scored.iter().map(|s| s.0).collect();
    let points: Vec<&VariancePoint> = scored.iter().map(|s| &s.1).collect();
    let mut phi: Vec<f64> = points.iter().map(|p| p.phi).collect();
    let score = |phi: &[f64], i: usize| phi[i].max(0.0) * weight[i];
    let predicted_max = (0..cands.len())
        .map(|i| score(&phi, i))
        .fold(0.0, f64::max)
        .sqrt();
    // Greedy batch with exact rank-one updates of φ (pivoted Cholesky of
    // the candidates' posterior covariance): cols[t][i] = k_t(x_i, s_t).
    let mut chosen: Vec<usize> = Vec::new();
    let mut cols: Vec<Vec<f64>> = Vec::new();
    while chosen.len() < batch.min(cands.len()) {
        let Some(best) = (0..cands.len())
            .filter(|i| !chosen.contains(i))
            .max_by(|&a, &b| score(&phi, a).total_cmp(&score(&phi, b)).then(b.cmp(&a)))
        else {
            break;
        };
        if phi[best] <= 1e-12 {
            break;
        }
        let col: Vec<f64> = (0..cands.len())
            .into_par_iter()
            .map(|i| {
                let mut k = model.posterior_correlation(points[i], points[best]);
                for c in &cols {
                    k -= c[i] * c[best];
                }
                k
            })
            .collect();
        let pivot = col[best].sqrt();
        let col: Vec<f64> = col.iter().map(|k| k / pivot).collect();
        for (p, c) in phi.iter_mut().zip(&col) {
            *p -= c * c;
        }
        cols.push(col);
        chosen.push(best);
    }
    Ok(Selection {
        points: chosen.iter().map(|&i| cands[i].clone()).collect(),
        predicted_max,
        candidates: cands.len(),
    })
}

/// Whether a (predicted) curve passes the admissibility filters
/// (§5.4.1; as [`load`] applies them to runs).
fn admissible(y: &[f64], f: &Admissibility) -> bool {
    let peak = y.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    !(f.min_peak_force.is_some_and(|p| peak < p)
        || f.reject_non_repulsive && y.iter().skip(f.contact_index).any(|&v| v <= 0.0))
}

/// One round of [`run_infill`].
#[derive(Debug, Clone, PartialEq)]
pub struct Round {
    /// Training runs in the design.
    pub runs: usize,
    /// Of those, admissible (kept by the filters).
    pub admissible: usize,
    /// (max, median) checking error (eq. 4.4), with a checking set.
    pub check: Option<(f64, f64)>,
    /// Max predicted error over the candidates (when a batch was chosen).
    pub predicted_max: Option<f64>,
    /// Runs added after this round.
    pub added: usize,
}

/// The checking runs of a store that pass `filters`: (parameters, curves).
///
/// # Errors
/// As [`load`].
pub fn checking_set(store: &Path, filters: &Admissibility) -> Result<(Design, Design)> {
    let mm = load(store, filters)?;
    Ok((mm.x, mm.y))
}

/// Fits `settings` to the kept runs of `mm`.
///
/// # Errors
/// Fewer than 2 kept runs; as [`KrigingModel::fit`].
pub fn fit_kept(mm: &MetaModel, settings: &KrigingSettings) -> Result<KrigingModel> {
    if mm.x.len() < 2 {
        return Err(SurrogateError::InvalidInput(format!(
            "{} admissible training runs: too few to fit (raise [design.infill] initial)",
            mm.x.len()
        )));
    }
    let (n, d, m) = (mm.x.len(), mm.x[0].len(), mm.y[0].len());
    let x = Mat::from_fn(n, d, |i, k| mm.x[i][k]);
    let y = Mat::from_fn(n, m, |i, j| mm.y[i][j]);
    KrigingModel::fit(x.as_ref(), y.as_ref(), settings)
}

/// Max and median of eq. 4.4 of `model` on checking runs (x, y).
///
/// # Errors
/// Prediction errors; an empty set.
pub fn checking_error(model: &KrigingModel, x: &[Vec<f64>], y: &[Vec<f64>]) -> Result<(f64, f64)> {
    let preds: Vec<Vec<f64>> = x
        .par_iter()
        .map(|xi| model.predict(xi))
        .collect::<Result<_>>()?;
    let s = crate::check::summarise(y, &preds)?;
    Ok((s.max, s.median))
}

/// Builds the training set adaptively into `store` (module docs):
/// `initial` is the starting Latin hypercube, `budget` the most training
/// runs, `check` the checking runs already built (parameters, curves; may
/// be empty), `seed` the seed of the candidates. `say` gets one line per
/// round. Stops early (without error) when `opts.cancel` is set.
///
/// # Errors
/// A store of another study or design; model fits; a sharded build.
#[allow(clippy::too_many_arguments)]
pub fn run_infill(
    model: &dyn ForwardModel,
    domain: &Domain,
    infill: &InfillSettings,
    initial: &[Vec<f64>],
    budget: usize,
    seed: u64,
    filters: &Admissibility,
    store: &Path,
    check: (&[Vec<f64>], &[Vec<f64>]),
    opts: &BuildOptions<'_>,
    say: &mut dyn FnMut(&str) -> Result<()>,
) -> Result<Vec<Round>> {
    if opts.shard.is_some_and(|s| s.count > 1) {
        return Err(SurrogateError::InvalidSettings(
            "adaptive infill ([design.infill]) runs as one process: remove --shard".into(),
        ));
    }
    let meta_of = |design: &[Vec<f64>]| {
        StoreMeta::new(
            model.parameter_names(),
            model.parameter_units(),
            model.time_grid().to_vec(),
            design.to_vec(),
            model.identity(),
        )
        .with_conditions(model.conditions())
    };
    // The design so far: the stored one when it starts with `initial`.
    let mut design = initial.to_vec();
    if let Ok(stored) = RunStore::existing(store).and_then(|s| s.meta())
        && stored.design.len() >= initial.len()
        && stored.design[..initial.len()] == *initial
    {
        design = stored.design;
    }
    let settings = infill.kriging_settings(domain);
    let mut rounds = Vec::new();
    loop {
        let st = RunStore::open_growing(store, &meta_of(&design))?;
        let s = build_into(model, &design, &st, opts)?;
        if s.remaining > 0 {
            say(&format!(
                "infill: stopped with {} of {} runs of the round missing (cancelled)\n",
                s.remaining,
                design.len()
            ))?;
            return Ok(rounds);
        }
        let mm = load(store, filters)?;
        let kriging = fit_kept(&mm, &settings)?;
        let check_err = if check.0.is_empty() {
            None
        } else {
            Some(checking_error(&kriging, check.0, check.1)?)
        };
        let mut round = Round {
            runs: design.len(),
            admissible: mm.x.len(),
            check: check_err,
            predicted_max: None,
            added: 0,
        };
        let reached = |e: f64| infill.target_max_error.is_some_and(|t| e <= t);
        let mut stop = design.len() >= budget || check_err.is_some_and(|(max, _)| reached(max));
        if !stop {
            let runs: Vec<(Vec<f64>, bool)> = mm
                .status
                .iter()
                .filter(|(_, label, _, _)| label != "missing")
                .map(|(i, label, _, _)| (design[*i].clone(), label == "failed"))
                .collect();
            let want = infill.batch.min(budget - design.len());
            let sel = select_batch(
                &kriging,
                domain,
                &runs,
                filters,
                check.0,
                want,
                infill.candidates,
                seed.wrapping_add(design.len() as u64),
            )?;
            round.predicted_max = Some(sel.predicted_max);
            if check.0.is_empty() && reached(sel.predicted_max) {
                stop = true;
            } else {
                round.added = sel.points.len();
                stop = sel.points.is_empty();
                design.extend(sel.points);
            }
        }
        let pct = |v: f64| format!("{:.3} %", 100.0 * v);
        say(&format!(
            "infill: {} runs ({} admissible){}{}{}\n",
            round.runs,
            round.admissible,
            round.check.map_or(String::new(), |(max, med)| format!(
                ", checking error max {}, median {}",
                pct(max),
                pct(med)
            )),
            round
                .predicted_max
                .map_or(String::new(), |p| format!(", predicted max {}", pct(p))),
            if round.added > 0 {
                format!(", adding {}", round.added)
            } else {
                ", done".into()
            }
        ))?;
        rounds.push(round);
        if stop {
            return Ok(rounds);
        }
    }
}
