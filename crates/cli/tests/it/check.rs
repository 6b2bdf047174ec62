//! `nlvid check` end to end: exit status, SI output, located errors.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers

use std::path::PathBuf;

use crate::common;
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

/// `check` refuses what a stage refuses, with the stage's own message.
#[test]
fn check_gives_the_stage_message_for_what_a_stage_refuses() {
    let material = "[material]\nmodel = \"neo-hookean-prony\"\nG0 = \"1 kPa\"\n\n\
                    [material.prony]\ng = [0.4, 0.3]\ntau = [\"0.5 s\", \"10 s\"]\n\n\
                    [loading]\nmode = \"uniaxial\"\nhistory = \"ramp-hold\"\nstretch = 1.5\n\
                    ramp = \"1 s\"\nhold = \"5 s\"\nmax_dt = \"10 ms\"\n";
    let build = "[forward]\nmodel = \"hertz-prony\"\nprobe_radius = \"2.5 um\"\nrate = \"1 um/s\"\n\
                 ramp = \"1 s\"\nhold = \"9 s\"\npoints = 50\n\n[design]\nn_train = 8\nn_check = 2\n\
                 seed = 3\n\n[design.parameters]\nG0 = { range = [\"80 Pa\", \"4 kPa\"] }\n\
                 g1 = { range = [0.01, 0.45] }\ng2 = { range = [0.01, 0.45] }\n\
                 tau1 = { range = [\"0.01 s\", \"2 s\"] }\ntau2 = { range = [\"2 s\", \"40 s\"] }\n\n\
                 [build]\nstore = \"store\"\nmin_peak_force = \"4 nN\"\n";
    let cases: [(&str, &str, &str, &str, &str); 7] = [
        (
            "readme-unit.toml",
            "material",
            material,
            "G0 = \"1 kPa\"",
            "C1 = \"0.12 N/m\"",
        ),
        ("missing.toml", "material", material, "G0 = \"1 kPa\"\n", ""),
        ("sum.toml", "material", material, "[0.4, 0.3]", "[0.7, 0.6]"),
        ("dt.toml", "material", material, "\"10 ms\"", "\"-10 ms\""),
        ("unknown.toml", "material", material, "stretch", "strech"),
        ("typo.toml", "build", build, "n_train", "n_trian"),
        ("units.toml", "build", build, "\"4 nN\"", "\"4 nm\""),
    ];
    for (name, stage, base, old, new) in cases {
        assert!(base.contains(old), "{name}");
        let p = write(name, &base.replace(old, new));
        let s = p.to_str().unwrap();
        let checked = nlvid(&["check", s]);
        let staged = if stage == "build" {
            nlvid(&["build", s, "--quiet"])
        } else {
            let o = p.with_extension("csv");
            nlvid(&[stage, s, "--output", o.to_str().unwrap()])
        };
        assert_eq!(
            checked.status.code(),
            Some(1),
            "{name}: {}",
            text(&checked.stdout)
        );
        assert_eq!(staged.status.code(), Some(1), "{name}");
        assert_eq!(text(&checked.stderr), text(&staged.stderr), "{name}");
    }
    // The typo is named, and the README's wrong unit reads as the README says.
    let e = text(
        &nlvid(&[
            "check",
            write("t2.toml", &build.replace("n_train", "n_trian"))
                .to_str()
                .unwrap(),
        ])
        .stderr,
    );
    assert!(
        e.contains("`design.n_train`") && e.contains("`n_trian`"),
        "{e}"
    );
    let e = text(
        &nlvid(&[
            "check",
            write(
                "u2.toml",
                &material.replace("G0 = \"1 kPa\"", "C1 = \"0.12 N/m\""),
            )
            .to_str()
            .unwrap(),
        ])
        .stderr,
    );
    assert!(
        e.contains("key `material.C1`: `0.12 N/m` is a force per length (N/m), expected a pressure or stress (Pa)"),
        "{e}"
    );
}

/// A missing file's OS error is printed once.
#[test]
fn os_errors_are_printed_once() {
    let out = nlvid(&["check", "/no/such/study.toml"]);
    let e = text(&out.stderr);
    assert_eq!(e.matches("os error 2").count(), 1, "{e}");
}

/// `nlvid material --json | head -0`: a closed stdout ends the command
/// quietly with status 0 (no `error: Broken pipe`).
#[test]
fn a_closed_stdout_pipe_is_quiet() {
    let study = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../examples/material/pipkin-rogers-ramp-hold.toml"
    );
    let out = common::temp_dir("check").join("pipe.csv");
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_nlvid"))
        .args(["material", "--json", study, "--output"])
        .arg(&out)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take()); // the reader goes away before anything is read
    let done = child.wait_with_output().unwrap();
    assert!(done.status.success(), "{}", text(&done.stderr));
    assert_eq!(text(&done.stderr), "");
}
