//! DACE-equivalent Kriging with many outputs sharing one correlation model
//! (Lophaven, Nielsen & Søndergaard 2002, ch. 2–3; thesis App. A.2).
//!
//! Fit: normalise sites and outputs (mean, n−1 standard deviation),
//! optionally rotate the outputs to their leading principal components,
//! choose θ by maximum likelihood (min ψ, eq. 2.25 of the report), then
//! factorise R once and solve for all outputs at once.
//!
//! Predict at x (eq. 2.16, 2.19–2.20 of the report):
//! `ŷ = f(x)ᵀβ + r(x)ᵀγ`, `γ = R⁻¹(Y − Fβ)`,
//! `MSE = σ²(1 + uᵀ(FᵀR⁻¹F)⁻¹u − rᵀR⁻¹r)`, `u = FᵀR⁻¹r − f`,
//! and their gradients with respect to x.

use faer::linalg::triangular_solve::{
    solve_lower_triangular_in_place, solve_upper_triangular_in_place,
};
use faer::{Accum, Mat, MatMut, MatRef, Par, Side};
use serde::{Deserialize, Serialize};

use crate::boxmin::{SearchResult, boxmin};
use crate::correlation::Correlation;
use crate::error::{Result, SurrogateError};
use crate::likelihood::{Eval, Factors, Problem};
use crate::optimise::{LogValue, OptimiserSettings, minimise};
use crate::regression::Regression;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

mod calibration;
mod reduced;
mod variance;

pub use calibration::{CalibrationData, VarianceCalibration};
pub use variance::{OutputCovariance, VariancePoint};

/// How θ is chosen.
#[derive(Debug, Clone)]
pub enum ThetaSearch {
    /// Use this θ (no likelihood optimisation).
    Fixed(Vec<f64>),
    /// DACE's `boxmin` from θ0 in `[lower, upper]` (reproduces published fits).
    Boxmin {
        /// Start.
        theta0: Vec<f64>,
        /// Lower bounds (> 0).
        lower: Vec<f64>,
        /// Upper bounds.
        upper: Vec<f64>,
    },
    /// Multistart projected BFGS on ln ψ(ln θ) (the default; see [`crate::optimise`]).
    Optimise {
        /// First start.
        theta0: Vec<f64>,
        /// Lower bounds (> 0).
        lower: Vec<f64>,
        /// Upper bounds.
        upper: Vec<f64>,
        /// Starts, iterations, seed.
        settings: OptimiserSettings,
    },
}

impl ThetaSearch {
    /// Default search for `dim` inputs: optimiser in `[1e-3, 1e2]` (per
    /// normalised unit) from θ = 1, and `p ∈ [0.1, 2]` from 1.9 for `expg`.
    pub fn default_for(correlation: Correlation, dim: usize) -> Self {
        let mut theta0 = vec![1.0; dim];
        let mut lower = vec![1e-3; dim];
        let mut upper = vec![1e2; dim];
        if correlation == Correlation::Expg {
            theta0.push(1.9);
            lower.push(0.1);
            upper.push(2.0);
        }
        ThetaSearch::Optimise {
            theta0,
            lower,
            upper,
            settings: OptimiserSettings::default(),
        }
    }
}

/// Exact proportionality of every output to a positive function s(x) of
/// one input: y(x) = s(x)·u(x). The fit krige u = y / s (or ln u with
/// [`KrigingSettings::log_outputs`]) and the predictor returns s(x)·û(x).
///
/// For the Lee–Radok Hertz models F ∝ G0 exactly (the force is linear in
/// the relaxation modulus, which is G0 times a function of g, τ); for the
/// FE model with a cantilever spring in series it is only approximately so.
/// A constant factor in s is irrelevant (outputs are normalised), so only
/// the shape of s matters.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum OutputScale {
    /// s(x) = x_k (x_k > 0 at every site and prediction point).
    Linear {
        /// Input index k.
        input: usize,
    },
    /// s(x) = exp(slope·x_k): input k is a log-coded factor — slope 1 when
    /// x_k = ln G0, slope ln(hi/lo) when x_k is the unit coordinate of a
    /// log axis [lo, hi].
    Exp {
        /// Input index k.
        input: usize,
        /// Slope of ln s in x_k.
        slope: f64,
    },
}

impl OutputScale {
    /// Input index k.
    pub fn input(&self) -> usize {
        match *self {
            OutputScale::Linear { input } | OutputScale::Exp { input, .. } => input,
        }
    }

    /// s(x) and ∂s/∂x_k.
    pub fn eval(&self, x: &[f64]) -> (f64, f64) {
        match *self {
            OutputScale::Linear { input } => (x[input], 1.0),
            OutputScale::Exp { input, slope } => {
                let s = (slope * x[input]).exp();
                (s, slope * s)
            }
        }
    }

    fn check(&self, x: &[f64], what: &str) -> Result<f64> {
        let (s, _) = self.eval(x);
        if s > 0.0 && s.is_finite() {
            Ok(s)
        } else {
            Err(SurrogateError::InvalidInput(format!(
                "output scale s(x) = {s} at {what} (input {} = {}): it must be finite and > 0",
                self.input(),
                x[self.input()]
            )))
        }
    }
}

