//! Inverse analysis: misfit (eq. 5.3), multistart constrained fits of one or several experiments, identifiability (thesis §3.1, §4.4, §5.4).

#![warn(missing_docs)]

mod domain;
mod error;
mod hertz;
mod identifiability;
mod measured;
mod misfit;
mod model;
mod optimise;
mod prony;
mod starts;

pub use domain::{BoundHit, BoundSide, Domain, LinearConstraint, Parameter, Scale};
pub use error::{InverseError, Result};
pub use hertz::{LeeRadokHertz, ramp_hold_grid, ramp_hold_indentation};
pub use identifiability::{Identifiability, SensitivityScaling, Z95, identifiability};
pub use measured::{
    AfmColumns, Calibration, CompressionColumns, Dimension, MeasuredCurve, ProtocolTolerance,
    read_afm_csv, read_compression_csv,
};
pub use misfit::{Experiment, Misfit, Segment, range_normalised_rmse, segment_weights};
pub use model::{FD_STEP_UNIT, Model, check_finite, check_len, fd_jacobian};
pub use optimise::{FitResult, LocalOptimum, MultiStart, Verification, verify};
pub use prony::{ModulusPoint, ParameterTable, PronyShear, PronyTerm};
pub use starts::{feasible_starts, latin_hypercube};
