//! `nlvid check` end to end: exit status, SI output, located errors.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers

use std::path::PathBuf;

mod common;
use common::{nlvid, text};

fn write(name: &str, text: &str) -> PathBuf {
    let p = common::temp_dir("check").join(name);
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn bundled_example_checks_and_prints_si_values() {
    let example = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../examples/study/capsule-compression.toml"
    );
    let out = nlvid(&["check", example]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let s = text(&out.stdout);
    assert!(s.contains("geometry.wall_thickness         4e-5 m"), "{s}");
    assert!(s.contains("material.C1                     2940 Pa"), "{s}");
    assert!(s.lines().last().unwrap().starts_with("ok: "), "{s}");
}

#[test]
fn json_output_is_one_document_with_si_values() {
    let p = write("j.toml", "[g]\nradius = \"12.22 um\"\nn = 3\n");
    let out = nlvid(&["check", "--json", p.to_str().unwrap()]);
    assert!(out.status.success());
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["values"][0]["key"], "g.radius");
    assert_eq!(v["values"][0]["value"], 12.22e-6);
    assert_eq!(v["values"][0]["unit"], "m");
    assert_eq!(v["values"][0]["line"], 2);
    assert_eq!(v["values"][1]["value"], 3);
    assert_eq!(v["sha256"].as_str().unwrap().len(), 64);
}

#[test]
fn syntax_error_fails_with_file_and_line() {
    let p = write("syn.toml", "[g]\nradius = \"1 um\n");
    let out = nlvid(&["check", p.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
    let e = text(&out.stderr);
    assert!(e.starts_with(&format!("error: {}:2:", p.display())), "{e}");
    assert!(out.stdout.is_empty());
}

#[test]
fn non_finite_values_fail_with_their_key() {
    let p = write("nan.toml", "[g]\nok = \"1 um\"\nbad = \"nan um\"\n");
    let out = nlvid(&["check", p.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
    assert_eq!(
        text(&out.stderr).trim_end(),
        format!(
            "error: {}:3:7: key `g.bad`: `nan um` is not a finite number",
            p.display()
        )
    );
    let p = write("inf.toml", "x = inf\n");
    let out = nlvid(&["check", p.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
    assert!(text(&out.stderr).contains(":1:5: key `x`: `inf` is not a finite number"));
}

#[test]
fn unreadable_quantities_warn_and_fail_only_with_strict() {
    let p = write(
        "warn.toml",
        "[p]\nspeed = \"5 mm/sec\"\nname = \"capsule one\"\n",
    );
    let out = nlvid(&["check", p.to_str().unwrap()]);
    assert!(out.status.success());
    let e = text(&out.stderr);
    assert!(
        e.contains(":2:9: key `p.speed`: `5 mm/sec` looks like a quantity but cannot be read: unknown unit `sec`"),
        "{e}"
    );
    assert!(!e.contains("p.name"), "{e}");
    let out = nlvid(&["check", "--strict", p.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
}

#[test]
fn missing_file_is_named() {
    let out = nlvid(&["check", "/no/such/study.toml"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(text(&out.stderr).starts_with("error: /no/such/study.toml: cannot read study file"));
}