/// Settings of a Kriging fit.
#[derive(Debug, Clone)]
pub struct KrigingSettings {
    /// Regression polynomial.
    pub regression: Regression,
    /// Correlation family.
    pub correlation: Correlation,
    /// θ choice.
    pub theta: ThetaSearch,
    /// Nugget added to the diagonal of R on top of DACE's (10+n)·eps.
    pub nugget: f64,
    /// Treat R as unusable when it is not positive definite or when the
    /// lower bound (max C_ii / min C_ii)² of its condition number exceeds
    /// 1e13, and then retry with nugget 1e-10, 1e-8, 1e-6, 1e-4 (the value
    /// used is reported). `false`: exactly DACE (any positive definite R).
    pub auto_nugget: bool,
    /// Reduce the outputs to the leading principal components holding this
    /// fraction of the variance of the standardised outputs (e.g. 0.99999).
    pub pca_energy: Option<f64>,
    /// Krige ln y instead of y (all outputs must be > 0). Force curves of
    /// a domain spanning decades of stiffness differ mostly by a factor;
    /// in ln y that factor is an additive term the regression captures,
    /// which keeps the *relative* error of soft and stiff cases alike.
    pub log_outputs: bool,
    /// Outputs exactly proportional to a function of one input (see
    /// [`OutputScale`]); `None`: no such structure used.
    pub output_scale: Option<OutputScale>,
    /// Krige in ln x_k for the inputs flagged here (empty: none; else one
    /// flag per input, flagged inputs must be > 0). Stored in the model,
    /// so `predict` takes the caller's x unchanged.
    pub log_inputs: Vec<bool>,
}

impl KrigingSettings {
    /// DACE-like defaults: given families, default optimiser, no nugget
    /// beyond DACE's, automatic nugget on failure, no output reduction.
    pub fn new(regression: Regression, correlation: Correlation, dim: usize) -> Self {
        KrigingSettings {
            regression,
            correlation,
            theta: ThetaSearch::default_for(correlation, dim),
            nugget: 0.0,
            auto_nugget: true,
            pca_energy: None,
            log_outputs: false,
            output_scale: None,
            log_inputs: Vec::new(),
        }
    }
}

/// Principal-component reduction of the standardised outputs.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Pca {
    /// Kept components k.
    pub n_components: usize,
    /// Fraction of variance of the standardised outputs they hold.
    pub energy: f64,
    /// Orthonormal basis V_k, m × k, column-major.
    pub basis: Vec<f64>,
    /// ρᵀρ/n of the kriged scores (k × k): σ² of output j is
    /// s_j² v_jᵀ Σ v_j (v_j row j of V_k), cross terms included.
    #[serde(default)]
    pub residual_cov: Vec<f64>,
}

/// What the fit did, for reports.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct FitReport {
    /// Final θ.
    pub theta: Vec<f64>,
    /// ψ(θ) on the kriged outputs (normalised, or PC scores).
    pub psi: f64,
    /// Likelihood evaluations used by the θ search (all sites, plus any
    /// on the screening subset).
    pub evaluations: usize,
    /// Of those, evaluations on the screening subset (cheap: subset³).
    #[serde(default)]
    pub screen_evaluations: usize,
    /// Search used (`fixed`, `boxmin`, `optimise`).
    pub search: String,
    /// Nugget added on top of DACE's (10+n)·eps.
    pub nugget: f64,
    /// Number of kriged outputs (m, or k principal components).
    pub kriged_outputs: usize,
    /// Variance fraction kept by the PCA (1 without reduction).
    pub energy: f64,
}

/// A fitted Kriging model (serialisable; all matrices column-major).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct KrigingModel {
    /// Regression polynomial.
    pub regression: Regression,
    /// Correlation family.
    pub correlation: Correlation,
    /// θ (normalised inputs; for `expg` the last entry is the power).
    pub theta: Vec<f64>,
    /// Input dimension d.
    pub dim: usize,
    /// Number of design sites n.
    pub n_sites: usize,
    /// Number of original outputs m.
    pub n_outputs: usize,
    /// Input means.
    pub x_mean: Vec<f64>,
    /// Input standard deviations (n−1; 1 for constant columns).
    pub x_std: Vec<f64>,
    /// Output means.
    pub y_mean: Vec<f64>,
    /// Output standard deviations (n−1; 1 for constant columns).
    pub y_std: Vec<f64>,
    /// Normalised sites, n × d.
    sites: Vec<f64>,
    /// β, p × q (normalised units / PC scores).
    pub beta: Vec<f64>,
    /// γ = C⁻ᵀρ, n × q.
    gamma: Vec<f64>,
    /// σ² of the kriged outputs (normalised units / PC scores), q.
    pub sigma2: Vec<f64>,
    /// C, F̃, G of R = CCᵀ, F̃ = C⁻¹F = QG, for the MSE only: n² numbers,
    /// so not written to the model file (a PCA model of n = 970 sites is
    /// then well under a MB instead of 20) and rebuilt from the sites, θ
    /// and the nugget on first use after loading (see
    /// [`variance`](self::variance)). Files with `c`, `ft`, `g` still load
    /// (the keys are ignored).
    #[serde(skip)]
    factors: std::sync::OnceLock<variance::MseFactors>,
    /// Output reduction, if any.
    pub pca: Option<Pca>,
    /// The model predicts ln y (see [`KrigingSettings::log_outputs`]).
    #[serde(default)]
    pub log_outputs: bool,
    /// Outputs are s(x)·(kriged quantity), see [`OutputScale`].
    #[serde(default)]
    pub output_scale: Option<OutputScale>,
    /// Inputs kriged in ln x (see [`KrigingSettings::log_inputs`]); the
    /// means, deviations and sites above are of ln x for those.
    #[serde(default)]
    pub log_inputs: Vec<bool>,
    /// How the model was obtained.
    pub report: FitReport,
}

/// Full prediction at one point.
#[derive(Debug, Clone)]
pub struct PointPrediction {
    /// ŷ(x), m values.
    pub y: Vec<f64>,
    /// ∂ŷ_j/∂x_k, row-major m × d.
    pub dy: Vec<f64>,
    /// MSE_j(x), m values.
    pub mse: Vec<f64>,
    /// ∂MSE_j/∂x_k, row-major m × d.
    pub dmse: Vec<f64>,
}

fn mean_std(col: impl Iterator<Item = f64>, n: usize) -> (f64, f64) {
    let col: Vec<f64> = col.collect();
    let mean = col.iter().sum::<f64>() / n as f64;
    let var = col.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n as f64 - 1.0);
    let sd = var.sqrt();
    (
        mean,
        if sd == 0.0 || !sd.is_finite() {
            1.0
        } else {
            sd
        },
    )
}

