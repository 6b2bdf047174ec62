//! Errors of the finite-element crate.

use nlvid_material::MaterialError;

/// Why a time step could not be completed, with what to change.
#[derive(Debug, Clone, PartialEq)]
pub struct NonConvergence {
    /// Last converged time t_n (s); the failing step started here.
    pub time: f64,
    /// Size of the last step tried (s), already at the minimum allowed.
    pub dt: f64,
    /// Residual norm reached at the last Newton iteration (N).
    pub residual: f64,
    /// Residual norm that would have counted as converged (N).
    pub tolerance: f64,
    /// Newton iterations used in the last attempt.
    pub iterations: usize,
    /// What failed in the last attempt (iteration limit, inverted element, …).
    pub cause: String,
}

/// What can go wrong in a finite-element run.
#[derive(Debug, thiserror::Error)]
pub enum FemError {
    /// A setting or parameter is outside its admissible range.
    #[error("invalid setting `{name}` = {value}: {reason}")]
    Setting {
        /// Setting name as users write it.
        name: &'static str,
        /// Offending value.
        value: f64,
        /// What the admissible range is.
        reason: &'static str,
    },
    /// The mesh is unusable (inverted element, missing node set, …).
    #[error("mesh: {0}")]
    Mesh(String),
    /// A material point could not be evaluated (e.g. det F ≤ 0).
    #[error("material at element {element}, point {point}: {source}")]
    Material {
        /// Element index.
        element: usize,
        /// Quadrature point within the element.
        point: usize,
        /// The material's own error.
        source: MaterialError,
    },
    /// The sparse factorisation failed (singular tangent).
    #[error("sparse solver: {0}")]
    Solver(String),
    /// A loading program cannot be run on this model (what and why).
    #[error("plate program: {0}")]
    Program(String),
    /// An output file could not be written.
    #[error("cannot write `{}`: {source}", file.display())]
    Io {
        /// The file.
        file: std::path::PathBuf,
        /// The system's error.
        source: std::io::Error,
    },
    /// The adaptive step reached its minimum size without converging.
    #[error(
        "no convergence after t = {:.6e} s with step {:.3e} s: residual {:.3e} N > tolerance {:.3e} N \
         after {} Newton iterations ({}); try a finer minimum step, a looser tolerance, \
         a softer contact penalty or a finer mesh near the contact",
        .0.time, .0.dt, .0.residual, .0.tolerance, .0.iterations, .0.cause
    )]
    NonConvergence(Box<NonConvergence>),
}

/// Result alias of the fem crate.
pub type Result<T> = std::result::Result<T, FemError>;
