//! Crash-safe store of meta-model runs: one JSON file per design point,
//! written to a temporary file, flushed with `fsync` and renamed into
//! place. A rename within a directory is atomic on POSIX file systems, so
//! after `kill -9` (or a node crash) every run file is either complete or
//! absent; a re-run skips complete files and redoes the rest. Shards on a
//! shared file system may write to one directory; [`merge`] joins
//! separate shard directories.
//!
//! Layout of a store directory:
//! `meta.json` (names, units, time grid, design, study hash) and
//! `runs/000123.json` (one per finished run).

use std::fs;
use std::path::{Path, PathBuf};

use nlvid_model::RunFailure;
use serde::{Deserialize, Serialize};

use crate::error::{Result, SurrogateError, io_err};

/// What every run of a build shares.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StoreMeta {
    /// Parameter names.
    pub parameter_names: Vec<String>,
    /// Parameter units (SI).
    pub parameter_units: Vec<String>,
    /// Time grid of the responses [s].
    pub time: Vec<f64>,
    /// The design: one row of parameters per run index.
    pub design: Vec<Vec<f64>>,
    /// Forward-model identity string.
    pub model: String,
    /// Hash of everything above (FNV-1a 64, hex).
    pub study_hash: String,
    /// What the forward model was built for ([`ForwardModel::conditions`]); not hashed
    /// (the model identity already covers it), absent in stores written before it was kept.
    ///
    /// [`ForwardModel::conditions`]: nlvid_model::ForwardModel::conditions
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub conditions: Option<nlvid_model::BuildConditions>,
}

impl StoreMeta {
    /// Build and hash.
    pub fn new(
        parameter_names: Vec<String>,
        parameter_units: Vec<String>,
        time: Vec<f64>,
        design: Vec<Vec<f64>>,
        model: String,
    ) -> Self {
        let mut m = StoreMeta {
            parameter_names,
            parameter_units,
            time,
            design,
            model,
            study_hash: String::new(),
            conditions: None,
        };
        m.study_hash = m.compute_hash();
        m
    }

    /// The same with the forward model's build conditions kept.
    pub fn with_conditions(mut self, conditions: Option<nlvid_model::BuildConditions>) -> Self {
        self.conditions = conditions;
        self
    }

    fn compute_hash(&self) -> String {
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        let mut eat = |b: &[u8]| {
            for &x in b {
                h ^= x as u64;
                h = h.wrapping_mul(0x0100_0000_01b3);
            }
        };
        for s in self.parameter_names.iter().chain(&self.parameter_units) {
            eat(s.as_bytes());
            eat(&[0]);
        }
        for t in &self.time {
            eat(&t.to_le_bytes());
        }
        for row in &self.design {
            for v in row {
                eat(&v.to_le_bytes());
            }
        }
        eat(self.model.as_bytes());
        format!("{h:016x}")
    }
}

/// Outcome of one run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "status", rename_all = "lowercase")]
pub enum RunOutcome {
    /// The response on the time grid.
    Ok {
        /// Values at every time of the grid.
        response: Vec<f64>,
    },
    /// The model failed.
    Failed {
        /// Why.
        failure: RunFailure,
    },
}

/// One stored run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunRecord {
    /// Design index.
    pub index: usize,
    /// Parameters (copy of the design row).
    pub params: Vec<f64>,
    /// Result.
    pub outcome: RunOutcome,
    /// Wall time of the run [s] (informative; not compared by merges).
    pub seconds: f64,
}

/// A store directory.
#[derive(Debug, Clone)]
pub struct RunStore {
    dir: PathBuf,
}

/// Write `bytes` to `path` atomically (temp file, fsync, rename).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    nlvid_study::write_atomic(path, bytes).map_err(io_err(path))
}

