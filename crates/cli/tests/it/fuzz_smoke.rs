//! Seeded random-input smoke run of the parsers every user input passes:
//! the study parser (with each stage's reader), the measured-curve CSV
//! reader, the design/table CSV reader, the loading-table reader and the
//! JPK reader. Valid seed files are damaged (byte flips, cuts, splices,
//! duplicated lines, inserted tokens); every damaged input must give a
//! value or an error with a message — never a panic. The default run takes
//! seconds; set `NLVID_FUZZ_ROUNDS` (e.g. 100000) for a long run, and see
//! docs/theory/afm.md for the cargo-fuzz targets of the JPK reader.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers

use std::path::Path;

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::common;

fn rounds(default: usize) -> usize {
    std::env::var("NLVID_FUZZ_ROUNDS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

const TOKENS: [&str; 16] = [
    "\"",
    "=",
    "[",
    "]",
    "\n",
    "{",
    "}",
    ",",
    "-",
    "1e308",
    "nan",
    "\"1 ns\"",
    "\"-3 kPa\"",
    "[[x]]",
    "#",
    "\u{feff}",
];

fn mutate(rng: &mut ChaCha8Rng, src: &[u8]) -> Vec<u8> {
    let mut b = src.to_vec();
    if b.is_empty() {
        return b;
    }
    for _ in 0..rng.random_range(1..4usize) {
        match rng.random_range(0..5u8) {
            0 => {
                let i = rng.random_range(0..b.len());
                b[i] ^= 1 << rng.random_range(0..8u32);
            }
            1 => b.truncate(rng.random_range(0..b.len())),
            2 => {
                let i = rng.random_range(0..b.len());
                let n = rng.random_range(1..32usize).min(b.len() - i);
                b.drain(i..i + n);
            }
            3 => {
                let i = rng.random_range(0..=b.len());
                let t = TOKENS[rng.random_range(0..TOKENS.len())];
                b.splice(i..i, t.bytes());
            }
            _ => {
                // Duplicate a line.
                let text = String::from_utf8_lossy(&b).into_owned();
                let lines: Vec<&str> = text.lines().collect();
                if !lines.is_empty() {
                    let k = rng.random_range(0..lines.len());
                    let mut out: Vec<&str> = lines.clone();
                    out.insert(k, lines[k]);
                    b = out.join("\n").into_bytes();
                }
            }
        }
        if b.is_empty() {
            break;
        }
    }
    b
}

fn examples(rel: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples")
        .join(rel)
}

#[test]
fn damaged_study_files_never_panic() {
    let dir = common::scratch("fuzz-study");
    let seeds: Vec<Vec<u8>> = [
        "material/pipkin-rogers-ramp-hold.toml",
        "material/cell-neo-hookean-prony-table.toml",
        "metamodel/hertz-prony.toml",
        "metamodel/membrane.toml",
        "demo/study.toml",
        "fit/study.toml",
    ]
    .iter()
    .map(|r| std::fs::read(examples(r)).unwrap())
    .collect();
    let mut rng = ChaCha8Rng::seed_from_u64(20);
    let (mut ok, mut err) = (0, 0);
    for round in 0..rounds(600) {
        let bytes = mutate(&mut rng, &seeds[round % seeds.len()]);
        let p = dir.join(format!("s{}.toml", round % 7));
        std::fs::write(&p, &bytes).unwrap();
        let results = common::read_study_every_way(&p);
        for r in results {
            match r {
                Ok(()) => ok += 1,
                Err(m) => {
                    assert!(!m.trim().is_empty(), "empty message for round {round}");
                    err += 1;
                }
            }
        }
    }
    assert!(
        err > ok / 4,
        "ok {ok}, err {err}: the damage should be detected"
    );
}

#[test]
fn damaged_csv_files_never_panic() {
    let dir = common::scratch("fuzz-csv");
    let curve = std::fs::read(examples("demo/data/A-stiff/a-stiff-01.csv")).unwrap();
    let curve = curve[..curve.len().min(4000)].to_vec();
    let design = b"index,G0 [Pa],g1 [1],g2 [1],tau1 [s],tau2 [s]\n0,1e3,0.2,0.3,0.1,5\n1,2e3,0.1,0.2,0.5,9\n".to_vec();
    let table = b"time_s,shear\n0,0\n1,0.1\n2,0.1\n".to_vec();
    let cols = nlvid_inverse::AfmColumns {
        time: "time".into(),
        piezo: "piezo".into(),
        deflection: "deflection".into(),
    };
    let cal = nlvid_inverse::Calibration {
        deflection_sensitivity: None,
        spring_constant: 0.12,
    };
    let mut rng = ChaCha8Rng::seed_from_u64(21);
    for round in 0..rounds(900) {
        let p = dir.join("d.csv");
        match round % 3 {
            0 => {
                std::fs::write(&p, mutate(&mut rng, &curve)).unwrap();
                if let Ok(c) = nlvid_inverse::read_afm_csv(&p, &cols, &cal) {
                    let _ = c.implausible();
                }
            }
            1 => {
                std::fs::write(&p, mutate(&mut rng, &design)).unwrap();
                let _ = nlvid_surrogate::read_table(&p);
            }
            _ => {
                std::fs::write(&p, mutate(&mut rng, &table)).unwrap();
                let _ = nlvid_material::read_table(&p, "shear");
            }
        }
    }
}

#[test]
fn damaged_jpk_files_never_panic() {
    let data = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../afm/tests/data/fmt-jpk-fd_flipsign_2015.05.22-15.31.49.352.jpk-force");
    let src = std::fs::read(data).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(22);
    for _ in 0..rounds(150) {
        let bytes = mutate(&mut rng, &src);
        if let Err(e) =
            nlvid_afm::read_jpk_bytes(&bytes, "damaged", &nlvid_afm::ReadOptions::default())
        {
            assert!(!e.to_string().is_empty());
        }
    }
}
