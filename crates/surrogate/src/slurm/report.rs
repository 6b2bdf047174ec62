//! What `nlvid slurm` prints: the job directory written (and submitted),
//! and the status of its tasks, as text and as JSON.

use super::{ArrayStatus, JobFiles, Submitted};

impl ArrayStatus {
    /// JSON: `tasks` (index, state, runs, expected), `merged`, `next`.
    pub fn to_json(&self) -> serde_json::Value {
        let tasks: Vec<_> = self
            .tasks
            .iter()
            .map(|t| {
                serde_json::json!({
                    "index": t.index, "state": format!("{:?}", t.state),
                    "runs": t.runs, "expected": t.expected,
                })
            })
            .collect();
        serde_json::json!({ "tasks": tasks, "merged": self.merged, "next": self.next_step() })
    }
}

impl JobFiles {
    /// JSON: the directory, the three scripts and, when submitted, the job ids.
    pub fn to_json(&self, ids: Option<&Submitted>) -> serde_json::Value {
        serde_json::json!({
            "dir": self.dir, "array_script": self.array, "merge_script": self.merge,
            "submit_script": self.submit,
            "array_job": ids.map(|i| &i.array_job),
            "merge_job": ids.map(|i| &i.merge_job),
        })
    }

    /// For people: the scripts written, then the submitted jobs and how to
    /// follow them, or how to submit.
    pub fn text(&self, ids: Option<&Submitted>) -> String {
        let mut s = format!(
            "wrote {} and {}\n",
            self.array.display(),
            self.merge.display()
        );
        match ids {
            Some(i) => s.push_str(&format!(
                "submitted array job {} (tasks {}) and merge job {} (afterok)\n\
                 follow: squeue -j {},{}; nlvid slurm --status {}\n",
                i.array_job,
                i.array,
                i.merge_job,
                i.array_job,
                i.merge_job,
                self.dir.display()
            )),
            None => s.push_str(&format!("submit with: {}\n", self.submit.display())),
        }
        s
    }
}
