//! `nlvid membrane <study>`: the `membrane` model of `[forward]`,
//! `[protocol]`, `[parameters]` (the schema `nlvid build` reads). Ch. II's
//! modulus is `G10` (G1(0)), the long-term fractions are `g1_long_term`,
//! `g2_long_term` (docs/theory/model.md); the former `[membrane]` section
//! and the old names fail naming the new ones.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers

use crate::common;
use common::{nlvid, scratch, text};

const STUDY: &str = r#"
[forward]
model = "membrane"
radius = "10 um"
wall_thickness = "0.1 um"
nodes = 48
points = 5

[protocol]
kind = "ramp-hold"
displacement = "2 um"
speed = "4 um/s"
hold = "0.5 s"
"#;

fn params(g10: &str) -> String {
    format!(
        "[parameters]\nG10 = \"{g10}\"\ngamma0 = 0.1\ng1_long_term = 0.5\ng2_long_term = 0.5\n\
         tau1 = \"1 s\"\ntau2 = \"1 s\"\n"
    )
}

fn run(dir: &std::path::Path, name: &str, body: &str) -> std::process::Output {
    let study = dir.join(format!("{name}.toml"));
    std::fs::write(&study, format!("{STUDY}{body}")).unwrap();
    nlvid(&["membrane", study.to_str().unwrap()])
}

/// Column `name` of `<dir>/<stem>.membrane/history.csv`.
fn column(dir: &std::path::Path, stem: &str, name: &str) -> Vec<f64> {
    let csv = std::fs::read_to_string(dir.join(format!("{stem}.membrane/history.csv"))).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    assert!(!csv.contains("C1"), "{header:?}");
    let j = header.iter().position(|h| *h == name).unwrap();
    csv.lines()
        .skip(1)
        .map(|l| l.split(',').nth(j).unwrap().parse().unwrap())
        .collect()
}

/// The solver works in eq. 2.47's units, so F = F̄ · G10 h0 r0 with F̄
/// independent of G10: doubling G10 doubles the force at every time and
/// leaves the displacement as it is.
#[test]
fn the_si_force_scales_with_g10_and_the_displacement_does_not() {
    let dir = scratch("membrane-g10");
    for (stem, g10) in [("a", "2 kPa"), ("b", "4 kPa")] {
        let out = run(&dir, stem, &params(g10));
        assert!(out.status.success(), "{}", text(&out.stderr));
    }
    let (fa, fb) = (column(&dir, "a", "force_N"), column(&dir, "b", "force_N"));
    assert!(fa.len() >= 5, "{fa:?}");
    assert!(fa.iter().any(|f| *f > 0.0));
    for (a, b) in fa.iter().zip(&fb) {
        assert!((b - 2.0 * a).abs() <= 1e-12 * a.abs().max(1e-30), "{a} {b}");
    }
    assert_eq!(
        column(&dir, "a", "displacement_m"),
        column(&dir, "b", "displacement_m")
    );
}

#[test]
fn old_membrane_keys_fail_naming_the_new_ones() {
    let dir = scratch("membrane-old-keys");
    let out = run(
        &dir,
        "old",
        "[membrane]\ncontrol = \"displacement\"\nprogram = \"ramp\"\n",
    );
    assert_eq!(out.status.code(), Some(1));
    let e = text(&out.stderr);
    assert!(
        e.contains("old.toml") && e.contains("[forward]") && e.contains("[parameters]"),
        "{e}"
    );
    for (old, new) in [("C1", "G10"), ("g1", "g1_long_term")] {
        let body = params("2 kPa").replace(&format!("\n{new} ="), &format!("\n{old} ="));
        let out = run(&dir, "old", &body);
        assert_eq!(out.status.code(), Some(1));
        let e = text(&out.stderr);
        assert!(e.contains(&format!("`parameters.{new}`")), "{old}: {e}");
    }
}
