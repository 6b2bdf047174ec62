//! Errors of cohort fitting, figure drawing and report writing.

use std::path::PathBuf;

/// Everything that can go wrong in this crate; each variant names where.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// A file or directory could not be read or written.
    #[error("{}: {message}", path.display())]
    Io {
        /// The file or directory.
        path: PathBuf,
        /// What failed.
        message: String,
    },
    /// Malformed input data (manifest, per-cell result, results table).
    #[error("{}:{line}: {message}", path.display())]
    Data {
        /// The file.
        path: PathBuf,
        /// 1-based line (0 when the whole file is concerned).
        line: u64,
        /// What is wrong and what to change.
        message: String,
    },
    /// The study file.
    #[error(transparent)]
    Study(#[from] nlvid_study::StudyError),
    /// A value outside the shared vocabulary (parameter domain, Prony series).
    #[error(transparent)]
    Model(#[from] nlvid_model::ModelError),
    /// The inverse analysis (model, misfit, optimiser).
    #[error(transparent)]
    Inverse(#[from] nlvid_inverse::InverseError),
    /// Group statistics.
    #[error(transparent)]
    Stats(#[from] nlvid_stats::StatsError),
    /// A figure could not be drawn.
    #[error("figure `{figure}`: {message}")]
    Plot {
        /// Figure file name.
        figure: String,
        /// Backend message.
        message: String,
    },
    /// Writing a report to the caller's output (stdout) failed, e.g. a
    /// closed pipe; the I/O error is the source.
    #[error("cannot write the output")]
    Output(#[source] std::io::Error),
    /// An invalid setting passed in code (not from a file).
    #[error("{0}")]
    InvalidSetting(String),
}

/// Result alias of this crate.
pub type Result<T> = std::result::Result<T, ReportError>;

impl ReportError {
    /// An I/O error on `path`.
    pub fn io(path: impl Into<PathBuf>, e: impl std::fmt::Display) -> Self {
        Self::Io {
            path: path.into(),
            message: e.to_string(),
        }
    }
}