impl RunStore {
    /// Open (creating if needed) a store for `meta`.
    ///
    /// # Errors
    /// I/O errors, or an existing store that belongs to another study
    /// (different hash) — delete it or choose another directory.
    pub fn open(dir: impl Into<PathBuf>, meta: &StoreMeta) -> Result<Self> {
        let dir = dir.into();
        fs::create_dir_all(dir.join("runs")).map_err(io_err(dir.join("runs")))?;
        let s = RunStore { dir };
        match s.meta() {
            Ok(existing) => {
                if existing.study_hash != meta.study_hash {
                    return Err(SurrogateError::InvalidSettings(format!(
                        "{} holds runs of another study (hash {} ≠ {}); use another directory",
                        s.dir.display(),
                        existing.study_hash,
                        meta.study_hash
                    )));
                }
            }
            Err(_) => {
                let bytes = serde_json::to_vec_pretty(meta)
                    .map_err(|e| SurrogateError::InvalidInput(e.to_string()))?;
                write_atomic(&s.meta_path(), &bytes)?;
            }
        }
        Ok(s)
    }

    /// Open (creating if needed) a store for `meta` whose design may extend
    /// the stored one (adaptive infill, [`crate::infill`]): an existing
    /// store is accepted when its design is a prefix of `meta.design` and
    /// everything else (names, units, time grid, model) is equal; its
    /// `meta.json` is then replaced atomically by `meta`. Runs are never
    /// removed.
    ///
    /// # Errors
    /// I/O errors; an existing store of another study, or whose design is
    /// not a prefix of this one.
    pub fn open_growing(dir: impl Into<PathBuf>, meta: &StoreMeta) -> Result<Self> {
        let dir = dir.into();
        if let Ok(existing) = RunStore::existing(&dir).and_then(|s| s.meta()) {
            let same = existing.parameter_names == meta.parameter_names
                && existing.parameter_units == meta.parameter_units
                && existing.time == meta.time
                && existing.model == meta.model
                && existing.design.len() <= meta.design.len()
                && existing.design[..] == meta.design[..existing.design.len()];
            if !same {
                return Err(SurrogateError::InvalidSettings(format!(
                    "{} holds runs of another study or another design (its {} design points \
                     are not the first of these {}); use another directory",
                    dir.display(),
                    existing.design.len(),
                    meta.design.len()
                )));
            }
            if existing.study_hash != meta.study_hash {
                let bytes = serde_json::to_vec_pretty(meta)
                    .map_err(|e| SurrogateError::InvalidInput(e.to_string()))?;
                write_atomic(&dir.join("meta.json"), &bytes)?;
            }
        }
        RunStore::open(dir, meta)
    }

    /// Open an existing store (for merge, export, check).
    pub fn existing(dir: impl Into<PathBuf>) -> Result<Self> {
        let s = RunStore { dir: dir.into() };
        s.meta()?;
        Ok(s)
    }

