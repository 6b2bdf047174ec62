//! The results.csv format: parsing, units, exclusions, errors, outputs.

use std::path::Path;

use nlvid_stats::{
    Method, StatsError, compare_over_time, group_curves, parse_results, write_group_curves,
    write_time_comparisons,
};

const TABLE: &str = "\
cell,group,G0_kPa,g1,tau1_ms,g2,tau2_s,status,reason,peak_force_nN
c1,MCF-10A,2.9,0.3,500,0.3,10,ok,,5.1
c2,MCF-7,1.9,0.35,400,0.4,12,,,4.2
c3,MCF-10A,3.1,0.28,600,0.3,9,failed,did not converge,
c4,MCF-7,1.5,0.4,450,0.42,11,ok,,4.0
c5,MCF-10A,2.5,0.3,550,0.33,10,ok,,4.9
";

fn parse(text: &str) -> Result<nlvid_stats::ResultsTable, StatsError> {
    parse_results(text.as_bytes(), Path::new("results.csv"))
}

#[test]
fn results_are_converted_to_si_and_exclusions_are_kept() {
    let t = parse(TABLE).unwrap();
    assert_eq!(t.terms, 2);
    assert_eq!(t.groups(), vec!["MCF-10A".to_string(), "MCF-7".to_string()]);
    assert_eq!(t.cells.len(), 4);
    let c1 = &t.cells[0];
    assert_eq!((c1.cell.as_str(), c1.line), ("c1", 2));
    assert_eq!(c1.relaxation.g0(), 2900.0);
    assert_eq!(c1.relaxation.prony().terms()[0].tau, 0.5);
    assert_eq!(c1.relaxation.prony().terms()[1].tau, 10.0);
    assert_eq!(t.excluded.len(), 1);
    assert_eq!(t.excluded[0].cell, "c3");
    assert_eq!(t.excluded[0].line, 4);
    assert_eq!(t.excluded[0].reason, "failed: did not converge");
    assert_eq!(t.group("MCF-10A").len(), 2);
}

#[test]
fn bracketed_units_and_missing_cell_column_work() {
    let t = parse("group,G0 [Pa],g1,tau1 (min)\nA,100,0.5,2\nA,200,0.5,1\n").unwrap();
    assert_eq!(t.cells[1].cell, "line 3");
    assert_eq!(t.cells[0].relaxation.prony().terms()[0].tau, 120.0);
}

#[test]
fn errors_name_file_line_and_column() {
    let e = parse("group,G0_kPa,g1,tau1_s\nA,2.9,0.3,x\n")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("results.csv") && e.contains("line 2") && e.contains("tau1_s"),
        "{e}"
    );
    let e = parse("group,G0_kPa,g1,tau1_s\nA,NaN,0.3,1\n")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("line 2") && e.contains("G0_kPa") && e.contains("not finite"),
        "{e}"
    );
    let e = parse("group,G0,g1,tau1_s\nA,1,0.3,1\n")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("line 1") && e.contains("modulus (pressure) unit"),
        "{e}"
    );
    let e = parse("group,G0_kPa,g1,tau1\nA,1,0.3,1\n")
        .unwrap_err()
        .to_string();
    assert!(e.contains("time unit"), "{e}");
    let e = parse("group,G0_kPa,g1\nA,1,0.3\n").unwrap_err().to_string();
    assert!(e.contains("`g1` has no `tau1_<unit>`"), "{e}");
    let e = parse("cell,G0_kPa\nc,1\n").unwrap_err().to_string();
    assert!(e.contains("missing column `group`"), "{e}");
    let e = parse("group,G0_kPa,g1,tau1_s,g2,tau2_s\nA,1,0.7,1,0.5,2\n")
        .unwrap_err()
        .to_string();
    assert!(e.contains("line 2") && e.contains("g_inf"), "{e}");
    let e = parse("group,G0_kPa,g1,tau1_s\nA,2.9,,1\n")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("line 2") && e.contains("`g1`") && e.contains("empty cell"),
        "{e}"
    );
    let e = parse("group,G0_kPa\n,1\n").unwrap_err().to_string();
    assert!(e.contains("empty group"), "{e}");
    let e = parse("group,G0_kPa,g1,tau1_s\nA,0,0.3,1\n")
        .unwrap_err()
        .to_string();
    assert!(e.contains("line 2") && e.contains("must be > 0"), "{e}");
}

/// The factor-2 class of error: a table whose modulus column is `C1`
/// (eq. 4.1's constant) is not read as G0, and a `G0` column gives the
/// G(t) of `nlvid_model::Relaxation` with that G0, bit for bit.
#[test]
fn the_modulus_column_is_the_shear_modulus_g0_and_c1_is_refused() {
    let e = parse("group,C1_kPa,g1,tau1_s\nA,1.45,0.3,0.5\n")
        .unwrap_err()
        .to_string();
    assert!(e.contains("`C1`") && e.contains("G0 = 2(C1 + C2)"), "{e}");
    let t = parse("group,G0_kPa,g1,tau1_s,g2,tau2_s\nA,2.9,0.3,0.5,0.2,10\nA,1.9,0.4,1,0.1,20\n")
        .unwrap();
    let cells = t.group("A");
    let want = nlvid_model::Relaxation::from_named(
        &nlvid_model::names::PRONY2,
        &[2900.0, 0.3, 0.2, 0.5, 10.0],
    )
    .unwrap();
    assert_eq!(cells[0], want);
    let times = [0.0, 0.7, 52.0];
    let g = group_curves("A", &cells, &times).unwrap();
    for (i, &t) in times.iter().enumerate() {
        let by_hand = (2900.0 * (0.5 + 0.3 * (-t / 0.5f64).exp() + 0.2 * (-t / 10.0f64).exp())
            + 1900.0 * (0.5 + 0.4 * (-t / 1.0f64).exp() + 0.1 * (-t / 20.0f64).exp()))
            / 2.0;
        assert!(
            (g.shear[i].mean - by_hand).abs() < 1e-9 * by_hand,
            "t = {t}"
        );
    }
}

#[test]
fn outputs_have_unit_suffixed_headers_and_one_row_per_time() {
    let t = parse(TABLE).unwrap();
    let times = [0.0, 26.0, 52.0];
    let ga = group_curves("MCF-10A", &t.group("MCF-10A"), &times).unwrap();
    let gb = group_curves("MCF-7", &t.group("MCF-7"), &times).unwrap();
    let mut buf = Vec::new();
    write_group_curves(&mut buf, &[ga, gb]).unwrap();
    let text = String::from_utf8(buf).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(
        lines[0],
        "group,n,time_s,G_mean_Pa,G_sd_Pa,G_norm_mean,G_norm_sd,E_mean_Pa,E_sd_Pa"
    );
    assert_eq!(lines.len(), 1 + 2 * 3);
    assert!(lines[1].starts_with("MCF-10A,2,0,2700,"), "{}", lines[1]);
    let cmp = compare_over_time(
        &t.group("MCF-10A"),
        &t.group("MCF-7"),
        &times,
        Method::MATLAB_RANKSUM,
    )
    .unwrap();
    let mut buf = Vec::new();
    write_time_comparisons(&mut buf, &cmp).unwrap();
    let text = String::from_utf8(buf).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 4);
    // 2 vs 2 cells, complete separation on G: exact p = 2/C(4,2) = 1/3.
    assert!(
        lines[1].starts_with("0,0.3333333333333333,exact,,1,exact,"),
        "{}",
        lines[1]
    );
}
