//! Meta-model builds as Slurm job arrays: one shard of [`crate::build`]
//! per array task, each into its own [`crate::RunStore`], then a merge job
//! ([`crate::merge`] and [`crate::export`]) that waits for every task with
//! `--dependency=afterok`.
//!
//! [`write`] puts into a job directory `nlvid-build.sbatch` (the array),
//! `nlvid-merge.sbatch`, `submit.sh` and `slurm.json` (the settings);
//! [`submit`] calls `sbatch` as `submit.sh` does; [`status()`] reads what
//! the tasks left (`state/`, `stores/`) and says what to do next.
//!
//! Fault tolerance comes from the store: every finished run is a file
//! renamed into place, so a task killed at any moment keeps its finished
//! runs and a requeued or re-submitted task runs only the rest. A task
//! whose `nlvid` dies by a signal asks Slurm to requeue it
//! (`scontrol requeue`, at most `max_requeue` times); node failures and
//! preemption are requeued by Slurm itself (`--requeue`).

mod scripts;
mod settings;
mod status;

use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::process::Command;

pub use scripts::{
    ARRAY_SCRIPT, MERGE_SCRIPT, SUBMIT_SCRIPT, array_script, merge_script, submit_script,
};
pub use settings::SlurmSettings;
pub use status::{ArrayStatus, TaskState, TaskStatus, status};

use crate::error::{Result, SurrogateError};
use crate::store::write_atomic;

/// The settings, as written by [`write`] and read by [`status()`].
pub const MANIFEST: &str = "slurm.json";

/// Paths of a written job directory.
#[derive(Debug, Clone, PartialEq)]
pub struct JobFiles {
    /// The job directory.
    pub dir: PathBuf,
    /// The array job script.
    pub array: PathBuf,
    /// The merge job script.
    pub merge: PathBuf,
    /// `submit.sh`.
    pub submit: PathBuf,
}

fn cannot_write(dir: &Path, e: &std::io::Error) -> SurrogateError {
    SurrogateError::InvalidSettings(format!(
        "cannot write the job directory {}: {e}. Choose --out on a file system you and every \
         compute node can write (project or scratch space shared by the nodes), and check your quota",
        dir.display()
    ))
}

/// Validates the settings and writes the scripts, `slurm.json` and the
/// directories `logs/`, `state/`, `stores/` into `settings.dir` (scripts
/// executable). Writing again with the same settings gives the same files,
/// so a build can be re-generated and re-submitted to resume.
///
/// # Errors
/// Invalid settings; a job directory that cannot be created or written
/// (the message says what to choose instead).
pub fn write(settings: &SlurmSettings) -> Result<JobFiles> {
    settings.validate()?;
    let dir = &settings.dir;
    for sub in ["logs", "state", "stores"] {
        let d = dir.join(sub);
        std::fs::create_dir_all(&d).map_err(|e| cannot_write(&d, &e))?;
    }
    let probe = dir.join("stores/.nlvid-write-test");
    std::fs::write(&probe, b"")
        .and_then(|()| std::fs::remove_file(&probe))
        .map_err(|e| cannot_write(&dir.join("stores"), &e))?;
    let files = JobFiles {
        dir: dir.clone(),
        array: dir.join(ARRAY_SCRIPT),
        merge: dir.join(MERGE_SCRIPT),
        submit: dir.join(SUBMIT_SCRIPT),
    };
    for (p, text) in [
        (&files.array, array_script(settings)),
        (&files.merge, merge_script(settings)),
        (&files.submit, submit_script(settings)),
    ] {
        write_atomic(p, text.as_bytes()).map_err(|e| match e {
            SurrogateError::Io { source, .. } => cannot_write(dir, &source),
            other => other,
        })?;
        make_executable(p)?;
    }
    let json = serde_json::to_vec_pretty(settings)
        .map_err(|e| SurrogateError::InvalidInput(e.to_string()))?;
    write_atomic(&dir.join(MANIFEST), &json)?;
    Ok(files)
}

