//! A real full disk (issue 20): each kind of writer of the one atomic write
//! path (`nlvid_study::write_atomic`) — the CLI's own outputs
//! (`nlvid_cli::output`), the report crate's (`nlvid_report::cohort`), the
//! surrogate store's (`nlvid_surrogate::store`) — runs out of space in the
//! middle of a file on a tiny tmpfs. The kernel returns ENOSPC (no signal,
//! unlike the `ulimit -f` stop of kill_anywhere.rs); afterwards the command
//! has failed with the OS's "No space left on device", every final-named
//! file is absent, complete, or the previous complete version, and no
//! temporary file is left.
//!
//! The tmpfs is mounted in a private user + mount namespace (`unshare
//! --user --map-root-user --mount`), which needs no root where the kernel
//! allows unprivileged user namespaces. Where it does not, these tests print
//! why and pass without checking anything; the injected-failure test of the
//! same write path (`a_full_disk_mid_file_keeps_the_previous_version_and_no_temporary`
//! in crates/study/src/atomic.rs) runs everywhere.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::common;

const NLVID: &str = env!("CARGO_BIN_EXE_nlvid");

/// Whether a private tmpfs can be mounted here.
fn can_mount() -> bool {
    let ok = Command::new("unshare")
        .args(["--user", "--map-root-user", "--mount", "sh", "-c"])
        .arg("d=$(mktemp -d) && mount -t tmpfs -o size=16k tmpfs \"$d\"; r=$?; rmdir \"$d\" 2>/dev/null; exit $r")
        .output()
        .is_ok_and(|o| o.status.success());
    if !ok {
        eprintln!(
            "full_disk: cannot mount a tmpfs in a user namespace here (unshare -Urm); \
             the real ENOSPC runs are skipped (the injected one in nlvid-study still runs)"
        );
    }
    ok
}

/// What a run on the tiny file system left.
struct Outcome {
    success: bool,
    stderr: String,
    /// A copy of the file system's contents after the run.
    after: PathBuf,
}

/// Mounts a tmpfs at `<case>/fs`, copies `<case>/seed/` into it, fills it
/// up to `free_kib` KiB of free space, runs `nlvid ARGS` (with `fs` for
/// `{fs}` in the arguments) from `cwd`, and copies what is left into
/// `<case>/after/`.
fn run_on_tiny_fs(case: &Path, free_kib: u64, cwd: &Path, args: &[&str]) -> Outcome {
    let (fs, seed, after) = (case.join("fs"), case.join("seed"), case.join("after"));
    for d in [&fs, &seed, &after] {
        std::fs::create_dir_all(d).unwrap();
    }
    let script = r#"set -e
mount -t tmpfs -o size=4m tmpfs "$FS"
cp -a "$SEED/." "$FS/"
avail=$(df -k --output=avail "$FS" | tail -1)
head -c $(( (avail - FREE) * 1024 )) /dev/zero > "$FS/filler"
set +e
cd "$CWD"
"$@" >/dev/null 2>"$CASE/stderr"
echo $? > "$CASE/rc"
rm -f "$FS/filler"
cp -a "$FS/." "$AFTER/"
"#;
    let args: Vec<String> = args
        .iter()
        .map(|a| a.replace("{fs}", &fs.to_string_lossy()))
        .collect();
    let o = Command::new("unshare")
        .args([
            "--user",
            "--map-root-user",
            "--mount",
            "sh",
            "-c",
            script,
            "sh",
            NLVID,
        ])
        .args(&args)
        .env("FS", &fs)
        .env("SEED", &seed)
        .env("AFTER", &after)
        .env("CASE", case)
        .env("CWD", cwd)
        .env("FREE", free_kib.to_string())
        .env("CI", "1")
        .env_remove("NLVID_LOG")
        .output()
        .unwrap();
    assert!(o.status.success(), "harness: {}", common::text(&o.stderr));
    let rc: i32 = std::fs::read_to_string(case.join("rc"))
        .unwrap()
        .trim()
        .parse()
        .unwrap();
    Outcome {
        success: rc == 0,
        stderr: std::fs::read_to_string(case.join("stderr")).unwrap(),
        after,
    }
}

