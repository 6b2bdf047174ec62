//! Design of experiments and DACE-equivalent Kriging surrogates with
//! checking errors (thesis ch. III, §4.4.1, §5.4.1, App. A.2).
//!
//! * [`KrigingModel`]: the DACE Kriging predictor (Lophaven, Nielsen &
//!   Søndergaard 2002) for many outputs sharing one correlation model —
//!   one Cholesky factorisation of R (n³/3 flops) per likelihood
//!   evaluation, all outputs as right-hand sides; predictor, MSE and
//!   their gradients. θ by DACE's `boxmin` or a multistart quasi-Newton
//!   search with analytic gradient (screened on a subset of sites for
//!   large n); optional nugget, principal component reduction of the
//!   outputs, ln outputs and exact output scaling y = s(x)·u(x)
//!   ([`OutputScale`], e.g. F ∝ G0).
//! * [`doe`]: Latin hypercubes (log axes, ESE optimisation, linear
//!   constraints) in an `nlvid_model::Domain`, separate training and
//!   checking sets.
//! * [`build`] runs an `nlvid_model::ForwardModel` (membrane, FE, analytic
//!   models of `nlvid-forward`) over a design in parallel into a crash-safe
//!   [`RunStore`] (atomic file per run, resumable, shardable, [`merge`]),
//!   [`load`] applies the admissibility filters, [`export`] writes
//!   `.npy`/CSV for numpy/pandas and a `meta.json` that stores the domain.
//! * [`slurm`]: a build as a Slurm job array (one shard per task) plus a
//!   merge job that waits for it; resumable, requeued when killed.
//! * [`infill`]: adaptive infill — a small Latin hypercube grown batch by
//!   batch where the predicted error is largest, up to a checking-error
//!   target or a run budget (`[design.infill]`).
//! * [`check`]: range-normalised RMSE (thesis eq. 4.4) on a checking set.
//!
//! ```
//! use faer::Mat;
//! use nlvid_surrogate::{Correlation, KrigingModel, KrigingSettings, Regression, ThetaSearch};
//! let x = Mat::from_fn(8, 1, |i, _| i as f64);
//! let y = Mat::from_fn(8, 1, |i, _| (i as f64).sin());
//! let mut s = KrigingSettings::new(Regression::Poly0, Correlation::Gauss, 1);
//! s.theta = ThetaSearch::Fixed(vec![1.0]);
//! let model = KrigingModel::fit(x.as_ref(), y.as_ref(), &s)?;
//! // Kriging interpolates the design sites.
//! assert!((model.predict(&[3.0])?[0] - 3f64.sin()).abs() < 1e-8);
//! # Ok::<(), nlvid_surrogate::SurrogateError>(())
//! ```

#![warn(missing_docs)]
// Index loops mirror the matrix formulas they implement.
#![allow(clippy::needless_range_loop)]

mod boxmin;
mod build;
pub mod check;
mod correlation;
pub mod doe;
mod error;
mod flag_build;
pub mod infill;
mod kriging;
mod likelihood;
pub mod optimise;
mod options;
mod regression;
pub mod slurm;
mod store;
mod study;
mod table;
mod trend;

pub use boxmin::{SearchResult, boxmin};
pub use build::{
    Admissibility, BuildOptions, BuildSummary, FilterCounts, MetaModel, Shard, build, export, load,
    write_npy,
};
pub use correlation::Correlation;
pub use error::{Result, SurrogateError};
pub use faer;
pub use flag_build::FlagBuild;
pub use kriging::{
    CalibrationData, FitReport, KrigingModel, KrigingSettings, OutputCovariance, OutputScale, Pca,
    PointPrediction, ThetaSearch, VarianceCalibration, VariancePoint, likelihood_psi,
};
pub use optimise::OptimiserSettings;
pub use options::FitOptions;
pub use regression::Regression;
pub use store::{RunOutcome, RunRecord, RunStore, StoreMeta, merge};
pub use study::{
    BuildSettings, BuildStudy, build_report, export_report, merge_report, read_domain, set_dir,
    shard_sets,
};
pub use table::{NamedModel, Predictions, Table, read_table, write_table};
pub use trend::{Trend, TrendTerm};
