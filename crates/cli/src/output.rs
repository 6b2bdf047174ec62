//! Output helpers shared by all subcommands: atomic file writes, curves and
//! parameters as JSON with unit-suffixed keys, and the `--json` convention.
//!
//! Convention: with `--json`, stdout carries exactly one JSON document and
//! nothing else; human-readable text goes to stdout otherwise; logs and
//! progress bars always go to stderr.

use std::io::Write;
use std::path::Path;

use anyhow::Context;
use serde_json::{Map, Value};

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

/// Checks, before any computation, that the directory `dir` exists and is
/// writable or can be created: its nearest existing ancestor is a
/// directory a file can be written into. Creates nothing.
///
/// # Errors
/// An ancestor is a file, `dir` is a file, or the directory is not
/// writable — naming the path and the OS error once.
pub fn check_output_dir(dir: &Path) -> anyhow::Result<()> {
    let mut at = dir;
    loop {
        if at.as_os_str().is_empty() {
            at = Path::new(".");
        }
        match std::fs::metadata(at) {
            Ok(m) if m.is_dir() => break,
            Ok(_) => anyhow::bail!(
                "output directory {}: {} is a file, not a directory",
                dir.display(),
                at.display()
            ),
            Err(_) => match at.parent() {
                Some(p) => at = p,
                None => anyhow::bail!("output directory {}: no existing parent", dir.display()),
            },
        }
    }
    let probe = at.join(format!(".nlvid-probe.{}.tmp", std::process::id()));
    match std::fs::File::create(&probe) {
        Ok(_) => {
            let _ = std::fs::remove_file(&probe);
            Ok(())
        }
        Err(e) => anyhow::bail!(
            "output directory {}: cannot write into {}: {e}",
            dir.display(),
            at.display()
        ),
    }
}

/// As [`check_output_dir`] for an output file: `file` is not a directory
/// and its directory is writable or can be created.
///
/// # Errors
/// As [`check_output_dir`]; `file` is a directory.
pub fn check_output_file(file: &Path) -> anyhow::Result<()> {
    if file.is_dir() {
        anyhow::bail!("output file {}: is a directory", file.display());
    }
    let dir = file.parent().unwrap_or(Path::new("."));
    check_output_dir(dir).with_context(|| format!("output file {}", file.display()))
}

/// Provenance to embed in every JSON result: the study file, its SHA-256
/// hash (see `nlvid_study::StudyHash`) and the program version.
pub fn provenance(study: &nlvid_study::Study) -> Value {
    serde_json::json!({
        "study": study.name(),
        "study_sha256": study.hash().to_string(),
        "nlvid_version": env!("CARGO_PKG_VERSION"),
    })
}

/// `<stem>.<suffix>` next to `study` (`cell.toml` → `cell.simulate.csv`):
/// where commands write their outputs by default.
pub fn next_to(study: &Path, suffix: &str) -> std::path::PathBuf {
    let stem = study
        .file_stem()
        .map_or_else(|| "study".into(), |s| s.to_string_lossy().into_owned());
    study.with_file_name(format!("{stem}.{suffix}"))
}

/// A curve as JSON: `{"time_s": [...], "<header>": [...], ...}`, the
/// headers of its CSV (unit-suffixed).
pub fn curve_json(curve: &nlvid_model::Curve) -> Value {
    let mut m = Map::new();
    m.insert("time_s".into(), Value::from(curve.time().to_vec()));
    for c in curve.channels() {
        m.insert(c.header(), Value::from(c.values.clone()));
    }
    Value::Object(m)
}

/// Named parameters as JSON with unit-suffixed keys: `{"G0_Pa": 1000,
/// "g1": 0.3, "tau1_s": 0.5}`.
pub fn parameters_json(params: &[(String, f64, String)]) -> Value {
    params
        .iter()
        .map(|(n, v, u)| {
            let key = if u.is_empty() || u == "1" {
                n.clone()
            } else {
                format!("{n}_{}", u.replace('/', "_per_"))
            };
            (key, Value::from(*v))
        })
        .collect::<Map<_, _>>()
        .into()
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
