//! What a Slurm build asks of the cluster, checked before any script is
//! written: every value ends up in a `#SBATCH` line or a shell script, so
//! each is held to the syntax Slurm accepts and to characters that cannot
//! change the script's meaning.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::error::{Result, SurrogateError};

/// Settings of a meta-model build as a Slurm job array plus a merge job.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SlurmSettings {
    /// The study file (absolute path, seen by the compute nodes).
    pub study: PathBuf,
    /// The `nlvid` program the tasks run (absolute path, seen by the
    /// compute nodes).
    pub nlvid: PathBuf,
    /// Job directory (absolute, on a file system every node can write):
    /// scripts, `logs/`, `state/`, per-task stores `stores/task-<i>`, the
    /// merged store `store/`.
    pub dir: PathBuf,
    /// Where the merge job exports X and Y (default `<dir>/export`).
    pub export: PathBuf,
    /// Array tasks = shards (task i builds shard i+1/n).
    pub array_size: usize,
    /// At most this many tasks run at once (`--array=…%k`); `None`: as
    /// many as the scheduler allows.
    pub throttle: Option<usize>,
    /// CPUs per task (`--cpus-per-task`; the task's rayon threads).
    pub cpus_per_task: usize,
    /// Wall-time limit per task and of the merge job (`--time`, Slurm
    /// syntax: `M`, `M:S`, `H:M:S`, `D-H`, `D-H:M`, `D-H:M:S`).
    pub time: String,
    /// Memory per task (`--mem`, e.g. `2G`); `None`: the partition default.
    pub mem: Option<String>,
    /// `--partition` (comma-separated list allowed).
    pub partition: Option<String>,
    /// `--account`.
    pub account: Option<String>,
    /// Node-local scratch for the task stores (e.g. `$TMPDIR` or
    /// `/local/$USER`, expanded on the node); the finished runs are
    /// copied to the shared task store at the end, every `sync_every`
    /// seconds and on SIGTERM. `None`: tasks write the shared store.
    pub scratch: Option<String>,
    /// Environment modules loaded before the build (`module load …`).
    pub modules: Vec<String>,
    /// A task whose `nlvid` is killed by a signal asks Slurm to requeue it
    /// at most this many times.
    pub max_requeue: usize,
    /// With `scratch`: copy finished runs back every this many seconds
    /// (0: only at the end).
    pub sync_every: u64,
}

impl SlurmSettings {
    /// Defaults for everything but the paths: 8 tasks, no throttle, 1 CPU,
    /// 1 hour, partition default memory, no scratch, 3 requeues, sync every
    /// 10 minutes; export to `<dir>/export`.
    pub fn new(study: PathBuf, nlvid: PathBuf, dir: PathBuf) -> Self {
        let export = dir.join("export");
        Self {
            study,
            nlvid,
            dir,
            export,
            array_size: 8,
            throttle: None,
            cpus_per_task: 1,
            time: "1:00:00".into(),
            mem: None,
            partition: None,
            account: None,
            scratch: None,
            modules: Vec::new(),
            max_requeue: 3,
            sync_every: 600,
        }
    }

