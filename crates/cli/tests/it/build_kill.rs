//! `nlvid build <study.toml>` as a child process: killed with SIGKILL after
//! some runs are stored and re-run, its export equals an uninterrupted
//! build's byte for byte; three shards merged with `nlvid merge` equal the
//! unsharded build byte for byte; the arrays load in numpy.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

use crate::common;

fn scratch(name: &str) -> PathBuf {
    common::scratch(&format!("build-{name}"))
}

/// Table 5.3 domain, hertz-prony; `extra` goes into [forward].
fn study(extra: &str, n_train: usize, n_check: usize) -> String {
    format!(
        r#"[forward]
model = "hertz-prony"
probe_radius = "2.5 um"
rate = "1 um/s"
ramp = "1 s"
hold = "9 s"
points = 120
{extra}
[design]
n_train = {n_train}
n_check = {n_check}
seed = 11

[design.parameters]
G0 = {{ range = ["80 Pa", "4 kPa"], log = true }}
g1 = {{ range = [0.01, 1.0] }}
g2 = {{ range = [0.01, 1.0] }}
tau1 = {{ range = ["0.01 s", "2 s"], log = true }}
tau2 = {{ range = ["2 s", "40 s"], log = true }}

[[design.constraint]]
coefficients = {{ g1 = 1, g2 = 1 }}
at_most = 0.99

[build]
store = "store"
export = "export"
min_peak_force = "4 nN"
reject_non_repulsive = true
"#
    )
}

fn write_study(dir: &Path, text: &str) -> PathBuf {
    std::fs::create_dir_all(dir).expect("dir");
    let p = dir.join("study.toml");
    std::fs::write(&p, text).expect("write study");
    p
}

fn nlvid(args: &[&std::ffi::OsStr]) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_nlvid"));
    c.args(args);
    c
}

fn ok(out: Output) -> String {
    assert!(
        out.status.success(),
        "stdout:\n{}\nstderr:\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn stored_runs(store: &Path) -> usize {
    std::fs::read_dir(store.join("runs")).map_or(0, |d| {
        d.filter_map(|e| e.ok())
            .filter(|e| e.path().extension().is_some_and(|x| x == "json"))
            .count()
    })
}

const EXPORTED: [&str; 8] = [
    "X.npy",
    "Y.npy",
    "t.npy",
    "X.csv",
    "Y.csv",
    "status.csv",
    "meta.json",
    "timing.csv",
];

/// Every exported file but timing.csv (wall times) equal byte for byte.
fn assert_same_export(a: &Path, b: &Path) {
    for set in ["train", "check"] {
        for f in &EXPORTED[..7] {
            let x = std::fs::read(a.join(set).join(f)).expect("export file");
            let y = std::fs::read(b.join(set).join(f)).expect("export file");
            assert!(
                x == y,
                "{set}/{f} differs between {} and {}",
                a.display(),
                b.display()
            );
        }
        assert!(b.join(set).join("timing.csv").is_file());
    }
}

#[test]
fn killed_build_resumes_to_the_same_export() {
    let root = scratch("kill");
    // 48 runs of 40 ms each (test_delay, a test-only option) on ≤ 2 threads.
    let text = study("test_delay = \"40 ms\"", 36, 12);
    let killed = write_study(&root.join("killed"), &text);
    let train_store = root.join("killed/store/train");
    let mut child = nlvid(&["build".as_ref(), killed.as_os_str(), "--quiet".as_ref()])
        .stdout(std::process::Stdio::null())
        .spawn()
        .expect("spawn");
    let start = Instant::now();
    while stored_runs(&train_store) < 6 && start.elapsed() < Duration::from_secs(120) {
        std::thread::sleep(Duration::from_millis(2));
    }
    child.kill().expect("kill"); // SIGKILL on Unix
    let _ = child.wait();
    let done = stored_runs(&train_store);
    assert!(
        (6..36).contains(&done) && !root.join("killed/export").exists(),
        "the build finished before it could be killed ({done} runs); make it slower"
    );

    let text_out = ok(
        nlvid(&["build".as_ref(), killed.as_os_str(), "--quiet".as_ref()])
            .output()
            .expect("re-run"),
    );
    let expect = format!(
        "train: 36 runs in shard: {done} already done, {} run now",
        36 - done
    );
    assert!(text_out.contains(&expect), "{text_out}\nexpected: {expect}");

    let straight = write_study(&root.join("straight"), &text);
    ok(
        nlvid(&["build".as_ref(), straight.as_os_str(), "--quiet".as_ref()])
            .output()
            .expect("uninterrupted build"),
    );
    assert_same_export(&root.join("killed/export"), &root.join("straight/export"));
}

#[test]
fn merged_shards_equal_the_unsharded_build_byte_for_byte() {
    let root = scratch("shards");
    let s = write_study(&root, &study("", 30, 10));
    let mut shard_dirs = Vec::new();
    for i in 1..=3 {
        let store = root.join(format!("shard{i}"));
        let shard = format!("{i}/3");
        ok(nlvid(&[
            "build".as_ref(),
            s.as_os_str(),
            "--shard".as_ref(),
            shard.as_ref(),
            "--store".as_ref(),
            store.as_os_str(),
            "--export".as_ref(),
            root.join(format!("shard{i}-export")).as_os_str(),
            "--quiet".as_ref(),
        ])
        .output()
        .expect("shard"));
        shard_dirs.push(store);
    }
    let mut args: Vec<&std::ffi::OsStr> = vec!["merge".as_ref()];
    args.extend(shard_dirs.iter().map(|d| d.as_os_str()));
    let merged = root.join("merged");
    let merged_export = root.join("merged-export");
    args.extend([
        "--out".as_ref(),
        merged.as_os_str(),
        "--export".as_ref(),
        merged_export.as_os_str(),
        "--study".as_ref(),
        s.as_os_str(),
    ]);
    ok(nlvid(&args).output().expect("merge"));
    ok(
        nlvid(&["build".as_ref(), s.as_os_str(), "--quiet".as_ref()])
            .output()
            .expect("unsharded"),
    );
    assert_same_export(&merged_export, &root.join("export"));
    // A shard alone is not the whole build (the comparison can fail).
    let one = std::fs::read(root.join("shard1-export/train/Y.npy")).expect("shard export");
    let all = std::fs::read(root.join("export/train/Y.npy")).expect("export");
    assert_ne!(one, all);

    // numpy reads the export without nlvid (skipped if numpy is missing).
    let has_numpy = Command::new("python3")
        .args(["-c", "import numpy"])
        .output()
        .is_ok_and(|o| o.status.success());
    if has_numpy {
        let dir = root.join("export/train");
        let script = r#"
import json, sys, csv
import numpy as np
d = sys.argv[1]
X, Y, t = np.load(d + "/X.npy"), np.load(d + "/Y.npy"), np.load(d + "/t.npy")[0]
meta = json.load(open(d + "/meta.json"))
rows = list(csv.DictReader(open(d + "/status.csv")))
kept = [r for r in rows if r["status"] == "ok"]
assert X.shape == (len(kept), len(meta["parameter_names"])), X.shape
assert Y.shape == (len(kept), len(t)) and len(t) == len(meta["time_s"])
assert meta["counts"]["kept"] == len(kept)
Xc = np.loadtxt(d + "/X.csv", delimiter=",", skiprows=1)[:, 1:]
assert np.array_equal(Xc, X)
print(X.shape[0], Y.shape[1], meta["parameter_names"])
"#;
        let out = ok(Command::new("python3")
            .args(["-c", script])
            .arg(&dir)
            .output()
            .expect("python3"));
        assert!(
            out.contains("120 ['G0', 'g1', 'g2', 'tau1', 'tau2']"),
            "{out}"
        );
    }
}

#[test]
fn flag_only_sample_and_build_still_work() {
    let root = scratch("flags");
    let domain = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/fit/domain.toml");
    ok(nlvid(&[
        "sample".as_ref(),
        "--domain".as_ref(),
        domain.as_os_str(),
        "-n".as_ref(),
        "8".as_ref(),
        "--out".as_ref(),
        root.as_os_str(),
    ])
    .output()
    .expect("sample"));
    let out = ok(nlvid(&[
        "build".as_ref(),
        "--design".as_ref(),
        root.join("train.csv").as_os_str(),
        "--store".as_ref(),
        root.join("store").as_os_str(),
        "--export".as_ref(),
        root.join("export").as_os_str(),
        "--points".as_ref(),
        "30".as_ref(),
        "--quiet".as_ref(),
    ])
    .output()
    .expect("build"));
    assert!(out.contains("exported 8 of 8 runs"), "{out}");
}

#[test]
fn a_bad_study_names_file_line_and_key() {
    let root = scratch("bad");
    let text = study("", 10, 0).replace("tau1 = {", "tau3 = {");
    let s = write_study(&root, &text);
    let out = nlvid(&[
        "sample".as_ref(),
        s.as_os_str(),
        "--out".as_ref(),
        root.as_os_str(),
    ])
    .output()
    .expect("sample");
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("study.toml:") && err.contains("design.parameters.tau1"),
        "{err}"
    );
}

