//! `nlvid membrane <study>`: ch. II's modulus is `G10` (G1(0)) in the study
//! keys and the CSV headers, the long-term fractions are `g1_long_term`,
//! `g2_long_term`; the old keys fail naming the new one
//! (docs/theory/model.md).
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers

mod common;
use common::{nlvid, scratch, text};

const RAMP: &str = "[membrane]\ncontrol = \"displacement\"\nprogram = \"ramp\"\nvalue = 0.2\n\
                    rate = 0.2\nt_end = 1.0\nsteps = 4\n";

fn run(dir: &std::path::Path, body: &str) -> std::process::Output {
    let study = dir.join("m.toml");
    std::fs::write(&study, format!("{RAMP}{body}")).unwrap();
    nlvid(&[
        "membrane",
        study.to_str().unwrap(),
        "--out",
        dir.join("out").to_str().unwrap(),
    ])
}

#[test]
fn scaled_history_uses_g10_and_its_si_force_is_the_dimensionless_force_times_g10_h0_r0() {
    let dir = scratch("membrane-g10");
    let out = run(
        &dir,
        "[membrane.material]\ngamma0 = 0.1\ng1_long_term = 0.5\ng2_long_term = 0.5\n\
         [membrane.scale]\nr0 = \"10 um\"\nh0 = \"0.1 um\"\nG10 = \"2 kPa\"\ntau1 = \"1 s\"\n",
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(
        text(&out.stdout).contains("F/(G10 h0 r0)"),
        "{}",
        text(&out.stdout)
    );
    let csv = std::fs::read_to_string(dir.join("out/history.csv")).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let col = |name: &str| {
        header
            .iter()
            .position(|h| *h == name)
            .unwrap_or_else(|| panic!("no column {name} in {header:?}"))
    };
    let (fbar, f_si) = (col("F_over_G10h0r0"), col("F_N"));
    assert!(!csv.contains("C1"), "{}", csv.lines().next().unwrap());
    let mut rows = 0;
    for line in csv.lines().skip(1) {
        let v: Vec<f64> = line.split(',').map(|x| x.parse().unwrap()).collect();
        // F = F̄ · G10 h0 r0 with G10 = 2 kPa, h0 = 0.1 µm, r0 = 10 µm.
        let by_hand = v[fbar] * 2000.0 * 0.1e-6 * 10e-6;
        assert!(
            (v[f_si] - by_hand).abs() <= 1e-12 * by_hand.abs().max(1e-30),
            "{line}"
        );
        rows += 1;
    }
    assert!(rows >= 5, "{rows} rows");
}

#[test]
fn old_membrane_keys_fail_naming_the_new_key() {
    let dir = scratch("membrane-old-keys");
    let out = run(
        &dir,
        "[membrane.material]\n[membrane.scale]\nr0 = \"10 um\"\nh0 = \"0.1 um\"\nc1 = \"2 kPa\"\n\
         tau1 = \"1 s\"\n",
    );
    assert_eq!(out.status.code(), Some(1));
    let e = text(&out.stderr);
    assert!(
        e.contains("m.toml:12") && e.contains("membrane.scale.c1") && e.contains("`G10`"),
        "{e}"
    );

    let out = run(&dir, "[membrane.material]\ng1 = 0.5\n");
    assert_eq!(out.status.code(), Some(1));
    let e = text(&out.stderr);
    assert!(
        e.contains("membrane.material.g1") && e.contains("`g1_long_term`"),
        "{e}"
    );

    let out = run(&dir, "[membrane.material]\nC1 = 1.0\n");
    assert_eq!(out.status.code(), Some(1));
    let e = text(&out.stderr);
    assert!(
        e.contains("membrane.material.C1") && e.contains("G10"),
        "{e}"
    );
}