    /// Checks every value; the message names the option and what to give.
    ///
    /// # Errors
    /// [`SurrogateError::InvalidSettings`] for the first bad value.
    pub fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(SurrogateError::InvalidSettings(m));
        for (name, p) in [
            ("study", &self.study),
            ("nlvid", &self.nlvid),
            ("out", &self.dir),
            ("export", &self.export),
        ] {
            check_path(name, p)?;
        }
        if self.array_size == 0 {
            return bad("--array-size 0: give at least 1 task".into());
        }
        if self.throttle == Some(0) {
            return bad("--throttle 0: give at least 1 (tasks running at once)".into());
        }
        if self.cpus_per_task == 0 {
            return bad("--cpus-per-task 0: give at least 1".into());
        }
        if !is_slurm_time(&self.time) {
            return bad(format!(
                "--time {:?}: not a Slurm time; use minutes, M:S, H:M:S, D-H, D-H:M or D-H:M:S (e.g. 2:00:00)",
                self.time
            ));
        }
        if let Some(m) = &self.mem
            && !is_slurm_mem(m)
        {
            return bad(format!(
                "--mem {m:?}: not a Slurm memory size; use a whole number with K, M, G or T (e.g. 2G)"
            ));
        }
        for (name, v) in [("partition", &self.partition), ("account", &self.account)] {
            if let Some(v) = v
                && !is_word(v, ",")
            {
                return bad(format!(
                    "--{name} {v:?}: use letters, digits and _ . - + (a list separated by commas)"
                ));
            }
        }
        for m in &self.modules {
            if !is_word(m, "/") {
                return bad(format!(
                    "--module {m:?}: a module name has letters, digits and _ . - + / (e.g. gcc/12.2)"
                ));
            }
        }
        if let Some(s) = &self.scratch
            && !is_scratch(s)
        {
            return bad(format!(
                "--scratch {s:?}: give an absolute path or one starting with an environment \
                 variable, with letters, digits, _ . - / and $VAR or ${{VAR}} (e.g. '$TMPDIR' or /local/$USER)"
            ));
        }
        Ok(())
    }

    /// Advice that does not stop the generation (printed by the caller).
    pub fn warnings(&self) -> Vec<String> {
        let mut w = Vec::new();
        if self.array_size > 1000 {
            w.push(format!(
                "--array-size {}: Slurm's default MaxArraySize is 1001 (indices 0–1000); see \
                 `scontrol show config | grep -i MaxArraySize` and your site's per-user job limits",
                self.array_size
            ));
        }
        if self.dir.starts_with("/tmp") || self.dir.starts_with("/var/tmp") {
            w.push(format!(
                "--out {}: /tmp is node-local on most clusters; the merge job and other nodes will \
                 not see the task stores. Use project or scratch space shared by all nodes",
                self.dir.display()
            ));
        }
        w
    }

    /// The array as Slurm writes it: `0-{n-1}` with `%k` when throttled.
    pub fn array_spec(&self) -> String {
        self.with_throttle(&format!("0-{}", self.array_size.saturating_sub(1)))
    }

    /// `indices` (e.g. `3,7`) with this build's throttle.
    pub fn with_throttle(&self, indices: &str) -> String {
        match self.throttle {
            Some(k) => format!("{indices}%{k}"),
            None => indices.to_string(),
        }
    }
}

/// The name of a Slurm job made from the study's file name.
pub(crate) fn job_name(study: &Path) -> String {
    let stem = study
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let clean: String = stem
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || "_.-".contains(c) {
                c
            } else {
                '_'
            }
        })
        .collect();
    if clean.is_empty() {
        "study".into()
    } else {
        clean
    }
}

/// Absolute, UTF-8, and free of characters that `#SBATCH` lines or file
/// name patterns would read differently (white space, quotes, `%`, `$`,
/// backslash, backquote).
fn check_path(name: &str, p: &Path) -> Result<()> {
    let Some(s) = p.to_str() else {
        return Err(SurrogateError::InvalidSettings(format!(
            "--{name} {}: not valid UTF-8; choose a path with plain characters",
            p.display()
        )));
    };
    if !p.is_absolute() {
        return Err(SurrogateError::InvalidSettings(format!(
            "--{name} {s}: must be an absolute path (compute nodes start in another directory)"
        )));
    }
    if let Some(c) = s
        .chars()
        .find(|c| c.is_whitespace() || "%$'\"\\`".contains(*c))
    {
        return Err(SurrogateError::InvalidSettings(format!(
            "--{name} {s}: contains {c:?}, which #SBATCH lines or Slurm file patterns cannot hold; \
             choose a path without spaces, quotes, %, $, \\ or `"
        )));
    }
    Ok(())
}

fn digits(s: &str) -> bool {
    !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit())
}

/// Slurm's `--time` syntax (sbatch(1)): `M`, `M:S`, `H:M:S`, `D-H`,
/// `D-H:M`, `D-H:M:S`, or `UNLIMITED`/`INFINITE`.
pub(crate) fn is_slurm_time(t: &str) -> bool {
    if t.eq_ignore_ascii_case("unlimited") || t.eq_ignore_ascii_case("infinite") {
        return true;
    }
    let (days, rest) = match t.split_once('-') {
        Some((d, r)) => (Some(d), r),
        None => (None, t),
    };
    if days.is_some_and(|d| !digits(d)) {
        return false;
    }
    let parts: Vec<&str> = rest.split(':').collect();
    parts.len() <= 3 && parts.iter().all(|p| digits(p))
}

/// Slurm's `--mem` syntax: a whole number with an optional unit K, M, G, T.
pub(crate) fn is_slurm_mem(m: &str) -> bool {
    let num = m
        .strip_suffix(['K', 'M', 'G', 'T', 'k', 'm', 'g', 't'])
        .unwrap_or(m);
    digits(num)
}

fn is_word(s: &str, extra: &str) -> bool {
    !s.is_empty()
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || "_.-+".contains(c) || extra.contains(c))
}

