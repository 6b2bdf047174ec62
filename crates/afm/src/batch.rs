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

/// Reports the progress of a batch: first the number of files found, then one call per
/// file read and analysed (from any thread). Both methods default to doing nothing.
pub trait Progress: Sync {
    /// The batch holds `files` files.
    fn start(&self, _files: usize) {}
    /// One more file is done (all its curves analysed or failed).
    fn file_done(&self) {}
}

/// No progress reporting.
#[derive(Debug, Clone, Copy, Default)]
pub struct NoProgress;

impl Progress for NoProgress {}

/// The files of a batch's inputs.
#[derive(Debug, Default)]
pub struct Inputs {
    /// Files to read: given files as they are, then the accepted files of each folder
    /// and glob (sorted within each).
    pub files: Vec<PathBuf>,
    /// Files found in folders and skipped because `accept` refused them.
    pub ignored: Vec<PathBuf>,
    /// Folders that could not be read and globs matching nothing.
    pub failures: Vec<CurveFailure>,
}

/// True if `text` holds a glob wildcard (`*`, `?` or `[`).
fn is_glob(text: &str) -> bool {
    text.contains(['*', '?', '['])
}

/// Whether `name` matches the glob `pattern`: `*` any run of characters, `?` one
/// character, `[abc]` / `[a-z]` / `[!a]` one character of (not of) a set.
pub fn glob_match(pattern: &str, name: &str) -> bool {
    let p: Vec<char> = pattern.chars().collect();
    let n: Vec<char> = name.chars().collect();
    // Iterative matcher with backtracking to the last `*`.
    let (mut pi, mut ni) = (0, 0);
    let mut star: Option<(usize, usize)> = None;
    while ni < n.len() {
        let step = match p.get(pi) {
            Some('*') => {
                star = Some((pi, ni));
                pi += 1;
                continue;
            }
            Some('?') => Some(pi + 1),
            Some('[') => match class_match(&p[pi..], n[ni]) {
                Some((true, len)) => Some(pi + len),
                Some((false, _)) => None,
                // an unclosed `[` is a literal
                None => (n[ni] == '[').then_some(pi + 1),
            },
            Some(c) if *c == n[ni] => Some(pi + 1),
            _ => None,
        };
        match (step, star) {
            (Some(next), _) => {
                pi = next;
                ni += 1;
            }
            (None, Some((sp, sn))) => {
                pi = sp + 1;
                ni = sn + 1;
                star = Some((sp, sn + 1));
            }
            (None, None) => return false,
        }
    }
    p[pi..].iter().all(|c| *c == '*')
}

/// A `[...]` class at the start of `p` against `c`: (matches, length of the class), or
/// `None` if the class is not closed (then `[` is compared literally).
fn class_match(p: &[char], c: char) -> Option<(bool, usize)> {
    let close = p.iter().skip(2).position(|x| *x == ']')? + 2;
    let (negate, body) = match p[1] {
        '!' | '^' => (true, &p[2..close]),
        _ => (false, &p[1..close]),
    };
    let mut hit = false;
    let mut i = 0;
    while i < body.len() {
        if i + 2 < body.len() && body[i + 1] == '-' {
            hit |= (body[i]..=body[i + 2]).contains(&c);
            i += 3;
        } else {
            hit |= body[i] == c;
            i += 1;
        }
    }
    Some((hit != negate, close + 1))
}

/// The paths matching a glob: wildcards may appear in any component; sorted.
fn glob_paths(pattern: &Path) -> Vec<PathBuf> {
    let mut at: Vec<PathBuf> = vec![PathBuf::new()];
    for comp in pattern.components() {
        let text = comp.as_os_str().to_string_lossy();
        let mut next = Vec::new();
        for base in &at {
            if !is_glob(&text) {
                next.push(base.join(comp));
                continue;
            }
            let dir = if base.as_os_str().is_empty() {
                Path::new(".")
            } else {
                base.as_path()
            };
            let Ok(entries) = std::fs::read_dir(dir) else {
                continue;
            };
            for e in entries.flatten() {
                let name = e.file_name().to_string_lossy().into_owned();
                // like a shell: a leading dot is matched only by a leading dot
                if name.starts_with('.') && !text.starts_with('.') {
                    continue;
                }
                if glob_match(&text, &name) {
                    next.push(base.join(&name));
                }
            }
        }
        at = next;
    }
    at.retain(|p| p.exists());
    at.sort();
    at
}

/// Every file under `dir` (recursively, hidden entries skipped), sorted by path.
fn files_under(dir: &Path, failures: &mut Vec<CurveFailure>) -> Vec<PathBuf> {
    let mut stack = vec![dir.to_path_buf()];
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
    found
}

/// The one reader of batch inputs (`nlvid inspect`, `fit`, `cohort`): files are kept as
/// given (whatever their name); folders are searched recursively for the files
/// `accept` takes (sorted by path; others are listed as ignored); an input that does not
/// exist and holds a wildcard (`*`, `?`, `[`) is a glob, its matches taken as given files
/// or searched as folders. A glob matching nothing, and an unreadable folder, is a
/// failure; the rest goes on.
pub fn expand_inputs<P: AsRef<Path>>(inputs: &[P], accept: impl Fn(&Path) -> bool) -> Inputs {
    let mut out = Inputs::default();
    let folder = |dir: &Path, out: &mut Inputs| {
        for path in files_under(dir, &mut out.failures) {
            if accept(&path) {
                out.files.push(path);
            } else {
                out.ignored.push(path);
            }
        }
    };
    for input in inputs {
        let input = input.as_ref();
        if input.is_dir() {
            folder(input, &mut out);
        } else if !input.exists() && is_glob(&input.to_string_lossy()) {
            let matches = glob_paths(input);
            if matches.is_empty() {
                out.failures.push(CurveFailure {
                    file: input.to_path_buf(),
                    curve: None,
                    error: AfmError::InvalidInput(format!(
                        "no file matches the pattern `{}`",
                        input.display()
                    )),
                });
            }
            for m in matches {
                if m.is_dir() {
                    folder(&m, &mut out);
                } else {
                    out.files.push(m);
                }
            }
        } else {
            out.files.push(input.to_path_buf());
        }
    }
    out
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
    for_each_curve_with(inputs, options, analyse, &NoProgress)
}

/// [`for_each_curve`] reporting to `progress` (the number of files, then each file done).
///
/// # Errors
/// As [`for_each_curve`].
pub fn for_each_curve_with<P, T, F>(
    inputs: &[P],
    options: &ReadOptions,
    analyse: F,
    progress: &dyn Progress,
) -> Result<Batch<T>>
where
    P: AsRef<Path>,
    T: Send,
    F: Fn(&ForceCurve) -> Result<T> + Sync,
{
    crate::jpk::check_override(options)?;
    let Inputs {
        files,
        ignored,
        mut failures,
    } = expand_inputs(inputs, is_afm_file);
    progress.start(files.len());
    let per_file: Vec<(Vec<BatchRow<T>>, Vec<CurveFailure>)> = files
        .par_iter()
        .map(|file| {
            let out = read_and_analyse(file, options, &analyse);
            progress.file_done();
            out
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

/// Read one file and analyse each of its curves: (rows, failures).
fn read_and_analyse<T, F>(
    file: &PathBuf,
    options: &ReadOptions,
    analyse: &F,
) -> (Vec<BatchRow<T>>, Vec<CurveFailure>)
where
    T: Send,
    F: Fn(&ForceCurve) -> Result<T> + Sync,
{
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
}
