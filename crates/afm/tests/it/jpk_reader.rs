//! The JPK reader against the values published with the two shared files
//! (tests/data/README.md, computed there by the Python package afmformats), and its
//! typed errors on damaged input.

// Reference values are copied verbatim from the README, digits and all.
#![allow(clippy::excessive_precision)]

use crate::common;

use common::*;
use nlvid_afm::{
    AfmError, CalibrationSource, ReadOptions, SegmentKind, read_force_curve, read_force_curve_with,
    read_force_map, read_jpk_bytes,
};

const TOL: f64 = 1e-12;

#[test]
fn relaxation_file_decodes_to_readme_values() {
    let c = read_force_curve(SR).expect("read");
    assert_eq!(c.format_version, "2.0");
    let kinds: Vec<_> = c.segments.iter().map(|s| s.kind).collect();
    assert_eq!(
        kinds,
        [
            SegmentKind::Hold,
            SegmentKind::Extend,
            SegmentKind::Hold,
            SegmentKind::Retract
        ]
    );
    let lens: Vec<_> = c.segments.iter().map(|s| s.len()).collect();
    assert_eq!(lens, [256, 2048, 7680, 1951]);
    assert_eq!(c.calibration.spring_constant, 1.0677);
    assert_eq!(c.calibration.sensitivity, 110.28e-9);
    assert_eq!(
        c.calibration.spring_constant_source,
        CalibrationSource::File
    );

    let want_mean = [
        -1.1667527118459774e-07,
        1.2185861117864535e-08,
        2.3613889957445826e-08,
        -1.4864363676098427e-07,
    ];
    for (seg, want) in c.segments.iter().zip(want_mean) {
        let got = mean(seg.force().expect("force"));
        assert!(
            rel(got, want) < TOL,
            "segment {}: {got} vs {want}",
            seg.index
        );
    }
    let ext = &c.segments[1];
    assert!(rel(mean(&ext.time), 1.499755859375) < TOL);
    assert!(rel(mean(&c.segments[2].time), 16.998046875) < TOL);
    assert!(rel(c.segments[3].time[20], 32.009765625) < TOL);
    assert!(rel(ext.force().expect("force")[1], -1.1663463779185065e-07) < TOL);
    // deflection = F/k, back in metres: volts × sensitivity
    let d = ext.deflection(&c.calibration).expect("deflection");
    assert!(rel(d[1], -1.1663463779185065e-07 / 1.0677) < TOL);
    // every channel is present and has the segment's length
    for s in &c.segments {
        assert_eq!(s.channels.len(), 7);
        assert!(s.channels.iter().all(|ch| ch.values.len() == s.len()));
    }
}

#[test]
fn approach_retract_file_decodes_to_readme_values() {
    let c = read_force_curve(FD).expect("read");
    assert_eq!(c.format_version, "0.12");
    assert_eq!(c.instrument.as_deref(), Some("A0042-CellHesion"));
    assert_eq!(
        c.position,
        Some((-1.6666666666666667e-5, -1.6666666666666667e-5))
    );
    assert_eq!(c.segments.len(), 2);
    assert_eq!(c.segments[0].kind, SegmentKind::Extend);
    assert_eq!(c.segments[1].kind, SegmentKind::Retract);
    assert_eq!(c.segments[0].len(), 2000);
    assert_eq!(c.segments[1].len(), 2000);
    let s = &c.segments[0];
    assert!(rel(s.force().expect("f")[0], -5.145579192349918e-10) < TOL);
    assert!(rel(s.height_piezo().expect("h")[0], 2.8783223430683289e-05) < TOL);
    assert!(rel(s.height().expect("h")[0], 2.2815672438768612e-05) < TOL);
    let ch = s.channel("strainGaugeHeight").expect("sgh");
    assert_eq!((ch.unit.as_str(), ch.conversion.as_str()), ("m", "nominal"));
    let ch = s.channel("height").expect("h");
    assert_eq!(
        (ch.unit.as_str(), ch.conversion.as_str()),
        ("m", "calibrated")
    );
    assert_eq!(c.calibration.spring_constant, 0.043493666407368466);
    // the retract segment starts where the extend segment ends
    assert!(rel(c.segments[1].time[0], 0.9999999999999998) < TOL);
}