    /// Directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    fn meta_path(&self) -> PathBuf {
        self.dir.join("meta.json")
    }

    fn run_path(&self, index: usize) -> PathBuf {
        self.dir.join("runs").join(format!("{index:06}.json"))
    }

    /// The store's meta data.
    pub fn meta(&self) -> Result<StoreMeta> {
        let p = self.meta_path();
        let text = fs::read_to_string(&p).map_err(io_err(&p))?;
        serde_json::from_str(&text).map_err(|e| SurrogateError::Parse {
            path: p,
            message: e.to_string(),
        })
    }

    /// A finished run, if present and complete.
    pub fn get(&self, index: usize) -> Option<RunRecord> {
        let text = fs::read_to_string(self.run_path(index)).ok()?;
        serde_json::from_str::<RunRecord>(&text)
            .ok()
            .filter(|r| r.index == index)
    }

    fn claim_path(&self, index: usize) -> PathBuf {
        self.dir.join("runs").join(format!("{index:06}.claim"))
    }

    /// Claims run `index` for this process, so that concurrent builds into
    /// one store share the work: the claim file `runs/<index>.claim` is
    /// created exclusively and holds the process id. `None` when a running
    /// process holds the claim; a claim of a process that no longer runs
    /// (killed) is taken over. The claim is released when dropped.
    ///
    /// # Errors
    /// The claim file cannot be created for another reason than existing.
    pub fn claim(&self, index: usize) -> Result<Option<Claim>> {
        let path = self.claim_path(index);
        for _ in 0..2 {
            match fs::OpenOptions::new()
                .write(true)
                .create_new(true)
                .open(&path)
            {
                Ok(mut f) => {
                    use std::io::Write as _;
                    f.write_all(std::process::id().to_string().as_bytes())
                        .map_err(io_err(&path))?;
                    return Ok(Some(Claim { path }));
                }
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                    let owner = fs::read_to_string(&path)
                        .ok()
                        .and_then(|t| t.trim().parse::<u32>().ok());
                    match owner {
                        Some(pid)
                            if pid != std::process::id()
                                && nlvid_study::process_alive(pid, &path) =>
                        {
                            return Ok(None);
                        }
                        // Ours from an earlier store in this process, or
                        // written by a process killed since: stale.
                        Some(_) => {
                            let _ = fs::remove_file(&path);
                        }
                        // Empty: being written right now, or its writer
                        // was killed between creating and writing it.
                        None => {
                            let age = fs::metadata(&path)
                                .and_then(|m| m.modified())
                                .ok()
                                .and_then(|t| t.elapsed().ok());
                            if age.is_some_and(|a| a.as_secs() >= 10) {
                                let _ = fs::remove_file(&path);
                            } else {
                                return Ok(None);
                            }
                        }
                    }
                }
                Err(e) => return Err(io_err(&path)(e)),
            }
        }
        Ok(None)
    }

    /// Store a run atomically.
    pub fn put(&self, rec: &RunRecord) -> Result<()> {
        let bytes =
            serde_json::to_vec(rec).map_err(|e| SurrogateError::InvalidInput(e.to_string()))?;
        write_atomic(&self.run_path(rec.index), &bytes)
    }

    /// All finished runs, by index.
    pub fn all(&self) -> Result<Vec<RunRecord>> {
        let n = self.meta()?.design.len();
        Ok((0..n).filter_map(|i| self.get(i)).collect())
    }
}

/// A claim on one run of a store ([`RunStore::claim`]); removed on drop.
#[derive(Debug)]
pub struct Claim {
    path: PathBuf,
}

impl Drop for Claim {
    fn drop(&mut self) {
        let _ = fs::remove_file(&self.path);
    }
}

/// Merge shard stores into `out` (all must share the study hash; a run
/// present in several shards must agree).
///
/// # Errors
/// Different studies, conflicting duplicate runs, I/O.
pub fn merge(shards: &[PathBuf], out: &Path) -> Result<usize> {
    let first = shards
        .first()
        .ok_or_else(|| SurrogateError::InvalidInput("no shard directories given".into()))?;
    let meta = RunStore::existing(first)?.meta()?;
    let dest = RunStore::open(out, &meta)?;
    let mut count = 0;
    for dir in shards {
        let s = RunStore::existing(dir)?;
        let m = s.meta()?;
        if m.study_hash != meta.study_hash {
            return Err(SurrogateError::InvalidInput(format!(
                "{} belongs to study {} but {} to {}",
                dir.display(),
                m.study_hash,
                first.display(),
                meta.study_hash
            )));
        }
        for rec in s.all()? {
            if let Some(prev) = dest.get(rec.index) {
                if prev.outcome != rec.outcome {
                    return Err(SurrogateError::InvalidInput(format!(
                        "run {} differs between shards ({})",
                        rec.index,
                        dir.display()
                    )));
                }
                continue;
            }
            dest.put(&rec)?;
            count += 1;
        }
    }
    Ok(count)
}