#[cfg(unix)]
fn make_executable(p: &Path) -> Result<()> {
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(p, std::fs::Permissions::from_mode(0o755))
        .map_err(crate::error::io_err(p))
}

#[cfg(not(unix))]
fn make_executable(_: &Path) -> Result<()> {
    Ok(())
}

/// Reads `slurm.json` of a job directory written by [`write`].
///
/// # Errors
/// No or unreadable `slurm.json` (the message says how to make one).
pub fn read_settings(dir: &Path) -> Result<SlurmSettings> {
    let p = dir.join(MANIFEST);
    let text = std::fs::read_to_string(&p).map_err(|e| {
        SurrogateError::InvalidInput(format!(
            "{}: {e}: not a job directory of `nlvid slurm` (generate one with \
             `nlvid slurm STUDY --out DIR`)",
            p.display()
        ))
    })?;
    serde_json::from_str(&text).map_err(|e| SurrogateError::Parse {
        path: p,
        message: e.to_string(),
    })
}

/// Job ids of a submitted build.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Submitted {
    /// The array job.
    pub array_job: String,
    /// The merge job (`afterok` on the array job).
    pub merge_job: String,
    /// The tasks submitted (`0-15%4`, or a subset such as `3,7%4`).
    pub array: String,
}

/// Whether `program` can be started: a path, or a name found on `PATH`.
fn on_path(program: &OsStr) -> bool {
    let p = Path::new(program);
    if p.components().count() > 1 {
        return p.is_file();
    }
    std::env::var_os("PATH")
        .is_some_and(|paths| std::env::split_paths(&paths).any(|d| d.join(p).is_file()))
}

/// What to try when `sbatch` refuses a job, from its message.
fn sbatch_hint(stderr: &str) -> &'static str {
    let e = stderr.to_ascii_lowercase();
    if e.contains("partition") {
        "check the partition name with `sinfo -s` and generate the scripts again with --partition"
    } else if e.contains("array") || e.contains("maxarraysize") {
        "the array is larger than the cluster allows (`scontrol show config | grep -i MaxArraySize`): \
         generate the scripts again with a smaller --array-size"
    } else if e.contains("submitjob") || e.contains("job limit") || e.contains("qosmax") {
        "you reached a per-user job limit (`sacctmgr show assoc user=$USER`): use a smaller \
         --array-size, or submit the rest later with ARRAY=… submit.sh"
    } else if e.contains("time limit") {
        "the --time is above the partition's limit (`sinfo -o '%P %l'`): generate the scripts again with a shorter --time"
    } else if e.contains("memory") || e.contains("node configuration") {
        "no node offers what the job asks (--mem, --cpus-per-task): see `sinfo -o '%P %c %m'`"
    } else if e.contains("account") {
        "check --account with `sacctmgr show assoc user=$USER format=account`"
    } else {
        "read the message above, fix the settings and generate the scripts again"
    }
}

fn run_sbatch(sbatch: &OsStr, args: &[String], what: &str) -> Result<String> {
    let out = Command::new(sbatch).args(args).output().map_err(|e| {
        SurrogateError::InvalidInput(format!(
            "could not start {}: {e}",
            Path::new(sbatch).display()
        ))
    })?;
    let stderr = String::from_utf8_lossy(&out.stderr).trim().to_string();
    if !out.status.success() {
        return Err(SurrogateError::InvalidInput(format!(
            "sbatch refused the {what} ({}): {stderr}\nwhat to do: {}",
            out.status,
            sbatch_hint(&stderr)
        )));
    }
    let stdout = String::from_utf8_lossy(&out.stdout);
    let id = stdout.trim().split(';').next().unwrap_or("").trim();
    if id.is_empty() || !id.bytes().all(|b| b.is_ascii_digit()) {
        return Err(SurrogateError::InvalidInput(format!(
            "sbatch submitted the {what} but printed no job id ({:?}); check `squeue -u $USER`",
            stdout.trim()
        )));
    }
    Ok(id.to_string())
}

