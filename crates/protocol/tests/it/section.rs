//! The `[protocol]` study section: defaults, units, and located errors.

use nlvid_protocol::{AfmScript, Label, Loading, ProtocolSettings, Quantity};
use nlvid_study::Study;

fn read(text: &str) -> Result<ProtocolSettings, nlvid_study::StudyError> {
    let mut st = Study::parse("study.toml", text)?;
    let p: ProtocolSettings = st.read("protocol")?;
    st.finish()?;
    Ok(p)
}

fn assert_close(a: &[f64], b: &[f64]) {
    assert_eq!(a.len(), b.len(), "{a:?} vs {b:?}");
    for (x, y) in a.iter().zip(b) {
        assert!((x - y).abs() < 1e-12, "{a:?} vs {b:?}");
    }
}

#[test]
fn afm_defaults_are_the_thesis_ch5_script() {
    let p = read("[protocol]\nkind = \"afm\"\noutput_points = 5095\n").unwrap();
    let Loading::Afm(s) = &p.loading else {
        panic!("not afm")
    };
    let thesis = AfmScript::thesis_ch5(0.12).unwrap();
    assert_eq!(s.cycle_rates, thesis.cycle_rates);
    assert_close(
        s.piezo().unwrap().breakpoints(),
        thesis.piezo().unwrap().breakpoints(),
    );
    assert!((s.engage.setpoint_force - 0.48e-9).abs() < 1e-21);
    let g = p.output_grid().unwrap().unwrap();
    assert_eq!(g.len(), 5095);
}

#[test]
fn afm_keys_with_units_override_the_defaults() {
    let p = read(
        r#"[protocol]
kind = "afm"
depth = "3 um"
engage_force = "0.36 nN"
engage_time = "5 s"
engage_hold = "15 s"
cycle_rates = ["10 um/s", "5 um/s", "1 um/s"]
"#,
    )
    .unwrap();
    let z = p.program().unwrap();
    // Same as the App. A script (first leg 3 µm).
    let app_a = AfmScript::thesis_app_a(0.072).unwrap().piezo().unwrap();
    assert_close(z.breakpoints(), app_a.breakpoints());
    let Loading::Afm(s) = &p.loading else {
        panic!("not afm")
    };
    assert_eq!(s.engage.hold, 15.0);
}

#[test]
fn ramp_hold_in_mm_per_s_and_dimensionless_load_unload() {
    let p = read(
        "[protocol]\nkind = \"ramp-hold\"\ntarget = \"1.5 mm\"\nrate = \"0.2 mm/s\"\nhold = \"20 s\"\n",
    )
    .unwrap();
    let z = p.program().unwrap();
    assert!((z.duration() - 27.5).abs() < 1e-12);
    assert_eq!(z.label(10.0), Label::Hold);
    let p = read(
        "[protocol]\nkind = \"load-unload\"\ncontrol = \"dimensionless\"\npeak = 0.78\nload_rate = 1\nunload_rate = 0.2\n",
    )
    .unwrap();
    let d = p.program().unwrap();
    assert_eq!(d.quantity(), Quantity::Dimensionless);
    assert!((d.duration() - (0.78 + 3.9)).abs() < 1e-12);
}

#[test]
fn errors_name_file_line_and_key() {
    let e = read("[protocol]\nkind = \"afm\"\ndepth = \"2 s\"\n")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("study.toml:3") && e.contains("protocol.depth"),
        "{e}"
    );
    let e = read("[protocol]\nkind = \"afm\"\nretract = \"3 um\"\n")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("study.toml:3") && e.contains("protocol.retract"),
        "{e}"
    );
    let e = read("[protocol]\nkind = \"ramp\"\n")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("protocol.kind") && e.contains("ramp-hold"),
        "{e}"
    );
    let e = read("[protocol]\nkind = \"step\"\namplitude = \"1 um\"\nhold = \"1 s\"\nholdd = 3\n")
        .unwrap_err()
        .to_string();
    assert!(e.contains("study.toml:5") && e.contains("holdd"), "{e}");
    let e = read("[protocol]\nkind = \"table\"\nfile = \"missing.csv\"\n")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("protocol.file") && e.contains("missing.csv"),
        "{e}"
    );
}

#[test]
fn table_kind_reads_the_csv_next_to_the_study() {
    let dir = std::env::temp_dir().join(format!("nlvid-protocol-section-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("z.csv"), "time_s,piezo_um\n0,0\n0.5,1\n1,1\n").unwrap();
    std::fs::write(dir.join("bad.csv"), "time_s,piezo_um\n0,0\n0.5,nan\n").unwrap();
    let text = "[protocol]\nkind = \"table\"\nfile = \"z.csv\"\n";
    let mut st = Study::parse_in("s.toml".into(), text.into(), dir.clone()).unwrap();
    let p: ProtocolSettings = st.read("protocol").unwrap();
    assert!((p.program().unwrap().value(0.25) - 0.5e-6).abs() < 1e-18);
    let text = "[protocol]\nkind = \"table\"\nfile = \"bad.csv\"\n";
    let mut st = Study::parse_in("s.toml".into(), text.into(), dir.clone()).unwrap();
    let e = st
        .read::<ProtocolSettings>("protocol")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("bad.csv") && e.contains("line 3") && e.contains("piezo_um"),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn bundled_example_study_protocol_reads_with_speed_displacement_and_sampling() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../examples/study/capsule-compression.toml"
    );
    let mut st = Study::load(path).unwrap();
    let p: ProtocolSettings = st.read("protocol").unwrap();
    let z = p.program().unwrap();
    // 0.6 mm at 5 mm/s = 0.12 s, then 50 s; 100 Hz → 5012 intervals.
    assert_close(z.breakpoints(), &[0.0, 0.12, 50.12]);
    assert!((z.value(0.06) - 0.3e-3).abs() < 1e-15);
    assert_eq!(p.output_points, Some(5013));
    let g = p.output_grid().unwrap().unwrap();
    assert!((g[1] - g[0] - 0.01).abs() < 1e-12);
}

#[test]
fn two_spellings_of_one_key_are_rejected() {
    let e = read("[protocol]\nkind = \"ramp-hold\"\ntarget = \"1 mm\"\ndisplacement = \"1 mm\"\nrate = \"1 mm/s\"\nhold = \"1 s\"\n")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("study.toml:4") && e.contains("mean the same"),
        "{e}"
    );
    let e = read("[protocol]\nkind = \"afm\"\nsampling = \"10 Hz\"\noutput_points = 100\n")
        .unwrap_err()
        .to_string();
    assert!(e.contains("not both"), "{e}");
}