fn to_vec(m: MatRef<'_, f64>) -> Vec<f64> {
    let mut v = Vec::with_capacity(m.nrows() * m.ncols());
    for j in 0..m.ncols() {
        v.extend(m.col(j).iter().copied());
    }
    v
}

fn view(v: &[f64], r: usize, c: usize) -> MatRef<'_, f64> {
    MatRef::from_column_major_slice(v, r, c)
}

fn check_theta(name: &str, t: &[f64], nt: usize) -> Result<()> {
    if t.len() != nt {
        return Err(SurrogateError::InvalidSettings(format!(
            "{name} has {} entries, the correlation model needs {nt}",
            t.len()
        )));
    }
    if t.iter().any(|v| !(v.is_finite() && *v > 0.0)) {
        return Err(SurrogateError::InvalidSettings(format!(
            "{name} = {t:?}: every entry must be finite and > 0"
        )));
    }
    Ok(())
}

impl KrigingModel {
    /// Fit to sites `x` (n × d) and outputs `y` (n × m).
    ///
    /// # Errors
    /// Shape mismatches, non-finite data, fewer than 2 sites, θ settings of
    /// the wrong length or sign, a regression matrix too ill conditioned
    /// for the sites, or R not positive definite at every θ tried (with
    /// the largest nugget allowed).
    pub fn fit(x: MatRef<'_, f64>, y: MatRef<'_, f64>, settings: &KrigingSettings) -> Result<Self> {
        let (n, d, m) = (x.nrows(), x.ncols(), y.ncols());
        if y.nrows() != n {
            return Err(SurrogateError::InvalidInput(format!(
                "{n} design sites but {} rows of outputs",
                y.nrows()
            )));
        }
        if n < 2 || d == 0 || m == 0 {
            return Err(SurrogateError::InvalidInput(format!(
                "need ≥ 2 sites, ≥ 1 input and ≥ 1 output (got n = {n}, d = {d}, m = {m})"
            )));
        }
        for (name, a) in [("x", x), ("y", y)] {
            for j in 0..a.ncols() {
                if let Some(i) = (0..n).find(|&i| !a[(i, j)].is_finite()) {
                    return Err(SurrogateError::InvalidInput(format!(
                        "{name} row {i}, column {j} is not finite ({})",
                        a[(i, j)]
                    )));
                }
            }
        }
        let p = settings.regression.n_terms(d);
        if p > n {
            return Err(SurrogateError::InvalidInput(format!(
                "{} regression needs at least {p} sites, got {n}",
                settings.regression.name()
            )));
        }
        let nt = settings.correlation.n_theta(d);
        match &settings.theta {
            ThetaSearch::Fixed(t) => check_theta("theta", t, nt)?,
            ThetaSearch::Boxmin {
                theta0,
                lower,
                upper,
            }
            | ThetaSearch::Optimise {
                theta0,
                lower,
                upper,
                ..
            } => {
                check_theta("theta0", theta0, nt)?;
                check_theta("lower bound of theta", lower, nt)?;
                check_theta("upper bound of theta", upper, nt)?;
                if let Some(k) = (0..nt).find(|&k| lower[k] > upper[k]) {
                    return Err(SurrogateError::InvalidSettings(format!(
                        "theta bound {k}: lower {} > upper {}",
                        lower[k], upper[k]
                    )));
                }
            }
        }
        if let Some(e) = settings.pca_energy
            && !(e > 0.0 && e <= 1.0)
        {
            return Err(SurrogateError::InvalidSettings(format!(
                "PCA energy fraction {e} must be in (0, 1]"
            )));
        }

        let yscaled;
        let y = if let Some(sc) = settings.output_scale {
            if sc.input() >= d {
                return Err(SurrogateError::InvalidSettings(format!(
                    "output scale uses input {} but there are {d} inputs",
                    sc.input()
                )));
            }
            let mut factors = Vec::with_capacity(n);
            let mut xi = vec![0.0; d];
            for i in 0..n {
                for k in 0..d {
                    xi[k] = x[(i, k)];
                }
                factors.push(sc.check(&xi, &format!("x row {i}"))?);
            }
            yscaled = Mat::from_fn(n, m, |i, j| y[(i, j)] / factors[i]);
            yscaled.as_ref()
        } else {
            y
        };
        let ylog;
        let y = if settings.log_outputs {
            for j in 0..m {
                if let Some(i) = (0..n).find(|&i| y[(i, j)] <= 0.0) {
                    return Err(SurrogateError::InvalidInput(format!(
                        "log outputs need y > 0, but y row {i}, column {j} is {}",
                        y[(i, j)]
                    )));
                }
            }
            ylog = Mat::from_fn(n, m, |i, j| y[(i, j)].ln());
            ylog.as_ref()
        } else {
            y
        };
        let xlog;
        let x = if settings.log_inputs.is_empty() {
            x
        } else {
            let li = &settings.log_inputs;
            if li.len() != d {
                return Err(SurrogateError::InvalidSettings(format!(
                    "log_inputs has {} flags for {d} inputs",
                    li.len()
                )));
            }
            for k in (0..d).filter(|&k| li[k]) {
                if let Some(i) = (0..n).find(|&i| x[(i, k)] <= 0.0) {
                    return Err(SurrogateError::InvalidInput(format!(
                        "input {k} is kriged in ln x but x row {i}, column {k} is {}",
                        x[(i, k)]
                    )));
                }
            }
            xlog = Mat::from_fn(n, d, |i, k| if li[k] { x[(i, k)].ln() } else { x[(i, k)] });
            xlog.as_ref()
        };
        let (x_mean, x_std): (Vec<f64>, Vec<f64>) = (0..d)
            .map(|k| mean_std(x.col(k).iter().copied(), n))
            .unzip();
        let (y_mean, y_std): (Vec<f64>, Vec<f64>) = (0..m)
            .map(|j| mean_std(y.col(j).iter().copied(), n))
            .unzip();
        let s = Mat::from_fn(n, d, |i, k| (x[(i, k)] - x_mean[k]) / x_std[k]);
        let ys = Mat::from_fn(n, m, |i, j| (y[(i, j)] - y_mean[j]) / y_std[j]);

        // Output rotation: PCA (truncated) or, for θ only, the exact
        // full-rank rotation when m > n (ψ is invariant under it).
        let need_rotation = settings.pca_energy.is_some() || m > n;
        let rot = if need_rotation {
            Some(principal_components(ys.as_ref())?)
        } else {
            None
        };
        let (kriged, pca, energy) = match (&rot, settings.pca_energy) {
            (Some(r), Some(e)) => {
                let k = r.components_for(e);
                let z = r.scores(k);
                let energy = r.energy(k);
                let basis = r.basis(ys.as_ref(), k);
                (
                    z,
                    Some(Pca {
                        n_components: k,
                        energy,
                        basis: to_vec(basis.as_ref()),
                        residual_cov: Vec::new(),
                    }),
                    energy,
                )
            }
            _ => (ys.clone(), None, 1.0),
        };
        let theta_outputs = match (&rot, &pca) {
            (Some(r), None) => r.scores(r.rank()),
            _ => kriged.clone(),
        };

        let nuggets: Vec<f64> = if settings.auto_nugget {
            std::iter::once(settings.nugget)
                .chain(
                    [1e-10, 1e-8, 1e-6, 1e-4]
                        .into_iter()
                        .filter(|&v| v > settings.nugget),
                )
                .collect()
        } else {
            vec![settings.nugget]
        };
        let mut last_theta = Vec::new();
        for &nugget in &nuggets {
            let max_cond = if settings.auto_nugget {
                1e13
            } else {
                f64::INFINITY
            };
            let mut prob = Problem::new(
                s.as_ref(),
                theta_outputs.as_ref(),
                settings.regression,
                settings.correlation,
                nugget,
            );
            prob.max_cond = max_cond;
            let (res, search, screen_evaluations) = search_theta(&prob, &settings.theta)?;
            last_theta = res.theta.clone();
            if !res.psi.is_finite() {
                continue;
            }
            let mut prob = Problem::new(
                s.as_ref(),
                kriged.as_ref(),
                settings.regression,
                settings.correlation,
                nugget,
            );
            prob.max_cond = max_cond;
            let Eval::Ok(fac) = prob.eval(&res.theta)? else {
                continue;
            };
            let Factors {
                c,
                ft,
                g,
                beta,
                rho,
                sigma2,
                psi,
            } = *fac;
            let mut pca = pca;
            if let Some(pc) = pca.as_mut() {
                let cov = rho.transpose() * &rho;
                pc.residual_cov = to_vec(cov.as_ref()).iter().map(|v| v / n as f64).collect();
            }
            let mut gamma = rho;
            solve_upper_triangular_in_place(c.transpose(), gamma.as_mut(), Par::rayon(0));
            let report = FitReport {
                theta: res.theta.clone(),
                psi,
                evaluations: res.evaluations,
                screen_evaluations,
                search: search.to_string(),
                nugget,
                kriged_outputs: kriged.ncols(),
                energy,
            };
            return Ok(KrigingModel {
                regression: settings.regression,
                correlation: settings.correlation,
                theta: res.theta,
                dim: d,
                n_sites: n,
                n_outputs: m,
                x_mean,
                x_std,
                y_mean,
                y_std,
                sites: to_vec(s.as_ref()),
                beta: to_vec(beta.as_ref()),
                gamma: to_vec(gamma.as_ref()),
                sigma2,
                factors: variance::MseFactors::new(c, ft, g).into(),
                pca,
                log_outputs: settings.log_outputs,
                output_scale: settings.output_scale,
                log_inputs: settings.log_inputs.clone(),
                report,
            });
        }
        Err(SurrogateError::NotPositiveDefinite {
            theta: last_theta,
            nugget: nuggets.last().copied().unwrap_or(0.0),
        })
    }

