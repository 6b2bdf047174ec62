//! Every JPK layout of the afmformats test data, against the values afmformats 0.18.7
//! reads from the same files (tests/data/README.md): force maps and QI maps whose segment
//! headers refer to the shared header, QI series with computed channels, curves extracted
//! from maps, creep files.

#![allow(clippy::excessive_precision)]

use crate::common;

use common::*;
use nlvid_afm::{ReadOptions, SegmentKind, read_force_map};

/// (file, curve index in the file, points per segment, force first/last (N),
/// measured height first/last (m), piezo height first (m), spring constant (N/m),
/// sensitivity (m/V)) as read by afmformats 0.18.7.
type Row = (
    &'static str,
    usize,
    &'static [usize],
    [f64; 2],
    [f64; 2],
    f64,
    f64,
    f64,
);

const ROWS: [Row; 11] = [
    (
        MAP,
        0,
        &[12030, 12030],
        [-4.742686262385487e-10, -5.138063562153474e-10],
        [7.055429689714916e-05, 7.051593757368061e-05],
        5.233973755300183e-05,
        0.015481694150356324,
        6.425794778156255e-08,
    ),
    (
        MAP,
        1,
        &[12030, 12030],
        [-5.07458734675603e-10, -5.225753017425483e-10],
        [7.736341781281607e-05, 7.731908498070372e-05],
        6.152546957099701e-05,
        0.015481694150356324,
        6.425794778156255e-08,
    ),
    (
        MAP,
        2,
        &[1627, 1599],
        [-5.854019294383471e-10, -6.301256262765287e-10],
        [0.0001001727719556085, 0.00010010565963460028],
        7.664345368215505e-05,
        0.015481694150356324,
        6.425794778156255e-08,
    ),
    (
        MAP,
        3,
        &[4141, 4069],
        [-5.831611810851241e-10, -6.154750633388361e-10],
        [0.0001002338395827877, 0.0001000589011481662],
        7.664345368215505e-05,
        0.015481694150356324,
        6.425794778156255e-08,
    ),
    (
        QI_DATA,
        0,
        &[300, 300],
        [-1.269014596090597e-10, -2.673061005740294e-10],
        [4.716154783699957e-06, 4.570760918977685e-06],
        3.1832270436208754e-06,
        0.03011408349962541,
        2.4459525780419943e-08,
    ),
    (
        QI_DATA,
        1,
        &[300, 300],
        [-1.3549741265691707e-10, -2.388920486518109e-10],
        [4.630416426331652e-06, 4.569497258172695e-06],
        3.184165076931837e-06,
        0.03011408349962541,
        2.4459525780419943e-08,
    ),
    (
        QI_DATA,
        2,
        &[297, 300],
        [-1.5048410831393407e-10, -2.489255608992364e-10],
        [4.628650100582292e-06, 4.583154359406839e-06],
        3.1851560493660514e-06,
        0.03011408349962541,
        2.4459525780419943e-08,
    ),
    (
        QI_DATA,
        3,
        &[300, 300],
        [-1.3373089229806925e-10, -2.3876853747363847e-10],
        [4.634751475489601e-06, 4.5747575061671455e-06],
        3.1900397211765953e-06,
        0.03011408349962541,
        2.4459525780419943e-08,
    ),
    (
        QI_SERIES,
        0,
        &[1000, 1000],
        [-1.713718698269193e-07, -1.714403586284827e-07],
        [2.8279049697474517e-06, 2.807478484172928e-06],
        2.8124244189314608e-06,
        35.028,
        9.760000000000001e-09,
    ),
    (
        EXTRACTED,
        0,
        &[10000, 4000],
        [-3.428532276099945e-10, -4.2241960208120896e-10],
        [6.835545004802403e-05, 6.82187777304443e-05],
        4.225735934736611e-05,
        0.01868898956509838,
        6.467548816068359e-08,
    ),
    (
        CREEP,
        0,
        &[3000, 3000, 3000],
        [1.1230465359122524e-08, 1.1192792018708865e-08],
        [4.740334616268e-05, 4.577092779676e-05],
        3.6163845005483336e-05,
        0.061,
        6.086e-08,
    ),
];

const TOL: f64 = 1e-12;

