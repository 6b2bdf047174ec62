//! Design of experiments: Latin hypercubes in a parameter [`Domain`]
//! (bounded box with linear or logarithmic axes, linear constraints such as
//! g1 + g2 < 1; thesis Tables 4.1, 5.3, A.2), an optimised (ESE, φ_p)
//! variant, and separate, non-overlapping training and checking sets
//! (thesis §4.4.1 steps 1–2). [`latin_hypercube_unit`] is the pipeline's one
//! Latin hypercube (the fitter's start points use it too).
//!
//! All designs are built in the unit cube and mapped to the box
//! ([`Domain::from_unit`]); every random choice comes from a seeded ChaCha8
//! generator.

use nlvid_model::Domain;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::error::{Result, SurrogateError};

/// A design: rows of parameter values (original units).
pub type Design = Vec<Vec<f64>>;

/// Random Latin hypercube of n points in [0,1]^d: each axis split into n
/// strata, each stratum hit once, jittered uniformly within it (per axis: a
/// Fisher–Yates permutation, then one uniform jitter per point).
pub fn latin_hypercube_unit(n: usize, d: usize, rng: &mut ChaCha8Rng) -> Vec<Vec<f64>> {
    let mut pts = vec![vec![0.0; d]; n];
    for k in 0..d {
        let perm = permutation(n, rng);
        for i in 0..n {
            pts[i][k] = (perm[i] as f64 + rng.random::<f64>()) / n as f64;
        }
    }
    pts
}

fn permutation(n: usize, rng: &mut ChaCha8Rng) -> Vec<usize> {
    let mut v: Vec<usize> = (0..n).collect();
    for i in (1..n).rev() {
        let j = rng.random_range(0..=i);
        v.swap(i, j);
    }
    v
}

/// φ_p space-filling criterion (Morris & Mitchell 1995), p = 50.
fn phi_p(d2: &[f64], n: usize) -> f64 {
    let mut s = 0.0;
    for i in 0..n {
        for j in i + 1..n {
            s += d2[i * n + j].max(1e-300).powf(-PHI_P / 2.0);
        }
    }
    s.powf(1.0 / PHI_P)
}

const PHI_P: f64 = 50.0;

fn dist2(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum()
}

/// Optimise a unit-cube Latin hypercube in place by the enhanced stochastic
/// evolutionary algorithm (Jin, Chen & Sudjianto 2005): column-wise swaps
/// that keep the Latin property, threshold acceptance on φ_p.
pub fn ese_optimise(pts: &mut [Vec<f64>], outer: usize, rng: &mut ChaCha8Rng) {
    let n = pts.len();
    if n < 3 {
        return;
    }
    let d = pts[0].len();
    let mut d2 = vec![0.0; n * n];
    for i in 0..n {
        for j in 0..n {
            d2[i * n + j] = dist2(&pts[i], &pts[j]);
        }
    }
    // Sum of d^-p over pairs involving rows i1, i2 (helper for updates).
    let pair_sum = |d2: &[f64]| -> f64 {
        let mut s = 0.0;
        for i in 0..n {
            for j in i + 1..n {
                s += d2[i * n + j].max(1e-300).powf(-PHI_P / 2.0);
            }
        }
        s
    };
    let mut cur = pair_sum(&d2);
    let mut best = cur;
    let mut best_pts = pts.to_vec();
    let mut th = 0.005 * phi_p(&d2, n).powf(PHI_P);
    let j_trials = (n / 5).clamp(2, 50);
    let m_inner = (2 * n * d / j_trials).clamp(10, 100);
    let mut row1 = vec![0.0; n];
    let mut row2 = vec![0.0; n];
    for _ in 0..outer {
        let old_best = best;
        let mut accepted = 0usize;
        let mut improved = 0usize;
        for it in 0..m_inner {
            let k = it % d;
            // Try J swaps in column k, keep the best.
            let mut cand: Option<(f64, usize, usize)> = None;
            for _ in 0..j_trials {
                let i1 = rng.random_range(0..n);
                let mut i2 = rng.random_range(0..n - 1);
                if i2 >= i1 {
                    i2 += 1;
                }
                let delta = swap_delta(pts, &d2, n, k, i1, i2, &mut row1, &mut row2);
                if cand.is_none_or(|c| delta < c.0) {
                    cand = Some((delta, i1, i2));
                }
            }
            let Some((delta, i1, i2)) = cand else {
                continue;
            };
            if delta <= th * rng.random::<f64>() {
                swap_delta(pts, &d2, n, k, i1, i2, &mut row1, &mut row2);
                let (a, b) = (pts[i1][k], pts[i2][k]);
                pts[i1][k] = b;
                pts[i2][k] = a;
                for l in 0..n {
                    d2[i1 * n + l] = row1[l];
                    d2[l * n + i1] = row1[l];
                    d2[i2 * n + l] = row2[l];
                    d2[l * n + i2] = row2[l];
                }
                cur += delta;
                accepted += 1;
                if cur < best {
                    best = cur;
                    best_pts.clone_from_slice(pts);
                    improved += 1;
                }
            }
        }
        // Threshold control (exploration vs improvement).
        let ratio = accepted as f64 / m_inner as f64;
        if best < old_best {
            if ratio > 0.1 && improved < accepted {
                th *= 0.8;
            } else if ratio < 0.1 {
                th /= 0.9;
            }
        } else if ratio < 0.1 {
            th /= 0.7;
        } else if ratio > 0.8 {
            th *= 0.9;
        }
        // Periodic exact refresh avoids drift of the running sum.
        cur = pair_sum(&d2);
    }
    pts.clone_from_slice(&best_pts);
}