    /// Number of kriged outputs q (m, or the number of kept components).
    pub fn n_kriged(&self) -> usize {
        self.sigma2.len()
    }

    fn p(&self) -> usize {
        self.regression.n_terms(self.dim)
    }

    fn check_x(&self, x: &[f64]) -> Result<()> {
        if x.len() != self.dim {
            return Err(SurrogateError::InvalidInput(format!(
                "point has {} coordinates, the model has {} inputs",
                x.len(),
                self.dim
            )));
        }
        if let Some(k) = x.iter().position(|v| !v.is_finite()) {
            return Err(SurrogateError::InvalidInput(format!(
                "coordinate {k} is not finite"
            )));
        }
        Ok(())
    }

    /// The model's internal coordinates of a caller's point (ln x_k for
    /// log inputs), after the length/finiteness checks.
    fn internal_x(&self, x: &[f64]) -> Result<Vec<f64>> {
        self.check_x(x)?;
        if self.log_inputs.is_empty() {
            return Ok(x.to_vec());
        }
        x.iter()
            .zip(&self.log_inputs)
            .enumerate()
            .map(|(k, (&v, &lg))| {
                if !lg {
                    Ok(v)
                } else if v > 0.0 {
                    Ok(v.ln())
                } else {
                    Err(SurrogateError::InvalidInput(format!(
                        "coordinate {k} = {v}: the model krige ln x_{k}, so it must be > 0"
                    )))
                }
            })
            .collect()
    }

    /// d(internal x_k)/dx_k (1/x_k for log inputs).
    fn dinternal(&self, x: &[f64], k: usize) -> f64 {
        if self.log_inputs.get(k).copied().unwrap_or(false) {
            1.0 / x[k]
        } else {
            1.0
        }
    }

    /// Scaled kriged prediction (f, r, z) at normalised point xn.
    fn scaled(&self, xn: &[f64], r: &mut [f64], f: &mut [f64], z: &mut [f64]) {
        let (n, d) = (self.n_sites, self.dim);
        self.regression.eval(xn, f);
        let mut dx = vec![0.0; d];
        for i in 0..n {
            for k in 0..d {
                dx[k] = xn[k] - self.sites[k * n + i];
            }
            r[i] = self.correlation.value(&self.theta, &dx);
        }
        self.combine(f, r, z);
    }

