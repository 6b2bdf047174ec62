//! An installed `nlvid demo` (issue 20): the binary, copied out of the
//! build tree and run from a folder with no `examples/`, finds the bundled
//! example embedded in itself, writes it to `OUT/example/` and runs the
//! whole demo — without reading the source tree it was built from.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers

use std::path::Path;
use std::process::Command;

use crate::common;

#[test]
fn installed_binary_runs_the_demo_from_its_embedded_copy() {
    let dir = common::scratch("demo-installed");
    let bin = dir.join("bin/nlvid");
    std::fs::create_dir_all(bin.parent().unwrap()).unwrap();
    std::fs::copy(env!("CARGO_BIN_EXE_nlvid"), &bin).unwrap();
    let work = dir.join("work");
    std::fs::create_dir_all(&work).unwrap();
    assert!(!work.join("examples").exists());
    let run = || {
        Command::new(&bin)
            .args(["demo", "--out", "out"])
            .current_dir(&work)
            .env_remove("NLVID_LOG")
            .env("CI", "1")
            .output()
            .unwrap()
    };
    let o = run();
    let (out, err) = (common::text(&o.stdout), common::text(&o.stderr));
    assert!(o.status.success(), "{out}\n{err}");
    // The demo used the written-out copy, not the source tree.
    let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/demo");
    let repo = repo.canonicalize().unwrap();
    assert!(out.contains("out/example/study.toml"), "{out}");
    assert!(!out.contains(&*repo.to_string_lossy()), "{out}");
    assert!(work.join("out/cohort/report/index.html").is_file());
    // The copy is the repository's example, byte for byte.
    for rel in [
        "study.toml",
        "metamodel.toml",
        "ground_truth.csv",
        "metamodel/model.json",
        "metamodel/meta.json",
    ] {
        assert_eq!(
            std::fs::read(work.join("out/example").join(rel)).unwrap(),
            std::fs::read(repo.join(rel)).unwrap(),
            "{rel}"
        );
    }
    let n = |d: &Path| std::fs::read_dir(d).unwrap().count();
    for g in ["A-stiff", "B-soft"] {
        let d = Path::new("data").join(g);
        assert_eq!(
            n(&work.join("out/example").join(&d)),
            n(&repo.join(&d)),
            "{g}"
        );
    }
    // A second run (resume) succeeds on the same copy.
    let again = run();
    assert!(again.status.success(), "{}", common::text(&again.stderr));
}

/// Every file of the repository's examples/demo is embedded, byte for
/// byte (the list is not maintained by hand).
#[test]
fn every_file_of_examples_demo_is_embedded() {
    use nlvid_cli::embedded_demo::{FILES, NOT_EMBEDDED};
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/demo");
    for rel in ["study.toml", "metamodel.toml", "ground_truth.csv"] {
        let (_, bytes) = FILES.iter().find(|(r, _)| *r == rel).unwrap();
        assert_eq!(
            *bytes,
            std::fs::read(root.join(rel)).unwrap().as_slice(),
            "{rel}"
        );
    }
    let data = FILES.iter().filter(|(r, _)| r.starts_with("data/")).count();
    assert!(data >= 2, "{data} curves embedded");
    assert!(NOT_EMBEDDED.is_empty(), "{NOT_EMBEDDED:?}");
}