/// Change of Σ d^-p if column k of rows i1, i2 were swapped; new distance
/// rows of i1, i2 are left in row1, row2.
#[allow(clippy::too_many_arguments)]
fn swap_delta(
    pts: &[Vec<f64>],
    d2: &[f64],
    n: usize,
    k: usize,
    i1: usize,
    i2: usize,
    row1: &mut [f64],
    row2: &mut [f64],
) -> f64 {
    let (a, b) = (pts[i1][k], pts[i2][k]);
    let e = -PHI_P / 2.0;
    let mut delta = 0.0;
    for l in 0..n {
        if l == i1 || l == i2 {
            continue;
        }
        let c = pts[l][k];
        let n1 = d2[i1 * n + l] - (a - c).powi(2) + (b - c).powi(2);
        let n2 = d2[i2 * n + l] - (b - c).powi(2) + (a - c).powi(2);
        delta += n1.max(1e-300).powf(e) + n2.max(1e-300).powf(e)
            - d2[i1 * n + l].max(1e-300).powf(e)
            - d2[i2 * n + l].max(1e-300).powf(e);
        row1[l] = n1;
        row2[l] = n2;
    }
    row1[i1] = 0.0;
    row2[i2] = 0.0;
    row1[i2] = d2[i1 * n + i2];
    row2[i1] = d2[i1 * n + i2];
    delta
}

/// Settings for [`sample`].
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct SampleSettings {
    /// Number of points.
    pub n: usize,
    /// Seed.
    pub seed: u64,
    /// ESE outer iterations (0: plain random Latin hypercube).
    #[serde(default = "default_outer")]
    pub optimise_iterations: usize,
}

fn default_outer() -> usize {
    30
}

/// Minimum pairwise distance of unit-cube points.
pub fn min_distance(pts: &[Vec<f64>]) -> f64 {
    let mut m = f64::INFINITY;
    for i in 0..pts.len() {
        for j in i + 1..pts.len() {
            m = m.min(dist2(&pts[i], &pts[j]));
        }
    }
    m.sqrt()
}

/// A space-filling design of `n` points in the domain (parameters).
///
/// Without constraints: an (optionally ESE-optimised) Latin hypercube.
/// With constraints: a Latin hypercube over the box large enough that
/// ≈ n of its points are feasible (size from the feasible fraction,
/// estimated with 20 000 seeded points), restricted to the feasible region;
/// surplus points are removed one at a time, always one of the closest
/// pair (greedy maximin pruning), so the design stays stratified and
/// space-filling inside the region instead of merely rejected.
///
/// # Errors
/// n = 0, or a feasible region too small to find (< 1e-4 of the box).
pub fn sample(domain: &Domain, s: &SampleSettings) -> Result<Design> {
    Ok(sample_unit(domain, s)?
        .iter()
        .map(|u| domain.from_unit(u))
        .collect())
}