/// A path expanded by the shell on the node: absolute or starting with a
/// variable; only `$NAME`/`${NAME}` expansions (no command substitution).
fn is_scratch(s: &str) -> bool {
    if !(s.starts_with('/') || s.starts_with('$')) {
        return false;
    }
    let b = s.as_bytes();
    let mut k = 0;
    while k < b.len() {
        let c = b[k] as char;
        if c == '$' {
            let rest = &s[k + 1..];
            let (name, used) = if let Some(r) = rest.strip_prefix('{') {
                match r.find('}') {
                    Some(e) => (&r[..e], e + 2),
                    None => return false,
                }
            } else {
                let e = rest
                    .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
                    .unwrap_or(rest.len());
                (&rest[..e], e)
            };
            let valid = !name.is_empty()
                && !name.starts_with(|c: char| c.is_ascii_digit())
                && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
            if !valid {
                return false;
            }
            k += 1 + used;
        } else if c.is_ascii_alphanumeric() || "_.-/".contains(c) {
            k += 1;
        } else {
            return false;
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    fn settings() -> SlurmSettings {
        SlurmSettings::new(
            "/home/u/study.toml".into(),
            "/home/u/bin/nlvid".into(),
            "/scratch/u/job".into(),
        )
    }

    #[test]
    fn slurm_times_follow_the_sbatch_manual() {
        for ok in [
            "30",
            "30:00",
            "2:00:00",
            "1-0",
            "1-12",
            "1-12:30",
            "1-12:30:00",
            "UNLIMITED",
        ] {
            assert!(is_slurm_time(ok), "{ok}");
        }
        for bad in ["", "2h", "1:2:3:4", "-1", "1-", "a-1", "1:x", "1 :00"] {
            assert!(!is_slurm_time(bad), "{bad}");
        }
    }

    #[test]
    fn memory_sizes_and_names_are_checked() {
        assert!(is_slurm_mem("2G") && is_slurm_mem("500") && is_slurm_mem("500m"));
        assert!(!is_slurm_mem("2GB") && !is_slurm_mem("G") && !is_slurm_mem("1.5G"));
        let mut s = settings();
        s.mem = Some("2 G".into());
        let e = s.validate().unwrap_err().to_string();
        assert!(e.contains("--mem \"2 G\"") && e.contains("e.g. 2G"), "{e}");
        s.mem = None;
        s.partition = Some("short;rm -rf".into());
        assert!(
            s.validate()
                .unwrap_err()
                .to_string()
                .contains("--partition")
        );
        s.partition = Some("short,long".into());
        s.modules = vec!["gcc/12.2".into()];
        assert!(s.validate().is_ok());
        s.modules = vec!["gcc $(id)".into()];
        assert!(s.validate().unwrap_err().to_string().contains("--module"));
    }

    #[test]
    fn scratch_takes_variables_but_no_command_substitution() {
        for ok in ["$TMPDIR", "${TMPDIR}/x", "/local/$USER/nlvid", "/scratch"] {
            assert!(is_scratch(ok), "{ok}");
        }
        for bad in ["tmp", "$(mktemp)", "/x/`id`", "${A", "$1/x", "/a b", "$"] {
            assert!(!is_scratch(bad), "{bad}");
        }
    }

    #[test]
    fn paths_must_be_absolute_and_plain() {
        let mut s = settings();
        s.dir = "job".into();
        assert!(s.validate().unwrap_err().to_string().contains("absolute"));
        s.dir = "/scratch/my job".into();
        let e = s.validate().unwrap_err().to_string();
        assert!(e.contains("--out") && e.contains("without spaces"), "{e}");
        s.dir = "/scratch/50%".into();
        assert!(s.validate().is_err());
    }

    #[test]
    fn counts_must_be_positive_and_large_arrays_warn() {
        let mut s = settings();
        s.array_size = 0;
        assert!(
            s.validate()
                .unwrap_err()
                .to_string()
                .contains("--array-size")
        );
        s.array_size = 5;
        s.throttle = Some(0);
        assert!(s.validate().unwrap_err().to_string().contains("--throttle"));
        s.throttle = Some(2);
        assert_eq!(s.array_spec(), "0-4%2");
        assert_eq!(s.with_throttle("1,3"), "1,3%2");
        assert!(s.warnings().is_empty());
        s.array_size = 2000;
        s.dir = "/tmp/job".into();
        let w = s.warnings();
        assert!(
            w[0].contains("MaxArraySize") && w[1].contains("node-local"),
            "{w:?}"
        );
    }

    #[test]
    fn job_names_are_plain() {
        assert_eq!(job_name(Path::new("/a/hertz-prony.toml")), "hertz-prony");
        assert_eq!(job_name(Path::new("/a/my study.toml")), "my_study");
    }
}
