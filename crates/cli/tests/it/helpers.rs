//! The binary's shared helpers (`nlvid_cli::output`, `nlvid_cli::args`) and
//! the library ones it prints with (`nlvid_model`, `nlvid_study`):
//! unit-suffixed JSON keys, outputs next to the study, atomic writes,
//! command-line quantities.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers

use std::fs;
use std::path::Path;

use nlvid_cli::args::quantity;
use nlvid_cli::output::write_atomic;
use nlvid_model::parameters_json;
use nlvid_study::next_to;

#[test]
fn json_keys_carry_units() {
    let c = nlvid_model::Curve::new(vec![0.0, 1.0])
        .and_then(|c| c.with("force", "N", vec![0.0, 2.0]))
        .and_then(|c| c.with("tension", "N/m", vec![1.0, 3.0]))
        .and_then(|c| c.with("stretch", "1", vec![1.0, 1.5]))
        .unwrap();
    let v = c.to_json();
    let keys: Vec<&String> = v.as_object().unwrap().keys().collect();
    assert_eq!(keys, ["time_s", "force_N", "tension_N_per_m", "stretch"]);
    let p = parameters_json(&[
        ("G0".into(), 1e3, "Pa".into()),
        ("g1".into(), 0.3, "1".into()),
    ]);
    assert_eq!(p, serde_json::json!({"G0_Pa": 1e3, "g1": 0.3}));
    assert_eq!(
        next_to(Path::new("dir/cell.toml"), "simulate.csv"),
        Path::new("dir/cell.simulate.csv")
    );
}

#[test]
fn atomic_write_replaces_the_file_and_leaves_no_temporary() {
    let dir = std::env::temp_dir().join(format!("nlvid-cli-atomic-{}", std::process::id()));
    fs::create_dir_all(&dir).unwrap();
    let p = dir.join("out.csv");
    write_atomic(&p, b"old").unwrap();
    write_atomic(&p, b"new").unwrap();
    assert_eq!(fs::read(&p).unwrap(), b"new");
    let names: Vec<_> = fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names, vec![std::ffi::OsString::from("out.csv")]);
    assert!(write_atomic(&dir.join("no/such/dir/x"), b"x").is_err());
    fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn command_line_quantities_are_checked_and_converted() {
    use nlvid_study::Dimension;
    assert_eq!(quantity("1ms", Dimension::TIME), Ok(1e-3));
    assert_eq!(
        quantity("2", Dimension::TIME).unwrap_err(),
        "`2` has no unit; expected a time (s), e.g. \"2 s\""
    );
    assert_eq!(
        quantity("2 um", Dimension::TIME).unwrap_err(),
        "`2 um` is a length (m), expected a time (s)"
    );
}

#[test]
fn bars_show_only_on_an_interactive_terminal_outside_ci() {
    use nlvid_cli::progress::enabled;
    assert!(enabled(true, false, false));
    assert!(!enabled(false, false, false));
    assert!(!enabled(true, true, false));
    assert!(!enabled(true, false, true));
}
