//! The scripts of `nlvid slurm` run under bash as Slurm would run them
//! (array index, job id and restart count in the environment), without a
//! cluster: the merged export equals the unsharded build's byte for byte
//! (shared stores and node-local scratch), a task whose nlvid is killed
//! asks to be requeued and gives up after `max_requeue`, and unwritable
//! stores, failing builds, missing tasks and a missing sbatch each say what
//! to do next. The real-Slurm run is `scripts/slurm-e2e.sh`.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use crate::common;

const STUDY: &str = r#"[forward]
model = "hertz-prony"
probe_radius = "2.5 um"
rate = "1 um/s"
ramp = "1 s"
hold = "9 s"
points = 60

[design]
n_train = 14
n_check = 5
seed = 7

[design.parameters]
G0 = { range = ["80 Pa", "4 kPa"], log = true }
g1 = { range = [0.01, 1.0] }
g2 = { range = [0.01, 1.0] }
tau1 = { range = ["0.01 s", "2 s"], log = true }
tau2 = { range = ["2 s", "40 s"], log = true }

[[design.constraint]]
coefficients = { g1 = 1, g2 = 1 }
at_most = 0.99

[build]
store = "store"
export = "export"
min_peak_force = "4 nN"
reject_non_repulsive = true
"#;

fn nlvid() -> &'static str {
    env!("CARGO_BIN_EXE_nlvid")
}

fn run(cmd: &mut Command) -> Output {
    cmd.env_remove("NLVID_LOG").output().expect("run")
}

fn ok(out: &Output) -> String {
    assert!(
        out.status.success(),
        "status {}\nstdout:\n{}\nstderr:\n{}",
        out.status,
        common::text(&out.stdout),
        common::text(&out.stderr)
    );
    common::text(&out.stdout)
}

/// A study in `root`, its scripts in `root/job` (extra `nlvid slurm` flags).
fn setup(root: &Path, extra: &[&str]) -> (PathBuf, PathBuf) {
    let study = root.join("study.toml");
    std::fs::write(&study, STUDY).expect("study");
    let job = root.join("job");
    let mut c = Command::new(nlvid());
    c.args([
        "slurm".as_ref(),
        study.as_os_str(),
        "--out".as_ref(),
        job.as_os_str(),
    ])
    .args(["--array-size", "3"])
    .args(extra);
    ok(&run(&mut c));
    (study, job)
}

/// Runs task `i` of the array script as slurmstepd would.
fn task(job: &Path, i: usize, env: &[(&str, &str)]) -> Output {
    let mut c = Command::new("bash");
    c.arg(job.join("nlvid-build.sbatch"))
        .env("SLURM_ARRAY_TASK_ID", i.to_string())
        .env("SLURM_ARRAY_JOB_ID", "77")
        .env_remove("SLURM_RESTART_COUNT");
    for (k, v) in env {
        c.env(k, v);
    }
    run(&mut c)
}

fn merge_job(job: &Path) -> Output {
    run(Command::new("bash").arg(job.join("nlvid-merge.sbatch")))
}

/// Every exported file but timing.csv, both sets, equal byte for byte.
fn assert_same_export(a: &Path, b: &Path) {
    for set in ["train", "check"] {
        for f in [
            "X.npy",
            "Y.npy",
            "t.npy",
            "X.csv",
            "Y.csv",
            "status.csv",
            "meta.json",
        ] {
            let x = std::fs::read(a.join(set).join(f)).expect("export file");
            let y = std::fs::read(b.join(set).join(f)).expect("export file");
            assert!(
                x == y,
                "{set}/{f} differs between {} and {}",
                a.display(),
                b.display()
            );
        }
    }
}

fn reference_export(root: &Path, study: &Path) -> PathBuf {
    let exp = root.join("ref-export");
    ok(&run(Command::new(nlvid())
        .args(["build".as_ref(), study.as_os_str(), "--quiet".as_ref()])
        .args(["--store".as_ref(), root.join("ref-store").as_os_str()])
        .args(["--export".as_ref(), exp.as_os_str()])));
    exp
}

