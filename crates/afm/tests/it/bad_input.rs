//! Damaged and mixed input in a batch: every bad curve or file is reported with its
//! file, curve index and reason, and every other curve is still processed.

use crate::common;

use std::path::{Path, PathBuf};

use common::*;
use nlvid_afm::{
    AfmError, HertzSettings, ReadOptions, for_each_curve, hertz_baseline, read_jpk_each,
};

/// A fresh temporary folder for one test.
fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("nlvid-afm-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("tmp dir");
    dir
}

fn put(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).expect("write");
    p
}

/// Number of samples in each curve, as a cheap analysis.
fn count(c: &nlvid_afm::ForceCurve) -> nlvid_afm::Result<usize> {
    Ok(c.len())
}

#[test]
fn truncated_and_corrupt_files_in_a_folder_are_reported_and_the_rest_read() {
    let dir = tmp("damaged");
    let good = std::fs::read(FD).expect("read");
    let sr = std::fs::read(SR).expect("read");
    put(&dir, "a-good.jpk-force", &good);
    put(&dir, "b-truncated.jpk-force", &sr[..sr.len() / 2]);
    // Corrupt a stored channel so that its CRC fails.
    let e = entries(&sr);
    let mut stored = zip_of(&e, true);
    let target = &e
        .iter()
        .find(|(n, _)| n == "segments/2/channels/vDeflection.dat")
        .expect("entry")
        .1;
    let pos = stored
        .windows(64)
        .position(|w| w == &target[1000..1064])
        .expect("stored data");
    stored[pos + 10] ^= 0x5a;
    put(&dir, "c-corrupt.jpk-force", &stored);
    put(&dir, "d-good.jpk-force", &sr);

    let batch = for_each_curve(&[&dir], &ReadOptions::default(), count).expect("batch");
    let read: Vec<_> = batch
        .rows
        .iter()
        .map(|r| {
            r.file
                .file_name()
                .expect("name")
                .to_string_lossy()
                .into_owned()
        })
        .collect();
    assert_eq!(read, ["a-good.jpk-force", "d-good.jpk-force"]);
    assert_eq!(batch.rows[0].value, 4000);
    assert_eq!(batch.failures.len(), 2);
    let trunc = &batch.failures[0];
    assert!(trunc.file.ends_with("b-truncated.jpk-force"));
    assert!(matches!(trunc.error, AfmError::NotZip { .. }), "{trunc}");
    assert!(trunc.to_string().contains("b-truncated.jpk-force"));
    assert!(trunc.to_string().contains("truncated"), "{trunc}");
    let corrupt = &batch.failures[1];
    assert!(corrupt.file.ends_with("c-corrupt.jpk-force"));
    assert!(
        matches!(&corrupt.error, AfmError::Corrupt { entry, .. } if entry == "segments/2/channels/vDeflection.dat"),
        "{corrupt}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_map_with_one_corrupt_curve_keeps_the_other_three() {
    let bytes = std::fs::read(data(MAP)).expect("read");
    let bad_entry = "index/2/segments/1/channels/vDeflection.dat";
    let bad = with_entry(&bytes, bad_entry, |d| d[..d.len() / 3].to_vec());
    let each = read_jpk_each(&bad, "map", &ReadOptions::default()).expect("file-level ok");
    assert_eq!(each.len(), 4);
    for (i, (index, curve)) in each.iter().enumerate() {
        assert_eq!(*index, Some(i));
        if i == 2 {
            let err = curve.as_ref().expect_err("curve 2 is damaged");
            assert!(
                matches!(err, AfmError::Truncated { entry, .. } if entry == bad_entry),
                "{err}"
            );
        } else {
            assert!(curve.is_ok(), "curve {i}: {curve:?}");
        }
    }
    // The strict reader refuses the file with the same reason.
    assert!(nlvid_afm::read_jpk_bytes(&bad, "map", &ReadOptions::default()).is_err());
    // In a batch: three rows and one failure naming file and curve.
    let dir = tmp("map");
    let path = put(&dir, "map.jpk-force-map", &bad);
    let batch = for_each_curve(&[path], &ReadOptions::default(), count).expect("batch");
    let curves: Vec<_> = batch.rows.iter().map(|r| r.curve).collect();
    assert_eq!(curves, [Some(0), Some(1), Some(3)]);
    assert_eq!(batch.failures.len(), 1);
    let f = &batch.failures[0];
    assert_eq!(f.curve, Some(2));
    let msg = f.to_string();
    assert!(msg.contains("map.jpk-force-map curve 2"), "{msg}");
    assert!(msg.contains(bad_entry), "{msg}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_shared_header_fault_names_the_shared_key_and_the_referring_segment() {
    let bytes = std::fs::read(data(MAP)).expect("read");
    let bad = with_text(
        &bytes,
        "shared-data/header.properties",
        "lcd-info.1.encoder.scaling.multiplier=5.547880093333494E-9",
        "lcd-info.1.encoder.scaling.multiplier=five",
    );
    let each = read_jpk_each(&bad, "map", &ReadOptions::default()).expect("file-level ok");
    for (i, (_, curve)) in each.iter().enumerate() {
        let err = curve.as_ref().expect_err("every curve uses lcd-info.1");
        match err {
            AfmError::BadValue { entry, key, .. } => {
                assert_eq!(key, "lcd-info.1.encoder.scaling.multiplier");
                assert!(
                    entry.starts_with("shared-data/header.properties"),
                    "{entry}"
                );
                assert!(
                    entry.contains("channel.vDeflection.lcd-info.*=1"),
                    "{entry}"
                );
                assert!(entry.contains(&format!("index/{i}/segments/0/")), "{entry}");
            }
            other => panic!("curve {i}: {other}"),
        }
    }
}

#[test]
fn a_folder_mixing_afm_and_other_files_reads_the_afm_files_and_lists_the_rest() {
    let dir = tmp("mixed");
    put(&dir, "curve.jpk-force", &std::fs::read(FD).expect("read"));
    std::fs::create_dir_all(dir.join("sub")).expect("sub");
    put(
        &dir.join("sub"),
        "grid.JPK-FORCE-MAP",
        &std::fs::read(data(MAP)).expect("read"),
    );
    put(&dir, "notes.txt", b"measured on tuesday");
    put(&dir, "export.csv", b"time,force\n0,1\n");
    put(&dir, ".hidden.jpk-force", b"editor swap file");
    put(&dir, "fake.jpk-force", b"time,force\n0,1\n");
    let batch = for_each_curve(&[&dir], &ReadOptions::default(), count).expect("batch");
    let files: Vec<_> = batch
        .rows
        .iter()
        .map(|r| {
            (
                r.file.strip_prefix(&dir).expect("in dir").to_owned(),
                r.curve,
            )
        })
        .collect();
    assert_eq!(
        files,
        [
            (PathBuf::from("curve.jpk-force"), None),
            (PathBuf::from("sub/grid.JPK-FORCE-MAP"), Some(0)),
            (PathBuf::from("sub/grid.JPK-FORCE-MAP"), Some(1)),
            (PathBuf::from("sub/grid.JPK-FORCE-MAP"), Some(2)),
            (PathBuf::from("sub/grid.JPK-FORCE-MAP"), Some(3)),
        ]
    );
    let ignored: Vec<_> = batch
        .ignored
        .iter()
        .map(|p| p.strip_prefix(&dir).expect("in dir").to_owned())
        .collect();
    assert_eq!(
        ignored,
        [PathBuf::from("export.csv"), PathBuf::from("notes.txt")]
    );
    assert_eq!(batch.failures.len(), 1);
    assert!(batch.failures[0].file.ends_with("fake.jpk-force"));
    assert!(matches!(batch.failures[0].error, AfmError::NotZip { .. }));
    // A missing input is a failure too, not an abort.
    let gone = dir.join("gone.jpk-force");
    let b = for_each_curve(
        &[gone.clone(), dir.join("curve.jpk-force")],
        &ReadOptions::default(),
        count,
    )
    .expect("batch");
    assert_eq!(b.rows.len(), 1);
    assert!(matches!(&b.failures[0].error, AfmError::Io { path, .. } if *path == gone));
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_curve_with_no_contact_is_reported_and_the_others_fitted() {
    // Replace the approach deflection of the force–distance file by a constant raw value:
    // the force never leaves its baseline.
    let bytes = std::fs::read(FD).expect("read");
    let flat = with_entry(&bytes, "segments/0/channels/vDeflection.dat", |d| {
        let mut d = d.to_vec();
        for c in d.chunks_exact_mut(2) {
            c.copy_from_slice(&100i16.to_be_bytes());
        }
        d
    });
    let dir = tmp("nocontact");
    put(&dir, "a.jpk-force", &bytes);
    put(&dir, "b-flat.jpk-force", &flat);
    put(&dir, "c.jpk-force", &bytes);
    let settings = HertzSettings::new(40e-9, 0.5);
    let batch = for_each_curve(&[&dir], &ReadOptions::default(), |c| {
        hertz_baseline(c, &settings)
    })
    .expect("batch");
    assert_eq!(batch.rows.len(), 2);
    for r in &batch.rows {
        assert!((r.value.youngs_modulus / 233.1e3 - 1.0).abs() < 0.01);
    }
    assert_eq!(batch.failures.len(), 1);
    let f = &batch.failures[0];
    assert!(f.file.ends_with("b-flat.jpk-force"));
    assert!(matches!(f.error, AfmError::NoContact(_)), "{f}");
    assert!(
        f.to_string()
            .contains("b-flat.jpk-force: no contact point found"),
        "{f}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn nonsense_overrides_stop_the_batch_before_it_starts() {
    let bad = ReadOptions {
        spring_constant: Some(f64::NAN),
        sensitivity: None,
    };
    assert!(matches!(
        for_each_curve(&[PathBuf::from(FD)], &bad, count),
        Err(AfmError::InvalidInput(_))
    ));
}
