//! Output helpers shared by all subcommands: atomic file writes and the
//! `--json` convention. Output checks and default paths are
//! `nlvid_study::{check_output_dir, check_output_file, next_to}`; curves and
//! parameters as JSON are `nlvid_model::{Curve::to_json, parameters_json}`.
//!
//! Convention: with `--json`, stdout carries exactly one JSON document and
//! nothing else; human-readable text goes to stdout otherwise; logs and
//! progress bars always go to stderr.

use std::io::Write;
use std::path::Path;

use anyhow::Context;
use serde_json::Value;

/// Writes `bytes` to `path` atomically: a temporary file in the same
/// directory, flushed to disk, then renamed over `path`. A reader (or a
/// resumed run) sees either the old file or the complete new one, never a
/// half-written file.
///
/// # Errors
/// The directory is not writable, the disk is full, or the rename fails; the
/// temporary file is removed on failure.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    nlvid_study::write_atomic(path, bytes)
        .with_context(|| format!("{}: cannot write", path.display()))
}

/// Prints one JSON document on stdout (the `--json` convention).
///
/// # Errors
/// Writing to stdout fails (e.g. a closed pipe).
pub fn print_json(value: &Value) -> anyhow::Result<()> {
    let mut text = serde_json::to_string_pretty(value)?;
    text.push('\n');
    print_text(&text)
}

/// The `--json` convention in one call: `value` as the one JSON document
/// with `json`, else `text`.
///
/// # Errors
/// Writing to stdout fails.
pub fn emit(json: bool, value: &Value, text: &str) -> anyhow::Result<()> {
    if json {
        print_json(value)
    } else {
        print_text(text)
    }
}

/// Writes `text` to stdout. A closed pipe (`nlvid … | head`) is an
/// `io::Error` that [`crate::report`] turns into a quiet exit, never a
/// panic as `print!` would.
///
/// # Errors
/// Writing to stdout fails.
pub fn print_text(text: &str) -> anyhow::Result<()> {
    let mut out = std::io::stdout().lock();
    out.write_all(text.as_bytes())?;
    out.flush()?;
    Ok(())
}

/// `println!` that returns the write error instead of panicking on a
/// closed stdout: `say!("{x} N")?;`.
#[macro_export]
macro_rules! say {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        writeln!(std::io::stdout(), $($arg)*)
    }};
}
