//! `nlvid inspect` on a folder / several files / a glob: one CSV row per curve on
//! stdout (or `--table`), JSON with `--json`, failures on stderr with file and reason,
//! exit status 3 when any curve failed, and the single-curve flags refused in a batch.

mod common;

use common::*;

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../afm/tests/data");

#[test]
fn a_folder_gives_one_row_per_curve_and_failures_are_listed() {
    let dir = scratch("inspect-batch");
    for (from, to) in [
        ("fmt-jpk-fd_spot3-0192.jpk-force", "a.jpk-force"),
        ("fmt-jpk-fd_map2x2_extracted.jpk-force-map", "b.jpk-force-map"),
    ] {
        std::fs::copy(format!("{DATA}/{from}"), dir.join(to)).expect("copy");
    }
    std::fs::write(dir.join("c.jpk-force"), b"PK\x03\x04 not really").expect("write");
    let d = dir.to_string_lossy().into_owned();
    let out = nlvid(&["inspect", &d, "--fit", "hertz", "--tip-radius", "40 nm"]);
    let stdout = text(&out.stdout);
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(3), "{stderr}");
    let lines: Vec<&str> = stdout.lines().collect();
    assert_eq!(lines.len(), 1 + 1 + 4 + 1, "{stdout}");
    assert!(lines[0].starts_with("file,curve,status,reason,model,"));
    assert_eq!(lines.iter().filter(|l| l.contains(",ok,,hertz-paraboloid,")).count(), 5);
    assert!(stderr.contains("c.jpk-force"), "{stderr}");
    assert!(stderr.contains("1 curve(s) or file(s) failed (5 analysed)"), "{stderr}");

    // JSON, a glob, and --table
    let table = dir.join("t.csv");
    let glob = format!("{d}/*.jpk-force*");
    let out = nlvid(&[
        "--json",
        "inspect",
        &glob,
        "--table",
        &table.to_string_lossy(),
    ]);
    assert_eq!(out.status.code(), Some(3));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("json");
    assert_eq!(v["curves"], 5);
    assert_eq!(v["failed"], 1);
    let t = std::fs::read_to_string(&table).expect("table");
    assert_eq!(t.lines().count(), 7);
}

#[test]
fn single_curve_flags_are_refused_in_a_batch() {
    let fd = format!("{DATA}/fmt-jpk-fd_spot3-0192.jpk-force");
    let out = nlvid(&["inspect", &fd, &fd, "--plot", "x.svg"]);
    assert!(!out.status.success());
    assert!(text(&out.stderr).contains("--plot applies to one curve"));
}