/// Every file under `dir`, relative path → bytes.
fn files(dir: &Path) -> Vec<(String, Vec<u8>)> {
    fn walk(root: &Path, d: &Path, out: &mut Vec<(String, Vec<u8>)>) {
        for e in std::fs::read_dir(d).unwrap().filter_map(Result::ok) {
            let p = e.path();
            if p.is_dir() {
                walk(root, &p, out);
            } else {
                let rel = p.strip_prefix(root).unwrap().to_string_lossy().into_owned();
                out.push((rel, std::fs::read(&p).unwrap()));
            }
        }
    }
    let mut out = Vec::new();
    walk(dir, dir, &mut out);
    out.sort();
    out
}

fn assert_failed_for_space(o: &Outcome, what: &str) {
    assert!(!o.success, "{what}: succeeded on a full disk");
    assert!(
        o.stderr.contains("No space left on device"),
        "{what}: the error does not say the disk is full:\n{}",
        o.stderr
    );
    for (rel, _) in files(&o.after) {
        let name = rel.rsplit('/').next().unwrap_or(&rel);
        assert!(
            !(name.starts_with('.') && name.ends_with(".tmp")),
            "{what}: temporary {rel} left"
        );
    }
}

/// The CLI's own outputs (`nlvid_cli::output::write_atomic`): `inspect
/// --csv` over an older CSV of the same name keeps the older CSV.
#[test]
fn cli_output_on_a_full_disk_keeps_the_previous_file() {
    if !can_mount() {
        return;
    }
    let case = common::scratch("full-disk-cli");
    let previous = b"segment,kind,time_s\n0,extend,0\n";
    std::fs::create_dir_all(case.join("seed")).unwrap();
    std::fs::write(case.join("seed/curve.csv"), previous).unwrap();
    let jpk = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../afm/tests/data/fmt-jpk-fd_spot3-0192.jpk-force");
    let jpk = jpk.to_string_lossy().into_owned();
    let o = run_on_tiny_fs(
        &case,
        8,
        &case,
        &["inspect", &jpk, "--csv", "{fs}/curve.csv"],
    );
    assert_failed_for_space(&o, "inspect --csv");
    assert_eq!(
        files(&o.after),
        [("curve.csv".to_string(), previous.to_vec())]
    );
}

/// The report crate's writer (`nlvid_report::cohort::write_atomic`, here
/// writing the demo's embedded example out): every file is the complete
/// bundled one or the previous version; the one that did not fit is the
/// previous version.
#[test]
fn report_writer_on_a_full_disk_leaves_complete_or_previous_files() {
    if !can_mount() {
        return;
    }
    let case = common::scratch("full-disk-report");
    let first_curve = "out/example/data/A-stiff/a-stiff-01.csv";
    let previous = b"time,piezo,deflection\n0,0,0\n";
    let seeded = case.join("seed").join(first_curve);
    std::fs::create_dir_all(seeded.parent().unwrap()).unwrap();
    std::fs::write(&seeded, previous).unwrap();
    let cwd = case.join("cwd"); // no examples/ here
    std::fs::create_dir_all(&cwd).unwrap();
    let o = run_on_tiny_fs(&case, 8, &cwd, &["demo", "--out", "{fs}/out"]);
    assert_failed_for_space(&o, "demo (embedded example)");
    let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/demo");
    let mut kept = 0;
    for (rel, bytes) in files(&o.after) {
        let Some(r) = rel.strip_prefix("out/example/") else {
            panic!("unexpected file {rel}");
        };
        if bytes == previous {
            kept += 1;
        } else {
            assert_eq!(bytes, std::fs::read(repo.join(r)).unwrap(), "{rel} is cut");
        }
    }
    assert_eq!(
        kept, 1,
        "the curve that did not fit is the previous version"
    );
}

/// The surrogate store's writer (`nlvid_surrogate::store::write_atomic`):
/// `build` runs out of space among its run records; every record left is
/// complete JSON.
#[test]
fn store_writer_on_a_full_disk_leaves_only_complete_records() {
    if !can_mount() {
        return;
    }
    let case = common::scratch("full-disk-store");
    common::build_study(&case.join("seed"));
    let o = run_on_tiny_fs(&case, 16, &case, &["build", "{fs}/study.toml", "--quiet"]);
    assert_failed_for_space(&o, "build");
    let mut json = 0;
    for (rel, bytes) in files(&o.after) {
        if rel.ends_with(".json") {
            json += 1;
            assert!(
                serde_json::from_slice::<serde_json::Value>(&bytes).is_ok(),
                "{rel} is not complete JSON ({} bytes)",
                bytes.len()
            );
        }
    }
    assert!(json > 0, "no record was written before the disk filled");
}