#[test]
fn calibration_override_rescales_force_exactly() {
    let file = read_force_curve(SR).expect("read");
    let opts = ReadOptions {
        spring_constant: Some(2.0),
        sensitivity: Some(100e-9),
    };
    let o = read_force_curve_with(SR, &opts).expect("read");
    assert_eq!(
        o.calibration.spring_constant_source,
        CalibrationSource::Override
    );
    let scale = (2.0 * 100e-9) / (1.0677 * 110.28e-9);
    for (a, b) in file.segments[2]
        .force()
        .expect("f")
        .iter()
        .zip(o.segments[2].force().expect("f"))
    {
        assert!((b - a * scale).abs() <= 1e-12 * a.abs().max(1e-12));
    }
}

#[test]
fn force_map_reads_every_curve() {
    // A two-curve map built from the real 2.0 file in the JPK map layout:
    // shared-data/ at the top, each curve under index/<n>/.
    let bytes = std::fs::read(SR).expect("read");
    let mut map = Vec::new();
    for (name, data) in entries(&bytes) {
        if name.starts_with("segments") {
            map.push((format!("index/0/{name}"), data.clone()));
            map.push((format!("index/1/{name}"), data));
        } else {
            map.push((name, data));
        }
    }
    let map = zip_of(&map, false);
    let curves = read_jpk_bytes(&map, "map", &ReadOptions::default()).expect("map");
    let single = read_force_curve(SR).expect("single");
    assert_eq!(curves.len(), 2);
    for (i, c) in curves.iter().enumerate() {
        assert_eq!(c.source, format!("map#{i}"));
        assert_eq!(c.segments, single.segments);
    }
    let dir = std::env::temp_dir().join(format!("nlvid-afm-map-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("tmp");
    let path = dir.join("two.jpk-force-map");
    std::fs::write(&path, &map).expect("write");
    assert_eq!(
        read_force_map(&path, &ReadOptions::default())
            .expect("map")
            .len(),
        2
    );
    assert!(matches!(
        read_force_curve(&path),
        Err(AfmError::InvalidInput(_))
    ));
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn csv_export_has_unit_suffixed_headers_and_all_rows() {
    let c = read_force_curve(FD).expect("read");
    let mut out = Vec::new();
    c.write_csv(&mut out).expect("csv");
    let text = String::from_utf8(out).expect("utf8");
    let mut lines = text.lines();
    assert_eq!(
        lines.next(),
        Some("segment,kind,time_s,height_m,vDeflection_N,strainGaugeHeight_m")
    );
    let first: Vec<f64> = lines
        .next()
        .expect("row")
        .split(',')
        .skip(2)
        .map(|v| v.parse().expect("number"))
        .collect();
    assert_eq!(first[2], -5.145579192349918e-10);
    assert_eq!(text.lines().count(), 1 + 4000);
}

// ---------- damaged input: typed errors, never a panic ----------

#[test]
fn missing_file_is_an_io_error_naming_the_path() {
    let err = read_force_curve("/nonexistent/x.jpk-force").expect_err("must fail");
    assert!(matches!(err, AfmError::Io { .. }));
    assert!(err.to_string().contains("/nonexistent/x.jpk-force"));
}

#[test]
fn truncated_file_is_reported_not_a_panic() {
    let bytes = std::fs::read(SR).expect("read");
    for cut in [0, 10, bytes.len() / 3, bytes.len() / 2, bytes.len() - 30] {
        let err = read_jpk_bytes(&bytes[..cut], "cut", &ReadOptions::default())
            .expect_err("truncated archive must fail");
        assert!(matches!(err, AfmError::NotZip { .. }), "cut {cut}: {err}");
        assert!(err.to_string().contains("truncated"), "{err}");
    }
}

#[test]
fn truncated_channel_data_names_the_entry() {
    let bytes = std::fs::read(SR).expect("read");
    let cut = with_entry(&bytes, "segments/2/channels/vDeflection.dat", |d| {
        d[..d.len() / 2].to_vec()
    });
    let err = read_jpk_bytes(&cut, "x", &ReadOptions::default()).expect_err("fail");
    match err {
        AfmError::Truncated {
            entry,
            expected,
            found_bytes,
            ..
        } => {
            assert_eq!(entry, "segments/2/channels/vDeflection.dat");
            assert_eq!(expected, 7680);
            assert_eq!(found_bytes, 7680);
        }
        other => panic!("wrong error {other}"),
    }
}

#[test]
fn corrupt_entry_fails_its_checksum() {
    let bytes = std::fs::read(SR).expect("read");
    let e = entries(&bytes);
    let mut stored = zip_of(&e, true);
    let target = &e
        .iter()
        .find(|(n, _)| n == "segments/2/channels/vDeflection.dat")
        .expect("entry")
        .1;
    let window = &target[1000..1064];
    let pos = stored
        .windows(window.len())
        .position(|w| w == window)
        .expect("stored data found");
    stored[pos + 10] ^= 0x5a;
    let err = read_jpk_bytes(&stored, "x", &ReadOptions::default()).expect_err("fail");
    assert!(
        matches!(&err, AfmError::Corrupt { entry, .. } if entry == "segments/2/channels/vDeflection.dat"),
        "{err}"
    );
}

#[test]
fn non_jpk_inputs_are_rejected() {
    let text = b"time,force\n0,1\n";
    assert!(matches!(
        read_jpk_bytes(text, "x.csv", &ReadOptions::default()),
        Err(AfmError::NotZip { .. })
    ));
    let other_zip = zip_of(&[("readme.txt".into(), b"hello".to_vec())], false);
    assert!(matches!(
        read_jpk_bytes(&other_zip, "x.zip", &ReadOptions::default()),
        Err(AfmError::NotJpk { .. })
    ));
    let no_version = zip_of(&[("header.properties".into(), b"a=b\n".to_vec())], false);
    assert!(matches!(
        read_jpk_bytes(&no_version, "x.zip", &ReadOptions::default()),
        Err(AfmError::NotJpk { .. })
    ));
    let no_segments = zip_of(
        &[(
            "header.properties".into(),
            b"jpk-data-file=spm-forcefile\nfile-format-version=2.0\n".to_vec(),
        )],
        false,
    );
    assert!(matches!(
        read_jpk_bytes(&no_segments, "x.zip", &ReadOptions::default()),
        Err(AfmError::NotJpk { .. })
    ));
}

#[test]
fn file_without_calibration_needs_an_override() {
    let bytes = std::fs::read(SR).expect("read");
    let shared = "shared-data/header.properties";
    let no_k = with_text(
        &bytes,
        shared,
        "lcd-info.1.conversion-set.conversion.force.defined=true",
        "lcd-info.1.conversion-set.conversion.force.defined=false",
    );
    let err = read_jpk_bytes(&no_k, "x", &ReadOptions::default()).expect_err("fail");
    assert!(
        matches!(
            err,
            AfmError::NoCalibration {
                quantity: "spring constant",
                ..
            }
        ),
        "{err}"
    );
    assert!(err.to_string().contains("--spring-constant"));
    let no_sens = with_text(
        &bytes,
        shared,
        "lcd-info.1.conversion-set.conversion.distance.defined=true",
        "lcd-info.1.conversion-set.conversion.distance.defined=false",
    );
    let err = read_jpk_bytes(&no_sens, "x", &ReadOptions::default()).expect_err("fail");
    assert!(matches!(
        err,
        AfmError::NoCalibration {
            quantity: "deflection sensitivity",
            ..
        }
    ));
    // with both overrides the file reads, and the force equals k·s·V
    let opts = ReadOptions {
        spring_constant: Some(1.0677),
        sensitivity: Some(110.28e-9),
    };
    let c = read_jpk_bytes(&no_k, "x", &opts).expect("override");
    let f = mean(c[0].segments[1].force().expect("f"));
    assert!(rel(f, 1.2185861117864535e-08) < TOL);
    // nonsense overrides are refused
    let bad = ReadOptions {
        spring_constant: Some(-1.0),
        sensitivity: None,
    };
    assert!(matches!(
        read_jpk_bytes(&bytes, "x", &bad),
        Err(AfmError::InvalidInput(_))
    ));
}

#[test]
fn bad_header_values_name_entry_and_key() {
    let bytes = std::fs::read(FD).expect("read");
    let hdr = "segments/0/segment-header.properties";
    let bad = with_text(
        &bytes,
        hdr,
        "force-segment-header.num-points=2000",
        "force-segment-header.num-points=lots",
    );
    let err = read_jpk_bytes(&bad, "x", &ReadOptions::default()).expect_err("fail");
    assert!(
        matches!(&err, AfmError::BadValue { entry, key, .. } if entry == hdr && key == "force-segment-header.num-points"),
        "{err}"
    );
    let bad = with_text(
        &bytes,
        hdr,
        "channel.vDeflection.data.type=short",
        "channel.vDeflection.data.type=complex",
    );
    assert!(matches!(
        read_jpk_bytes(&bad, "x", &ReadOptions::default()),
        Err(AfmError::Unsupported { .. })
    ));
    let bad = with_text(
        &bytes,
        hdr,
        "channel.vDeflection.data.encoder.scaling.multiplier=3.0921021713588157E-4",
        "",
    );
    assert!(matches!(
        read_jpk_bytes(&bad, "x", &ReadOptions::default()),
        Err(AfmError::MissingKey { .. })
    ));
}

#[test]
fn integer_and_float_storage_decode_like_short() {
    // Re-encode the approach file's vDeflection raw shorts as 32-bit integers and as
    // 32-bit floats; with the same encoder scaling the forces must be identical.
    let bytes = std::fs::read(FD).expect("read");
    let reference = read_force_curve(FD).expect("read");
    let entry = "segments/0/channels/vDeflection.dat";
    let hdr = "segments/0/segment-header.properties";
    let shorts: Vec<i16> = entries(&bytes)
        .into_iter()
        .find(|(n, _)| n == entry)
        .expect("entry")
        .1
        .chunks_exact(2)
        .map(|c| i16::from_be_bytes([c[0], c[1]]))
        .collect();
    let as_i32: Vec<u8> = shorts
        .iter()
        .flat_map(|v| i32::from(*v).to_be_bytes())
        .collect();
    let as_f32: Vec<u8> = shorts
        .iter()
        .flat_map(|v| f32::from(*v).to_be_bytes())
        .collect();
    for (ty, data) in [("integer", as_i32), ("float-data", as_f32)] {
        let b = with_entry(&bytes, entry, |_| data.clone());
        let b = with_text(
            &b,
            hdr,
            "channel.vDeflection.data.type=short",
            &format!("channel.vDeflection.data.type={ty}"),
        );
        let c = read_jpk_bytes(&b, "x", &ReadOptions::default()).expect(ty);
        assert_eq!(
            c[0].segments[0].force().expect("f"),
            reference.segments[0].force().expect("f"),
            "{ty}"
        );
    }
}

#[test]
fn constant_force_pause_is_a_creep_segment() {
    let bytes = std::fs::read(SR).expect("read");
    let hdr = "segments/2/segment-header.properties";
    let b = with_text(
        &bytes,
        hdr,
        "segment-settings.type=constant-height-pause",
        "segment-settings.type=constant-force-pause",
    );
    let b = with_text(
        &b,
        hdr,
        "pause-option.type=constant-height",
        "pause-option.type=constant-force",
    );
    let c = read_jpk_bytes(&b, "x", &ReadOptions::default()).expect("read");
    assert_eq!(c[0].segments[2].kind, SegmentKind::Creep);
    assert_eq!(c[0].segments[0].kind, SegmentKind::Hold);
}

#[test]
fn regression_fuzz_utf16_bom_header_does_not_panic() {
    // Crash found by the replace_entry fuzz target: a header starting with a UTF-16LE
    // byte-order mark and an odd byte count made java-properties' decoder panic.
    let bytes = std::fs::read(FD).expect("read");
    let mut evil = vec![0xff, 0xfe];
    evil.extend(std::iter::repeat_n(0xff, 15));
    evil.extend([0x6c, 0x00]);
    for entry in ["header.properties", "segments/1/segment-header.properties"] {
        let b = with_entry(&bytes, entry, |_| evil.clone());
        let r = read_jpk_bytes(&b, "x", &ReadOptions::default());
        assert!(r.is_err(), "{entry}: {r:?}");
    }
    // Latin-1 text still decodes byte for byte: 'µ' (0xB5) in a value survives.
    let b = with_entry(&bytes, "segments/1/segment-header.properties", |d| {
        let mut d = d.to_vec();
        d.extend(b"\nforce-segment-header.name.name=retract\xb5\n");
        d
    });
    let c = read_jpk_bytes(&b, "x", &ReadOptions::default()).expect("latin-1");
    assert_eq!(c[0].segments[1].name, "retract\u{b5}");
}
