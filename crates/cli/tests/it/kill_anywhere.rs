//! Kill anywhere, resume: `nlvid build`, `cohort` and `report` are stopped
//! (1) by a file-size limit (`ulimit -f`), which kills the process with
//! SIGXFSZ in the middle of writing a file (a stand-in for a full disk; the
//! real ENOSPC, which the process survives, is full_disk.rs) — and (2) by SIGKILL at
//! seeded random times. After each stop every final-named output file is
//! absent or complete and byte-identical to an uninterrupted run; after a
//! resume the outputs equal the uninterrupted run and no temporary file is
//! left. The default run stops each command at a few points; the ignored
//! test `kill_at_many_random_points` stops each at ten
//! (`cargo test -p nlvid --test it kill_anywhere:: -- --ignored`).
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

use nlvid_report::demo::{DemoSpec, write_demo_data};

use crate::common;

const NLVID: &str = env!("CARGO_BIN_EXE_nlvid");

/// Files that record wall-clock times and legitimately differ between runs.
fn nondeterministic(rel: &str) -> bool {
    rel.ends_with("timing.csv") || rel.contains("runs/") || rel.starts_with("cells/")
}

fn is_temp(name: &str) -> bool {
    name.starts_with('.') && name.ends_with(".tmp")
}

/// Every file under `dir` (relative path → bytes).
fn snapshot(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    fn walk(root: &Path, d: &Path, out: &mut BTreeMap<String, Vec<u8>>) {
        let Ok(rd) = std::fs::read_dir(d) else { return };
        for e in rd.filter_map(Result::ok) {
            let p = e.path();
            if p.is_dir() {
                walk(root, &p, out);
            } else if let Ok(b) = std::fs::read(&p) {
                let rel = p.strip_prefix(root).unwrap().to_string_lossy().into_owned();
                out.insert(rel, b);
            }
        }
    }
    let mut out = BTreeMap::new();
    walk(dir, dir, &mut out);
    out
}

/// After a stop: every final-named file is absent or equals `reference`
/// (wall-time files: parse completely). Returns the number of files seen.
fn assert_absent_or_complete(dir: &Path, reference: &BTreeMap<String, Vec<u8>>, what: &str) {
    for (rel, bytes) in snapshot(dir) {
        let name = rel.rsplit('/').next().unwrap_or(&rel);
        if is_temp(name) {
            continue;
        }
        if nondeterministic(&rel) {
            if rel.ends_with(".json") {
                assert!(
                    serde_json::from_slice::<serde_json::Value>(&bytes).is_ok(),
                    "{what}: {rel} is a cut JSON file ({} bytes)",
                    bytes.len()
                );
            } else {
                assert!(bytes.ends_with(b"\n"), "{what}: {rel} is cut");
            }
            continue;
        }
        let Some(want) = reference.get(&rel) else {
            panic!("{what}: {rel} is not an output of the uninterrupted run");
        };
        assert!(
            &bytes == want,
            "{what}: {rel} has {} bytes, the uninterrupted run's has {}",
            bytes.len(),
            want.len()
        );
    }
}

/// After the resume: the deterministic files equal the reference, none is
/// missing, and no temporary is left.
fn assert_resumed(dir: &Path, reference: &BTreeMap<String, Vec<u8>>, what: &str) {
    let got = snapshot(dir);
    for rel in got.keys() {
        let name = rel.rsplit('/').next().unwrap_or(rel);
        assert!(
            !is_temp(name),
            "{what}: temporary {rel} left after the resume"
        );
    }
    for (rel, want) in reference {
        if nondeterministic(rel) {
            assert!(got.contains_key(rel), "{what}: {rel} missing after resume");
            continue;
        }
        assert!(
            got.get(rel) == Some(want),
            "{what}: {rel} differs from the uninterrupted run after resume"
        );
    }
}

/// The cells' curves are written with the analytic Lee–Radok ramp-hold
/// (`hertz-prony`, the demo's protocol): the demo's own FE writer costs
/// seconds per cell, and what is tested here is the run, not the model.
const LEE_RADOK: &str = "[forward]\nmodel = \"hertz-prony\"\nprobe_radius = \"2.5 um\"\n\
                         rate = \"2 um/s\"\nramp = \"1 s\"\nhold = \"51 s\"\npoints = 520\n";

/// The demo cohort (2 × `cells` cells) in `dir`; returns (study, data).
fn cohort_inputs(dir: &Path, cells: usize) -> (PathBuf, PathBuf) {
    let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/demo");
    std::fs::create_dir_all(dir.join("metamodel")).unwrap();
    for f in [
        "study.toml",
        "metamodel.toml",
        "metamodel/model.json",
        "metamodel/meta.json",
        "metamodel/check.json",
    ] {
        std::fs::copy(repo.join(f), dir.join(f)).unwrap();
    }
    let spec = DemoSpec {
        cells_per_group: cells,
        ..DemoSpec::default()
    };
    std::fs::write(dir.join("lee-radok.toml"), LEE_RADOK).unwrap();
    let files =
        write_demo_data(&spec, &dir.join("study.toml"), &dir.join("lee-radok.toml")).unwrap();
    (files.study, files.data)
}

struct Case {
    what: &'static str,
    /// The command writing into `out` (the part after `nlvid`).
    args: Vec<std::ffi::OsString>,
    /// Where its final-named files are.
    out: PathBuf,
}

