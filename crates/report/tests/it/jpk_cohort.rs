//! `nlvid cohort` on a folder of instrument files, no CSV conversion and no
//! `[fit.calibration]` (issue 14): one row per curve (each curve of a force map a
//! row), and the bad inputs — a truncated file, a map with one corrupt curve, a
//! non-AFM file in the folder, a curve with no contact — each reported with the file
//! (and curve) named while every other curve is processed.

use std::io::{Cursor, Read, Write};
use std::path::{Path, PathBuf};

use nlvid_report::cell::CellStatus;
use nlvid_report::cohort::{self, RunOptions};
use nlvid_report::settings::CohortSettings;

fn afm_data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../afm/tests/data")
        .join(name)
}

/// `bytes` (a ZIP) with entry `name` replaced by `f(old)`.
fn with_entry(bytes: &[u8], name: &str, f: impl Fn(&[u8]) -> Vec<u8>) -> Vec<u8> {
    let mut zip = zip::ZipArchive::new(Cursor::new(bytes)).expect("zip");
    let mut w = zip::ZipWriter::new(Cursor::new(Vec::new()));
    let opts = zip::write::SimpleFileOptions::default();
    let mut found = false;
    for i in 0..zip.len() {
        let mut e = zip.by_index(i).expect("entry");
        let mut buf = Vec::new();
        e.read_to_end(&mut buf).expect("bytes");
        let n = e.name().to_string();
        if n.ends_with('/') {
            w.add_directory(n.trim_end_matches('/'), opts).expect("dir");
            continue;
        }
        if n == name {
            buf = f(&buf);
            found = true;
        }
        w.start_file(n.as_str(), opts).expect("start");
        w.write_all(&buf).expect("write");
    }
    assert!(found, "{name} not in the archive");
    w.finish().expect("finish").into_inner()
}

#[test]
fn a_folder_of_jpk_files_gives_one_row_per_curve_and_names_every_bad_one() {
    let dir = std::env::temp_dir().join(format!("nlvid-jpk-cohort-{}", std::process::id()));
    let cells_dir = dir.join("cells");
    std::fs::create_dir_all(&cells_dir).expect("dir");
    let sr = std::fs::read(afm_data("fmt-jpk-sr_cell1-0008.jpk-force")).expect("sr");
    let put = |name: &str, bytes: &[u8]| std::fs::write(cells_dir.join(name), bytes).expect("put");
    put("a.jpk-force", &sr);
    put("b-truncated.jpk-force", &sr[..sr.len() / 2]);
    // every deflection sample of the pause, extend and hold the same raw value
    let mut flat = sr.clone();
    for seg in 0..3 {
        flat = with_entry(
            &flat,
            &format!("segments/{seg}/channels/vDeflection.dat"),
            |d| {
                let mut d = d.to_vec();
                for c in d.chunks_exact_mut(2) {
                    c.copy_from_slice(&100i16.to_be_bytes());
                }
                d
            },
        );
    }
    put("c-flat.jpk-force", &flat);
    let map = std::fs::read(afm_data("fmt-jpk-fd_map2x2_extracted.jpk-force-map")).expect("map");
    let bad_entry = "index/2/segments/1/channels/vDeflection.dat";
    put(
        "d.jpk-force-map",
        &with_entry(&map, bad_entry, |d| d[..d.len() / 3].to_vec()),
    );
    put("notes.txt", b"not a curve\n");
    put("e.jpk-force", &sr);
    let study = dir.join("study.toml");
    std::fs::write(
        &study,
        "title = \"JPK folder\"\n[probe]\nradius = \"5 um\"\npoisson = 0.5\n\
         [fit]\nmodel = \"lee-radok\"\nramp = \"1 s\"\nhold_end = \"30 s\"\nstarts = 2\nseed = 1\n",
    )
    .expect("study");

    let settings = CohortSettings::load(&study).expect("no [fit.calibration] needed");
    let cells = cohort::discover(&cells_dir).expect("discover");
    let files: Vec<&str> = cells.iter().map(|c| c.file.as_str()).collect();
    assert_eq!(
        files,
        [
            "a.jpk-force",
            "b-truncated.jpk-force",
            "c-flat.jpk-force",
            "d.jpk-force-map#0",
            "d.jpk-force-map#1",
            "d.jpk-force-map#2",
            "d.jpk-force-map#3",
            "e.jpk-force"
        ],
        "notes.txt skipped, one cell per map curve"
    );
    let out = dir.join("out");
    let run = cohort::run_cohort(
        &settings,
        &study,
        &cells_dir,
        &cells,
        &out,
        &RunOptions::default(),
    )
    .expect("the cohort runs to the end");
    let rows = cohort::read_cells(&out).expect("rows");
    assert_eq!(rows.len(), 8, "one row per curve");
    let row = |f: &str| rows.iter().find(|r| r.file == f).expect(f);
    for good in ["a.jpk-force", "e.jpk-force"] {
        let r = row(good);
        assert_ne!(r.status, CellStatus::Failed, "{good}: {}", r.reason);
        assert!(r.parameter("G0").is_some_and(|g| g > 0.0));
    }
    // identical files give identical results
    assert_eq!(
        row("a.jpk-force").parameter("G0"),
        row("e.jpk-force").parameter("G0")
    );
    let reason = |f: &str| {
        let r = row(f);
        assert_eq!(r.status, CellStatus::Failed, "{f}");
        eprintln!("{f}: {}", r.reason);
        r.reason.clone()
    };
    assert!(reason("b-truncated.jpk-force").contains("b-truncated.jpk-force"));
    let flat = reason("c-flat.jpk-force");
    assert!(
        flat.contains("c-flat.jpk-force") && flat.contains("no contact point"),
        "{flat}"
    );
    let corrupt = reason("d.jpk-force-map#2");
    assert!(
        corrupt.contains("d.jpk-force-map curve 2") && corrupt.contains(bad_entry),
        "{corrupt}"
    );
    // the map's intact curves are approach/retract only: read, then refused by name
    for i in [0, 1, 3] {
        let r = reason(&format!("d.jpk-force-map#{i}"));
        assert!(
            r.contains(&format!("d.jpk-force-map curve {i}")) && r.contains("hold"),
            "{r}"
        );
    }
    let text = run.text();
    assert!(
        text.contains("8 cells") && text.contains("6 failed"),
        "{text}"
    );
    assert!(
        text.contains("c-flat.jpk-force") && text.contains("d.jpk-force-map#2"),
        "{text}"
    );
    std::fs::remove_dir_all(&dir).ok();
}
