//! `nlvid material` end to end: the bundled examples run, the CSV has the
//! documented columns, `--json` is one document with the same curve, and bad
//! study files fail with a located message.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers

use std::path::PathBuf;

use crate::common;
use common::nlvid;

fn tmp(name: &str) -> PathBuf {
    common::temp_dir("material").join(name)
}

fn example(name: &str) -> String {
    format!(
        "{}/../../examples/material/{name}",
        env!("CARGO_MANIFEST_DIR")
    )
}

#[test]
fn ramp_hold_example_writes_csv_with_unit_suffixed_headers() {
    let out_csv = tmp("rh.csv");
    let out = nlvid(&[
        "material",
        &example("pipkin-rogers-ramp-hold.toml"),
        "-o",
        out_csv.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let csv = std::fs::read_to_string(&out_csv).unwrap();
    let mut lines = csv.lines();
    assert_eq!(
        lines.next(),
        Some("time_s,stretch,sigma_1_Pa,sigma_2_Pa,sigma_3_Pa")
    );
    assert_eq!(lines.next(), Some("0,1,0,0,0"));
    let last: Vec<f64> = csv
        .lines()
        .last()
        .unwrap()
        .split(',')
        .map(|x| x.parse().unwrap())
        .collect();
    assert_eq!(last[0], 10.5);
    assert_eq!(last[1], 2.0);
    // Relaxed below the instantaneous Mooney–Rivlin value 2(λ²−1/λ)(C1+C2/λ).
    let instantaneous = 2.0 * (4.0 - 0.5) * (1000.0 + 100.0 / 2.0);
    assert!(last[2] > 0.0 && last[2] < instantaneous);
}

#[test]
fn json_output_carries_the_same_curve_and_provenance() {
    let out_csv = tmp("shear.csv");
    let out = nlvid(&[
        "--json",
        "material",
        &example("cell-neo-hookean-prony-table.toml"),
        "--output",
        out_csv.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["model"], "neo-hookean-prony");
    assert_eq!(v["mode"], "simple-shear");
    // The study gives the shear modulus G0 = 1 kPa; the neo-Hookean C1 of
    // eq. 4.1 is G0/2 (docs/theory/model.md).
    assert_eq!(v["parameters"]["G0_Pa"], 1000.0);
    assert_eq!(v["parameters"]["C1_Pa"], 500.0);
    assert_eq!(v["provenance"]["study_sha256"].as_str().unwrap().len(), 64);
    let csv = std::fs::read_to_string(&out_csv).unwrap();
    let rows = csv.lines().count() - 1;
    assert_eq!(v["curve"]["sigma_12_Pa"].as_array().unwrap().len(), rows);
    assert!(csv.starts_with("time_s,shear,sigma_1_Pa,sigma_2_Pa,sigma_3_Pa,sigma_11_Pa,sigma_22_Pa,sigma_12_Pa,N_1_Pa,N_2_Pa\n"));
}

#[test]
fn bad_study_fails_with_file_line_and_key() {
    let p = tmp("bad.toml");
    std::fs::write(
        &p,
        "[material]\nmodel = \"neo-hookean\"\nC1 = \"1 kPa\"\n[loading]\nmode = \"uniaxial\"\n\
         history = \"step\"\nstretch = 2\nhold = \"10 parsecs\"\n",
    )
    .unwrap();
    let out = nlvid(&["material", p.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
    let e = String::from_utf8_lossy(&out.stderr);
    assert!(
        e.contains("bad.toml:8") && e.contains("loading.hold"),
        "{e}"
    );
}
