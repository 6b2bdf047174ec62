//! Meta-model build (thesis §4.4.1 steps 1–3, §5.4.1): run the forward
//! model at every design point in parallel, store each result atomically
//! ([`crate::store`]), resume after interruption, build one shard of a
//! Slurm job array, apply the admissibility filters, export X and Y for
//! numpy/pandas.

use std::path::Path;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::Instant;

use nlvid_model::{Domain, FailureKind, ForwardModel, RunFailure};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::{Result, SurrogateError, io_err};
use crate::store::{RunOutcome, RunRecord, RunStore, StoreMeta, write_atomic};

/// Slice `index`/`count` of a build: run indices i with i mod count = index
/// (interleaved, so shards get similar parameter mixes).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// This shard, 0-based.
    pub index: usize,
    /// Number of shards.
    pub count: usize,
}

impl Shard {
    /// The whole build.
    pub const ALL: Shard = Shard { index: 0, count: 1 };

    /// Parse `i/n` (1-based `i`, as Slurm's `SLURM_ARRAY_TASK_ID` + 1 or
    /// a human would write it: `1/4` … `4/4`).
    pub fn parse(s: &str) -> Result<Self> {
        let bad =
            || SurrogateError::InvalidSettings(format!("--shard {s}: expected i/n with 1 ≤ i ≤ n"));
        let (a, b) = s.split_once('/').ok_or_else(bad)?;
        let i: usize = a.trim().parse().map_err(|_| bad())?;
        let n: usize = b.trim().parse().map_err(|_| bad())?;
        if i == 0 || n == 0 || i > n {
            return Err(bad());
        }
        Ok(Shard {
            index: i - 1,
            count: n,
        })
    }

    /// Whether run `i` belongs to this shard.
    pub fn contains(&self, i: usize) -> bool {
        i % self.count == self.index
    }
}

/// Options of a build.
#[derive(Default)]
pub struct BuildOptions<'a> {
    /// Slice to build (default: all).
    pub shard: Option<Shard>,
    /// Show a progress bar on stderr.
    pub progress: bool,
    /// Set to stop starting new runs (runs in progress finish and are
    /// stored); used for graceful interruption and tests.
    pub cancel: Option<&'a AtomicBool>,
}

/// What a build did.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct BuildSummary {
    /// Runs in this shard.
    pub in_shard: usize,
    /// Found already finished (resumed).
    pub skipped: usize,
    /// Run now.
    pub ran: usize,
    /// Of those run now, failed.
    pub failed: usize,
    /// Not run because of cancellation.
    pub remaining: usize,
    /// Run meanwhile by another build into the same store (work shared
    /// through [`RunStore::claim`]).
    #[serde(default)]
    pub by_others: usize,
}

/// Run the model at every design point of the shard not yet in the store.
///
/// # Errors
/// Store I/O errors (a failing run is stored as a failure, not an error).
pub fn build(
    model: &dyn ForwardModel,
    design: &[Vec<f64>],
    store_dir: &Path,
    opts: &BuildOptions<'_>,
) -> Result<BuildSummary> {
    let meta = StoreMeta::new(
        model.parameter_names(),
        model.parameter_units(),
        model.time_grid().to_vec(),
        design.to_vec(),
        model.identity(),
    )
    .with_conditions(model.conditions());
    build_into(model, design, &RunStore::open(store_dir, &meta)?, opts)
}