    /// z = βᵀf + γᵀr for every kriged output.
    fn combine(&self, f: &[f64], r: &[f64], z: &mut [f64]) {
        let (n, q, p) = (self.n_sites, self.n_kriged(), self.p());
        // z = βᵀf + γᵀr: a gemv over the n × q matrix γ (memory bound when
        // q = m is large: n·m·8 bytes per curve), parallel above ~1e6 entries.
        let par = if n * q > 1 << 20 {
            Par::rayon(0)
        } else {
            Par::Seq
        };
        let mut zm = MatMut::from_column_major_slice_mut(z, q, 1);
        faer::linalg::matmul::matmul(
            zm.as_mut(),
            Accum::Replace,
            view(&self.gamma, n, q).transpose(),
            MatRef::from_column_major_slice(r, n, 1),
            1.0,
            par,
        );
        faer::linalg::matmul::matmul(
            zm,
            Accum::Add,
            view(&self.beta, p, q).transpose(),
            MatRef::from_column_major_slice(f, p, 1),
            1.0,
            Par::Seq,
        );
    }

    /// Map kriged values z (normalised outputs or PC scores) to outputs.
    fn unscale(&self, z: &[f64], out: &mut [f64], add_mean: bool) {
        let m = self.n_outputs;
        match &self.pca {
            None => out.copy_from_slice(z),
            Some(pca) => {
                out.iter_mut().for_each(|v| *v = 0.0);
                for (k, zk) in z.iter().enumerate() {
                    let col = &pca.basis[k * m..(k + 1) * m];
                    for j in 0..m {
                        out[j] += col[j] * zk;
                    }
                }
            }
        }
        for j in 0..m {
            out[j] *= self.y_std[j];
            if add_mean {
                out[j] += self.y_mean[j];
            }
        }
    }

    /// Predictor ŷ(x) (report eq. 2.16), m values.
    ///
    /// # Errors
    /// `x` of the wrong length or not finite.
    pub fn predict(&self, x: &[f64]) -> Result<Vec<f64>> {
        let xi = self.internal_x(x)?;
        let xn: Vec<f64> = (0..self.dim)
            .map(|k| (xi[k] - self.x_mean[k]) / self.x_std[k])
            .collect();
        let mut r = vec![0.0; self.n_sites];
        let mut f = vec![0.0; self.p()];
        let mut z = vec![0.0; self.n_kriged()];
        self.scaled(&xn, &mut r, &mut f, &mut z);
        let mut y = vec![0.0; self.n_outputs];
        self.unscale(&z, &mut y, true);
        if self.log_outputs {
            y.iter_mut().for_each(|v| *v = v.exp());
        }
        if let Some(sc) = self.output_scale {
            let s = sc.check(x, "the prediction point")?;
            y.iter_mut().for_each(|v| *v *= s);
        }
        Ok(y)
    }

    /// Predictor at many points (rows of `x`, n_points × d) → n_points × m.
    pub fn predict_many(&self, x: MatRef<'_, f64>) -> Result<Mat<f64>> {
        use rayon::prelude::*;
        let rows: Vec<Vec<f64>> = (0..x.nrows())
            .into_par_iter()
            .map(|i| {
                let xi: Vec<f64> = (0..x.ncols()).map(|k| x[(i, k)]).collect();
                self.predict(&xi)
            })
            .collect::<Result<_>>()?;
        Ok(Mat::from_fn(rows.len(), self.n_outputs, |i, j| rows[i][j]))
    }

    /// Process variance σ² of each original output in its own units
    /// (DACE's `dmodel.sigma2`); with an [`OutputScale`] it is that of the
    /// kriged u = y/s (the variance of y at x is s(x)²σ²), with ln outputs
    /// that of ln y (or ln u).
    pub fn process_variance(&self) -> Vec<f64> {
        let m = self.n_outputs;
        match &self.pca {
            None => (0..m)
                .map(|j| self.sigma2[j] * self.y_std[j].powi(2))
                .collect(),
            Some(pca) => {
                let k = pca.n_components;
                (0..m)
                    .map(|j| {
                        let mut s = 0.0;
                        for a in 0..k {
                            for b in 0..k {
                                s += pca.basis[a * m + j]
                                    * pca.basis[b * m + j]
                                    * pca.residual_cov[b * k + a];
                            }
                        }
                        s * self.y_std[j].powi(2)
                    })
                    .collect()
            }
        }
    }

    /// Size of the basis φ(x) = [f(x); r(x)] of [`KrigingModel::basis`]:
    /// regression terms p plus design sites n.
    pub fn n_basis(&self) -> usize {
        self.p() + self.n_sites + usize::from(self.output_scale.is_some())
    }

    /// The predictor written as ŷ(x) = μ + Bᵀφ(x) (report eq. 2.16 with the
    /// output scaling and any PCA rotation folded into B): returns B,
    /// column-major `n_basis() × m`, and μ (the output means, m values).
    /// With an [`OutputScale`] s(x), ŷ = s·(μ + Bᵀφ) = [B; μᵀ]ᵀ[sφ; s]: B
    /// gets μᵀ as a last row and the returned μ is 0. Not valid for a
    /// model with `log_outputs` (ŷ is then not linear in any basis).
    /// Cost O(n_basis · q · m) once per model; used by the fast eq. 5.3
    /// misfit of the inverse stage.
    pub fn basis_coefficients(&self) -> (Vec<f64>, Vec<f64>) {
        let (n, p, q, m) = (self.n_sites, self.p(), self.n_kriged(), self.n_outputs);
        let nb = p + n;
        // C = [β; γ], nb × q (column j holds kriged output j).
        let c = |a: usize, j: usize| {
            if a < p {
                self.beta[j * p + a]
            } else {
                self.gamma[j * n + (a - p)]
            }
        };
        let mut b = vec![0.0; nb * m];
        let mut row = vec![0.0; q];
        let mut out = vec![0.0; m];
        for a in 0..nb {
            for (j, v) in row.iter_mut().enumerate() {
                *v = c(a, j);
            }
            self.unscale(&row, &mut out, false);
            for j in 0..m {
                b[j * nb + a] = out[j];
            }
        }
        if self.output_scale.is_none() {
            return (b, self.y_mean.clone());
        }
        let nb1 = nb + 1;
        let mut b1 = vec![0.0; nb1 * m];
        for j in 0..m {
            b1[j * nb1..j * nb1 + nb].copy_from_slice(&b[j * nb..(j + 1) * nb]);
            b1[j * nb1 + nb] = self.y_mean[j];
        }
        (b1, vec![0.0; m])
    }

