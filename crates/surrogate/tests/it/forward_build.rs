//! A forward model of `nlvid-forward` built end to end through the
//! surrogate build (moved here from `nlvid-forward`: forward models do not
//! depend on the meta-model crate).

#![allow(clippy::unwrap_used)]

use nlvid_forward::from_study;
use nlvid_study::Study;

/// The small afm-fe example study built end to end through the surrogate
/// build (4 FE runs, coarse mesh, short protocol). Heavy: run with
/// `cargo test --release -p nlvid-forward -- --ignored`.
#[test]
#[ignore = "runs 4 finite-element simulations (seconds each)"]
fn afm_fe_example_builds_end_to_end() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples/metamodel/afm-fe.toml");
    let mut st = Study::load(&path).unwrap();
    let model = from_study(&mut st).unwrap();
    let design = vec![
        vec![600.0, 0.55, 0.28, 0.45, 13.8],
        vec![375.0, 0.63, 0.03, 0.024, 8.8],
        vec![2170.0, 0.064, 0.16, 0.086, 19.1],
        vec![268.0, 0.32, 0.45, 0.014, 2.35],
    ];
    let dir = std::env::temp_dir().join(format!("nlvid-forward-afm-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let s = nlvid_surrogate::build(
        model.as_ref(),
        &design,
        &dir,
        &nlvid_surrogate::BuildOptions::default(),
    )
    .unwrap();
    assert_eq!((s.ran, s.failed), (4, 0));
    let mm = nlvid_surrogate::load(&dir, &nlvid_surrogate::Admissibility::default()).unwrap();
    for (y, (_, _, _, secs)) in mm.y.iter().zip(&mm.status) {
        let peak = y.iter().copied().fold(0.0, f64::max);
        // Above the 0.48 nN engagement force, relaxed at the end of the hold.
        assert!(peak > 0.48e-9 && y[y.len() - 1] < peak, "peak {peak}");
        eprintln!("afm-fe run: {secs:.2} s, peak {peak:.3e} N");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
