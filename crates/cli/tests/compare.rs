//! `nlvid compare` end to end on the example results table: outputs,
//! p-values with a closed form, exclusions, and argument errors.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers

use std::path::PathBuf;

mod common;
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
    assert!(s.contains("relaxation at 52 s"), "{s}");
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
