//! Atomic result files: every file nlvid writes (per-run and per-cell
//! results, exported tables and arrays, model files, plots, reports) goes
//! through [`write_atomic`], the one write path of the workspace.

use std::collections::HashSet;
use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// Directories whose stale temporaries this process already removed.
static CLEANED: Mutex<Option<HashSet<PathBuf>>> = Mutex::new(None);

/// Writes `bytes` to `path` atomically: a temporary file
/// `.<name>.<pid>.tmp` in the same directory, flushed to disk (`fsync`),
/// then renamed over `path`. A reader, or a run resumed after `kill -9` or
/// a full disk, sees either the old file or the whole new one, never a
/// part. The temporary file is removed on failure; temporaries left by a
/// killed process are removed by the first write into the same directory
/// of the next run ([`clean_stale_temps`]).
///
/// # Errors
/// The directory does not exist or is not writable, the disk is full, or the
/// rename fails.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    write_atomic_with(path, bytes, |f, b| f.write_all(b))
}

/// [`write_atomic`] with the step that writes the bytes into the temporary
/// file given by the caller: the test-only seam through which the tests
/// inject a failure in the middle of a file (a full disk, `ENOSPC`, after
/// part of the bytes), where no small file system can be mounted. Every
/// other step — temporary name, `fsync`, rename, removal on failure — is
/// the one [`write_atomic`] runs.
///
/// # Errors
/// As [`write_atomic`], and whatever `write` returns.
#[doc(hidden)]
pub fn write_atomic_with(
    path: &Path,
    bytes: &[u8],
    write: impl FnOnce(&mut fs::File, &[u8]) -> std::io::Result<()>,
) -> std::io::Result<()> {
    let dir = path
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .map_or_else(|| PathBuf::from("."), Path::to_path_buf);
    let name = path
        .file_name()
        .ok_or_else(|| std::io::Error::new(std::io::ErrorKind::InvalidInput, "not a file path"))?;
    clean_once(&dir);
    let tmp = dir.join(format!(
        ".{}.{}.tmp",
        name.to_string_lossy(),
        std::process::id()
    ));
    let result = (|| {
        let mut f = fs::File::create(&tmp)?;
        write(&mut f, bytes)?;
        f.sync_all()?;
        fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    result
}

fn clean_once(dir: &Path) {
    let Ok(mut guard) = CLEANED.lock() else {
        return;
    };
    let set = guard.get_or_insert_with(HashSet::new);
    if set.insert(dir.to_path_buf()) {
        drop(guard);
        let _ = clean_stale_temps(dir);
    }
}

/// The process id in a temporary name `.<name>.<pid>.tmp`, if it is one.
fn temp_pid(file_name: &str) -> Option<u32> {
    let stem = file_name.strip_prefix('.')?.strip_suffix(".tmp")?;
    let (_, pid) = stem.rsplit_once('.')?;
    pid.parse().ok()
}

/// Whether process `pid` (which wrote the file `path`) is running: on
/// systems with `/proc`, whether `/proc/<pid>` exists; elsewhere, whether
/// `path` is younger than an hour. Stale temporaries and stale work claims
/// (a build's `runs/<i>.claim`) are told apart from live ones with it.
pub fn process_alive(pid: u32, path: &Path) -> bool {
    alive(pid, path)
}

fn alive(pid: u32, path: &Path) -> bool {
    if pid == std::process::id() {
        return true;
    }
    let proc_root = Path::new("/proc/self");
    if proc_root.exists() {
        return Path::new("/proc").join(pid.to_string()).exists();
    }
    fs::metadata(path)
        .and_then(|m| m.modified())
        .ok()
        .and_then(|t| t.elapsed().ok())
        .is_none_or(|age| age.as_secs() < 3600)
}

/// Removes the temporaries [`write_atomic`] left in `dir` when its process
/// was killed (its pid no longer runs); a temporary of a running process
/// (a concurrent build into the same store) is kept. Returns how many were
/// removed.
///
/// # Errors
/// `dir` cannot be listed.
pub fn clean_stale_temps(dir: &Path) -> std::io::Result<usize> {
    let mut removed = 0;
    for entry in fs::read_dir(dir)? {
        let Ok(entry) = entry else { continue };
        let name = entry.file_name();
        let Some(pid) = name.to_str().and_then(temp_pid) else {
            continue;
        };
        let p = entry.path();
        if !alive(pid, &p) && fs::remove_file(&p).is_ok() {
            removed += 1;
        }
    }
    Ok(removed)
}

/// Checks, before any computation, that the directory `dir` exists and is
/// writable or can be created: its nearest existing ancestor is a
/// directory a file can be written into. Creates nothing.
///
/// # Errors
/// An ancestor is a file, `dir` is a file, or the directory is not
/// writable — naming the path and the OS error once.
pub fn check_output_dir(dir: &Path) -> std::io::Result<()> {
    let fail = |m: String| {
        Err(std::io::Error::other(format!(
            "output directory {}: {m}",
            dir.display()
        )))
    };
    let mut at = dir;
    loop {
        if at.as_os_str().is_empty() {
            at = Path::new(".");
        }
        match fs::metadata(at) {
            Ok(m) if m.is_dir() => break,
            Ok(_) => return fail(format!("{} is a file, not a directory", at.display())),
            Err(_) => match at.parent() {
                Some(p) => at = p,
                None => return fail("no existing parent".into()),
            },
        }
    }
    let probe = at.join(format!(".nlvid-probe.{}.tmp", std::process::id()));
    match fs::File::create(&probe) {
        Ok(_) => {
            let _ = fs::remove_file(&probe);
            Ok(())
        }
        Err(e) => fail(format!("cannot write into {}: {e}", at.display())),
    }
}

/// As [`check_output_dir`] for an output file: `file` is not a directory
/// and its directory is writable or can be created.
///
/// # Errors
/// As [`check_output_dir`]; `file` is a directory.
pub fn check_output_file(file: &Path) -> std::io::Result<()> {
    let fail = |m: String| {
        Err(std::io::Error::other(format!(
            "output file {}: {m}",
            file.display()
        )))
    };
    if file.is_dir() {
        return fail("is a directory".into());
    }
    let dir = file.parent().unwrap_or(Path::new("."));
    check_output_dir(dir).or_else(|e| fail(e.to_string()))
}

/// `<stem>.<suffix>` next to `study` (`cell.toml` → `cell.simulate.csv`):
/// where commands write their outputs by default.
pub fn next_to(study: &Path, suffix: &str) -> PathBuf {
    let stem = study
        .file_stem()
        .map_or_else(|| "study".into(), |s| s.to_string_lossy().into_owned());
    study.with_file_name(format!("{stem}.{suffix}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn replaces_the_file_and_leaves_no_temporary() {
        let dir = std::env::temp_dir().join(format!("nlvid-atomic-{}", std::process::id()));
        fs::create_dir_all(&dir).unwrap();
        let path = dir.join("out.csv");
        write_atomic(&path, b"old").unwrap();
        write_atomic(&path, b"new").unwrap();
        assert_eq!(fs::read(&path).unwrap(), b"new");
        let left: Vec<_> = fs::read_dir(&dir).unwrap().collect();
        assert_eq!(left.len(), 1, "{left:?}");
        assert!(write_atomic(&dir.join("missing/out.csv"), b"x").is_err());
        fs::remove_dir_all(&dir).unwrap();
    }

    /// A full disk in the middle of a file (injected: part of the bytes
    /// reach the temporary file, then `ENOSPC`): the final name keeps the
    /// previous complete version (or stays absent), no temporary is left,
    /// and the error is the OS's "no space" error. The real thing (a tiny
    /// tmpfs) is crates/cli/tests/it/full_disk.rs.
    #[test]
    fn a_full_disk_mid_file_keeps_the_previous_version_and_no_temporary() {
        let dir = std::env::temp_dir().join(format!("nlvid-atomic-full-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap();
        let full = |f: &mut fs::File, b: &[u8]| {
            f.write_all(&b[..b.len() / 2])?;
            Err(std::io::Error::from_raw_os_error(28)) // ENOSPC
        };
        let new: Vec<u8> = (0..100_000u32).flat_map(|i| i.to_le_bytes()).collect();
        // A file that existed: still the previous complete version.
        let old = dir.join("old.csv");
        write_atomic(&old, b"previous,complete\n1,2\n").unwrap();
        let e = write_atomic_with(&old, &new, full).unwrap_err();
        assert_eq!(e.kind(), std::io::ErrorKind::StorageFull, "{e}");
        assert_eq!(fs::read(&old).unwrap(), b"previous,complete\n1,2\n");
        // A new file: absent.
        let fresh = dir.join("fresh.json");
        assert!(write_atomic_with(&fresh, &new, full).is_err());
        assert!(!fresh.exists());
        // A failure on the first byte: the same.
        let none = |_: &mut fs::File, _: &[u8]| Err(std::io::Error::from_raw_os_error(28));
        assert!(write_atomic_with(&fresh, &new, none).is_err());
        assert!(!fresh.exists());
        let mut left: Vec<_> = fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .collect();
        left.sort();
        assert_eq!(left, ["old.csv"], "a temporary was left");
        // The seam writes what write_atomic writes when nothing fails.
        write_atomic_with(&fresh, &new, |f, b| f.write_all(b)).unwrap();
        assert_eq!(fs::read(&fresh).unwrap(), new);
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn stale_temporaries_of_dead_processes_are_removed_live_ones_kept() {
        let dir = std::env::temp_dir().join(format!("nlvid-atomic-stale-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap();
        // pid 4194304 is above Linux's pid_max limit: never a running process.
        let dead = dir.join(".cohort.json.4194304.tmp");
        fs::write(&dead, b"half").unwrap();
        let mine = dir.join(format!(".x.csv.{}.tmp", std::process::id()));
        fs::write(&mine, b"in flight").unwrap();
        let other = dir.join("notes.tmp");
        fs::write(&other, b"user file").unwrap();
        write_atomic(&dir.join("out.csv"), b"x").unwrap();
        if Path::new("/proc/self").exists() {
            assert!(!dead.exists(), "stale temporary survived");
        }
        assert!(mine.exists() && other.exists());
        assert_eq!(temp_pid(".a.b.csv.12.tmp"), Some(12));
        assert_eq!(temp_pid("a.12.tmp"), None);
        fs::remove_dir_all(&dir).unwrap();
    }
}