#[test]
fn array_tasks_and_merge_equal_the_unsharded_build() {
    let root = common::scratch("slurm-shared");
    let (study, job) = setup(&root, &["--throttle", "2"]);
    for i in 0..3 {
        let log = ok(&task(&job, i, &[]));
        assert!(
            log.contains(&format!("shard {}/3", i + 1)) && log.contains("done"),
            "{log}"
        );
        assert!(job.join(format!("state/task-{i}.ok")).is_file());
    }
    // A shard does not export into the study's [build] export directory.
    assert!(!root.join("export").exists());
    // Running a task again resumes: nothing left to run.
    let again = ok(&task(&job, 1, &[]));
    assert!(again.contains("done"), "{again}");
    let shard = run(Command::new(nlvid())
        .args(["build".as_ref(), study.as_os_str(), "--quiet".as_ref()])
        .args(["--shard", "2/3", "--store"])
        .arg(job.join("stores/task-1")));
    assert!(ok(&shard).contains("train: 5 runs in shard: 5 already done, 0 run now"));

    ok(&merge_job(&job));
    assert_same_export(&job.join("export"), &reference_export(&root, &study));
    let st = run(Command::new(nlvid()).args(["slurm", "--status"]).arg(&job));
    assert!(ok(&st).contains("next: done"));
}

#[test]
fn scratch_stores_are_copied_back_and_cleaned() {
    let root = common::scratch("slurm-scratch");
    let node = root.join("node-local");
    std::fs::create_dir_all(&node).expect("node dir");
    let (study, job) = setup(
        &root,
        &["--scratch", "$NODE_SCRATCH/x", "--sync-every", "1"],
    );
    let env = [("NODE_SCRATCH", node.to_str().expect("utf-8"))];
    for i in 0..3 {
        ok(&task(&job, i, &env));
    }
    // The runs are in the shared task stores; scratch is emptied.
    assert_eq!(
        std::fs::read_dir(node.join("x")).expect("scratch").count(),
        0
    );
    ok(&merge_job(&job));
    assert_same_export(&job.join("export"), &reference_export(&root, &study));
}

/// A wrapper that runs nlvid, then dies by SIGKILL after a build (as if
/// killed just after its last stored run).
fn killed_nlvid(root: &Path) -> PathBuf {
    let p = root.join("nlvid-killed");
    std::fs::write(
        &p,
        format!(
            "#!/bin/bash\n\"{}\" \"$@\"\n[ \"$1\" = build ] && kill -KILL $$\nexit 0\n",
            nlvid()
        ),
    )
    .expect("wrapper");
    chmod_x(&p);
    p
}

fn chmod_x(p: &Path) {
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(p, std::fs::Permissions::from_mode(0o755)).expect("chmod");
}

/// A stand-in for scontrol: logs its arguments and, as Slurm does after
/// `scontrol requeue`, sends SIGTERM to the batch script.
fn fake_scontrol(root: &Path) -> String {
    let bin = root.join("bin");
    std::fs::create_dir_all(&bin).expect("bin");
    let p = bin.join("scontrol");
    std::fs::write(
        &p,
        format!(
            "#!/bin/bash\necho \"$*\" >> {}/scontrol.log\nkill -TERM $PPID\n",
            root.display()
        ),
    )
    .expect("scontrol");
    chmod_x(&p);
    format!(
        "{}:{}",
        bin.display(),
        std::env::var("PATH").unwrap_or_default()
    )
}

#[test]
fn a_killed_task_asks_to_be_requeued_then_gives_up_with_advice() {
    let root = common::scratch("slurm-requeue");
    let wrapper = killed_nlvid(&root);
    let (_, job) = setup(
        &root,
        &[
            "--nlvid",
            wrapper.to_str().expect("utf-8"),
            "--max-requeue",
            "2",
        ],
    );
    let path = fake_scontrol(&root);
    let out = task(&job, 1, &[("PATH", &path)]);
    let log = ok(&out);
    assert!(
        log.contains("killed by signal 9") && log.contains("requeue 1 of 2"),
        "{log}"
    );
    assert_eq!(
        std::fs::read_to_string(root.join("scontrol.log")).expect("scontrol log"),
        "requeue 77_1\n"
    );
    assert!(!job.join("state/task-1.failed").exists());
    // The finished runs are kept for the next attempt.
    assert_eq!(
        std::fs::read_dir(job.join("stores/task-1/train/runs"))
            .expect("runs")
            .count(),
        5
    );

    // After max_requeue requeues the task fails and says what to do.
    let out = task(&job, 1, &[("PATH", &path), ("SLURM_RESTART_COUNT", "2")]);
    assert_eq!(out.status.code(), Some(137));
    let log = common::text(&out.stdout);
    assert!(
        log.contains("killed by signal 9 in 3 attempts") && log.contains("--mem"),
        "{log}"
    );
    let msg = std::fs::read_to_string(job.join("state/task-1.failed")).expect("failed marker");
    assert!(msg.contains("ARRAY=1 "), "{msg}");
}

