//! The bundled example `examples/demo/` embedded in the binary, so an
//! installed `nlvid demo` runs without the source tree. Which files are
//! embedded is decided in one place, `crates/cli/build.rs`: every file
//! under `examples/demo/` (study, meta-model study, pre-built meta-model,
//! cells' curves, ground truth, README), except a file over 32 MiB, which
//! is listed in [`NOT_EMBEDDED`] and looked for where the example is
//! written out.

use std::path::{Path, PathBuf};

include!(concat!(env!("OUT_DIR"), "/demo_files.rs"));

/// Writes the embedded example into `dir` (created if missing) and returns
/// `dir`. Each file is written atomically, and only when its bytes differ,
/// so a second `nlvid demo` rewrites nothing.
///
/// # Errors
/// `dir` cannot be created or written (naming the path), or a file too
/// large to embed is not already in `dir` (naming where it is expected).
pub fn write_to(dir: &Path) -> nlvid_report::Result<PathBuf> {
    for (rel, bytes) in FILES {
        let path = dir.join(rel);
        if std::fs::read(&path).is_ok_and(|old| old == *bytes) {
            continue;
        }
        nlvid_report::cohort::write_atomic(&path, bytes)?;
    }
    for (rel, len) in NOT_EMBEDDED {
        let path = dir.join(rel);
        if !path.is_file() {
            return Err(nlvid_report::ReportError::InvalidSetting(format!(
                "{}: the demo's `{rel}` ({:.1} MB) is too large to be embedded in this binary; \
                 copy examples/demo/{rel} of the nlvid repository there, or give --demo with \
                 a checkout's examples/demo",
                path.display(),
                *len as f64 / 1e6
            )));
        }
    }
    Ok(dir.to_path_buf())
}
