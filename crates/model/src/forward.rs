//! The forward-model contract: parameters (SI, in the order of
//! [`ForwardModel::parameter_names`]) → the response on a fixed time grid,
//! or a typed failure. The analytic Lee–Radok model, the membrane solver
//! and the finite-element models implement it (crate `nlvid-forward`);
//! meta-model builds, Kriging checks and fit re-checks call it.

use serde::{Deserialize, Serialize};

/// Why a run produced no response.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum FailureKind {
    /// A nonlinear or time-step iteration did not converge.
    NotConverged,
    /// The parameters are outside what the model accepts.
    InvalidParameters,
    /// The model returned something unusable (NaN, wrong length, …).
    BadResponse,
    /// Anything else (I/O of an external solver, …).
    Other,
}

/// A failed run: what, when (model time, if known) and a message saying
/// what to change.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunFailure {
    /// Category.
    pub kind: FailureKind,
    /// Model time at failure [s], if the model knows it.
    pub time: Option<f64>,
    /// Human-readable reason.
    pub message: String,
}

impl RunFailure {
    /// A failure of `kind` with no time.
    pub fn new(kind: FailureKind, message: impl Into<String>) -> Self {
        Self {
            kind,
            time: None,
            message: message.into(),
        }
    }
}

impl std::fmt::Display for RunFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.time {
            Some(t) => write!(f, "{:?} at t = {t:e} s: {}", self.kind, self.message),
            None => write!(f, "{:?}: {}", self.kind, self.message),
        }
    }
}

impl std::error::Error for RunFailure {}

/// A forward model: one run maps parameters to the response on
/// [`ForwardModel::time_grid`].
pub trait ForwardModel: Sync {
    /// Parameter names ([`crate::names`]), in the order of the parameter
    /// vector.
    fn parameter_names(&self) -> Vec<String>;
    /// SI units of the parameters (same order; `"1"` when dimensionless).
    fn parameter_units(&self) -> Vec<String>;
    /// The fixed time grid [s] of every response.
    fn time_grid(&self) -> &[f64];
    /// Name and SI unit of the response channel (e.g. `("force", "N")`).
    fn response(&self) -> (&str, &str) {
        ("force", "N")
    }
    /// Index of the first time point after contact (filters look from here).
    fn contact_index(&self) -> usize {
        0
    }
    /// Identifier included in the study hash (model name and settings).
    fn identity(&self) -> String;
    /// What the model is built for (protocol, time span, geometry), stored with a
    /// meta-model so fits can check data against it; `None` if not described.
    fn conditions(&self) -> Option<crate::BuildConditions> {
        None
    }
    /// Run at `params` (SI): the response at every time of the grid.
    fn run(&self, params: &[f64]) -> Result<Vec<f64>, RunFailure>;
}
