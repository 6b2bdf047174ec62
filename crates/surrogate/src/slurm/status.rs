//! What the tasks of a Slurm build left behind (`state/task-<i>.ok` or
//! `.failed`, the runs in `stores/task-<i>`) and what to do next. Reads
//! files only, so it works after the jobs are gone from `squeue` and on a
//! machine without Slurm.

use std::fmt;
use std::path::Path;

use super::scripts::{MERGE_SCRIPT, SUBMIT_SCRIPT};
use super::settings::SlurmSettings;
use crate::error::Result;
use crate::store::RunStore;

/// How a task ended, as far as its files tell.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum TaskState {
    /// Its build finished (`state/task-<i>.ok`).
    Done,
    /// It stopped with this message (`state/task-<i>.failed`).
    Failed(String),
    /// It started but has not finished: running, pending after a requeue,
    /// or lost (node crash, cluster outage, cancelled).
    Unfinished,
    /// No trace of it.
    NotStarted,
}

/// One task.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TaskStatus {
    /// Array index (shard index + 1 of the build).
    pub index: usize,
    /// How it ended.
    pub state: TaskState,
    /// Runs in its store (training and checking sets).
    pub runs: usize,
    /// Runs of its shard, when its store exists.
    pub expected: Option<usize>,
}

/// Every task and the merge.
#[derive(Debug, Clone, PartialEq)]
pub struct ArrayStatus {
    /// The build's settings (`slurm.json`).
    pub settings: SlurmSettings,
    /// Task by task.
    pub tasks: Vec<TaskStatus>,
    /// The merge job finished (`state/merge.ok`).
    pub merged: bool,
    /// The merge job stopped with this message (`state/merge.failed`).
    pub merge_failure: Option<String>,
}

/// Runs of shard `i` of `n` in a design of `len` runs (indices k with
/// k mod n = i, [`crate::Shard::contains`]).
fn shard_len(len: usize, i: usize, n: usize) -> usize {
    if i < len { (len - 1 - i) / n + 1 } else { 0 }
}

fn count_runs(store: &Path) -> usize {
    std::fs::read_dir(store.join("runs")).map_or(0, |d| {
        d.filter_map(|e| e.ok())
            .filter(|e| {
                let name = e.file_name();
                let name = name.to_string_lossy();
                name.strip_suffix(".json")
                    .is_some_and(|s| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit()))
            })
            .count()
    })
}

/// Slurm's index list: `0,2-4,7`.
pub(crate) fn index_list(ix: &[usize]) -> String {
    let mut parts = Vec::new();
    let mut k = 0;
    while k < ix.len() {
        let mut e = k;
        while e + 1 < ix.len() && ix[e + 1] == ix[e] + 1 {
            e += 1;
        }
        parts.push(if e > k {
            format!("{}-{}", ix[k], ix[e])
        } else {
            ix[k].to_string()
        });
        k = e + 1;
    }
    parts.join(",")
}

/// Reads a job directory written by [`super::write`].
///
/// # Errors
/// No `slurm.json` in `dir`.
pub fn status(dir: &Path) -> Result<ArrayStatus> {
    let settings = super::read_settings(dir)?;
    let n = settings.array_size;
    let state = dir.join("state");
    let mut tasks = Vec::with_capacity(n);
    for i in 0..n {
        let store = dir.join("stores").join(format!("task-{i}"));
        let mut runs = 0;
        let mut expected = None;
        for set in ["train", "check"] {
            let s = store.join(set);
            runs += count_runs(&s);
            if let Ok(meta) = RunStore::existing(&s).and_then(|st| st.meta()) {
                *expected.get_or_insert(0) += shard_len(meta.design.len(), i, n);
            }
        }
        let failed = std::fs::read_to_string(state.join(format!("task-{i}.failed")));
        let state = if state.join(format!("task-{i}.ok")).is_file() {
            TaskState::Done
        } else if let Ok(msg) = failed {
            TaskState::Failed(msg.trim().to_string())
        } else if store.exists() {
            TaskState::Unfinished
        } else {
            TaskState::NotStarted
        };
        tasks.push(TaskStatus {
            index: i,
            state,
            runs,
            expected,
        });
    }
    Ok(ArrayStatus {
        merged: state.join("merge.ok").is_file(),
        merge_failure: std::fs::read_to_string(state.join("merge.failed"))
            .ok()
            .map(|s| s.trim().to_string()),
        settings,
        tasks,
    })
}

impl ArrayStatus {
    fn indices(&self, f: impl Fn(&TaskState) -> bool) -> Vec<usize> {
        self.tasks
            .iter()
            .filter(|t| f(&t.state))
            .map(|t| t.index)
            .collect()
    }

    /// Tasks that stopped with an error.
    pub fn failed(&self) -> Vec<usize> {
        self.indices(|s| matches!(s, TaskState::Failed(_)))
    }

    /// Tasks not done and not failed.
    pub fn unfinished(&self) -> Vec<usize> {
        self.indices(|s| matches!(s, TaskState::Unfinished | TaskState::NotStarted))
    }

