//! Cohorts of cells, the HTML report and the bundled demo (thesis §5.2.3,
//! §5.4.2, Figs. 5.3–5.8 and 5.14–5.19, App. A).
//!
//! What it models:
//! - [`settings`]: the study's `[fit]` section, one reader for `nlvid fit`
//!   and `nlvid cohort`, and what a cohort reads besides it;
//! - [`fit`]: one parameter set fitted to one or several curves on
//!   surrogates, re-checked with the real model (`nlvid fit`);
//! - [`cell`]: one cell — its AFM curve read (F = k d, δ = Z − d), the five
//!   Prony parameters of eq. 5.1 fitted with the misfit of eq. 5.3 in the
//!   Table 5.3 domain on a pre-built Kriging meta-model (or the analytic
//!   Lee–Radok model), the Hertz baseline (eq. 1.1) of the loading ramp,
//!   the cell's height (eq. B.1) and base diameter √(d1·d2) when given,
//!   peak force and relaxation of the peak-normalised curve; a failed cell
//!   is a result with its reason, never an error;
//! - [`cohort`]: every cell in parallel, one result file per cell written
//!   atomically (a re-run fits only what is missing), the results table in
//!   the format of docs/cli/compare.md;
//! - [`report`]: the self-contained HTML page with inline SVG figures
//!   (data overview, per-cell fits, group G(t) with p(t), tables);
//! - [`uncertainty`]: group bands of the mean G(t) and the rank-sum p(t)
//!   over posterior draws, from the cells' posteriors (study `[posterior]`);
//! - [`demo`]: the bundled example's curve writer: two groups of cells made
//!   by the study's forward model from known distributions, with noise.
//!
//! The bundled demo fits on an N = 970 meta-model of the FE cell model
//! (`afm-fe`, setup 1) and its cells' curves are made by that FE model.
//!
//! Cost: a cell costs one multistart fit (8 SLSQP starts; on a meta-model
//! of N training runs each misfit evaluation is O(N²), tens of ms per cell
//! for N = 400); reading the meta-model and its Gram matrix (O(N²·m)) is
//! paid once per cohort; a report is dominated by SVG drawing (well under a
//! second for tens of cells).
//!
//! ```no_run
//! use std::path::Path;
//! use nlvid_report::{cohort, report, settings::CohortSettings};
//! # fn main() -> nlvid_report::Result<()> {
//! let study = Path::new("examples/demo/study.toml");
//! let input = Path::new("examples/demo/data");
//! let settings = CohortSettings::load(study)?;
//! let cells = cohort::discover(input)?;
//! let out = Path::new("demo-out");
//! let run = cohort::run_cohort(&settings, study, input, &cells, out, &Default::default())?;
//! assert_eq!(run.pending, 0);
//! let page = report::write_report(out, &report::ReportOptions::default())?;
//! println!("report: {}", page.html.display());
//! # Ok(())
//! # }
//! ```

#![warn(missing_docs)]

pub mod cell;
pub mod check;
pub mod cohort;
pub mod compare;
pub mod demo;
mod error;
mod figures;
pub mod fit;
mod input;
pub mod report;
pub mod settings;
pub mod uncertainty;

pub use error::{ReportError, Result};