/// Whether the point u of the unit cube maps to a point satisfying every
/// constraint of the domain.
fn feasible(domain: &Domain, u: &[f64]) -> bool {
    domain.feasible(&domain.from_unit(u), 0.0)
}

fn sample_unit(domain: &Domain, s: &SampleSettings) -> Result<Vec<Vec<f64>>> {
    if s.n == 0 {
        return Err(SurrogateError::InvalidSettings(
            "number of design points must be > 0".into(),
        ));
    }
    let d = domain.len();
    let mut rng = ChaCha8Rng::seed_from_u64(s.seed);
    if domain.constraints().is_empty() {
        let mut pts = latin_hypercube_unit(s.n, d, &mut rng);
        ese_optimise(&mut pts, s.optimise_iterations, &mut rng);
        return Ok(pts);
    }
    let trials = 20_000;
    let hits = (0..trials)
        .filter(|_| {
            let u: Vec<f64> = (0..d).map(|_| rng.random::<f64>()).collect();
            feasible(domain, &u)
        })
        .count();
    if hits < 2 {
        return Err(SurrogateError::InvalidSettings(format!(
            "the constraints leave almost no feasible region ({hits} of {trials} random points)"
        )));
    }
    let frac = hits as f64 / trials as f64;
    let mut big = ((s.n as f64 / frac) * 1.15).ceil() as usize + 2;
    for _ in 0..20 {
        let mut pts = latin_hypercube_unit(big, d, &mut rng);
        ese_optimise(&mut pts, s.optimise_iterations.min(10), &mut rng);
        let mut feas: Vec<Vec<f64>> = pts.into_iter().filter(|u| feasible(domain, u)).collect();
        if feas.len() >= s.n {
            prune_to(&mut feas, s.n);
            return Ok(feas);
        }
        big = (big as f64 * 1.3).ceil() as usize;
    }
    Err(SurrogateError::InvalidSettings(
        "could not fill the feasible region; check the constraints".into(),
    ))
}

/// Remove points until n remain, each time the member of the closest pair
/// with the smaller distance to its second-nearest neighbour.
fn prune_to(pts: &mut Vec<Vec<f64>>, n: usize) {
    while pts.len() > n {
        let m = pts.len();
        let mut best = (f64::INFINITY, 0, 0);
        for i in 0..m {
            for j in i + 1..m {
                let dd = dist2(&pts[i], &pts[j]);
                if dd < best.0 {
                    best = (dd, i, j);
                }
            }
        }
        let nn2 = |i: usize, other: usize| {
            (0..m)
                .filter(|&l| l != i && l != other)
                .map(|l| dist2(&pts[i], &pts[l]))
                .fold(f64::INFINITY, f64::min)
        };
        let (_, i, j) = best;
        let drop = if nn2(i, j) < nn2(j, i) { i } else { j };
        pts.swap_remove(drop);
    }
}

/// Training and checking designs for one domain (thesis §4.4.1): two
/// independent designs from separate seed streams, the checking points
/// kept at least `min_gap` (unit-cube distance, e.g. 1e-6) away from every
/// training point (offending checking points are replaced).
///
/// # Errors
/// As [`sample`].
pub fn training_and_checking(
    domain: &Domain,
    n_train: usize,
    n_check: usize,
    seed: u64,
    optimise_iterations: usize,
    min_gap: f64,
) -> Result<(Design, Design)> {
    let train = sample_unit(
        domain,
        &SampleSettings {
            n: n_train,
            seed,
            optimise_iterations,
        },
    )?;
    let check_seed = seed ^ 0x9E37_79B9_7F4A_7C15;
    let mut check = sample_unit(
        domain,
        &SampleSettings {
            n: n_check,
            seed: check_seed,
            optimise_iterations,
        },
    )?;
    let mut rng = ChaCha8Rng::seed_from_u64(check_seed.wrapping_add(1));
    let d = domain.len();
    for c in check.iter_mut() {
        let mut tries = 0;
        while train.iter().any(|t| dist2(t, c) < min_gap * min_gap) {
            tries += 1;
            if tries > 1000 {
                return Err(SurrogateError::InvalidSettings(
                    "could not place a checking point away from the training set".into(),
                ));
            }
            let u: Vec<f64> = (0..d).map(|_| rng.random::<f64>()).collect();
            if feasible(domain, &u) {
                *c = u;
            }
        }
    }
    Ok((
        train.iter().map(|u| domain.from_unit(u)).collect(),
        check.iter().map(|u| domain.from_unit(u)).collect(),
    ))
}