#[test]
fn unwritable_stores_failing_builds_and_missing_tasks_say_what_to_do() {
    let root = common::scratch("slurm-bad");
    let (study, job) = setup(&root, &[]);

    // Task 0 cannot create its store (a file is in the way; root ignores modes).
    let stores = job.join("stores");
    std::fs::remove_dir_all(&stores).expect("rm stores");
    std::fs::write(&stores, b"").expect("file in the way");
    let out = task(&job, 0, &[]);
    assert_eq!(out.status.code(), Some(3));
    let log = common::text(&out.stdout);
    assert!(
        log.contains("cannot write the task store") && log.contains("--out"),
        "{log}"
    );
    std::fs::remove_file(&stores).expect("rm file");
    std::fs::create_dir(&stores).expect("stores");

    // Task 1's build fails (the study is gone): exit status and resubmission.
    let moved = root.join("study.moved");
    std::fs::rename(&study, &moved).expect("move study");
    let out = task(&job, 1, &[]);
    assert_eq!(out.status.code(), Some(1));
    let log = common::text(&out.stdout);
    assert!(
        log.contains("failed with exit status 1") && log.contains("ARRAY=1 "),
        "{log}"
    );
    std::fs::rename(&moved, &study).expect("restore study");

    // Task 2 done, 0 and 1 not: the merge refuses and names them.
    ok(&task(&job, 2, &[]));
    let out = merge_job(&job);
    assert!(!out.status.success());
    let log = common::text(&out.stdout);
    assert!(
        log.contains("tasks 0,1 left no store") && log.contains("ARRAY=0,1 "),
        "{log}"
    );

    // --status lists every task and exits 1 until the build is merged.
    let out = run(Command::new(nlvid()).args(["slurm", "--status"]).arg(&job));
    assert_eq!(out.status.code(), Some(1));
    let text = common::text(&out.stdout);
    assert!(
        text.contains("task 0: FAILED") && text.contains("cannot write"),
        "{text}"
    );
    // Shard 3/3 of 14 + 5 runs: indices 2, 5, 8, 11 and 2.
    assert!(text.contains("task 2: done (5/5 runs)"), "{text}");
    assert!(
        text.contains("tasks 0-1 failed") && text.contains("ARRAY=0-1 "),
        "{text}"
    );
}

#[test]
fn bad_settings_and_a_missing_sbatch_are_reported_before_anything_runs() {
    let root = common::scratch("slurm-args");
    let study = root.join("study.toml");
    std::fs::write(&study, STUDY).expect("study");
    let out = run(Command::new(nlvid())
        .args([
            "slurm".as_ref(),
            study.as_os_str(),
            "--out".as_ref(),
            root.join("j").as_os_str(),
        ])
        .args(["--time", "2h"]));
    assert!(!out.status.success());
    assert!(common::text(&out.stderr).contains("--time \"2h\": not a Slurm time"));

    // No sbatch on PATH: the scripts are written, submission says where to go.
    let out = run(Command::new(nlvid())
        .args([
            "slurm".as_ref(),
            study.as_os_str(),
            "--out".as_ref(),
            root.join("j").as_os_str(),
        ])
        .arg("--submit")
        .env("PATH", root.join("empty-bin")));
    assert!(!out.status.success());
    let err = common::text(&out.stderr);
    assert!(
        err.contains("sbatch not found on PATH") && err.contains("login node"),
        "{err}"
    );
    assert!(root.join("j/submit.sh").is_file());

    // A bad study is reported with file and key before any script is written.
    std::fs::write(&study, STUDY.replace("n_train = 14", "n_train = -1")).expect("study");
    let out = run(Command::new(nlvid()).args([
        "slurm".as_ref(),
        study.as_os_str(),
        "--out".as_ref(),
        root.join("k").as_os_str(),
    ]));
    assert!(!out.status.success() && !root.join("k").exists());
    assert!(
        common::text(&out.stderr).contains("n_train"),
        "{}",
        common::text(&out.stderr)
    );
}
