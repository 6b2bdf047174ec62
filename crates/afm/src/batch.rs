//! Many curves at once: files, force maps and folders in, one result per curve out, and
//! every curve that could not be read or analysed listed with its file, index and reason
//! instead of stopping the batch.
//!
//! Files, and the curves of a map, are read and analysed in parallel (rayon); a curve is
//! dropped once analysed, so a batch holds only the per-curve results.

use std::fmt;
use std::path::{Path, PathBuf};

use rayon::prelude::*;

use crate::curve::ForceCurve;
use crate::error::{AfmError, Result};
use crate::ibw::read_ibw_bytes;
use crate::jpk::{JpkArchive, ReadOptions};

/// File name endings of the instrument files a folder is searched for (lower case).
pub const AFM_EXTENSIONS: [&str; 5] = [
    ".jpk-force",
    ".jpk-force-map",
    ".jpk-qi-data",
    ".jpk-qi-series",
    ".ibw",
];

/// A curve (or a whole file) that could not be read or analysed.
#[derive(Debug)]
pub struct CurveFailure {
    /// The file.
    pub file: PathBuf,
    /// Index of the curve in a map (`None`: a single-curve file, or the whole file failed).
    pub curve: Option<usize>,
    /// Why.
    pub error: AfmError,
}

impl fmt::Display for CurveFailure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.curve {
            Some(i) => write!(f, "{} curve {i}: {}", self.file.display(), self.error),
            None => write!(f, "{}: {}", self.file.display(), self.error),
        }
    }
}

/// One analysed curve.
#[derive(Debug, Clone, PartialEq)]
pub struct BatchRow<T> {
    /// The file.
    pub file: PathBuf,
    /// Index of the curve in a map (`None` for a single-curve file).
    pub curve: Option<usize>,
    /// The analysis result.
    pub value: T,
}

/// Outcome of a batch: one row per curve analysed, one failure per curve (or file) that
/// was not, and the files of searched folders that are not AFM files.
#[derive(Debug)]
pub struct Batch<T> {
    /// Curves analysed, in input order (files sorted within a folder, curves by index).
    pub rows: Vec<BatchRow<T>>,
    /// Curves or files that failed, in the same order.
    pub failures: Vec<CurveFailure>,
    /// Files found in folders and skipped because their names do not end in one of
    /// [`AFM_EXTENSIONS`].
    pub ignored: Vec<PathBuf>,
}

/// True if `path`'s name ends in one of [`AFM_EXTENSIONS`] (case-insensitive).
pub fn is_afm_file(path: &Path) -> bool {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().to_lowercase())
        .unwrap_or_default();
    AFM_EXTENSIONS.iter().any(|e| name.ends_with(e))
}

/// True for Asylum Research Igor binary waves (name ends in `.ibw`); every other file
/// is read as JPK.
fn is_ibw(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.to_string_lossy().eq_ignore_ascii_case("ibw"))
}

/// Expand `inputs`: files are kept as given (whatever their name); folders are searched
/// recursively for AFM files (sorted by path). Returns (files, ignored, failures).
fn expand<P: AsRef<Path>>(inputs: &[P]) -> (Vec<PathBuf>, Vec<PathBuf>, Vec<CurveFailure>) {
    let mut files = Vec::new();
    let mut ignored = Vec::new();
    let mut failures = Vec::new();
    for input in inputs {
        let input = input.as_ref();
        if input.is_dir() {
            let mut stack = vec![input.to_path_buf()];
            let mut found = Vec::new();
            while let Some(dir) = stack.pop() {
                let entries = match std::fs::read_dir(&dir) {
                    Ok(e) => e,
                    Err(source) => {
                        failures.push(CurveFailure {
                            file: dir.clone(),
                            curve: None,
                            error: AfmError::Io { path: dir, source },
                        });
                        continue;
                    }
                };
                for entry in entries.flatten() {
                    let path = entry.path();
                    let hidden = path
                        .file_name()
                        .is_some_and(|n| n.to_string_lossy().starts_with('.'));
                    if hidden {
                        continue;
                    }
                    if path.is_dir() {
                        stack.push(path);
                    } else {
                        found.push(path);
                    }
                }
            }
            found.sort();
            for path in found {
                if is_afm_file(&path) {
                    files.push(path);
                } else {
                    ignored.push(path);
                }
            }
        } else {
            files.push(input.to_path_buf());
        }
    }
    (files, ignored, failures)
}

/// Read every curve of `inputs` (files, maps, folders) and apply `analyse` to each, in
/// parallel over files. A file or curve that cannot be read, and a curve `analyse`
/// rejects, becomes a [`CurveFailure`]; the batch always runs to the end.
///
/// # Errors
/// [`AfmError::InvalidInput`] only for nonsensical calibration overrides in `options`.
pub fn for_each_curve<P, T, F>(inputs: &[P], options: &ReadOptions, analyse: F) -> Result<Batch<T>>
where
    P: AsRef<Path>,
    T: Send,
    F: Fn(&ForceCurve) -> Result<T> + Sync,
{
    crate::jpk::check_override(options)?;
    let (files, ignored, mut failures) = expand(inputs);
    let per_file: Vec<(Vec<BatchRow<T>>, Vec<CurveFailure>)> = files
        .par_iter()
        .map(|file| {
            let fail = |curve, error| CurveFailure {
                file: file.clone(),
                curve,
                error,
            };
            let bytes = match std::fs::read(file) {
                Ok(b) => b,
                Err(source) => {
                    let error = AfmError::Io {
                        path: file.clone(),
                        source,
                    };
                    return (Vec::new(), vec![fail(None, error)]);
                }
            };
            let name = file.display().to_string();
            let results: Vec<(Option<usize>, Result<T>)> = if is_ibw(file) {
                match read_ibw_bytes(&bytes, &name, options) {
                    Ok(c) => vec![(None, analyse(&c))],
                    Err(error) => return (Vec::new(), vec![fail(None, error)]),
                }
            } else {
                let archive = match JpkArchive::open(&bytes, &name, options) {
                    Ok(a) => a,
                    Err(error) => return (Vec::new(), vec![fail(None, error)]),
                };
                // Curves of a map in parallel too; each is dropped once analysed.
                (0..archive.len())
                    .into_par_iter()
                    .map(|i| (archive.index(i), archive.read(i).and_then(|c| analyse(&c))))
                    .collect()
            };
            let mut rows = Vec::new();
            let mut fails = Vec::new();
            for (curve, r) in results {
                match r {
                    Ok(value) => rows.push(BatchRow {
                        file: file.clone(),
                        curve,
                        value,
                    }),
                    Err(error) => fails.push(fail(curve, error)),
                }
            }
            (rows, fails)
        })
        .collect();
    let mut rows = Vec::new();
    for (r, f) in per_file {
        rows.extend(r);
        failures.extend(f);
    }
    Ok(Batch {
        rows,
        failures,
        ignored,
    })
}
