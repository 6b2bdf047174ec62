//! Reading measured CSV files: conversions and errors naming file and row.

use std::path::PathBuf;

use nlvid_inverse::{
    AfmColumns, Calibration, CompressionColumns, InverseError, ProtocolTolerance, read_afm_csv,
    read_compression_csv,
};

fn write(name: &str, text: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("nlvid-inverse-tests-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("tmp dir");
    let p = dir.join(name);
    std::fs::write(&p, text).expect("write");
    p
}

fn afm_cols() -> AfmColumns {
    AfmColumns {
        time: "time".into(),
        piezo: "height".into(),
        deflection: "vDeflection".into(),
    }
}

fn cal() -> Calibration {
    Calibration {
        deflection_sensitivity: Some(110.28e-9),
        spring_constant: 1.0677,
    }
}

#[test]
fn afm_volts_are_converted_to_force_and_indentation() {
    let p = write(
        "afm_v.csv",
        "time [ms],height (um),vDeflection [V]\n0,0,0\n10,1.0,0.5\n20,2.0,1.0\n",
    );
    let c = read_afm_csv(&p, &afm_cols(), &cal()).expect("read");
    assert_eq!(c.time(), vec![0.0, 0.01, 0.02]);
    let d = 1.0 * 110.28e-9;
    assert!((c.force()[2] - 1.0677 * d).abs() < 1e-20);
    let delta = c.indentation().expect("delta");
    assert!((delta[2] - (2e-6 - d)).abs() < 1e-18);
    assert_eq!(c.lines, vec![2, 3, 4]);
}

#[test]
fn afm_deflection_in_metres_or_newtons_gives_the_same_curve() {
    let pm = write(
        "afm_m.csv",
        "t [s],height [m],vDeflection [nm]\n0,0,0\n1,2e-6,100\n",
    );
    let pf = write(
        "afm_f.csv",
        "t [s],height [m],vDeflection [nN]\n0,0,0\n1,2e-6,106.77\n",
    );
    let cols = AfmColumns {
        time: "t".into(),
        ..afm_cols()
    };
    let a = read_afm_csv(&pm, &cols, &cal()).expect("m");
    let b = read_afm_csv(&pf, &cols, &cal()).expect("f");
    assert!((a.force()[1] - 106.77e-9).abs() < 1e-18);
    assert!((b.force()[1] - 106.77e-9).abs() < 1e-18);
    let (da, db) = (a.indentation().expect("a"), b.indentation().expect("b"));
    assert!((da[1] - db[1]).abs() < 1e-18 && (da[1] - 1.9e-6).abs() < 1e-15);
}

fn data_error(e: InverseError) -> (usize, String, String) {
    match e {
        InverseError::Data {
            row,
            column,
            message,
            path,
        } => {
            assert!(path.to_string_lossy().ends_with(".csv"));
            (row, column, message)
        }
        other => panic!("expected a Data error, got {other}"),
    }
}

#[test]
fn nlvid_output_headers_with_unit_suffixes_are_accepted() {
    let p = write(
        "suffix.csv",
        "time_s,height_um,vDeflection_nN\n0,0,0\n1,2,106.77\n",
    );
    let c = read_afm_csv(&p, &afm_cols(), &cal()).expect("read");
    assert!((c.force()[1] - 106.77e-9).abs() < 1e-18);
    assert!((c.displacement()[1] - 2e-6).abs() < 1e-18);
}

#[test]
fn malformed_files_name_the_row_and_column() {
    // missing column
    let p = write("missing.csv", "time [s],height [um]\n0,0\n");
    let (row, col, msg) = data_error(read_afm_csv(&p, &afm_cols(), &cal()).expect_err("missing"));
    assert_eq!((row, col.as_str()), (1, "vDeflection"));
    assert!(msg.contains("not found"), "{msg}");
    // NaN on line 4
    let p = write(
        "nan.csv",
        "time [s],height [um],vDeflection [V]\n0,0,0\n1,1,0.1\n2,NaN,0.2\n",
    );
    let (row, col, _) = data_error(read_afm_csv(&p, &afm_cols(), &cal()).expect_err("nan"));
    assert_eq!((row, col.as_str()), (4, "height"));
    // not a number
    let p = write(
        "text.csv",
        "time [s],height [um],vDeflection [V]\n0,0,0\n1,abc,0.1\n",
    );
    let (row, _, msg) = data_error(read_afm_csv(&p, &afm_cols(), &cal()).expect_err("text"));
    assert_eq!(row, 3);
    assert!(msg.contains("'abc'"));
    // non-monotonic time on line 4
    let p = write(
        "time.csv",
        "time [s],height [um],vDeflection [V]\n0,0,0\n2,1,0.1\n1,2,0.2\n",
    );
    let (row, col, msg) = data_error(read_afm_csv(&p, &afm_cols(), &cal()).expect_err("time"));
    assert_eq!((row, col.as_str()), (4, "time"));
    assert!(msg.contains("increase"), "{msg}");
    // wrong unit: time in metres
    let p = write("unit.csv", "time [m],height [um],vDeflection [V]\n0,0,0\n");
    let (row, col, msg) = data_error(read_afm_csv(&p, &afm_cols(), &cal()).expect_err("unit"));
    assert_eq!((row, col.as_str()), (1, "time"));
    assert!(msg.contains("'m'"), "{msg}");
    // no unit at all
    let p = write("nounit.csv", "time,height [um],vDeflection [V]\n0,0,0\n");
    let (_, col, msg) = data_error(read_afm_csv(&p, &afm_cols(), &cal()).expect_err("nounit"));
    assert_eq!(col, "time");
    assert!(msg.contains("no unit"));
    // volts without sensitivity
    let p = write("volts.csv", "time [s],height [um],vDeflection [V]\n0,0,0\n");
    let no_s = Calibration {
        deflection_sensitivity: None,
        spring_constant: 0.12,
    };
    let (_, col, msg) = data_error(read_afm_csv(&p, &afm_cols(), &no_s).expect_err("sens"));
    assert_eq!(col, "vDeflection");
    assert!(msg.contains("sensitivity"));
}

#[test]
fn compression_run_with_contact_area_is_read_in_si() {
    let p = write(
        "comp.csv",
        "time [s],plate [mm],force [mN],area [mm^2]\n0,0,0,0\n0.5,0.1,2.5,1.5\n",
    );
    let cols = CompressionColumns {
        time: "time".into(),
        displacement: "plate".into(),
        force: "force".into(),
        contact_area: Some("area".into()),
    };
    let c = read_compression_csv(&p, &cols).expect("read");
    assert!((c.displacement()[1] - 1e-4).abs() < 1e-18);
    assert!((c.force()[1] - 2.5e-3).abs() < 1e-18);
    assert!((c.contact_area().expect("area")[1] - 1.5e-6).abs() < 1e-20);
    let bad = CompressionColumns {
        force: "F".into(),
        ..cols
    };
    let (row, col, _) = data_error(read_compression_csv(&p, &bad).expect_err("F"));
    assert_eq!((row, col.as_str()), (1, "F"));
}

fn ramp_hold_csv(name: &str, rate_um_s: f64, depth_um: f64, end: f64) -> PathBuf {
    let mut s = String::from("time [s],height [um],vDeflection [V]\n");
    let n = (end / 0.01).round() as usize;
    for i in 0..=n {
        let t = i as f64 * 0.01;
        s.push_str(&format!("{t},{},0\n", (rate_um_s * t).min(depth_um) + 5.0));
    }
    write(name, &s)
}

#[test]
fn protocol_mismatches_name_file_row_and_time() {
    let te = [0.0, 0.2, 2.0];
    let ze = [0.0, 2e-6, 2e-6];
    let tol = ProtocolTolerance::default();
    // matching run (with a piezo offset of 5 um, removed)
    let ok = read_afm_csv(
        &ramp_hold_csv("ok.csv", 10.0, 2.0, 2.0),
        &afm_cols(),
        &cal(),
    )
    .expect("ok");
    ok.check_protocol(&te, &ze, tol).expect("matches");
    // too short
    let short = read_afm_csv(
        &ramp_hold_csv("short.csv", 10.0, 2.0, 1.5),
        &afm_cols(),
        &cal(),
    )
    .expect("r");
    let e = short.check_protocol(&te, &ze, tol).expect_err("duration");
    assert!(
        matches!(e, InverseError::ProtocolMismatch { row: 152, .. }),
        "{e}"
    );
    assert!(e.to_string().contains("duration"));
    // wrong amplitude
    let deep = read_afm_csv(
        &ramp_hold_csv("deep.csv", 10.0, 2.5, 2.0),
        &afm_cols(),
        &cal(),
    )
    .expect("r");
    let e = deep.check_protocol(&te, &ze, tol).expect_err("amplitude");
    assert!(e.to_string().contains("amplitude"), "{e}");
    // wrong rate (5 um/s instead of 10): first deviating sample > 6 % of 2 um
    let slow = read_afm_csv(
        &ramp_hold_csv("slow.csv", 5.0, 2.0, 2.0),
        &afm_cols(),
        &cal(),
    )
    .expect("r");
    let tol6 = ProtocolTolerance {
        displacement: 0.06,
        ..tol
    };
    let e = slow.check_protocol(&te, &ze, tol6).expect_err("rate");
    match e {
        InverseError::ProtocolMismatch {
            row, time, message, ..
        } => {
            // |5t - 10t| = 5t um > 0.12 um first at t = 0.03 s (line 5)
            assert_eq!(row, 5, "{message}");
            assert!((time - 0.03).abs() < 1e-12);
        }
        other => panic!("{other}"),
    }
}

#[test]
fn resampling_is_linear_and_refuses_grids_beyond_the_data() {
    let p = write(
        "res.csv",
        "time [s],height [um],vDeflection [V]\n1,0,0\n2,1,1\n3,3,2\n",
    );
    let c = read_afm_csv(&p, &afm_cols(), &cal()).expect("read");
    let z = c
        .resample(c.displacement(), &[0.0, 0.5, 1.5, 2.0])
        .expect("resample");
    let expect = [0.0, 0.5e-6, 2e-6, 3e-6];
    for (a, b) in z.iter().zip(expect) {
        assert!((a - b).abs() < 1e-18, "{z:?}");
    }
    let e = c
        .resample(c.displacement(), &[0.0, 2.5])
        .expect_err("beyond");
    assert!(
        matches!(e, InverseError::ProtocolMismatch { row: 4, .. }),
        "{e}"
    );
}

#[test]
fn a_measured_curve_becomes_an_experiment_on_the_model_grid() {
    use nlvid_inverse::{Experiment, LeeRadokHertz, Model};
    use nlvid_model::Domain;
    let domain = Domain::table_5_3(0.01).expect("domain");
    let grid: Vec<f64> = (0..=20).map(|i| i as f64 * 0.1).collect();
    let delta: Vec<f64> = grid.iter().map(|t| (10e-6 * t).min(2e-6)).collect();
    let model = LeeRadokHertz::new(domain, grid, &delta, 2.5e-6, 0.5).expect("model");
    let x = [1000.0, 0.3, 0.3, 0.1, 5.0];
    let clean = model.response(&x).expect("y");
    // the measured file samples twice as densely, starting at t = 3 s
    let mut s = String::from("time [s],height [um],vDeflection [nN]\n");
    for i in 0..=40 {
        let t = i as f64 * 0.05;
        let f = if i % 2 == 0 {
            clean[i / 2]
        } else {
            0.5 * (clean[i / 2] + clean[i / 2 + 1])
        };
        s.push_str(&format!("{},{},{}\n", 3.0 + t, 10.0 * t, f * 1e9));
    }
    let p = write("exp.csv", &s);
    let curve = read_afm_csv(&p, &afm_cols(), &cal()).expect("read");
    let e = Experiment::from_measured("RH", model, &curve, curve.force(), None).expect("e");
    for (a, b) in e.data.iter().zip(&clean) {
        assert!((a - b).abs() < 1e-9 * b.abs().max(1e-12), "{a} vs {b}");
    }
    assert!(e.misfit(&x).expect("misfit") < 1e-9);
}
