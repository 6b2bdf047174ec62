//! Inverse analysis: find the material parameters whose predicted
//! force–time curve(s) best reproduce measured ones (thesis §3.1, §4.4.1
//! step 5, §4.4.2, §5.4.1, App. A.2).
//!
//! What it models:
//! - [`Model`]: any forward model (Kriging surrogate, membrane or FE run,
//!   or the analytic [`LeeRadokHertz`]) maps parameters in a bounded
//!   `nlvid_model::Domain` (named, unit-carrying, log-scaled where they span
//!   decades, linear constraints such as g1 + g2 ≤ 1 − ε, one parameter
//!   order) to a curve on a fixed time grid, with an analytic or
//!   finite-difference Jacobian;
//! - [`Misfit`]: the range-normalised RMSE of eq. 5.3, with optional
//!   per-segment weights, summed over experiments fitted with one
//!   parameter set, and its gradient; [`BasisMisfit`] computes the same
//!   value in O(N²) for Kriging-form models y = μ + Bᵀφ(x) ([`BasisModel`]),
//!   [`ReducedMisfit`] in the reduced output space of a PCA-reduced
//!   surrogate ŷ = A c(x) ([`ReducedModel`]: O(N·q·n + r²) per evaluation,
//!   nothing growing with m), [`SurrogateMisfit`] picks the fast form per
//!   surrogate; all are [`Objective`]s;
//! - [`MultiStart`]: seeded feasible Latin-hypercube starts, SLSQP local
//!   runs, clustering into distinct optima, alternatives within a misfit
//!   tolerance, bound flags; [`verify`] re-scores the optimum with another
//!   (real) model, [`rerun`] with any `nlvid_model::ForwardModel` (same
//!   parameters in the same order, response interpolated onto the data
//!   grid);
//! - [`FixedInputs`], [`Fixed`]: some model inputs held at known values
//!   (a cell's measured height and diameter on a meta-model that has them
//!   as inputs) while the others are fitted — the fit, the Gauss–Newton
//!   intervals and the posterior see the free parameters only;
//! - [`identifiability`]: scaled sensitivities, their singular values and
//!   Gauss–Newton confidence intervals;
//! - [`KrigingSurrogate`]: a `nlvid-surrogate` Kriging model as a [`Model`]
//!   and [`BasisModel`], on the domain its `meta.json` stores
//!   ([`load_kriging_surrogate`]); [`ForwardFromModel`] runs any [`Model`]
//!   through `nlvid_surrogate::build`;
//! - [`posterior`]: per-curve posteriors on a Kriging surrogate (noise
//!   estimated from the curve, Kriging MSE in the variance, uniform prior
//!   on the domain), an affine-invariant ensemble sampler, split R̂ and
//!   effective sample size, credible intervals and G(t) bands;
//! - [`relaxation`], [`FitResult::relaxation`]: G(t) of eq. 5.1 as the
//!   shared `nlvid_model::Relaxation` (E(t) = 3G(t));
//! - [`read_afm_csv`] / [`read_compression_csv`]: measured curves in, with
//!   protocol checks and resampling onto a model grid.
//!
//! Cost: a fit costs (starts × ~40–80 iterations) misfit evaluations, each
//! one model response plus, for gradient steps, one Jacobian; see
//! docs/theory/inverse.md for measured times.
//!
//! ```
//! use nlvid_inverse::{Experiment, LeeRadokHertz, Misfit, Model, MultiStart,
//!                     ramp_hold_grid, ramp_hold_indentation};
//! use nlvid_model::Domain;
//! # fn main() -> nlvid_inverse::Result<()> {
//! let domain = Domain::table_5_3(0.01)?; // G0, g1, g2, tau1, tau2
//! let t = ramp_hold_grid(0.2, 40, 52.0, 120, 1e-3)?;
//! let delta = ramp_hold_indentation(&t, 10e-6, 2e-6);
//! let model = LeeRadokHertz::new(domain.clone(), t, &delta, 2.5e-6, 0.5)?;
//! let x_true = [900.0, 0.5, 0.3, 0.05, 12.0];
//! let data = model.response(&x_true)?;
//! let misfit = Misfit::new(vec![Experiment::new("RH", model, data, None)?])?;
//! let fit = MultiStart::new().with_starts(4)?.with_seed(1).fit(&misfit)?;
//! assert!(fit.best.misfit < 1e-4);
//! let g = fit.relaxation()?;
//! assert!((g.value(0.0) / 900.0 - 1.0).abs() < 1e-2);
//! # Ok(())
//! # }
//! ```

#![warn(missing_docs)]

mod basis;
mod error;
mod fixed;
mod hertz;
mod identifiability;
mod measured;
mod misfit;
mod model;
mod optimise;
mod plausible;
mod plot;
pub mod posterior;
mod prony;
mod reduced;
mod rerun;
mod starts;
mod surrogate;
mod surrogate_file;

pub use basis::{AsModel, BasisExperiment, BasisMisfit, BasisModel, gram};
pub use error::{InverseError, Result};
pub use fixed::{Fixed, FixedInputs};
pub use hertz::{LeeRadokHertz, ramp_hold_grid, ramp_hold_indentation};
pub use identifiability::{Identifiability, SensitivityScaling, Z95, identifiability};
pub use measured::{
    AfmColumns, Calibration, CompressionColumns, MeasuredCurve, ProtocolTolerance, read_afm_csv,
    read_compression_csv,
};
pub use misfit::{
    Experiment, Misfit, MisfitTerm, Objective, Segment, SummedMisfit, range_normalised_rmse,
    segment_weights,
};
pub use model::{FD_STEP_UNIT, Model, check_finite, check_jacobian, check_len, fd_jacobian};
pub use optimise::{DEFAULT_STARTS, FitResult, LocalOptimum, MultiStart, Verification, verify};
pub use plausible::{Implausible, MAX_FORCE, MAX_LENGTH};
pub use plot::{FigureCurve, FitFigure};
pub use posterior::{Posterior, PosteriorSettings, sample_posterior, sample_posterior_fixed};
pub use prony::{ParameterTable, relaxation};
pub use reduced::{Projection, ReducedExperiment, ReducedMisfit, ReducedModel, projection};
pub use rerun::{Rerun, rerun};
pub use starts::feasible_starts;
pub use surrogate::{Coordinates, ForwardFromModel, KrigingSurrogate};
pub use surrogate_file::{
    Precomputed, SurrogateCurve, SurrogateFit, SurrogateFitter, SurrogateMeta, SurrogateMisfit,
    load_kriging_surrogate, read_meta,
};
