//! The Asylum Research `.ibw` reader against the values afmformats 0.18.7 (via igor2)
//! reads from the two public example files (tests/data/README.md), and its errors on
//! damaged input.

#![allow(clippy::excessive_precision)]

use crate::common;

use common::*;
use nlvid_afm::{AfmError, ReadOptions, SegmentKind, for_each_curve, read_ibw_bytes};

const U3: &str = "fmt-igor-fd_U3_3_p10004.ibw";
const SIN: &str = "fmt-igor-fd_SiN_FD_plot.ibw";

/// (file, extend/retract lengths, k, InvOLS, force first / at the turn / last / max,
/// measured height first / min, piezo height first), afmformats 0.18.7.
type Row = (&'static str, [usize; 2], f64, f64, [f64; 4], [f64; 2], f64);
const ROWS: [Row; 2] = [
    (
        U3,
        [5058, 5039],
        0.31451,
        2.0364e-07,
        [
            -2.8047433264788424e-09,
            1.7729617241002416e-07,
            -2.806346488526401e-09,
            1.7784070394100127e-07,
        ],
        [6.4155087784456555e-06, -1.0322237358195707e-06],
        6.41493124931003e-06,
    ),
    (
        SIN,
        [1009, 1007],
        1.1841,
        4.499e-08,
        [
            -3.8749501385382246e-09,
            6.143514141854212e-09,
            -3.870568310304634e-09,
            6.166312793709494e-09,
        ],
        [-1.1956911976085394e-06, -1.409596620760567e-06],
        -1.1957095011894125e-06,
    ),
];

fn max(v: impl Iterator<Item = f64>) -> f64 {
    v.fold(f64::NEG_INFINITY, f64::max)
}

#[test]
fn ibw_force_curves_match_afmformats() {
    for (file, lens, k, sens, force, height, piezo) in ROWS {
        let bytes = std::fs::read(data(file)).expect("read");
        let c = read_ibw_bytes(&bytes, file, &ReadOptions::default()).expect(file);
        let kinds: Vec<_> = c.segments.iter().map(|s| s.kind).collect();
        assert_eq!(kinds, [SegmentKind::Extend, SegmentKind::Retract], "{file}");
        let got: Vec<_> = c.segments.iter().map(|s| s.len()).collect();
        assert_eq!(got, lens, "{file}");
        assert_eq!(c.calibration.spring_constant, k);
        assert_eq!(c.calibration.sensitivity, sens);
        let (ext, ret) = (&c.segments[0], &c.segments[1]);
        let f_ext = ext.force().expect("force");
        let f_ret = ret.force().expect("force");
        let fmax = max(f_ext.iter().chain(f_ret).copied());
        let hmin = -max(ext
            .height()
            .expect("h")
            .iter()
            .chain(ret.height().expect("h"))
            .map(|h| -h));
        for (name, got, want) in [
            ("force[0]", f_ext[0], force[0]),
            ("force at the turn", f_ext[f_ext.len() - 1], force[1]),
            ("force[-1]", f_ret[f_ret.len() - 1], force[2]),
            ("max force", fmax, force[3]),
            ("height[0]", ext.height().expect("h")[0], height[0]),
            ("min height", hmin, height[1]),
            ("piezo[0]", ext.height_piezo().expect("p")[0], piezo),
        ] {
            // The file stores f32. afmformats (numpy 2) multiplies Defl by k in f32,
            // nlvid in f64: forces agree to f32 rounding (2⁻²³), heights exactly.
            let tol = if name.contains("height") || name.contains("piezo") {
                0.0
            } else {
                f64::from(f32::EPSILON)
            };
            assert!(rel(got, want) <= tol, "{file} {name}: {got} vs {want}");
        }
        // Time from the wave scaling: 0.5 ms per sample, continuous across segments.
        assert_eq!(ext.time[1], 5e-4);
        assert!((ret.time[0] - lens[0] as f64 * 5e-4).abs() < 1e-15);
    }
}

#[test]
fn ibw_calibration_override_rescales_the_force() {
    let bytes = std::fs::read(data(U3)).expect("read");
    let base = read_ibw_bytes(&bytes, U3, &ReadOptions::default()).expect("read");
    let opts = ReadOptions {
        spring_constant: Some(0.5),
        sensitivity: Some(2.0 * 2.0364e-07),
    };
    let c = read_ibw_bytes(&bytes, U3, &opts).expect("override");
    let f0 = base.segments[0].force().expect("f")[100];
    let f1 = c.segments[0].force().expect("f")[100];
    assert!(rel(f1, f0 / 0.31451 * 0.5 * 2.0) < 1e-14);
}

#[test]
fn damaged_ibw_files_are_reported_not_panics() {
    let bytes = std::fs::read(data(SIN)).expect("read");
    // Truncations everywhere: header, data, note, labels.
    // Header 64 B, wave header + data to 24 576, note to 41 099, column labels to 41 227.
    for cut in [0, 1, 30, 100, 400, 10_000, 24_600, 30_000, 41_200] {
        let r = read_ibw_bytes(&bytes[..cut], "cut.ibw", &ReadOptions::default());
        assert!(r.is_err(), "cut at {cut} read");
    }
    let err =
        read_ibw_bytes(&bytes[..10_000], "cut.ibw", &ReadOptions::default()).expect_err("cut");
    assert!(matches!(err, AfmError::Truncated { .. }), "{err}");
    // A JPK file or text is not an ibw.
    let jpk = std::fs::read(FD).expect("read");
    assert!(matches!(
        read_ibw_bytes(&jpk, "x.ibw", &ReadOptions::default()),
        Err(AfmError::NotIbw { .. })
    ));
    // A missing spring constant is a calibration error naming the note key.
    let key = b"SpringConstant: 1.1841";
    let pos = bytes
        .windows(key.len())
        .position(|w| w == key)
        .expect("key in note");
    let mut no_k = bytes.clone();
    no_k[pos..pos + 14].copy_from_slice(b"SpringKonstant");
    let err = read_ibw_bytes(&no_k, "x.ibw", &ReadOptions::default()).expect_err("no k");
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
    assert!(err.to_string().contains("SpringConstant"));
    // Random damage never panics.
    let mut state = 0x2545_f491_4f6c_dd1d_u64;
    for _ in 0..300 {
        let mut b = bytes.clone();
        for _ in 0..8 {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let i = (state % b.len() as u64) as usize;
            b[i] = (state >> 32) as u8;
        }
        let _ = read_ibw_bytes(&b, "fuzz.ibw", &ReadOptions::default());
    }
}

#[test]
fn batches_take_ibw_files_with_jpk_files() {
    let dir = std::env::temp_dir().join(format!("nlvid-afm-ibw-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("tmp");
    for f in [U3, SIN] {
        std::fs::copy(data(f), dir.join(f)).expect("copy");
    }
    std::fs::copy(FD, dir.join("fd.jpk-force")).expect("copy");
    let b =
        for_each_curve(&[&dir], &ReadOptions::default(), |c| Ok(c.segments.len())).expect("batch");
    assert_eq!(b.rows.len(), 3, "{:?}", b.failures);
    assert!(b.failures.is_empty());
    std::fs::remove_dir_all(&dir).ok();
}