/// "… N runs in shard: A already done, B run now …" → B for `set`.
fn run_now(text: &str, set: &str) -> usize {
    let line = text
        .lines()
        .find(|l| l.starts_with(&format!("{set}: ")) && l.contains("run now"))
        .unwrap_or_else(|| panic!("no `{set}` build line in:\n{text}"));
    let before = line.split(" run now").next().unwrap_or("");
    before
        .rsplit(' ')
        .next()
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("cannot read the run count in `{line}`"))
}

#[test]
fn concurrent_builds_into_one_store_share_the_work() {
    let root = scratch("concurrent");
    // 32 runs of 40 ms each: long enough for both builds to overlap.
    let s = write_study(&root, &study("test_delay = \"40 ms\"", 24, 8));
    let spawn = || {
        nlvid(&["build".as_ref(), s.as_os_str(), "--quiet".as_ref()])
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .expect("spawn")
    };
    let (a, b) = (spawn(), spawn());
    let (a, b) = (
        ok(a.wait_with_output().expect("a")),
        ok(b.wait_with_output().expect("b")),
    );
    for (set, n) in [("train", 24), ("check", 8)] {
        let (ra, rb) = (run_now(&a, set), run_now(&b, set));
        assert_eq!(
            ra + rb,
            n,
            "{set}: the two builds ran {ra} + {rb} runs of {n}:\n{a}\n{b}"
        );
    }
    assert!(
        a.contains("by another build") || b.contains("by another build"),
        "{a}\n{b}"
    );
    let straight = write_study(
        &root.join("straight"),
        &study("test_delay = \"40 ms\"", 24, 8),
    );
    ok(
        nlvid(&["build".as_ref(), straight.as_os_str(), "--quiet".as_ref()])
            .output()
            .expect("straight build"),
    );
    // No claim file is left, and the shared build equals a single one.
    let claims = std::fs::read_dir(root.join("store/train/runs"))
        .expect("runs")
        .filter_map(Result::ok)
        .filter(|e| e.path().extension().is_some_and(|x| x == "claim"))
        .count();
    assert_eq!(claims, 0);
    assert_same_export(&root.join("export"), &root.join("straight/export"));
}
