//! `nlvid inspect` on many files ([`nlvid_afm::inspect_batch`]): folders, globs and
//! files in, one row per curve out (CSV and JSON), failures listed with file, curve and
//! reason, progress reported per file; and the glob matcher of the one batch input
//! reader ([`nlvid_afm::expand_inputs`]).

use crate::common;

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use common::*;
use nlvid_afm::batch::glob_match;
use nlvid_afm::{
    ContactMethod, Progress, QuickFitKind, ReadOptions, batch_csv, batch_json, expand_inputs,
    inspect_batch,
};

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("nlvid-afm-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("tmp dir");
    dir
}

fn copy(from: &str, dir: &Path, name: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::copy(from, &p).expect("copy");
    p
}

#[derive(Default)]
struct Count {
    files: AtomicUsize,
    done: AtomicUsize,
}

impl Progress for Count {
    fn start(&self, files: usize) {
        self.files.store(files, Ordering::SeqCst);
    }
    fn file_done(&self) {
        self.done.fetch_add(1, Ordering::SeqCst);
    }
}

#[test]
fn glob_matcher_follows_shell_rules() {
    for (p, n, want) in [
        ("*.jpk-force", "a.jpk-force", true),
        ("*.jpk-force", "a.jpk-force-map", false),
        ("*.jpk-force*", "a.jpk-force-map", true),
        ("cell?-0008*", "cell1-0008.jpk-force", true),
        ("cell?-0008*", "cell12-0008.jpk-force", false),
        ("cell[12]-*", "cell2-x", true),
        ("cell[!12]-*", "cell2-x", false),
        ("cell[0-9]-*", "cell7-x", true),
        ("cell[a-c]-*", "cell7-x", false),
        ("a*b*c", "aXXbYYc", true),
        ("a*b*c", "aXXbYY", false),
        ("*", "", true),
        ("?", "", false),
        ("[abc", "[abc", true),
    ] {
        assert_eq!(glob_match(p, n), want, "{p} vs {n}");
    }
}

#[test]
fn a_folder_gives_one_row_per_curve_and_lists_failures_and_other_files() {
    let dir = tmp("inspect-batch");
    copy(FD, &dir, "a-fd.jpk-force");
    copy(&data(MAP), &dir, "b-map.jpk-force-map");
    let sr = std::fs::read(SR).expect("read");
    std::fs::write(dir.join("c-truncated.jpk-force"), &sr[..sr.len() / 3]).expect("write");
    std::fs::write(dir.join("notes.txt"), "not a curve").expect("write");

    let progress = Count::default();
    let fit = Some((QuickFitKind::Hertz { poisson: 0.5 }, 40e-9));
    let batch = inspect_batch(
        &[&dir],
        &ReadOptions::default(),
        fit,
        ContactMethod::default(),
        &progress,
    )
    .expect("batch");
    // 1 single curve + 4 map curves; the truncated file fails as a whole
    assert_eq!(batch.rows.len(), 5);
    assert_eq!(
        batch.rows.iter().map(|r| r.curve).collect::<Vec<_>>(),
        [None, Some(0), Some(1), Some(2), Some(3)]
    );
    assert_eq!(batch.failures.len(), 1);
    assert!(batch.failures[0].file.ends_with("c-truncated.jpk-force"));
    assert_eq!(batch.ignored, [dir.join("notes.txt")]);
    assert_eq!(progress.files.load(Ordering::SeqCst), 3);
    assert_eq!(progress.done.load(Ordering::SeqCst), 3);

    // fd_spot3: JPK's published E = 233.1 kPa (R = 40 nm, ν = 0.5)
    let fd = &batch.rows[0].value;
    assert_eq!(fd.model, Some("hertz-paraboloid"));
    let e = fd
        .values
        .iter()
        .find(|(k, _)| k == "youngs_modulus_Pa")
        .expect("E")
        .1;
    assert!((e / 233.1e3 - 1.0).abs() < 0.01, "E = {e}");

    let csv = batch_csv(&batch);
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines.len(), 1 + 5 + 1, "{csv}");
    let header: Vec<&str> = lines[0].split(',').collect();
    assert_eq!(&header[..5], ["file", "curve", "status", "reason", "model"]);
    assert!(header.contains(&"youngs_modulus_Pa"));
    assert!(header.contains(&"spring_constant_N_per_m"));
    for l in &lines[1..] {
        // every row has every column (the reason of the failure has no comma here, or is quoted)
        assert!(
            l.contains(",ok,,hertz-paraboloid,") || l.contains(",failed,"),
            "{l}"
        );
    }
    let failed = lines[6];
    assert!(failed.contains("c-truncated.jpk-force") && failed.contains(",failed,"));
    let e_col = header
        .iter()
        .position(|h| *h == "youngs_modulus_Pa")
        .expect("col");
    let first: Vec<&str> = lines[1].split(',').collect();
    assert_eq!(first[e_col].parse::<f64>().expect("number"), e);

    let json = batch_json(&batch);
    assert_eq!(json["curves"], 5);
    assert_eq!(json["failed"], 1);
    assert_eq!(json["rows"][2]["curve"], 1);
    assert!(
        json["failures"][0]["reason"]
            .as_str()
            .is_some_and(|r| !r.is_empty())
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn globs_select_files_and_a_glob_matching_nothing_is_a_failure() {
    let dir = tmp("inspect-glob");
    copy(FD, &dir, "x1.jpk-force");
    copy(FD, &dir, "x2.jpk-force");
    copy(&data(MAP), &dir, "x3.jpk-force-map");
    let pattern = dir.join("x*.jpk-force");
    let none = dir.join("nothing-*.jpk-force");
    let found = expand_inputs(&[&pattern, &none], |_| true);
    assert_eq!(
        found.files,
        [dir.join("x1.jpk-force"), dir.join("x2.jpk-force")]
    );
    assert_eq!(found.failures.len(), 1);
    assert!(
        found.failures[0]
            .to_string()
            .contains("nothing-*.jpk-force")
    );

    // without a fit: one summary row per curve, the failure listed, the batch complete
    let batch = inspect_batch(
        &[&pattern, &dir.join("x3.jpk-force-map"), &none],
        &ReadOptions::default(),
        None,
        ContactMethod::default(),
        &nlvid_afm::NoProgress,
    )
    .expect("batch");
    assert_eq!(batch.rows.len(), 2 + 4);
    assert_eq!(batch.failures.len(), 1);
    let seg = |i: usize| {
        batch.rows[i]
            .value
            .values
            .iter()
            .find(|(k, _)| k == "segments")
            .expect("segments")
            .1
    };
    // fd_spot3: extend + retract
    assert_eq!(seg(0), 2.0);
    let _ = std::fs::remove_dir_all(&dir);
}