    /// The basis φ(x) = [f(x); r(x)] (p regression terms, then the n
    /// correlations with the design sites, at the normalised point) and
    /// ∂φ/∂x with respect to the *unnormalised* x, row-major
    /// `n_basis() × d`.
    ///
    /// # Errors
    /// `x` of the wrong length or not finite.
    pub fn basis(&self, x: &[f64]) -> Result<(Vec<f64>, Vec<f64>)> {
        let xi = self.internal_x(x)?;
        let (n, d, p) = (self.n_sites, self.dim, self.p());
        let xn: Vec<f64> = (0..d)
            .map(|k| (xi[k] - self.x_mean[k]) / self.x_std[k])
            .collect();
        let mut phi = vec![0.0; p + n];
        let mut dphi = vec![0.0; (p + n) * d];
        self.regression.eval(&xn, &mut phi[..p]);
        let mut df = vec![0.0; d * p];
        self.regression.jacobian(&xn, &mut df);
        for l in 0..p {
            for k in 0..d {
                dphi[l * d + k] = df[k * p + l] / self.x_std[k];
            }
        }
        let mut dx = vec![0.0; d];
        let mut g = vec![0.0; d];
        for i in 0..n {
            for k in 0..d {
                dx[k] = xn[k] - self.sites[k * n + i];
            }
            phi[p + i] = self.correlation.value_and_grad_d(&self.theta, &dx, &mut g);
            for k in 0..d {
                dphi[(p + i) * d + k] = g[k] / self.x_std[k];
            }
        }
        for k in 0..d {
            let dk = self.dinternal(x, k);
            if dk != 1.0 {
                for a in 0..p + n {
                    dphi[a * d + k] *= dk;
                }
            }
        }
        if let Some(sc) = self.output_scale {
            let (sv, ds) = sc.eval(x);
            sc.check(x, "the basis point")?;
            let kk = sc.input();
            for a in 0..p + n {
                for k in 0..d {
                    dphi[a * d + k] *= sv;
                }
                dphi[a * d + kk] += ds * phi[a];
                phi[a] *= sv;
            }
            phi.push(sv);
            dphi.extend((0..d).map(|k| if k == kk { ds } else { 0.0 }));
        }
        Ok((phi, dphi))
    }

    /// Predictor, its gradient, MSE and MSE gradient at x (report eqs.
    /// 2.16, 2.19–2.20; DACE `predictor` with four outputs).
    ///
    /// # Errors
    /// `x` of the wrong length or not finite.
    pub fn predict_full(&self, x: &[f64]) -> Result<PointPrediction> {
        let xi = self.internal_x(x)?;
        let mut pp = self.predict_full_unscaled(&xi)?;
        let d = self.dim;
        for k in 0..d {
            let dk = self.dinternal(x, k);
            if dk != 1.0 {
                for j in 0..pp.y.len() {
                    pp.dy[j * d + k] *= dk;
                    pp.dmse[j * d + k] *= dk;
                }
            }
        }
        let Some(sc) = self.output_scale else {
            return Ok(pp);
        };
        // y = s·u: ∂y = s∂u + u∂s, MSE_y = s²MSE_u, ∂MSE_y = s²∂MSE_u + 2s∂s MSE_u.
        let s = sc.check(x, "the prediction point")?;
        let (_, ds) = sc.eval(x);
        let kk = sc.input();
        let PointPrediction {
            mut y,
            mut dy,
            mut mse,
            mut dmse,
        } = pp;
        for j in 0..y.len() {
            for k in 0..d {
                dy[j * d + k] *= s;
                dmse[j * d + k] *= s * s;
            }
            dy[j * d + kk] += y[j] * ds;
            dmse[j * d + kk] += 2.0 * s * ds * mse[j];
            y[j] *= s;
            mse[j] *= s * s;
        }
        Ok(PointPrediction { y, dy, mse, dmse })
    }

