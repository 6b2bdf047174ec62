//! `nlvid compare` end to end on the example results table: outputs,
//! p-values with a closed form, exclusions, and argument errors.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers

use std::path::PathBuf;

use crate::common;
use common::{nlvid, text};

const EXAMPLE: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../stats/tests/data/results_example.csv"
);

fn out_dir(tag: &str) -> PathBuf {
    common::temp_dir(&format!("compare-{tag}"))
}

#[test]
fn example_table_json_summary_and_csv_outputs() {
    let dir = out_dir("json");
    let out = nlvid(&[
        "--json",
        "compare",
        EXAMPLE,
        "--out-dir",
        dir.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["cells_used"], 16);
    assert_eq!(v["excluded"][0]["cell"], "mcf-7-09");
    assert_eq!(v["excluded"][0]["line"], 18);
    let tests = v["comparison"]["tests"].as_array().unwrap();
    // 8 vs 8 with complete separation at 52 s: exact p = 2 / C(16, 8).
    let p52 = tests[1]["test"]["p"].as_f64().unwrap();
    assert!((p52 - 2.0 / 12870.0).abs() < 1e-15, "{p52}");
    assert_eq!(tests[1]["test"]["method"], "exact");
    assert_eq!(tests[1]["effect_a_minus_b"]["rank_biserial"], 1.0);
    let groups = std::fs::read_to_string(dir.join("results_example.groups.csv")).unwrap();
    assert_eq!(groups.lines().count(), 1 + 2 * 53);
    let pv = std::fs::read_to_string(dir.join("results_example.pvalues.csv")).unwrap();
    assert!(pv.starts_with("time_s,p_G,method_G,z_G,p_G_norm,"), "{pv}");
    assert_eq!(pv.lines().count(), 1 + 53);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn text_output_lists_the_excluded_cell_and_the_tests() {
    let dir = out_dir("text");
    let out = nlvid(&[
        "compare",
        EXAMPLE,
        "--out-dir",
        dir.to_str().unwrap(),
        "--points",
        "5",
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let s = text(&out.stdout);
    assert!(
        s.contains("excluded mcf-7-09 (MCF-7, line 18): failed: fit did not converge"),
        "{s}"
    );
    assert!(s.contains("relaxation 1 − G(52 s)/G(0)"), "{s}");
    assert!(s.contains("p < 0.05 at 5 of 5 times"), "{s}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn bad_arguments_are_reported() {
    let out = nlvid(&["compare", EXAMPLE, "--t-end", "52"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        text(&out.stderr).contains("has no unit"),
        "{}",
        text(&out.stderr)
    );
    let out = nlvid(&["compare", EXAMPLE, "--groups", "MCF-10A,X"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(text(&out.stderr).contains("no usable cells in group `X`"));
    let out = nlvid(&["compare", EXAMPLE, "--method", "ttest"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(text(&out.stderr).contains("--method `ttest`"));
    let out = nlvid(&["compare", "/nonexistent/results.csv"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(text(&out.stderr).contains("/nonexistent/results.csv"));
}

/// `--out-dir` names a folder that does not exist yet: it is created.
#[test]
fn out_dir_is_created_when_missing() {
    let base = out_dir("mkdir");
    let dir = base.join("new/nested");
    assert!(!dir.exists());
    let out = nlvid(&["compare", EXAMPLE, "--out-dir", dir.to_str().unwrap()]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(dir.join("results_example.groups.csv").is_file());
    assert!(dir.join("results_example.pvalues.csv").is_file());
    std::fs::remove_dir_all(&base).ok();
}

/// `--json` carries p(t) at every time of a non-uniform `--times` grid,
/// equal to the pvalues CSV; at t = 0 and 52 s the 8-vs-8 groups are
/// completely separated in G: exact p = 2 / C(16, 8).
#[test]
fn json_has_p_of_t_on_a_non_uniform_grid() {
    let dir = out_dir("times");
    let out = nlvid(&[
        "--json",
        "compare",
        EXAMPLE,
        "--times",
        "0 s,0.1 s,1 s,10 s,52 s",
        "--out-dir",
        dir.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let pt = v["comparison"]["p_of_t"].as_array().unwrap();
    let t: Vec<f64> = pt.iter().map(|r| r["time_s"].as_f64().unwrap()).collect();
    assert_eq!(t, [0.0, 0.1, 1.0, 10.0, 52.0]);
    assert_eq!(v["t_end_s"], 52.0);
    let p52 = pt[4]["p_G"].as_f64().unwrap();
    assert!((p52 - 2.0 / 12870.0).abs() < 1e-15, "{p52}");
    let csv = std::fs::read_to_string(dir.join("results_example.pvalues.csv")).unwrap();
    for (line, row) in csv.lines().skip(1).zip(pt) {
        let p: f64 = line.split(',').nth(1).unwrap().parse().unwrap();
        assert_eq!(p, row["p_G"].as_f64().unwrap(), "{line}");
    }
    let out = nlvid(&["compare", EXAMPLE, "--times", "0 s,2 s,1 s"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(
        text(&out.stderr).contains("increasing"),
        "{}",
        text(&out.stderr)
    );
    std::fs::remove_dir_all(&dir).ok();
}