#[test]
fn every_curve_of_every_layout_matches_afmformats() {
    for (file, i, lens, force, height, piezo, k, sens) in ROWS {
        let curves = read_force_map(data(file), &ReadOptions::default())
            .unwrap_or_else(|e| panic!("{file}: {e}"));
        let c = &curves[i];
        let got: Vec<usize> = c.segments.iter().map(|s| s.len()).collect();
        assert_eq!(got, lens, "{file}#{i}");
        let first = &c.segments[0];
        let last = c.segments.last().expect("segments");
        let f0 = first.force().expect("force")[0];
        let f1 = *last.force().expect("force").last().expect("sample");
        let h0 = first.height().expect("height")[0];
        let h1 = *last.height().expect("height").last().expect("sample");
        let p0 = first.height_piezo().expect("piezo")[0];
        for (name, got, want) in [
            ("force[0]", f0, force[0]),
            ("force[-1]", f1, force[1]),
            ("height[0]", h0, height[0]),
            ("height[-1]", h1, height[1]),
            ("piezo[0]", p0, piezo),
            ("k", c.calibration.spring_constant, k),
            ("sensitivity", c.calibration.sensitivity, sens),
        ] {
            assert!(rel(got, want) < TOL, "{file}#{i} {name}: {got} vs {want}");
        }
    }
}

#[test]
fn maps_read_all_curves_named_by_their_index() {
    for (file, n) in [(MAP, 4), (QI_DATA, 4)] {
        let curves = read_force_map(data(file), &ReadOptions::default()).expect("map");
        assert_eq!(curves.len(), n, "{file}");
        for (i, c) in curves.iter().enumerate() {
            assert!(c.source.ends_with(&format!("{file}#{i}")), "{}", c.source);
            let kinds: Vec<_> = c.segments.iter().map(|s| s.kind).collect();
            assert_eq!(kinds, [SegmentKind::Extend, SegmentKind::Retract]);
        }
    }
}

#[test]
fn qi_raster_channels_are_computed_from_start_and_step() {
    let c = &read_force_map(data(QI_SERIES), &ReadOptions::default()).expect("qi")[0];
    let seg = &c.segments[0];
    let t = seg.channel("time").expect("time channel");
    assert_eq!(t.unit, "s");
    // segment header: channel.time.data.start=1.0E-4, step=2.0E-4, 1000 points
    assert_eq!(t.values.len(), 1000);
    assert_eq!(t.values[0], 1.0e-4);
    assert!((t.values[999] - (1.0e-4 + 999.0 * 2.0e-4)).abs() < 1e-15);
}

#[test]
fn creep_file_has_a_constant_force_pause() {
    let c = &read_force_map(data(CREEP), &ReadOptions::default()).expect("creep")[0];
    let kinds: Vec<_> = c.segments.iter().map(|s| s.kind).collect();
    assert_eq!(
        kinds,
        [
            SegmentKind::Extend,
            SegmentKind::Creep,
            SegmentKind::Retract
        ]
    );
    // afmformats: "duration intermediate" = 3 s
    assert_eq!(c.segments[1].duration, 3.0);
}

#[test]
fn the_fifteen_published_relaxation_curves_read() {
    let curves = fig5d();
    assert_eq!(curves.len(), 15);
    for (name, bytes) in curves {
        let c = nlvid_afm::read_jpk_bytes(&bytes, &name, &ReadOptions::default())
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        let kinds: Vec<_> = c[0].segments.iter().map(|s| s.kind).collect();
        assert_eq!(
            kinds,
            [
                SegmentKind::Hold,
                SegmentKind::Extend,
                SegmentKind::Hold,
                SegmentKind::Retract
            ],
            "{name}"
        );
    }
}

#[test]
fn a_missing_shared_section_names_the_reference() {
    // Point curve 1's extend header at a shared settings section that does not exist.
    let bytes = std::fs::read(data(MAP)).expect("read");
    let entry = "index/1/segments/0/segment-header.properties";
    let bad = with_text(
        &bytes,
        entry,
        "force-segment-header.force-segment-header-info.*=0",
        "force-segment-header.force-segment-header-info.*=7",
    );
    let err = nlvid_afm::read_jpk_bytes(&bad, "m", &ReadOptions::default()).expect_err("fail");
    let msg = err.to_string();
    assert!(msg.contains("shared-data/header.properties"), "{msg}");
    assert!(msg.contains("force-segment-header-info.7."), "{msg}");
    assert!(msg.contains(entry), "{msg}");
}