impl Case {
    fn command(&self) -> Command {
        let mut c = Command::new(NLVID);
        c.args(&self.args)
            .env("NLVID_NO_PROGRESS", "1")
            .env_remove("NLVID_LOG")
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null());
        c
    }

    fn run_ok(&self) -> Duration {
        let t = Instant::now();
        let st = self.command().status().unwrap();
        assert!(st.success(), "{}: {:?} failed", self.what, self.args);
        t.elapsed()
    }

    /// Runs under a file-size limit of `kib` KiB (a full disk): the kernel
    /// kills the process with SIGXFSZ in the middle of its first larger
    /// write. Returns whether it was killed.
    fn run_limited(&self, kib: u64) -> bool {
        let mut c = Command::new("bash");
        c.arg("-c")
            .arg(format!("ulimit -f {kib}; exec \"$0\" \"$@\""))
            .arg(NLVID)
            .args(&self.args)
            .env("NLVID_NO_PROGRESS", "1")
            .env_remove("NLVID_LOG")
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null());
        !c.status().unwrap().success()
    }

    fn kill_after(&self, after: Duration) {
        let mut child = self.command().spawn().unwrap();
        std::thread::sleep(after);
        let _ = child.kill();
        let _ = child.wait();
    }
}

/// Seeded uniform numbers in [0, 1) (64-bit LCG, top bits).
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// A case, its reference snapshot, the reference's wall time and the
/// function that removes its outputs.
type Prepared = (Case, BTreeMap<String, Vec<u8>>, Duration, Box<dyn Fn()>);

/// The three cases in `root`: a build, a cohort and a report of a finished
/// cohort. Returns them with the reference snapshot of each (an
/// uninterrupted run, whose outputs are then removed), its wall time and
/// the function that removes its outputs.
fn cases(root: &Path, name: &str) -> Vec<Prepared> {
    let mut out = Vec::new();
    for (i, what) in ["build", "cohort", "report"].into_iter().enumerate() {
        let make = |dir: &Path| -> (Case, Box<dyn Fn()>) {
            match i {
                0 => {
                    let s = common::build_study(dir);
                    let d = dir.to_path_buf();
                    (
                        Case {
                            what,
                            args: vec!["build".into(), s.into(), "--quiet".into()],
                            out: d.join("export"),
                        },
                        Box::new(move || {
                            let _ = std::fs::remove_dir_all(d.join("export"));
                            let _ = std::fs::remove_dir_all(d.join("store"));
                        }),
                    )
                }
                1 => {
                    let (s, data) = cohort_inputs(dir, 4);
                    let o = dir.join("out");
                    (
                        Case {
                            what,
                            args: vec![
                                "cohort".into(),
                                s.into(),
                                data.into(),
                                "--out".into(),
                                o.clone().into(),
                            ],
                            out: o.clone(),
                        },
                        Box::new(move || {
                            let _ = std::fs::remove_dir_all(&o);
                        }),
                    )
                }
                _ => {
                    let (s, data) = cohort_inputs(dir, 3);
                    let c = dir.join("cohort");
                    let st = Command::new(NLVID)
                        .args(["cohort".as_ref(), s.as_os_str(), data.as_os_str()])
                        .arg("--out")
                        .arg(&c)
                        .env("NLVID_NO_PROGRESS", "1")
                        .output()
                        .unwrap();
                    assert!(st.status.success(), "{}", common::text(&st.stderr));
                    let o = dir.join("report");
                    (
                        Case {
                            what,
                            args: vec!["report".into(), c.into(), "--out".into(), o.clone().into()],
                            out: o.clone(),
                        },
                        Box::new(move || {
                            let _ = std::fs::remove_dir_all(&o);
                        }),
                    )
                }
            }
        };
        // The reference runs in the same directory (outputs record their
        // paths), then its outputs are removed.
        let (case, reset) = make(&root.join(format!("{name}-{what}")));
        let took = case.run_ok();
        let snap = snapshot(&case.out);
        assert!(!snap.is_empty(), "{what}: no output");
        reset();
        out.push((case, snap, took, reset));
    }
    out
}

#[test]
fn a_full_disk_mid_write_leaves_no_cut_file_and_resumes() {
    let root = common::scratch("kill-disk");
    for (case, reference, _, _) in cases(&root, "disk") {
        // The largest output decides the limit: half of it.
        let biggest = reference.values().map(Vec::len).max().unwrap() as u64;
        let kib = (biggest / 2 / 1024).max(1);
        assert!(
            case.run_limited(kib),
            "{}: finished under a {kib} KiB file-size limit",
            case.what
        );
        assert_absent_or_complete(&case.out, &reference, case.what);
        case.run_ok();
        assert_resumed(&case.out, &reference, case.what);
    }
}

fn kill_at_random_points(points: usize, seed: u64) {
    let root = common::scratch(&format!("kill-random-{seed}"));
    let mut rng = Lcg(seed);
    for (case, reference, took, reset) in cases(&root, "random") {
        for _ in 0..points {
            reset();
            // A first kill somewhere in the run, then a second one in the
            // resumed run, then the resume to the end.
            for _ in 0..2 {
                let at = took.mul_f64(rng.next());
                case.kill_after(at);
                assert_absent_or_complete(&case.out, &reference, case.what);
            }
            case.run_ok();
            assert_resumed(&case.out, &reference, case.what);
        }
    }
}

#[test]
fn kill_at_two_random_points() {
    kill_at_random_points(2, 20);
}

#[test]
#[ignore = "long: ten kill points per command"]
fn kill_at_many_random_points() {
    kill_at_random_points(10, 2020);
}