/// Submits the array job (all tasks, or the Slurm index list `tasks`, e.g.
/// `3,7`), then the merge job with `--dependency=afterok:<array id>
/// --kill-on-invalid-dep=yes`, the two calls of `submit.sh`. `sbatch` is
/// the program to call (normally `"sbatch"`, found on `PATH`).
///
/// # Errors
/// `sbatch` missing (with what to do: a login node, `module load slurm`,
/// or `submit.sh` later), or refusing a job (its message and a hint).
pub fn submit(settings: &SlurmSettings, tasks: Option<&str>, sbatch: &OsStr) -> Result<Submitted> {
    let dir = &settings.dir;
    if !on_path(sbatch) {
        return Err(SurrogateError::InvalidInput(format!(
            "{} not found on PATH: this machine cannot submit Slurm jobs. The scripts are written \
             to {}; submit them from a login node of the cluster (on some sites after \
             `module load slurm`) with {}",
            Path::new(sbatch).display(),
            dir.display(),
            dir.join(SUBMIT_SCRIPT).display()
        )));
    }
    if let Some(t) = tasks
        && (t.is_empty() || !t.chars().all(|c| c.is_ascii_digit() || ",-:".contains(c)))
    {
        return Err(SurrogateError::InvalidSettings(format!(
            "tasks {t:?}: give Slurm array indices such as 3,7 or 0-4"
        )));
    }
    let array = match tasks {
        Some(t) => settings.with_throttle(t),
        None => settings.array_spec(),
    };
    let array_job = run_sbatch(
        sbatch,
        &[
            "--parsable".into(),
            format!("--array={array}"),
            dir.join(ARRAY_SCRIPT).to_string_lossy().into_owned(),
        ],
        "array job",
    )?;
    let merge_job = run_sbatch(
        sbatch,
        &[
            "--parsable".into(),
            format!("--dependency=afterok:{array_job}"),
            "--kill-on-invalid-dep=yes".into(),
            dir.join(MERGE_SCRIPT).to_string_lossy().into_owned(),
        ],
        "merge job",
    )
    .map_err(|e| {
        SurrogateError::InvalidInput(format!(
            "{e}\nThe array job {array_job} is submitted; once it is done, merge with \
             `sbatch {}` or `nlvid merge {}/stores/task-* --out {}/store --export {} --study {}`",
            dir.join(MERGE_SCRIPT).display(),
            dir.display(),
            dir.display(),
            settings.export.display(),
            settings.study.display()
        ))
    })?;
    Ok(Submitted {
        array_job,
        merge_job,
        array,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("nlvid-slurm-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).expect("temp dir");
        d
    }

    fn settings(dir: &Path) -> SlurmSettings {
        let mut s = SlurmSettings::new(
            "/home/u/study.toml".into(),
            "/home/u/bin/nlvid".into(),
            dir.join("job"),
        );
        s.array_size = 4;
        s.throttle = Some(2);
        s
    }

    /// A stand-in for sbatch: logs its arguments, prints a job id.
    fn fake_sbatch(dir: &Path, body: &str) -> PathBuf {
        let p = dir.join("sbatch");
        std::fs::write(
            &p,
            format!(
                "#!/bin/sh\necho \"$*\" >> {}/sbatch.log\n{body}\n",
                dir.display()
            ),
        )
        .expect("fake sbatch");
        make_executable(&p).expect("chmod");
        p
    }

    #[test]
    fn write_makes_the_directories_scripts_and_manifest() {
        let root = temp("write");
        let s = settings(&root);
        let f = write(&s).expect("write");
        for d in ["logs", "state", "stores"] {
            assert!(f.dir.join(d).is_dir(), "{d}");
        }
        assert_eq!(
            std::fs::read_to_string(&f.array).expect("array"),
            array_script(&s)
        );
        assert_eq!(read_settings(&f.dir).expect("manifest"), s);
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            let mode = std::fs::metadata(&f.submit)
                .expect("meta")
                .permissions()
                .mode();
            assert_eq!(mode & 0o111, 0o111);
        }
    }

    #[test]
    fn an_unwritable_job_directory_says_what_to_choose() {
        let root = temp("unwritable");
        // A path below a regular file cannot be created, even by root.
        std::fs::write(root.join("file"), b"").expect("file");
        let mut s = settings(&root);
        s.dir = root.join("file/job");
        s.export = s.dir.join("export");
        let e = write(&s).unwrap_err().to_string();
        assert!(e.contains("cannot write the job directory"), "{e}");
        assert!(e.contains("every compute node can write"), "{e}");
    }

    #[test]
    fn submit_chains_the_merge_on_the_array_like_submit_sh() {
        let root = temp("submit");
        let s = settings(&root);
        write(&s).expect("write");
        let sb = fake_sbatch(&root, "echo '4242;cluster'");
        let got = submit(&s, None, sb.as_os_str()).expect("submit");
        assert_eq!(got.array_job, "4242");
        assert_eq!(got.merge_job, "4242");
        let log = std::fs::read_to_string(root.join("sbatch.log")).expect("log");
        let job = s.dir.display();
        assert_eq!(
            log,
            format!(
                "--parsable --array=0-3%2 {job}/nlvid-build.sbatch\n\
                 --parsable --dependency=afterok:4242 --kill-on-invalid-dep=yes {job}/nlvid-merge.sbatch\n"
            )
        );
        // submit.sh makes the same two calls (with ARRAY= for a subset).
        std::fs::remove_file(root.join("sbatch.log")).expect("rm");
        let _ = submit(&s, Some("1,3"), sb.as_os_str()).expect("subset");
        let ours = std::fs::read_to_string(root.join("sbatch.log")).expect("log");
        std::fs::remove_file(root.join("sbatch.log")).expect("rm");
        let path = format!(
            "{}:{}",
            root.display(),
            std::env::var("PATH").unwrap_or_default()
        );
        let out = Command::new("bash")
            .arg(s.dir.join(SUBMIT_SCRIPT))
            .env("PATH", path)
            .env("ARRAY", "1,3")
            .output()
            .expect("bash");
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let theirs = std::fs::read_to_string(root.join("sbatch.log")).expect("log");
        assert_eq!(ours, theirs);
        assert!(theirs.starts_with("--parsable --array=1,3%2 "), "{theirs}");
    }

    #[test]
    fn a_missing_sbatch_says_where_to_submit_from() {
        let root = temp("nosbatch");
        let s = settings(&root);
        write(&s).expect("write");
        let e = submit(&s, None, OsStr::new("sbatch-that-does-not-exist"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("not found on PATH") && e.contains("login node"),
            "{e}"
        );
        assert!(e.contains("submit.sh"), "{e}");
        // submit.sh says the same without nlvid.
        let bash = std::env::split_paths(&std::env::var_os("PATH").unwrap_or_default())
            .map(|d| d.join("bash"))
            .find(|p| p.is_file())
            .expect("bash on PATH");
        let out = Command::new(bash)
            .arg(s.dir.join(SUBMIT_SCRIPT))
            .env("PATH", "/nonexistent")
            .output()
            .expect("bash");
        assert_eq!(out.status.code(), Some(127));
        assert!(String::from_utf8_lossy(&out.stderr).contains("sbatch not found on PATH"));
    }

    #[test]
    fn a_refused_submission_gives_slurms_reason_and_a_hint() {
        let root = temp("refused");
        let s = settings(&root);
        write(&s).expect("write");
        let sb = fake_sbatch(
            &root,
            "echo 'sbatch: error: Batch job submission failed: Invalid partition name specified' >&2; exit 1",
        );
        let e = submit(&s, None, sb.as_os_str()).unwrap_err().to_string();
        assert!(
            e.contains("Invalid partition name") && e.contains("sinfo -s"),
            "{e}"
        );
        let e = submit(&s, Some("1;rm"), sb.as_os_str())
            .unwrap_err()
            .to_string();
        assert!(e.contains("array indices"), "{e}");
    }
}