/// The study's `[design]` section: the parameter domain of a forward
/// model, the sizes of the training and checking sets and the seed.
///
/// ```toml
/// [design]
/// n_train = 100
/// n_check = 50
/// seed = 7
/// ese = true                 # optimised LHS (default); false: random LHS
/// [design.parameters]        # every parameter of the model, its SI unit
/// G0 = { range = ["80 Pa", "4 kPa"], log = true }
/// g1 = { range = [0.01, 1.0] }
/// [[design.constraint]]      # Σ coefficients·x ≤ at_most
/// coefficients = { g1 = 1, g2 = 1 }
/// at_most = 0.99
/// [design.infill]            # optional: adaptive infill (crate::infill)
/// initial = 40
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct DesignSettings {
    /// Domain in the model's parameter order.
    pub domain: Domain,
    /// Training points N.
    pub n_train: usize,
    /// Checking points (separate design, may be 0).
    pub n_check: usize,
    /// Seed.
    pub seed: u64,
    /// ESE outer iterations (0: plain random Latin hypercube).
    pub ese_iterations: usize,
    /// `[design.infill]`: build the training set adaptively
    /// ([`crate::infill`]) from a Latin hypercube of `initial` points up to
    /// `n_train` runs.
    pub infill: Option<InfillSettings>,
}

impl DesignSettings {
    /// Reads `[design]` for a model with these parameter names and SI
    /// units (`"1"` for dimensionless); every parameter must be given.
    ///
    /// # Errors
    /// Missing or unknown parameters, wrong units, empty ranges, log axes
    /// with lower ≤ 0, constraints naming unknown parameters — each naming
    /// file, line and key.
    pub fn from_section(
        s: &mut nlvid_study::Section,
        names: &[String],
        units: &[String],
    ) -> nlvid_study::Result<Self> {
        use nlvid_study::Bounds;
        let n_train = s.req_usize("n_train", Bounds::closed(2.0, 1e7))?;
        let n_check = s
            .opt_usize("n_check", Bounds::closed(0.0, 1e7))?
            .unwrap_or(0);
        let seed = s.opt_u64("seed")?.unwrap_or(1);
        let ese = s.opt_bool("ese")?.unwrap_or(true);
        let iters = s.opt_usize("ese_iterations", Bounds::closed(1.0, 1e6))?;
        if !ese && iters.is_some() {
            return Err(s.invalid("ese_iterations", "given with ese = false"));
        }
        let ese_iterations = if ese { iters.unwrap_or(30) } else { 0 };
        let domain = Domain::from_section(s, names, units)?;
        let infill = match s.opt_subsection("infill")? {
            None => None,
            Some(mut sub) => {
                let i = InfillSettings::from_section(&mut sub, names, n_train)?;
                sub.finish()?;
                Some(i)
            }
        };
        Ok(Self {
            domain,
            n_train,
            n_check,
            seed,
            ese_iterations,
            infill,
        })
    }

    /// The training and checking designs ([`training_and_checking`], checking
    /// points at least 1e-6 (unit cube) from every training point). With
    /// `[design.infill]` the training design is the starting Latin
    /// hypercube of `initial` points (the checking design is the same as
    /// without infill: it depends on the seed and `n_check` only).
    ///
    /// # Errors
    /// As [`training_and_checking`].
    pub fn designs(&self) -> Result<(Design, Design)> {
        let (train, check) = training_and_checking(
            &self.domain,
            self.infill.as_ref().map_or(self.n_train, |i| i.initial),
            self.n_check.max(1),
            self.seed,
            self.ese_iterations,
            1e-6,
        )?;
        Ok((train, if self.n_check == 0 { Vec::new() } else { check }))
    }

