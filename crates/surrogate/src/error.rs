//! The crate's error type.

use std::path::PathBuf;

/// Everything that can go wrong while sampling, building, fitting or checking.
#[derive(Debug, thiserror::Error)]
pub enum SurrogateError {
    /// Inputs of inconsistent or unusable shape/value.
    #[error("invalid input: {0}")]
    InvalidInput(String),
    /// Settings that cannot work (bad bounds, wrong θ length, …).
    #[error("invalid settings: {0}")]
    InvalidSettings(String),
    /// The correlation matrix is not positive definite for every θ tried,
    /// even with the largest nugget allowed.
    #[error(
        "correlation matrix not positive definite at θ = {theta:?} (nugget {nugget:e}); \
         remove duplicate design sites or allow a larger nugget"
    )]
    NotPositiveDefinite {
        /// Correlation parameters at which the factorisation failed.
        theta: Vec<f64>,
        /// Nugget that was on the diagonal.
        nugget: f64,
    },
    /// The regression matrix F is too ill conditioned for the design sites.
    #[error(
        "regression matrix ill conditioned (rcond {rcond:e}): poor combination of \
         regression model and design sites; use a lower polynomial degree or more sites"
    )]
    IllConditionedRegression {
        /// Reciprocal condition number found.
        rcond: f64,
    },
    /// A file could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// A file had content that could not be parsed.
    #[error("{path}: {message}")]
    Parse {
        /// The file.
        path: PathBuf,
        /// What went wrong and where (line/row, column).
        message: String,
    },
}

/// Result alias of this crate.
pub type Result<T> = std::result::Result<T, SurrogateError>;

pub(crate) fn io_err(path: impl Into<PathBuf>) -> impl FnOnce(std::io::Error) -> SurrogateError {
    let path = path.into();
    move |source| SurrogateError::Io { path, source }
}
