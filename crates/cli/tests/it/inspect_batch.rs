//! `nlvid inspect` on a folder / several files / a glob: one CSV row per curve on
//! stdout (or `--table`), JSON with `--json`, failures on stderr with file and reason,
//! exit status 3 when any curve failed, and the single-curve flags refused in a batch.

use crate::common;

use common::*;

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../afm/tests/data");

#[test]
fn a_folder_gives_one_row_per_curve_and_failures_are_listed() {
    let dir = scratch("inspect-batch");
    for (from, to) in [
        ("fmt-jpk-fd_spot3-0192.jpk-force", "a.jpk-force"),
        (
            "fmt-jpk-fd_map2x2_extracted.jpk-force-map",
            "b.jpk-force-map",
        ),
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
    assert_eq!(
        lines
            .iter()
            .filter(|l| l.contains(",ok,,hertz-paraboloid,"))
            .count(),
        5
    );
    assert!(stderr.contains("c.jpk-force"), "{stderr}");
    assert!(
        stderr.contains("1 curve(s) or file(s) failed (5 analysed)"),
        "{stderr}"
    );

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

/// The public curves of crates/afm/tests/data a Hertz fit takes (27 curves in 22 files:
/// the 15 fig. 5d relaxation curves, `fd_spot3`, the 2×2 map, the QI map and series, the
/// extracted curve, the creep file), hard-linked in turn into `dir` until exactly
/// `curves` curves. Returns the number of files.
fn bench_folder(dir: &std::path::Path, curves: usize) -> usize {
    use std::io::Read;
    let src = dir.join("src");
    std::fs::create_dir_all(&src).expect("src");
    let bytes = std::fs::read(format!("{DATA}/10.1002_btm2.10294_fig5d-cell1.zip")).expect("zip");
    let mut zip = zip::ZipArchive::new(std::io::Cursor::new(bytes)).expect("zip");
    let mut sources: Vec<(std::path::PathBuf, usize)> = Vec::new();
    for i in 0..zip.len() {
        let mut f = zip.by_index(i).expect("entry");
        let name = f.name().rsplit('/').next().unwrap_or("").to_string();
        if !name.ends_with(".jpk-force") {
            continue;
        }
        let mut b = Vec::new();
        f.read_to_end(&mut b).expect("inflate");
        let p = src.join(&name);
        std::fs::write(&p, b).expect("write");
        sources.push((p, 1));
    }
    sources.sort();
    assert_eq!(sources.len(), 15);
    for (name, n) in [
        ("fmt-jpk-fd_spot3-0192.jpk-force", 1),
        ("fmt-jpk-fd_map2x2_extracted.jpk-force-map", 4),
        ("fmt-jpk-fd_2020.02.07-16.29.05.036.jpk-qi-data", 4),
        ("fmt-jpk-fd_qi-data-2021.04.13.jpk-qi-series", 1),
        ("fmt-jpk-fd_flipsign_2015.05.22-15.31.49.352.jpk-force", 1),
        ("fmt-jpk-cc_pr14-brain-2021.06.30.jpk-force", 1),
    ] {
        sources.push((format!("{DATA}/{name}").into(), n));
    }
    let out = dir.join("curves");
    std::fs::create_dir_all(&out).expect("curves");
    let (mut total, mut files) = (0, 0);
    for (path, n) in sources.iter().cycle() {
        if total == curves {
            break;
        }
        if total + n > curves {
            continue;
        }
        let name = path.file_name().expect("name").to_string_lossy();
        let link = out.join(format!("{files:04}-{name}"));
        if std::fs::hard_link(path, &link).is_err() {
            std::fs::copy(path, &link).expect("copy");
        }
        total += n;
        files += 1;
    }
    files
}

/// Issue 14's benchmark: 1000 public curves through `nlvid inspect --fit hertz FOLDER`
/// in ≤ 10 s wall on 2 cores. Release build only (crates/afm/benches/README.md):
/// `cargo test --release -p nlvid --test it inspect_batch:: -- --ignored --nocapture`.
/// The folder stays at `<temp>/nlvid-inspect-bench-1000/curves` for timing the whole process
/// from outside (e.g. `hyperfine`).
#[test]
#[ignore = "benchmark: run with --release (crates/afm/benches/README.md)"]
fn thousand_public_curves_through_inspect_fit_hertz_in_10_s() {
    let dir = std::env::temp_dir().join("nlvid-inspect-bench-1000");
    let _ = std::fs::remove_dir_all(&dir);
    let files = bench_folder(&dir, 1000);
    let folder = dir.join("curves").to_string_lossy().into_owned();
    let t0 = std::time::Instant::now();
    let out = nlvid(&[
        "--json",
        "inspect",
        &folder,
        "--fit",
        "hertz",
        "--tip-radius",
        "5 um",
    ]);
    let wall = t0.elapsed().as_secs_f64();
    assert!(out.status.success(), "{}", text(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("json");
    assert_eq!(v["curves"], 1000);
    assert_eq!(v["failed"], 0);
    eprintln!("{files} files, 1000 curves: {wall:.2} s wall; folder {folder}");
    assert!(wall <= 10.0, "{wall} s");
}