    /// `nlvid sample`: [`DesignSettings::designs`] written into `out`
    /// (created) as `train.csv` and, when there is one, `check.csv`
    /// (header: the domain's parameter names); returns the numbers of
    /// training and checking points.
    ///
    /// # Errors
    /// As [`DesignSettings::designs`]; a file that cannot be written.
    pub fn write_designs(&self, out: &std::path::Path) -> Result<(usize, usize)> {
        let (train, check) = self.designs()?;
        std::fs::create_dir_all(out).map_err(crate::error::io_err(out))?;
        let header = self.domain.names();
        for (name, rows) in [("train.csv", &train), ("check.csv", &check)] {
            if !rows.is_empty() {
                let mut buf = Vec::new();
                crate::write_table(&mut buf, &header, rows)?;
                let path = out.join(name);
                nlvid_study::write_atomic(&path, &buf).map_err(crate::error::io_err(path))?;
            }
        }
        Ok((train.len(), check.len()))
    }
}

/// `[design.infill]` of a build study.
///
/// ```toml
/// [design]
/// n_train = 300              # with infill: the budget of training runs
/// [design.infill]
/// initial = 100              # Latin hypercube to start from
/// batch = 10                 # runs added per round
/// target_max_error = 0.01    # stop when the max checking error is ≤ 1 %
/// proportional_to = "G0"     # outputs ∝ this parameter (OutputScale)
/// pca = 0.999999             # output principal components kept
/// candidates = 4000          # candidate points per round
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct InfillSettings {
    /// Size of the starting Latin hypercube.
    pub initial: usize,
    /// Runs added per round.
    pub batch: usize,
    /// Stop when the max checking error (eq. 4.4; the max predicted error
    /// without a checking set) is at most this fraction.
    pub target_max_error: Option<f64>,
    /// Candidate points per round.
    pub candidates: usize,
    /// Index of the parameter every output is proportional to.
    pub proportional_to: Option<usize>,
    /// Energy of the output principal components kept in the fits.
    pub pca_energy: Option<f64>,
}

