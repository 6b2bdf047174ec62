//! Errors of the protocol crate.

use std::path::PathBuf;

/// What can go wrong when building or reading a loading program.
#[derive(Debug, thiserror::Error)]
pub enum ProtocolError {
    /// A parameter of a program or grid is outside its admissible domain.
    #[error("protocol parameter `{name}` = {value} is out of range: {reason}")]
    Parameter {
        /// Parameter name as users write it.
        name: &'static str,
        /// Offending value.
        value: f64,
        /// What the admissible range is.
        reason: &'static str,
    },
    /// A program was finished without any segment of positive duration.
    #[error("loading program has no segment of positive duration")]
    Empty,
    /// The table file could not be opened or read.
    #[error("{}: cannot read table: {source}", file.display())]
    Io {
        /// The file.
        file: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// The CSV itself is malformed (quoting, ragged rows, encoding).
    #[error("{}: line {line}: malformed CSV: {message}", file.display())]
    Csv {
        /// The file.
        file: PathBuf,
        /// 1-based line number (the header is line 1).
        line: u64,
        /// What the CSV reader reported.
        message: String,
    },
    /// A required column is missing or cannot be identified.
    #[error("{}: {message} (columns found: {found})", file.display())]
    Column {
        /// The file.
        file: PathBuf,
        /// What was looked for and why it failed.
        message: String,
        /// The header as read, comma separated.
        found: String,
    },
    /// A cell is not a finite number.
    #[error("{}: line {line}, column `{column}`: {message}", file.display())]
    Value {
        /// The file.
        file: PathBuf,
        /// 1-based line number (the header is line 1).
        line: u64,
        /// Column header.
        column: String,
        /// What is wrong with the cell.
        message: String,
    },
    /// Time does not increase strictly from one row to the next.
    #[error(
        "{}: line {line}: time {time} s does not increase (previous row has {previous} s); \
         rows must be sorted by strictly increasing time",
        file.display()
    )]
    NonMonotonicTime {
        /// The file.
        file: PathBuf,
        /// 1-based line number (the header is line 1).
        line: u64,
        /// Time on this row, seconds.
        time: f64,
        /// Time on the previous row, seconds.
        previous: f64,
    },
}

/// Result alias of the protocol crate.
pub type Result<T> = std::result::Result<T, ProtocolError>;
