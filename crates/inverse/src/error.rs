//! Errors of the inverse-analysis stage.

use std::path::PathBuf;

/// Result alias of this crate.
pub type Result<T> = std::result::Result<T, InverseError>;

/// Everything that can go wrong while setting up or running a fit.
#[derive(Debug, thiserror::Error)]
pub enum InverseError {
    /// A parameter domain or setting is invalid (what, and what to change).
    #[error("invalid setting: {0}")]
    InvalidSetting(String),

    /// A parameter vector, domain or Prony series outside the shared
    /// vocabulary's rules (wrong length, invalid bounds, g∞ ≤ 0, …).
    #[error(transparent)]
    Vocabulary(#[from] nlvid_model::ModelError),

    /// Two curves that must share a time grid do not.
    #[error("curve length mismatch in {what}: expected {expected} points, got {got}")]
    LengthMismatch {
        /// Which curve.
        what: String,
        /// Number of points expected (the model's time grid).
        expected: usize,
        /// Number of points given.
        got: usize,
    },

    /// A forward model (surrogate or real) failed at a parameter set.
    #[error("model evaluation failed at x = {x:?}: {message}")]
    Model {
        /// Parameters (SI) at which it failed.
        x: Vec<f64>,
        /// The model's own message.
        message: String,
    },

    /// The model returned a non-finite value.
    #[error("model returned a non-finite value at time index {index} (t = {time} s) for x = {x:?}")]
    NonFinite {
        /// Time index of the first non-finite value.
        index: usize,
        /// Time (s) of that index.
        time: f64,
        /// Parameters (SI).
        x: Vec<f64>,
    },

    /// The reference curve has zero range, so eq. 5.3 is undefined.
    #[error(
        "reference curve '{what}' has zero range: the range-normalised RMSE (eq. 5.3) is undefined"
    )]
    ZeroRange {
        /// Which curve.
        what: String,
    },

    /// No start point of the multistart optimiser produced a result.
    #[error(
        "optimiser failed from all {starts} start points (last status: {last}); \
         increase max_evals or the number of starts, or check the model near the bounds"
    )]
    NoConvergence {
        /// Number of starts tried.
        starts: usize,
        /// Status of the last failed local run.
        last: String,
    },

    /// A linear-algebra step failed (e.g. SVD did not converge).
    #[error("linear algebra failed in {0}")]
    LinearAlgebra(String),

    /// Reading a data file failed at the I/O or CSV level.
    #[error("{path}: {message}")]
    Io {
        /// File.
        path: PathBuf,
        /// What happened.
        message: String,
    },

    /// A data file is malformed; names file, row (1-based, header = row 1) and column.
    #[error("{path}: row {row}, column '{column}': {message}")]
    Data {
        /// File.
        path: PathBuf,
        /// 1-based line number in the file (the header is line 1); 0 = the file as a whole.
        row: usize,
        /// Column name (as requested by the caller).
        column: String,
        /// What is wrong and what to change.
        message: String,
    },

    /// The measured loading history does not match the expected protocol.
    #[error("{path}: protocol mismatch at row {row} (t = {time} s): {message}")]
    ProtocolMismatch {
        /// File.
        path: PathBuf,
        /// 1-based line number of the worst (or first) offending sample.
        row: usize,
        /// Time of that sample (s).
        time: f64,
        /// Which quantity differs and by how much.
        message: String,
    },

    /// Drawing or writing a figure failed.
    #[error("{path}: cannot draw the figure: {message}")]
    Plot {
        /// Figure file.
        path: PathBuf,
        /// What happened.
        message: String,
    },
}