    fn predict_full_unscaled(&self, x: &[f64]) -> Result<PointPrediction> {
        let (n, d, q, p, m) = (
            self.n_sites,
            self.dim,
            self.n_kriged(),
            self.p(),
            self.n_outputs,
        );
        let xn: Vec<f64> = (0..d)
            .map(|k| (x[k] - self.x_mean[k]) / self.x_std[k])
            .collect();
        let mut f = vec![0.0; p];
        self.regression.eval(&xn, &mut f);
        let mut df = vec![0.0; d * p];
        self.regression.jacobian(&xn, &mut df);
        let mut r = Mat::<f64>::zeros(n, 1);
        let mut dr = Mat::<f64>::zeros(n, d);
        let mut dx = vec![0.0; d];
        let mut g = vec![0.0; d];
        for i in 0..n {
            for k in 0..d {
                dx[k] = xn[k] - self.sites[k * n + i];
            }
            r[(i, 0)] = self.correlation.value_and_grad_d(&self.theta, &dx, &mut g);
            for k in 0..d {
                dr[(i, k)] = g[k];
            }
        }
        // Scaled predictor and Jacobian dz (q × d).
        let mut z = vec![0.0; q];
        let mut dz = vec![0.0; q * d];
        let rv: Vec<f64> = r.col(0).iter().copied().collect();
        self.combine(&f, &rv, &mut z);
        for j in 0..q {
            let b = &self.beta[j * p..(j + 1) * p];
            let gm = &self.gamma[j * n..(j + 1) * n];
            for k in 0..d {
                dz[j * d + k] = dot(&df[k * p..(k + 1) * p], b)
                    + (0..n).map(|i| dr[(i, k)] * gm[i]).sum::<f64>();
            }
        }
        // MSE factor φ = 1 + |v|² − |rt|², rt = C⁻¹r, v = G⁻ᵀ(F̃ᵀrt − f).
        let fac = self.mse_factors()?;
        let (c, ft, gmat) = (fac.c(n), fac.ft(n, p), fac.g(p));
        let mut rt = r.clone();
        solve_lower_triangular_in_place(c, rt.as_mut(), Par::Seq);
        let mut v = ft.transpose() * &rt;
        for k in 0..p {
            v[(k, 0)] -= f[k];
        }
        solve_lower_triangular_in_place(gmat.transpose(), v.as_mut(), Par::Seq);
        let phi = 1.0 + v.col(0).iter().map(|a| a * a).sum::<f64>()
            - rt.col(0).iter().map(|a| a * a).sum::<f64>();
        // ∂φ/2 = (F̃ Gv − rt)ᵀ C⁻¹ dr − (df Gv)ᵀ, Gv = G⁻¹v.
        let mut gv = v.clone();
        solve_upper_triangular_in_place(gmat, gv.as_mut(), Par::Seq);
        let mut w = Mat::<f64>::zeros(n, 1);
        faer::linalg::matmul::matmul(w.as_mut(), Accum::Replace, ft, gv.as_ref(), 1.0, Par::Seq);
        for i in 0..n {
            w[(i, 0)] -= rt[(i, 0)];
        }
        // (C⁻¹dr)ᵀ w = drᵀ (C⁻ᵀ w)
        solve_upper_triangular_in_place(c.transpose(), w.as_mut(), Par::Seq);
        let half_dphi: Vec<f64> = (0..d)
            .map(|k| {
                (0..n).map(|i| dr[(i, k)] * w[(i, 0)]).sum::<f64>()
                    - (0..p).map(|l| df[k * p + l] * gv[(l, 0)]).sum::<f64>()
            })
            .collect();

        let mut y = vec![0.0; m];
        self.unscale(&z, &mut y, true);
        let mut dy = vec![0.0; m * d];
        let mut col = vec![0.0; q];
        let mut out = vec![0.0; m];
        for k in 0..d {
            for j in 0..q {
                col[j] = dz[j * d + k];
            }
            self.unscale(&col, &mut out, false);
            for j in 0..m {
                dy[j * d + k] = out[j] / self.x_std[k];
            }
        }
        let pv = self.process_variance();
        let mse: Vec<f64> = pv.iter().map(|s| s * phi).collect();
        let mut dmse = vec![0.0; m * d];
        for j in 0..m {
            for k in 0..d {
                dmse[j * d + k] = 2.0 * pv[j] * half_dphi[k] / self.x_std[k];
            }
        }
        if self.log_outputs {
            // y = exp(ŷ_ln); MSE by the delta method, MSE_y ≈ y²·MSE_ln.
            let (mut y, mut dy, mut mse, mut dmse) = (y, dy, mse, dmse);
            for j in 0..m {
                y[j] = y[j].exp();
                let y2 = y[j] * y[j];
                for k in 0..d {
                    dmse[j * d + k] = 2.0 * y2 * dy[j * d + k] * mse[j] + y2 * dmse[j * d + k];
                    dy[j * d + k] *= y[j];
                }
                mse[j] *= y2;
            }
            return Ok(PointPrediction { y, dy, mse, dmse });
        }
        Ok(PointPrediction { y, dy, mse, dmse })
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Eigen-decomposition of the Gram matrix Ys Ysᵀ (n × n), eigenvalues
/// descending: Ys = U Λ^{1/2} Vᵀ.
struct Rotation {
    lambda: Vec<f64>,
    u: Mat<f64>,
}

fn principal_components(ys: MatRef<'_, f64>) -> Result<Rotation> {
    let n = ys.nrows();
    let mut gram = Mat::<f64>::zeros(n, n);
    faer::linalg::matmul::matmul(
        gram.as_mut(),
        Accum::Replace,
        ys,
        ys.transpose(),
        1.0,
        Par::rayon(0),
    );
    let evd = gram.self_adjoint_eigen(Side::Lower).map_err(|e| {
        SurrogateError::InvalidInput(format!(
            "eigen-decomposition of the output Gram matrix failed: {e:?}"
        ))
    })?;
    let s = evd.S();
    let uu = evd.U();
    // faer sorts ascending; reverse.
    let lambda: Vec<f64> = (0..n).rev().map(|i| s[i].max(0.0)).collect();
    let u = Mat::from_fn(n, n, |i, j| uu[(i, n - 1 - j)]);
    Ok(Rotation { lambda, u })
}

impl Rotation {
    fn total(&self) -> f64 {
        self.lambda.iter().sum()
    }
    fn rank(&self) -> usize {
        let tol = self.lambda.first().copied().unwrap_or(0.0) * 1e-13;
        self.lambda.iter().take_while(|&&l| l > tol).count().max(1)
    }
    fn components_for(&self, energy: f64) -> usize {
        let tot = self.total();
        if tot <= 0.0 {
            return 1;
        }
        let mut acc = 0.0;
        for (k, l) in self.lambda.iter().enumerate() {
            acc += l;
            if acc >= energy * tot {
                return (k + 1).min(self.rank());
            }
        }
        self.rank()
    }
    fn energy(&self, k: usize) -> f64 {
        let tot = self.total();
        if tot <= 0.0 {
            1.0
        } else {
            self.lambda[..k].iter().sum::<f64>() / tot
        }
    }
    /// Scores Z = U_k Λ_k^{1/2} (n × k).
    fn scores(&self, k: usize) -> Mat<f64> {
        Mat::from_fn(self.u.nrows(), k, |i, j| {
            self.u[(i, j)] * self.lambda[j].sqrt()
        })
    }
    /// Basis V_k = Ysᵀ U_k Λ_k^{−1/2} (m × k).
    fn basis(&self, ys: MatRef<'_, f64>, k: usize) -> Mat<f64> {
        let uk = Mat::from_fn(self.u.nrows(), k, |i, j| {
            self.u[(i, j)] / self.lambda[j].sqrt()
        });
        let mut v = Mat::<f64>::zeros(ys.ncols(), k);
        faer::linalg::matmul::matmul(
            v.as_mut(),
            Accum::Replace,
            ys.transpose(),
            uk.as_ref(),
            1.0,
            Par::rayon(0),
        );
        v
    }
}

/// Run the configured θ search on a problem.
fn search_theta(
    prob: &Problem<'_>,
    search: &ThetaSearch,
) -> Result<(SearchResult, &'static str, usize)> {
    match search {
        ThetaSearch::Fixed(t) => {
            let psi = match prob.eval(t)? {
                Eval::Ok(f) => f.psi,
                Eval::Infeasible => f64::INFINITY,
            };
            Ok((
                SearchResult {
                    theta: t.clone(),
                    psi,
                    evaluations: 1,
                },
                "fixed",
                0,
            ))
        }
        ThetaSearch::Boxmin {
            theta0,
            lower,
            upper,
        } => {
            let mut obj = |t: &[f64]| -> Result<f64> {
                Ok(match prob.eval(t)? {
                    Eval::Ok(f) => f.psi,
                    Eval::Infeasible => f64::INFINITY,
                })
            };
            Ok((boxmin(theta0, lower, upper, &mut obj)?, "boxmin", 0))
        }
        ThetaSearch::Optimise {
            theta0,
            lower,
            upper,
            settings,
        } => {
            let n = prob.s.nrows();
            let ns = settings.screen_sites;
            if ns > 0 && n > 2 * ns && ns >= prob.f.ncols() + 2 {
                // Multistart on a seeded random subset, then one start on all sites.
                let mut rng = ChaCha8Rng::seed_from_u64(settings.seed ^ 0x5EED);
                let mut idx: Vec<usize> = (0..n).collect();
                for i in (1..n).rev() {
                    let j = rng.random_range(0..=i);
                    idx.swap(i, j);
                }
                idx.truncate(ns);
                idx.sort_unstable();
                let ss = Mat::from_fn(ns, prob.s.ncols(), |i, k| prob.s[(idx[i], k)]);
                let ys = Mat::from_fn(ns, prob.y.ncols(), |i, j| prob.y[(idx[i], j)]);
                let mut sub = Problem::new(
                    ss.as_ref(),
                    ys.as_ref(),
                    prob.regression,
                    prob.corr,
                    prob.diag_add - (10.0 + n as f64) * f64::EPSILON,
                );
                sub.max_cond = prob.max_cond;
                let screen = minimise(theta0, lower, upper, settings, &mut lazy_objective(&sub))?;
                let start = if screen.psi.is_finite() {
                    screen.theta
                } else {
                    theta0.clone()
                };
                let one = OptimiserSettings {
                    starts: 1,
                    max_iter: settings.refine_iter,
                    ..settings.clone()
                };
                let mut res = minimise(&start, lower, upper, &one, &mut lazy_objective(prob))?;
                res.evaluations += screen.evaluations;
                return Ok((res, "optimise (screened)", screen.evaluations));
            }
            Ok((
                minimise(theta0, lower, upper, settings, &mut lazy_objective(prob))?,
                "optimise",
                0,
            ))
        }
    }
}

/// The optimiser's objective on a problem: ln ψ, and its gradient only
/// when asked, from the factors of the last evaluation when θ is the same.
fn lazy_objective<'p>(prob: &'p Problem<'_>) -> impl FnMut(&[f64], bool) -> Result<LogValue> + 'p {
    let mut last: Option<(Vec<f64>, Box<Factors>)> = None;
    move |t: &[f64], want_grad: bool| {
        let fac = match last.take() {
            Some((lt, f)) if lt == t => f,
            _ => match prob.eval(t)? {
                Eval::Ok(f) => f,
                Eval::Infeasible => return Ok(None),
            },
        };
        let lnpsi = fac.psi.ln();
        let grad = if want_grad {
            prob.grad_log_psi(t, &fac)
        } else {
            Vec::new()
        };
        last = Some((t.to_vec(), fac));
        Ok(Some((lnpsi, grad)))
    }
}

/// ψ(θ) for sites and outputs as given (normalised as in a fit, no PCA),
/// for reports and tests; `f64::INFINITY` where R is not positive definite.
pub fn likelihood_psi(
    x: MatRef<'_, f64>,
    y: MatRef<'_, f64>,
    regression: Regression,
    correlation: Correlation,
    theta: &[f64],
) -> Result<f64> {
    let (n, d, m) = (x.nrows(), x.ncols(), y.ncols());
    let (xm, xs): (Vec<f64>, Vec<f64>) = (0..d)
        .map(|k| mean_std(x.col(k).iter().copied(), n))
        .unzip();
    let (ymn, ysd): (Vec<f64>, Vec<f64>) = (0..m)
        .map(|j| mean_std(y.col(j).iter().copied(), n))
        .unzip();
    let s = Mat::from_fn(n, d, |i, k| (x[(i, k)] - xm[k]) / xs[k]);
    let ys = Mat::from_fn(n, m, |i, j| (y[(i, j)] - ymn[j]) / ysd[j]);
    let prob = Problem::new(s.as_ref(), ys.as_ref(), regression, correlation, 0.0);
    Ok(match prob.eval(theta)? {
        Eval::Ok(f) => f.psi,
        Eval::Infeasible => f64::INFINITY,
    })
}