impl InfillSettings {
    /// Reads `[design.infill]` for parameters `names` and budget `n_train`.
    ///
    /// # Errors
    /// Missing `initial`, `initial` > `n_train`, values out of range, an
    /// unknown parameter in `proportional_to` (file, line, key).
    pub fn from_section(
        s: &mut nlvid_study::Section,
        names: &[String],
        n_train: usize,
    ) -> nlvid_study::Result<Self> {
        use nlvid_study::Bounds;
        let initial = s.req_usize("initial", Bounds::closed(2.0, 1e7))?;
        if initial > n_train {
            return Err(s.invalid(
                "initial",
                format!("{initial} starting runs exceed the budget n_train = {n_train}"),
            ));
        }
        let batch = s
            .opt_usize("batch", Bounds::closed(1.0, 1e6))?
            .unwrap_or(10);
        let target_max_error = s.opt_f64("target_max_error", Bounds::open(0.0, 1.0))?;
        let candidates = s
            .opt_usize("candidates", Bounds::closed(10.0, 1e7))?
            .unwrap_or(4000);
        let proportional_to = match s.opt_str("proportional_to")? {
            None => None,
            Some(p) => Some(names.iter().position(|n| *n == p).ok_or_else(|| {
                s.invalid(
                    "proportional_to",
                    format!(
                        "`{p}` is not a parameter (parameters: {})",
                        names.join(", ")
                    ),
                )
            })?),
        };
        let pca_energy = Some(
            s.opt_f64("pca", Bounds::open_closed(0.0, 1.0))?
                .unwrap_or(1.0 - 1e-6),
        );
        Ok(Self {
            initial,
            batch,
            target_max_error,
            candidates,
            proportional_to,
            pca_energy,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use nlvid_model::{LinearConstraint, Parameter, Scale};

    /// Axes a ∈ [a.0, a.1], tau ∈ [1e-2, 1e2] s (log if `log`), g ∈ [0, 1].
    fn box3_from(a: (f64, f64), log: bool, constraints: Vec<LinearConstraint>) -> Domain {
        let tau_scale = if log { Scale::Log } else { Scale::Linear };
        Domain::new(vec![
            Parameter::new("a", "1", a.0, a.1, Scale::Linear),
            Parameter::new("tau", "s", 1e-2, 1e2, tau_scale),
            Parameter::new("g", "1", 0.0, 1.0, Scale::Linear),
        ])
        .and_then(|d| d.with_constraints(constraints))
        .expect("valid test domain")
    }

    fn box3(log: bool) -> Domain {
        box3_from((1.0, 2.0), log, vec![])
    }

    fn assert_latin(domain: &Domain, design: &Design) {
        let n = design.len();
        for k in 0..domain.len() {
            let mut seen = vec![false; n];
            for x in design {
                let u = domain.to_unit(x)[k];
                let s = ((u * n as f64).floor() as usize).min(n - 1);
                assert!(!seen[s], "axis {k}: stratum {s} hit twice");
                seen[s] = true;
            }
        }
    }

    #[test]
    fn latin_property_holds_for_plain_and_optimised_designs_on_log_axes() {
        let d = box3(true);
        for it in [0, 20] {
            let design = sample(
                &d,
                &SampleSettings {
                    n: 40,
                    seed: 7,
                    optimise_iterations: it,
                },
            )
            .unwrap();
            assert_eq!(design.len(), 40);
            assert_latin(&d, &design);
            for x in &design {
                assert!(x[1] >= 1e-2 && x[1] <= 1e2);
            }
        }
    }

    #[test]
    fn log_axis_spreads_points_evenly_over_decades() {
        let d = box3(true);
        let design = sample(
            &d,
            &SampleSettings {
                n: 40,
                seed: 3,
                optimise_iterations: 0,
            },
        )
        .unwrap();
        // 4 decades, 40 strata: exactly 10 points per decade.
        for dec in 0..4 {
            let lo = 1e-2 * 10f64.powi(dec);
            let c = design
                .iter()
                .filter(|x| x[1] >= lo && x[1] < lo * 10.0)
                .count();
            assert_eq!(c, 10);
        }
    }

    #[test]
    fn ese_improves_the_maximin_distance() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let mut pts = latin_hypercube_unit(30, 3, &mut rng);
        let before = min_distance(&pts);
        ese_optimise(&mut pts, 30, &mut rng);
        assert!(
            min_distance(&pts) > before,
            "{} vs {before}",
            min_distance(&pts)
        );
    }

    #[test]
    fn same_seed_same_design() {
        let d = box3(false);
        let s = SampleSettings {
            n: 20,
            seed: 5,
            optimise_iterations: 5,
        };
        assert_eq!(sample(&d, &s).unwrap(), sample(&d, &s).unwrap());
    }

    #[test]
    fn constrained_design_is_feasible_and_more_space_filling_than_rejection() {
        // a ∈ [0, 1]; g1 + g2 ≤ 1 on axes 0 and 2.
        let d = box3_from(
            (0.0, 1.0),
            false,
            vec![LinearConstraint {
                coefficients: vec![1.0, 0.0, 1.0],
                rhs: 1.0,
                label: "a + g <= 1".into(),
            }],
        );
        let n = 60;
        let design = sample(
            &d,
            &SampleSettings {
                n,
                seed: 2,
                optimise_iterations: 20,
            },
        )
        .unwrap();
        assert_eq!(design.len(), n);
        assert!(design.iter().all(|x| x[0] + x[2] <= 1.0));
        // Rejection sampling of plain random points, same size.
        let mut rng = ChaCha8Rng::seed_from_u64(2);
        let mut rej = Vec::new();
        while rej.len() < n {
            let u: Vec<f64> = (0..3).map(|_| rng.random::<f64>()).collect();
            if feasible(&d, &u) {
                rej.push(u);
            }
        }
        let ours: Vec<Vec<f64>> = design.iter().map(|x| d.to_unit(x)).collect();
        assert!(
            min_distance(&ours) > 1.5 * min_distance(&rej),
            "{} vs {}",
            min_distance(&ours),
            min_distance(&rej)
        );
        // Both halves of the triangle are populated in proportion to area.
        let low = design.iter().filter(|x| x[0] < 0.5).count() as f64 / n as f64;
        assert!((low - 0.75).abs() < 0.1, "fraction with g1 < 0.5: {low}");
    }

    #[test]
    fn training_and_checking_sets_do_not_overlap() {
        let d = box3(true);
        let (t, c) = training_and_checking(&d, 50, 20, 9, 5, 1e-3).unwrap();
        assert_eq!((t.len(), c.len()), (50, 20));
        for x in &c {
            let ux = d.to_unit(x);
            for y in &t {
                assert!(dist2(&ux, &d.to_unit(y)).sqrt() >= 1e-3);
            }
        }
    }
}