    /// What to do next, in one paragraph.
    pub fn next_step(&self) -> String {
        let dir = self.settings.dir.display();
        let submit = self.settings.dir.join(SUBMIT_SCRIPT);
        let submit = submit.display();
        if self.merged {
            return format!(
                "done: merged store {dir}/store, export {}",
                self.settings.export.display()
            );
        }
        let failed = self.failed();
        let unfinished = self.unfinished();
        let mut s = String::new();
        if !failed.is_empty() {
            let l = index_list(&failed);
            s.push_str(&format!(
                "tasks {l} failed (reasons above, logs in {dir}/logs/task-<i>.out). Fix the cause, \
                 then submit them again: ARRAY={l} {submit} — their finished runs are kept and not \
                 run again, and a new merge job waits for them. "
            ));
        }
        if !unfinished.is_empty() {
            let l = index_list(&unfinished);
            s.push_str(&format!(
                "tasks {l} have not finished: if `squeue -u $USER` still lists them, wait; if not \
                 (cluster outage, cancelled, node failure), submit them again: ARRAY={l} {submit} \
                 — they resume where they stopped."
            ));
        }
        if s.is_empty() {
            s = match &self.merge_failure {
                Some(m) => format!(
                    "every task is done but the merge failed: {m}. After fixing it: sbatch {dir}/{MERGE_SCRIPT}"
                ),
                None => format!(
                    "every task is done but the merge has not run: if `squeue -u $USER` lists it, \
                     wait; if not (it was cancelled because a task had failed), run sbatch {dir}/{MERGE_SCRIPT}"
                ),
            };
        }
        s.trim_end().to_string()
    }
}

impl fmt::Display for ArrayStatus {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "{}: {} tasks of {}",
            self.settings.dir.display(),
            self.tasks.len(),
            self.settings.study.display()
        )?;
        for t in &self.tasks {
            let runs = match t.expected {
                Some(e) => format!("{}/{e} runs", t.runs),
                None => format!("{} runs", t.runs),
            };
            match &t.state {
                TaskState::Done => writeln!(f, "  task {}: done ({runs})", t.index)?,
                TaskState::Failed(m) => writeln!(f, "  task {}: FAILED ({runs}): {m}", t.index)?,
                TaskState::Unfinished => writeln!(
                    f,
                    "  task {}: not finished ({runs}; running, pending or lost)",
                    t.index
                )?,
                TaskState::NotStarted => writeln!(f, "  task {}: not started", t.index)?,
            }
        }
        write!(f, "next: {}", self.next_step())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::store::{RunOutcome, RunRecord, StoreMeta};

    #[test]
    fn shards_lengths_add_up_to_the_design() {
        for len in 0..30 {
            for n in 1..7 {
                let total: usize = (0..n).map(|i| shard_len(len, i, n)).sum();
                assert_eq!(total, len, "len {len}, n {n}");
                for i in 0..n {
                    let direct = (0..len).filter(|k| k % n == i).count();
                    assert_eq!(shard_len(len, i, n), direct);
                }
            }
        }
    }

    #[test]
    fn index_lists_use_slurm_ranges() {
        assert_eq!(index_list(&[0, 2, 3, 4, 7]), "0,2-4,7");
        assert_eq!(index_list(&[5]), "5");
        assert_eq!(index_list(&[]), "");
    }

    #[test]
    fn status_tells_done_failed_unfinished_and_what_to_do() {
        let root = std::env::temp_dir().join(format!("nlvid-slurm-status-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&root);
        let mut s = SlurmSettings::new(
            "/home/u/study.toml".into(),
            "/home/u/bin/nlvid".into(),
            root.join("job"),
        );
        s.array_size = 4;
        let files = super::super::write(&s).expect("write");
        let design: Vec<Vec<f64>> = (0..10).map(|k| vec![k as f64]).collect();
        let meta = StoreMeta::new(
            vec!["a".into()],
            vec!["1".into()],
            vec![0.0],
            design,
            "m".into(),
        );
        // Task 0 done (runs 0, 4, 8), task 1 failed after one run, task 2
        // started (one run), task 3 never started.
        for (task, runs) in [(0, vec![0, 4, 8]), (1, vec![1]), (2, vec![2])] {
            let st = RunStore::open(files.dir.join(format!("stores/task-{task}/train")), &meta)
                .expect("store");
            for k in runs {
                st.put(&RunRecord {
                    index: k,
                    params: vec![k as f64],
                    outcome: RunOutcome::Ok {
                        response: vec![1.0],
                    },
                    seconds: 0.1,
                })
                .expect("put");
            }
        }
        std::fs::write(files.dir.join("state/task-0.ok"), b"").expect("ok");
        std::fs::write(
            files.dir.join("state/task-1.failed"),
            b"nlvid build failed\n",
        )
        .expect("f");
        let st = status(&files.dir).expect("status");
        let states: Vec<_> = st.tasks.iter().map(|t| t.state.clone()).collect();
        assert_eq!(
            states,
            [
                TaskState::Done,
                TaskState::Failed("nlvid build failed".into()),
                TaskState::Unfinished,
                TaskState::NotStarted
            ]
        );
        assert_eq!((st.tasks[0].runs, st.tasks[0].expected), (3, Some(3)));
        assert_eq!((st.tasks[1].runs, st.tasks[1].expected), (1, Some(3)));
        assert_eq!(st.tasks[3].expected, None);
        let text = st.to_string();
        assert!(
            text.contains("task 1: FAILED (1/3 runs): nlvid build failed"),
            "{text}"
        );
        assert!(
            text.contains("tasks 1 failed") && text.contains("ARRAY=1 "),
            "{text}"
        );
        assert!(
            text.contains("tasks 2-3 have not finished") && text.contains("ARRAY=2-3 "),
            "{text}"
        );

        for t in 1..4 {
            let _ = std::fs::remove_file(files.dir.join(format!("state/task-{t}.failed")));
            std::fs::write(files.dir.join(format!("state/task-{t}.ok")), b"").expect("ok");
        }
        assert!(
            status(&files.dir)
                .expect("status")
                .next_step()
                .contains("merge has not run")
        );
        std::fs::write(files.dir.join("state/merge.ok"), b"").expect("ok");
        assert!(
            status(&files.dir)
                .expect("status")
                .next_step()
                .starts_with("done")
        );
    }
}
