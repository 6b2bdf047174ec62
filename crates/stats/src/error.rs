//! Errors of the stats crate.

use std::path::PathBuf;

/// What can go wrong in a statistical computation or a results table.
#[derive(Debug, thiserror::Error)]
pub enum StatsError {
    /// A sample is empty or too small for the requested quantity.
    #[error("{what}: needs at least {needed} values, got {got}")]
    TooFew {
        /// Which sample / group.
        what: String,
        /// Minimum size.
        needed: usize,
        /// Actual size.
        got: usize,
    },
    /// A value is NaN or infinite.
    #[error("{what}: value #{index} is not finite ({value})")]
    NotFinite {
        /// Which sample.
        what: &'static str,
        /// 0-based index of the value.
        index: usize,
        /// The value.
        value: f64,
    },
    /// The exact null distribution is too expensive for these sizes.
    #[error(
        "exact rank-sum distribution for n1 = {n1}, n2 = {n2} would take ~{ops:.1e} operations; \
         use the asymptotic method"
    )]
    ExactTooLarge {
        /// First sample size.
        n1: usize,
        /// Second sample size.
        n2: usize,
        /// Estimated operation count.
        ops: f64,
    },
    /// The results table cannot be opened or read.
    #[error("{}: cannot read: {source}", file.display())]
    Io {
        /// The file.
        file: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// The results table is malformed.
    #[error("{}: line {line}{}: {message}", file.display(), column.as_ref().map(|c| format!(", column `{c}`")).unwrap_or_default())]
    Table {
        /// The file.
        file: PathBuf,
        /// 1-based line (the header is line 1; 0 when not applicable).
        line: u64,
        /// Column header, if the problem is in one cell.
        column: Option<String>,
        /// What is wrong.
        message: String,
    },
    /// A group comparison cannot be made as asked (grid, groups).
    #[error("group comparison: {0}")]
    Comparison(String),
    /// Writing an output failed.
    #[error("cannot write output: {0}")]
    Write(String),
}

/// Result alias of the stats crate.
pub type Result<T> = std::result::Result<T, StatsError>;
