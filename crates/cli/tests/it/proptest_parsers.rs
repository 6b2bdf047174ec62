//! Property-based smoke run (proptest, fixed seed: the same cases on every
//! CI run) of the parsers every user input passes: the study parser with
//! each stage's reader, the CSV readers (measured AFM curve, design/table
//! CSV, material loading table, protocol table, results table) and the JPK
//! reader. Properties: no input panics, and every error names where —
//! study errors the file and line (`s.toml:LINE:COL`) or the key, CSV
//! errors the file; JPK errors are only checked to be non-empty (the
//! reader names the archive entry or key; the caller adds the file). 4 s
//! in all in the dev profile on the shared 2-core machine (load ~15); `PROPTEST_CASES=20000` (and a different
//! `NLVID_PROPTEST_SEED`) for a long run; docs/theory/afm.md gives the
//! cargo-fuzz runs of the JPK reader.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers

use std::path::{Path, PathBuf};

use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, RngSeed, TestRunner};

use crate::common;

/// The runner: fixed seed (`NLVID_PROPTEST_SEED` to change it), `cases`
/// by default (`PROPTEST_CASES` to change it), no persistence files.
fn runner(cases: u32) -> TestRunner {
    let seed = std::env::var("NLVID_PROPTEST_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(20261125);
    let cases = std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(cases);
    TestRunner::new_with_rng(
        Config {
            cases,
            failure_persistence: None,
            rng_algorithm: RngAlgorithm::ChaCha,
            rng_seed: RngSeed::Fixed(seed),
            ..Config::default()
        },
        proptest::test_runner::TestRng::deterministic_rng(RngAlgorithm::ChaCha),
    )
}

fn examples(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples")
        .join(rel)
}

/// A value for a study key: valid and invalid quantities, numbers, strings,
/// arrays, tables.
fn value() -> impl Strategy<Value = String> {
    prop_oneof![
        (
            -1e6..1e6f64,
            prop::sample::select(vec![
                "", "Pa", "kPa", "um", "nm", "mm", "s", "ms", "ns", "N/m", "%", "Hz", "um/s",
                "kPa/s", "furlong",
            ])
        )
            .prop_map(|(v, u)| format!("\"{v} {u}\"")),
        any::<f64>().prop_map(|v| format!("{v:?}")),
        any::<i64>().prop_map(|v| v.to_string()),
        prop::sample::select(vec![
            "nan",
            "inf",
            "-inf",
            "true",
            "\"\"",
            "[]",
            "{}",
            "\"1 ns\"",
            "[0.2, \"10 %\"]",
            "[\"0.5 s\", \"12 s\"]",
            "{ range = [\"80 Pa\", \"4000 Pa\"], log = true }",
            "\"-3 kPa\"",
            "1e308",
            "\"1e400 Pa\"",
        ])
        .prop_map(str::to_string),
        "[ -~]{0,12}".prop_map(|s| format!("{s:?}")),
    ]
}

/// A study: a valid seed file with some values replaced, keys renamed,
/// lines dropped or garbage lines inserted.
fn study() -> impl Strategy<Value = String> {
    let seeds: Vec<String> = [
        "material/pipkin-rogers-ramp-hold.toml",
        "metamodel/hertz-prony.toml",
        "metamodel/membrane.toml",
        "demo/study.toml",
        "fit/study.toml",
        "study/capsule-compression.toml",
    ]
    .iter()
    .map(|r| std::fs::read_to_string(examples(r)).unwrap())
    .collect();
    (
        prop::sample::select(seeds),
        prop::collection::vec((any::<prop::sample::Index>(), 0..4u8, value()), 1..5),
    )
        .prop_map(|(seed, edits)| {
            let mut lines: Vec<String> = seed.lines().map(str::to_string).collect();
            for (at, op, v) in edits {
                let i = at
                    .index(lines.len().max(1))
                    .min(lines.len().saturating_sub(1));
                match op {
                    0 => {
                        if let Some((k, _)) = lines[i].split_once('=') {
                            lines[i] = format!("{k}= {v}");
                        }
                    }
                    1 => {
                        if let Some((k, rest)) = lines[i].split_once('=') {
                            lines[i] = format!("{}x ={rest}", k.trim_end());
                        }
                    }
                    2 => {
                        lines.remove(i);
                    }
                    _ => lines.insert(i, format!("extra_key = {v}")),
                }
                if lines.is_empty() {
                    break;
                }
            }
            lines.join("\n")
        })
}

/// Whether a study error names where: the file and a line, or a key.
fn names_where(message: &str) -> bool {
    let located = message
        .split_once("s.toml:")
        .is_some_and(|(_, rest)| rest.starts_with(|c: char| c.is_ascii_digit()));
    located || message.contains("key `") || message.contains("s.toml")
}

#[test]
fn study_parser_and_stage_readers_never_panic_and_name_where() {
    let dir = common::scratch("proptest-study");
    let p = dir.join("s.toml");
    let (ok, err) = (std::cell::Cell::new(0u32), std::cell::Cell::new(0u32));
    runner(1000)
        .run(&study(), |text| {
            std::fs::write(&p, &text).unwrap();
            let results = common::read_study_every_way(&p);
            for r in results {
                match r {
                    Ok(()) => ok.set(ok.get() + 1),
                    Err(m) => {
                        err.set(err.get() + 1);
                        prop_assert!(names_where(&m), "error names no file/line/key: {m}\n{text}");
                    }
                }
            }
            Ok(())
        })
        .unwrap();
    // The damage is seen (and not everything is refused).
    let (ok, err) = (ok.get(), err.get());
    assert!(err > 0 && ok > 0, "ok {ok}, err {err}");
}

/// A CSV: a header and rows of random cells (numbers, blanks, text, NaN,
/// other delimiters).
fn csv(header: &'static str) -> impl Strategy<Value = String> {
    let cell = prop_oneof![
        4 => (-1e3..1e3f64).prop_map(|v| format!("{v}")),
        1 => prop::sample::select(vec!["", "nan", "inf", "x", "1;2", "\"1,5\"", "1e999", " "])
            .prop_map(str::to_string),
    ];
    let row = prop::collection::vec(cell, 0..6).prop_map(|c| c.join(","));
    (prop::bool::weighted(0.9), prop::collection::vec(row, 0..12)).prop_map(move |(keep, rows)| {
        let mut s = if keep {
            format!("{header}\n")
        } else {
            String::new()
        };
        for r in rows {
            s.push_str(&r);
            s.push('\n');
        }
        s
    })
}

#[test]
fn csv_readers_never_panic_and_name_the_file() {
    let dir = common::scratch("proptest-csv");
    let cols = nlvid_inverse::AfmColumns {
        time: "time".into(),
        piezo: "piezo".into(),
        deflection: "deflection".into(),
    };
    let cal = nlvid_inverse::Calibration {
        deflection_sensitivity: None,
        spring_constant: 0.12,
    };
    let readers: [(&'static str, &'static str); 5] = [
        ("curve.csv", "time,piezo,deflection"),
        (
            "design.csv",
            "index,G0 [Pa],g1 [1],g2 [1],tau1 [s],tau2 [s]",
        ),
        ("loading.csv", "time_s,shear"),
        ("program.csv", "time_s,displacement_m"),
        ("results.csv", "cell,group,G0,g1,tau1,g2,tau2"),
    ];
    for (k, (name, header)) in readers.into_iter().enumerate() {
        let p = dir.join(name);
        runner(300)
            .run(&csv(header), |text| {
                std::fs::write(&p, &text).unwrap();
                let r: Result<(), String> = match k {
                    0 => nlvid_inverse::read_afm_csv(&p, &cols, &cal)
                        .map(|c| {
                            let _ = c.implausible();
                        })
                        .map_err(|e| e.to_string()),
                    1 => nlvid_surrogate::read_table(&p)
                        .map(|_| ())
                        .map_err(|e| e.to_string()),
                    2 => nlvid_material::read_table(&p, "shear").map(|_| ()),
                    3 => {
                        nlvid_protocol::read_table(&p, nlvid_protocol::Quantity::Displacement, None)
                            .map(|_| ())
                            .map_err(|e| e.to_string())
                    }
                    _ => nlvid_stats::read_results(&p)
                        .map(|_| ())
                        .map_err(|e| e.to_string()),
                };
                if let Err(m) = r {
                    prop_assert!(m.contains(name), "{name}: error names no file: {m}\n{text}");
                }
                Ok(())
            })
            .unwrap();
    }
}

#[test]
fn jpk_reader_never_panics_and_gives_a_message() {
    let data = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../afm/tests/data/fmt-jpk-fd_spot3-0192.jpk-force");
    let src = std::fs::read(data).unwrap();
    let n = src.len();
    let damage = (
        prop::collection::vec((0..n, any::<u8>()), 0..8),
        prop::option::weighted(0.3, 0..n),
    );
    runner(400)
        .run(&damage, |(flips, cut)| {
            let mut b = src.clone();
            for (i, v) in flips {
                b[i] = v;
            }
            if let Some(c) = cut {
                b.truncate(c);
            }
            let opts = nlvid_afm::ReadOptions::default();
            if let Err(e) = nlvid_afm::read_jpk_bytes(&b, "damaged.jpk-force", &opts) {
                let m = e.to_string();
                prop_assert!(!m.trim().is_empty());
            }
            Ok(())
        })
        .unwrap();
}
