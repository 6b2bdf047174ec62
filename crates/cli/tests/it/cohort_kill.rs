//! A real interruption: `nlvid cohort` is killed (SIGKILL) while it fits,
//! then re-run into the same directory; the results table must equal the
//! one of an uninterrupted run byte for byte.

use std::path::Path;
use std::process::Command;
use std::time::{Duration, Instant};

use nlvid_report::demo::{DemoSpec, write_demo_data};

use crate::common;
use common::scratch;

fn count_cells(out: &Path) -> usize {
    let Ok(groups) = std::fs::read_dir(out.join("cells")) else {
        return 0;
    };
    groups
        .filter_map(|g| g.ok())
        .filter_map(|g| std::fs::read_dir(g.path()).ok())
        .flat_map(|d| d.filter_map(|e| e.ok()))
        .filter(|e| e.path().extension().is_some_and(|x| x == "json"))
        .count()
}

/// The cells' curves are written with the analytic Lee–Radok ramp-hold
/// (`hertz-prony`, the demo's protocol): the demo's own FE writer costs
/// seconds per cell, and what is tested here is the run, not the model.
const LEE_RADOK: &str = "[forward]\nmodel = \"hertz-prony\"\nprobe_radius = \"2.5 um\"\n\
                         rate = \"2 um/s\"\nramp = \"1 s\"\nhold = \"51 s\"\npoints = 520\n";

#[test]
fn killed_cohort_resumes_to_the_same_table() {
    let root = scratch("kill");
    // The bundled demo's study and meta-model, 2 × 30 cells, 24 starts
    // each: long enough to be killed mid-way.
    let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/demo");
    let dir = root.join("study");
    std::fs::create_dir_all(dir.join("metamodel")).expect("dir");
    for f in [
        "metamodel.toml",
        "metamodel/model.json",
        "metamodel/meta.json",
        "metamodel/check.json",
    ] {
        std::fs::copy(repo.join(f), dir.join(f)).expect("copy");
    }
    let study = std::fs::read_to_string(repo.join("study.toml")).expect("study");
    assert!(study.contains("starts = 64\n"));
    std::fs::write(
        dir.join("study.toml"),
        study.replace("starts = 64\n", "starts = 24\n"),
    )
    .expect("study");
    let spec = DemoSpec {
        cells_per_group: 30,
        ..DemoSpec::default()
    };
    std::fs::write(dir.join("lee-radok.toml"), LEE_RADOK).expect("forward");
    let files =
        write_demo_data(&spec, &dir.join("study.toml"), &dir.join("lee-radok.toml")).expect("demo");
    let nlvid = env!("CARGO_BIN_EXE_nlvid");
    let cohort = |out: &Path| {
        let mut c = Command::new(nlvid);
        c.arg("cohort")
            .arg(&files.study)
            .arg(&files.data)
            .arg("--out")
            .arg(out)
            .env("NLVID_NO_PROGRESS", "1");
        c
    };

    let killed = root.join("killed");
    let mut child = cohort(&killed).spawn().expect("spawn");
    let start = Instant::now();
    while count_cells(&killed) < 5 && start.elapsed() < Duration::from_secs(120) {
        std::thread::sleep(Duration::from_millis(2));
    }
    child.kill().expect("kill");
    let _ = child.wait();
    let done = count_cells(&killed);
    assert!(
        !killed.join("results.csv").exists() && done < 60,
        "the run finished before it could be killed ({done} cells); make the cohort larger"
    );

    let rerun = cohort(&killed).output().expect("re-run");
    assert!(
        rerun.status.success(),
        "{}",
        String::from_utf8_lossy(&rerun.stderr)
    );
    let text = String::from_utf8_lossy(&rerun.stdout);
    assert!(
        text.contains(&format!("{} fitted now, {done} reused", 60 - done)),
        "{text}"
    );

    let straight = root.join("straight");
    let once = cohort(&straight).output().expect("uninterrupted run");
    assert!(once.status.success());
    let a = std::fs::read_to_string(killed.join("results.csv")).expect("table");
    let b = std::fs::read_to_string(straight.join("results.csv")).expect("table");
    assert_eq!(a.lines().count(), 61);
    assert_eq!(a, b);
}