/// [`build`] into an opened store (whose meta data holds `design`).
pub(crate) fn build_into(
    model: &dyn ForwardModel,
    design: &[Vec<f64>],
    store: &RunStore,
    opts: &BuildOptions<'_>,
) -> Result<BuildSummary> {
    let shard = opts.shard.unwrap_or(Shard::ALL);
    let todo_all: Vec<usize> = (0..design.len()).filter(|&i| shard.contains(i)).collect();
    let in_shard = todo_all.len();
    let todo: Vec<usize> = todo_all
        .into_iter()
        .filter(|&i| store.get(i).is_none())
        .collect();
    let skipped = in_shard - todo.len();
    let bar = if opts.progress {
        let b = indicatif::ProgressBar::new(in_shard as u64);
        b.set_style(
            indicatif::ProgressStyle::with_template(
                "{bar:40} {pos}/{len} runs, {per_sec}, eta {eta}",
            )
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        b.set_position(skipped as u64);
        b
    } else {
        indicatif::ProgressBar::hidden()
    };
    let ran = AtomicUsize::new(0);
    let failed = AtomicUsize::new(0);
    let m = model.time_grid().len();
    // Runs another build into the same store holds: waited for at the end.
    let deferred = std::sync::Mutex::new(Vec::new());
    let others = AtomicUsize::new(0);
    let cancelled = || opts.cancel.is_some_and(|c| c.load(Ordering::SeqCst));
    let run_one = |i: usize| -> Result<bool> {
        let Some(_claim) = store.claim(i)? else {
            return Ok(false);
        };
        if store.get(i).is_some() {
            // Finished by another build just before.
            others.fetch_add(1, Ordering::Relaxed);
            bar.inc(1);
            return Ok(true);
        }
        let t0 = Instant::now();
        let outcome = match model.run(&design[i]) {
            Ok(r) if r.len() != m => RunOutcome::Failed {
                failure: RunFailure {
                    kind: FailureKind::BadResponse,
                    time: None,
                    message: format!("response has {} values, time grid {m}", r.len()),
                },
            },
            Ok(r) if r.iter().any(|v| !v.is_finite()) => {
                let k = r.iter().position(|v| !v.is_finite()).unwrap_or(0);
                RunOutcome::Failed {
                    failure: RunFailure {
                        kind: FailureKind::BadResponse,
                        time: model.time_grid().get(k).copied(),
                        message: "non-finite response value".into(),
                    },
                }
            }
            Ok(response) => RunOutcome::Ok { response },
            Err(failure) => RunOutcome::Failed { failure },
        };
        if matches!(outcome, RunOutcome::Failed { .. }) {
            failed.fetch_add(1, Ordering::Relaxed);
        }
        let rec = RunRecord {
            index: i,
            params: design[i].clone(),
            outcome,
            seconds: t0.elapsed().as_secs_f64(),
        };
        store.put(&rec)?;
        ran.fetch_add(1, Ordering::Relaxed);
        bar.inc(1);
        Ok(true)
    };
    todo.par_iter().try_for_each(|&i| -> Result<()> {
        if !cancelled() && !run_one(i)? {
            deferred.lock().map_err(|_| poisoned())?.push(i);
        }
        Ok(())
    })?;
    // Wait for the runs other builds claimed; take over those whose
    // builder was killed.
    let mut waiting = deferred.into_inner().map_err(|_| poisoned())?;
    while !waiting.is_empty() && !cancelled() {
        let before = waiting.len();
        let mut still = Vec::new();
        for i in waiting {
            if store.get(i).is_some() {
                others.fetch_add(1, Ordering::Relaxed);
                bar.inc(1);
            } else if !run_one(i)? {
                still.push(i);
            }
        }
        if still.len() == before {
            std::thread::sleep(std::time::Duration::from_millis(20));
        }
        waiting = still;
    }
    bar.finish_and_clear();
    let (ran, by_others) = (ran.into_inner(), others.into_inner());
    Ok(BuildSummary {
        in_shard,
        skipped,
        ran,
        failed: failed.into_inner(),
        remaining: in_shard - skipped - ran - by_others,
        by_others,
    })
}

fn poisoned() -> SurrogateError {
    SurrogateError::InvalidInput("a build thread panicked".into())
}

/// Admissibility filters of the thesis (§5.4.1, App. A.2).
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct Admissibility {
    /// Remove runs whose peak response is below this [N].
    pub min_peak_force: Option<f64>,
    /// Remove runs with any non-positive (non-repulsive) force after contact.
    pub reject_non_repulsive: bool,
    /// First time index after contact.
    #[serde(default)]
    pub contact_index: usize,
}

impl Admissibility {
    /// Reads the filter keys of the study's `[build]` section:
    /// `min_peak_force` (a force, e.g. `"4 nN"`) and
    /// `reject_non_repulsive` (bool); `contact_index` comes from the model.
    ///
    /// # Errors
    /// Wrong unit or type (file, line, key).
    pub fn from_section(
        s: &mut nlvid_study::Section,
        contact_index: usize,
    ) -> nlvid_study::Result<Self> {
        use nlvid_study::{Bounds, Dimension};
        Ok(Self {
            min_peak_force: s.opt_quantity(
                "min_peak_force",
                Dimension::FORCE,
                Bounds::non_negative(),
            )?,
            reject_non_repulsive: s.opt_bool("reject_non_repulsive")?.unwrap_or(false),
            contact_index,
        })
    }
}

/// Counts of a filtered meta-model.
#[derive(Debug, Clone, Default, Serialize, Deserialize, PartialEq)]
pub struct FilterCounts {
    /// Design points.
    pub design: usize,
    /// Not (yet) run.
    pub missing: usize,
    /// Failed runs.
    pub failed: usize,
    /// Removed by the peak-force threshold.
    pub below_peak: usize,
    /// Removed for non-repulsive force after contact.
    pub non_repulsive: usize,
    /// Kept.
    pub kept: usize,
}

/// A meta-model ready for Kriging: kept runs only.
#[derive(Debug, Clone)]
pub struct MetaModel {
    /// Shared data.
    pub meta: StoreMeta,
    /// Design indices of the kept rows.
    pub index: Vec<usize>,
    /// Parameters of kept runs.
    pub x: Vec<Vec<f64>>,
    /// Responses of kept runs.
    pub y: Vec<Vec<f64>>,
    /// All records (kept or not) with their status label.
    pub status: Vec<(usize, String, String, f64)>,
    /// Filter counts.
    pub counts: FilterCounts,
}

/// Load a store and apply the filters.
pub fn load(store_dir: &Path, filt: &Admissibility) -> Result<MetaModel> {
    let store = RunStore::existing(store_dir)?;
    let meta = store.meta()?;
    let mut mm = MetaModel {
        counts: FilterCounts {
            design: meta.design.len(),
            ..Default::default()
        },
        meta,
        index: vec![],
        x: vec![],
        y: vec![],
        status: vec![],
    };
    for i in 0..mm.meta.design.len() {
        let Some(rec) = store.get(i) else {
            mm.counts.missing += 1;
            mm.status.push((i, "missing".into(), String::new(), 0.0));
            continue;
        };
        match rec.outcome {
            RunOutcome::Failed { failure } => {
                mm.counts.failed += 1;
                mm.status
                    .push((i, "failed".into(), failure.to_string(), rec.seconds));
            }
            RunOutcome::Ok { response } => {
                let peak = response.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                let label = if filt.min_peak_force.is_some_and(|p| peak < p) {
                    mm.counts.below_peak += 1;
                    "below_peak"
                } else if filt.reject_non_repulsive
                    && response.iter().skip(filt.contact_index).any(|&f| f <= 0.0)
                {
                    mm.counts.non_repulsive += 1;
                    "non_repulsive"
                } else {
                    mm.counts.kept += 1;
                    mm.index.push(i);
                    mm.x.push(rec.params.clone());
                    mm.y.push(response);
                    "ok"
                };
                mm.status
                    .push((i, label.into(), String::new(), rec.seconds));
            }
        }
    }
    Ok(mm)
}

/// Write a little-endian f64 C-order `.npy` file (numpy format 1.0).
pub fn write_npy(path: &Path, rows: &[Vec<f64>], ncols: usize) -> Result<()> {
    let mut header = format!(
        "{{'descr': '<f8', 'fortran_order': False, 'shape': ({}, {}), }}",
        rows.len(),
        ncols
    );
    let unpadded = 10 + header.len() + 1;
    header.push_str(&" ".repeat((64 - unpadded % 64) % 64));
    header.push('\n');
    let mut bytes = Vec::with_capacity(10 + header.len() + rows.len() * ncols * 8);
    bytes.extend_from_slice(b"\x93NUMPY\x01\x00");
    bytes.extend_from_slice(&(header.len() as u16).to_le_bytes());
    bytes.extend_from_slice(header.as_bytes());
    for r in rows {
        for v in r {
            bytes.extend_from_slice(&v.to_le_bytes());
        }
    }
    write_atomic(path, &bytes)
}

/// Writes a CSV table (header, rows) through [`write_atomic`]: the file is
/// absent or complete, never cut by a kill or a full disk.
fn write_csv(
    path: &Path,
    head: Vec<String>,
    rows: impl Iterator<Item = Vec<String>>,
) -> Result<()> {
    let err = |e: csv::Error| SurrogateError::Parse {
        path: path.to_path_buf(),
        message: e.to_string(),
    };
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(&head).map_err(err)?;
    for r in rows {
        w.write_record(&r).map_err(err)?;
    }
    let bytes = w
        .into_inner()
        .map_err(|e| SurrogateError::InvalidInput(format!("CSV buffer: {e}")))?;
    write_atomic(path, &bytes)
}

/// Export a filtered meta-model to `dir`: `X.csv`, `Y.csv`, `X.npy`,
/// `Y.npy`, `t.npy`, `status.csv` (index, status, reason), `timing.csv`
/// (index, status, wall seconds) and `meta.json` (names, units, time,
/// study hash, filter counts, and the parameter `domain` the design was
/// drawn in, which `nlvid fit` and `nlvid cohort` read back). Everything
/// but `timing.csv` is a deterministic function of the store's results.
///
/// # Errors
/// A `domain` whose parameters are not the store's (names, order), a run
/// outside it; I/O.
pub fn export(mm: &MetaModel, dir: &Path, domain: Option<&Domain>) -> Result<()> {
    if let Some(d) = domain {
        d.check_names(&mm.meta.parameter_names)
            .map_err(|e| SurrogateError::InvalidInput(format!("export domain: {e}")))?;
        if let Some((i, _)) = mm
            .index
            .iter()
            .zip(&mm.x)
            .find(|(_, x)| !d.contains(x, 1e-9))
        {
            return Err(SurrogateError::InvalidInput(format!(
                "export domain: design point {i} lies outside it"
            )));
        }
    }
    std::fs::create_dir_all(dir).map_err(io_err(dir))?;
    let x_rows = mm.index.iter().zip(&mm.x).map(|(i, x)| {
        std::iter::once(i.to_string())
            .chain(x.iter().map(|v| format!("{v:e}")))
            .collect::<Vec<_>>()
    });
    let head = std::iter::once("index".to_string()).chain(
        mm.meta
            .parameter_names
            .iter()
            .zip(&mm.meta.parameter_units)
            .map(|(n, u)| format!("{n} [{u}]")),
    );
    write_csv(&dir.join("X.csv"), head.collect(), x_rows)?;
    write_csv(
        &dir.join("Y.csv"),
        mm.meta
            .time
            .iter()
            .map(|t| format!("F(t={t:e} s) [N]"))
            .collect(),
        mm.y.iter()
            .map(|y| y.iter().map(|v| format!("{v:e}")).collect()),
    )?;
    // status.csv is deterministic (merged shards and resumed builds
    // reproduce it byte for byte); wall times go to timing.csv.
    write_csv(
        &dir.join("status.csv"),
        vec!["index".into(), "status".into(), "reason".into()],
        mm.status
            .iter()
            .map(|(i, s, r, _)| vec![i.to_string(), s.clone(), r.clone()]),
    )?;
    write_csv(
        &dir.join("timing.csv"),
        vec!["index".into(), "status".into(), "seconds".into()],
        mm.status
            .iter()
            .map(|(i, s, _, sec)| vec![i.to_string(), s.clone(), format!("{sec:e}")]),
    )?;
    write_npy(&dir.join("X.npy"), &mm.x, mm.meta.parameter_names.len())?;
    write_npy(&dir.join("Y.npy"), &mm.y, mm.meta.time.len())?;
    write_npy(
        &dir.join("t.npy"),
        std::slice::from_ref(&mm.meta.time),
        mm.meta.time.len(),
    )?;
    let sidecar = serde_json::json!({
        "parameter_names": mm.meta.parameter_names,
        "parameter_units": mm.meta.parameter_units,
        "time_s": mm.meta.time,
        "study_hash": mm.meta.study_hash,
        "model": mm.meta.model,
        "domain": domain,
        "conditions": mm.meta.conditions,
        "counts": mm.counts,
        "files": {"X": "X.npy / X.csv (rows: kept runs)", "Y": "Y.npy / Y.csv", "t": "t.npy", "status": "status.csv", "timing": "timing.csv (wall seconds per run; the only file that differs between identical builds)"},
    });
    let bytes = serde_json::to_vec_pretty(&sidecar)
        .map_err(|e| SurrogateError::InvalidInput(e.to_string()))?;
    write_atomic(&dir.join("meta.json"), &bytes)
}
