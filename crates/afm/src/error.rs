//! The crate's error type: every way reading or fitting a measured curve can fail.

use std::path::PathBuf;

/// Result alias used throughout `nlvid-afm`.
pub type Result<T, E = AfmError> = std::result::Result<T, E>;

/// Everything that can go wrong while reading, preparing or fitting an AFM curve.
///
/// Reader errors name the archive entry (and key) at fault; fit errors say what
/// did not converge and what to change.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum AfmError {
    /// The file could not be opened or read.
    #[error("cannot read {path}: {source}")]
    Io {
        /// File that failed.
        path: PathBuf,
        /// Underlying error.
        source: std::io::Error,
    },
    /// The bytes are not a readable ZIP archive (truncated download, wrong file type).
    #[error(
        "not a JPK file: {detail} (a .jpk-force file is a ZIP archive; is the file truncated?)"
    )]
    NotZip {
        /// What the ZIP reader reported.
        detail: String,
    },
    /// A ZIP archive that is not a JPK force file (no `header.properties`, wrong `jpk-data-file`).
    #[error("not a JPK force file: {detail}")]
    NotJpk {
        /// Why the archive was rejected.
        detail: String,
    },
    /// The bytes are not an Igor binary wave force curve (Asylum Research `.ibw`).
    #[error("not an Asylum Research .ibw force curve: {detail}")]
    NotIbw {
        /// What is missing or inconsistent.
        detail: String,
    },
    /// An archive entry could not be decompressed (CRC mismatch, damaged deflate stream).
    #[error("corrupt entry '{entry}': {detail}")]
    Corrupt {
        /// Entry name inside the archive.
        entry: String,
        /// What went wrong.
        detail: String,
    },
    /// A channel file holds fewer bytes than its header promises.
    #[error(
        "truncated channel data '{entry}': header promises {expected} points ({expected_bytes} bytes), file holds {found_bytes} bytes"
    )]
    Truncated {
        /// Entry name inside the archive.
        entry: String,
        /// Points announced by the header.
        expected: usize,
        /// Bytes those points need.
        expected_bytes: usize,
        /// Bytes actually present.
        found_bytes: usize,
    },
    /// A `.properties` header could not be parsed.
    #[error("{entry}: bad properties syntax at line {line}: {detail}")]
    Properties {
        /// Entry name inside the archive.
        entry: String,
        /// 1-based line number reported by the parser.
        line: usize,
        /// Parser message.
        detail: String,
    },
    /// A required header key is absent.
    #[error("{entry}: missing key '{key}'")]
    MissingKey {
        /// Entry (header file) that should hold the key.
        entry: String,
        /// The key.
        key: String,
    },
    /// A header key holds a value that cannot be used.
    #[error("{entry}: key '{key}' = '{value}': expected {expected}")]
    BadValue {
        /// Entry (header file) holding the key.
        entry: String,
        /// The key.
        key: String,
        /// Its value.
        value: String,
        /// What was expected instead.
        expected: String,
    },
    /// A feature of the JPK format this reader does not implement.
    #[error("{entry}: unsupported {what}")]
    Unsupported {
        /// Entry (header file) where it was met.
        entry: String,
        /// The unsupported feature.
        what: String,
    },
    /// The file lacks a calibration needed to convert deflection to force.
    #[error(
        "no {quantity} calibration in {entry} (channel vDeflection, conversion '{conversion}' undefined); give it explicitly (study `spring_constant` / `sensitivity`, CLI --spring-constant / --sensitivity)"
    )]
    NoCalibration {
        /// "spring constant" or "deflection sensitivity".
        quantity: &'static str,
        /// Header file that was searched.
        entry: String,
        /// Conversion slot that was missing or undefined.
        conversion: String,
    },
    /// A channel the operation needs is absent from a segment.
    #[error("segment {segment}: no channel '{channel}' (available: {available})")]
    MissingChannel {
        /// Segment index.
        segment: usize,
        /// Channel name that was requested.
        channel: String,
        /// Channels that are present.
        available: String,
    },
    /// A curve has no segment of the requested kind.
    #[error("curve has no {kind} segment")]
    MissingSegment {
        /// Kind that was requested.
        kind: String,
    },
    /// Input to a preparation or fit step is unusable.
    #[error("invalid input: {0}")]
    InvalidInput(String),
    /// No contact point could be found.
    #[error("no contact point found: {0}")]
    NoContact(String),
    /// A fit did not converge or produced a non-finite result.
    #[error("{fit} fit did not converge: {detail}; {hint}")]
    NotConverged {
        /// Which fit.
        fit: &'static str,
        /// What went wrong (iterations, last cost...).
        detail: String,
        /// What to change.
        hint: &'static str,
    },
    /// Writing a plot failed.
    #[error("cannot write plot {path}: {detail}")]
    Plot {
        /// Target file.
        path: PathBuf,
        /// Backend message.
        detail: String,
    },
}
