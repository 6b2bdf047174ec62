//! Tabulated histories from CSV: values, units and error messages.

use std::path::Path;

use nlvid_protocol::{Label, ProtocolError, Quantity, parse_table, read_table};

fn parse(text: &str, q: Quantity) -> Result<nlvid_protocol::Program, ProtocolError> {
    parse_table(text.as_bytes(), Path::new("z.csv"), q, None)
}

#[test]
fn table_in_ms_and_um_is_converted_to_si_and_interpolated() {
    let p = parse(
        "time_ms,piezo_um,note\n0,0,a\n100,1.0,b\n300,2.0,c\n",
        Quantity::Displacement,
    )
    .unwrap();
    assert_eq!(p.breakpoints(), vec![0.0, 0.1, 0.3]);
    assert!((p.value(0.05) - 0.5e-6).abs() < 1e-18);
    assert!((p.value(0.2) - 1.5e-6).abs() < 1e-18);
    assert!((p.rate(0.2) - 5e-6).abs() < 1e-15);
    assert_eq!(p.label(0.2), Label::Tabulated);
}

#[test]
fn bracketed_units_and_named_value_column_work() {
    let text = "t [s], Z [nm], d [nm]\n0,0,0\n1,1000,10\n";
    let p = parse_table(
        text.as_bytes(),
        Path::new("z.csv"),
        Quantity::Displacement,
        Some("Z"),
    )
    .unwrap();
    assert!((p.value(0.5) - 0.5e-6).abs() < 1e-18);
    // Two length columns and no name: ambiguous.
    let e = parse(text, Quantity::Displacement).unwrap_err().to_string();
    assert!(e.contains("several") && e.contains("z.csv"), "{e}");
}

#[test]
fn nan_cell_error_names_file_line_and_column() {
    let e = parse("time_s,piezo_um\n0,0\n0.1,NaN\n", Quantity::Displacement)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("z.csv") && e.contains("line 3") && e.contains("piezo_um"),
        "{e}"
    );
    let e = parse("time_s,piezo_um\n0,0\n0.1,abc\n", Quantity::Displacement)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("line 3") && e.contains("`abc` is not a number"),
        "{e}"
    );
}

#[test]
fn non_monotonic_time_error_names_the_row() {
    let e = parse(
        "time_s,piezo_um\n0,0\n0.2,1\n0.1,2\n",
        Quantity::Displacement,
    )
    .unwrap_err();
    assert!(
        matches!(e, ProtocolError::NonMonotonicTime { line: 4, .. }),
        "{e}"
    );
    let e = e.to_string();
    assert!(e.contains("z.csv") && e.contains("line 4"), "{e}");
}

#[test]
fn missing_columns_and_units_are_reported_with_the_header() {
    let e = parse("piezo_um\n0\n1\n", Quantity::Displacement)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("no time column") && e.contains("piezo_um"),
        "{e}"
    );
    let e = parse("time,piezo_um\n0,0\n1,1\n", Quantity::Displacement)
        .unwrap_err()
        .to_string();
    assert!(e.contains("needs a time unit"), "{e}");
    let e = parse("time_s,force_nN\n0,0\n1,1\n", Quantity::Displacement)
        .unwrap_err()
        .to_string();
    assert!(e.contains("no Displacement column"), "{e}");
    let e = parse("time_s,piezo_um\n0,0\n", Quantity::Displacement)
        .unwrap_err()
        .to_string();
    assert!(e.contains("at least 2 data rows"), "{e}");
}

#[test]
fn unreadable_file_error_names_the_file() {
    let e = read_table(
        Path::new("/nonexistent/z.csv"),
        Quantity::Displacement,
        None,
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("/nonexistent/z.csv"), "{e}");
}

#[test]
fn afm_script_written_at_its_breakpoints_reads_back_identically() {
    let z = nlvid_protocol::AfmScript::thesis_ch5(0.12)
        .unwrap()
        .piezo()
        .unwrap();
    let mut csv = String::from("time_s,piezo_m\n");
    for &t in z.breakpoints() {
        csv.push_str(&format!("{t},{}\n", z.value(t)));
    }
    let back = parse(&csv, Quantity::Displacement).unwrap();
    assert_eq!(back.breakpoints(), z.breakpoints());
    for i in 0..=1000 {
        let t = 52.8 * i as f64 / 1000.0;
        assert!((back.value(t) - z.value(t)).abs() < 1e-18, "t = {t}");
        if !z.breakpoints().contains(&t) {
            assert!((back.rate(t) - z.rate(t)).abs() < 1e-12, "t = {t}");
        }
    }
}
