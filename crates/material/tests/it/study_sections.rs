//! `[material]` and `[loading]` study sections: values in SI, and every bad
//! input rejected with a message naming file, line and key.

use nlvid_material::homogeneous::{History, Mode};
use nlvid_material::{LoadingSpec, MaterialSpec};
use nlvid_study::Study;

fn material(text: &str) -> Result<MaterialSpec, String> {
    let mut s = Study::parse("m.toml", text).map_err(|e| e.to_string())?;
    s.read::<MaterialSpec>("material")
        .map_err(|e| e.to_string())
}

fn loading_in(dir: &std::path::Path, text: &str) -> Result<LoadingSpec, String> {
    let mut s = Study::parse_in("l.toml".into(), text.into(), dir.to_path_buf())
        .map_err(|e| e.to_string())?;
    s.read::<LoadingSpec>("loading").map_err(|e| e.to_string())
}

fn loading(text: &str) -> Result<LoadingSpec, String> {
    loading_in(&std::env::temp_dir(), text)
}

fn expect_err(r: Result<impl std::fmt::Debug, String>, needles: &[&str]) {
    let e = r.expect_err("must be rejected");
    for n in needles {
        assert!(e.contains(n), "error `{e}` lacks `{n}`");
    }
}

#[test]
fn pipkin_rogers_eq_2_56_section_reads_in_si() {
    let m = material(
        "[material]\nmodel = \"pipkin-rogers\"\nG10 = \"2 kPa\"\ngamma0 = 0.1\ng1_long_term = 0.3\n\
         g2_long_term = \"60 %\"\ntau1 = \"500 ms\"\nc = 0.5\na = 0.2\n",
    )
    .expect("valid");
    let MaterialSpec::PipkinRogers(pr) = m else {
        panic!("wrong model")
    };
    assert_eq!(pr.g1().g0(), 2000.0);
    assert!((pr.g2().g0() - 200.0).abs() < 1e-12);
    assert!((pr.g1().g_inf() - 600.0).abs() < 1e-9);
    assert!((pr.g2().prony().terms()[0].tau - 1.0).abs() < 1e-12); // τ2 = τ1/c
}

#[test]
fn prony_tables_and_elastic_models_read_in_si() {
    let m = material(
        "[material]\nmodel = \"mooney-rivlin-prony\"\nC1 = \"2.94 kPa\"\nalpha = 0.3\n\
         [material.prony]\ng = [0.25, \"10 %\"]\ntau = [\"0.5 s\", \"12 s\"]\n",
    )
    .expect("valid");
    let MaterialSpec::PronyViscoelastic(pv) = m else {
        panic!("wrong model")
    };
    assert!((pv.elastic().c2() - 882.0).abs() < 1e-9);
    assert!((pv.prony().long_term_weight() - 0.65).abs() < 1e-12);
    let m = material(
        "[material]\nmodel = \"qlv\"\nbeta = 0.2\n[material.G1]\nG10 = \"1 kPa\"\ng = [0.5]\ntau = [\"1 s\"]\n",
    )
    .expect("valid");
    let MaterialSpec::PipkinRogers(q) = m else {
        panic!("wrong model")
    };
    assert!((q.g2().g0() - 200.0).abs() < 1e-12);
}

#[test]
fn bad_material_sections_name_file_line_and_key() {
    expect_err(
        material("[material]\nmodel = \"ogden\"\n"),
        &["m.toml:2", "material.model", "pipkin-rogers"],
    );
    expect_err(
        material("[material]\nmodel = \"neo-hookean\"\nC1 = 500\n"),
        &["m.toml:3", "material.C1", "no unit"],
    );
    expect_err(
        material("[material]\nmodel = \"neo-hookean\"\nC1 = \"0.12 N/m\"\n"),
        &["m.toml:3", "material.C1", "expected a pressure"],
    );
    expect_err(
        material("[material]\nmodel = \"neo-hookean\"\nC1 = \"nan Pa\"\n"),
        &["m.toml:3", "material.C1"],
    );
    expect_err(
        material("[material]\nmodel = \"neo-hookean\"\nC1 = \"-1 kPa\"\n"),
        &["m.toml:3", "material.C1"],
    );
    expect_err(
        material(
            "[material]\nmodel = \"mooney-rivlin\"\nC1 = \"1 kPa\"\nC2 = \"1 Pa\"\nalpha = 0.1\n",
        ),
        &["m.toml:5", "material.alpha", "not both"],
    );
    expect_err(
        material("[material]\nmodel = \"neo-hookean\"\nC1 = \"1 kPa\"\nC2 = \"1 Pa\"\n"),
        &["m.toml:4", "material.C2", "C2 = 0"],
    );
    expect_err(
        material(
            "[material]\nmodel = \"neo-hookean-prony\"\nC1 = \"1 kPa\"\n[material.prony]\n\
             g = [0.6, 0.5]\ntau = [\"1 s\", \"2 s\"]\n",
        ),
        &["m.toml:5", "material.prony.g", "term 2", "g_inf"],
    );
    expect_err(
        material(
            "[material]\nmodel = \"neo-hookean-prony\"\nC1 = \"1 kPa\"\n[material.prony]\n\
             g = [0.1, 0.2]\ntau = [\"1 s\"]\n",
        ),
        &["m.toml:6", "material.prony.tau", "one per term"],
    );
    expect_err(
        material(
            "[material]\nmodel = \"neo-hookean-prony\"\nC1 = \"1 kPa\"\n[material.prony]\n\
             g = [0.1]\ntau = [\"1 m\"]\n",
        ),
        &["m.toml:6", "material.prony.tau[0]", "expected a time"],
    );
    expect_err(
        material(
            "[material]\nmodel = \"pipkin-rogers\"\nG10 = \"1 kPa\"\ngamma0 = 0.1\ng1_long_term = 1.5\n\
             g2_long_term = 0.5\ntau1 = \"1 s\"\nc = 1\n",
        ),
        &["m.toml:5", "material.g1_long_term"],
    );
}

/// One key, one quantity (docs/theory/model.md): `G0` is the shear modulus,
/// `C1` the constant of eq. 4.1, so `G0 = 2 kPa` and `C1 = 1 kPa` are the
/// same neo-Hookean material; ch. II's G1(0) is `G10`, and the old keys
/// whose meaning changed are refused with the new key named.
#[test]
fn a_modulus_key_names_one_quantity_and_old_keys_name_their_replacement() {
    let prony = "[material.prony]\ng = [0.4, 0.3]\ntau = [\"0.5 s\", \"10 s\"]\n";
    let by_g0 = material(&format!(
        "[material]\nmodel = \"neo-hookean-prony\"\nG0 = \"2 kPa\"\n{prony}"
    ))
    .expect("valid");
    let by_c1 = material(&format!(
        "[material]\nmodel = \"neo-hookean-prony\"\nC1 = \"1 kPa\"\n{prony}"
    ))
    .expect("valid");
    assert_eq!(by_g0, by_c1, "G0 = 2 C1 for a neo-Hookean cell");
    let MaterialSpec::PronyViscoelastic(pv) = &by_g0 else {
        panic!("wrong model")
    };
    assert_eq!(pv.elastic().c1(), 1000.0);
    let g = pv.shear_relaxation().expect("valid");
    assert_eq!(g.g0(), 2000.0);
    let (_, params) = by_g0.parameters();
    let value = |n: &str| params.iter().find(|p| p.0 == n).map(|p| p.1);
    assert_eq!((value("G0"), value("C1")), (Some(2000.0), Some(1000.0)));

    // Mooney–Rivlin from G0 and alpha: C1 = G0 / (2 (1 + alpha)).
    let m = material("[material]\nmodel = \"mooney-rivlin\"\nG0 = \"3 kPa\"\nalpha = 0.5\n")
        .expect("valid");
    let MaterialSpec::Elastic(mr) = m else {
        panic!("wrong model")
    };
    assert_eq!((mr.c1(), mr.c2()), (1000.0, 500.0));

    expect_err(
        material("[material]\nmodel = \"neo-hookean\"\nG0 = \"2 kPa\"\nC1 = \"1 kPa\"\n"),
        &["m.toml:3", "material.G0", "not both"],
    );
    expect_err(
        material("[material]\nmodel = \"neo-hookean\"\n"),
        &["material.G0", "missing", "C1"],
    );
    expect_err(
        material(
            "[material]\nmodel = \"pipkin-rogers\"\nC1 = \"1 kPa\"\ngamma0 = 0.1\ng1_long_term = 0.5\n\
             g2_long_term = 0.5\ntau1 = \"1 s\"\nc = 1\n",
        ),
        &["m.toml:3", "material.C1", "write `G10`"],
    );
    expect_err(
        material(
            "[material]\nmodel = \"pipkin-rogers\"\n[material.G1]\nG0 = \"1 kPa\"\ng = [0.5]\n\
             tau = [\"1 s\"]\n[material.G2]\nG20 = \"1 kPa\"\ng = [0.5]\ntau = [\"1 s\"]\n",
        ),
        &["m.toml:4", "material.G1.G0", "write `G10`"],
    );
    expect_err(
        material(
            "[material]\nmodel = \"qlv\"\nbeta = 0.2\n[material.G]\nG0 = \"1 kPa\"\ng = [0.5]\ntau = [\"1 s\"]\n",
        ),
        &["material.G", "write `G1`"],
    );
}

#[test]
fn loading_histories_read_in_si() {
    let l = loading("[loading]\nmode = \"uniaxial\"\nhistory = \"ramp-hold\"\nstretch = 2\nramp = \"500 ms\"\nhold = \"1 min\"\n")
        .expect("valid");
    assert_eq!(l.mode, Mode::Uniaxial);
    assert_eq!(
        l.history,
        History::RampHold {
            value: 2.0,
            ramp: 0.5,
            hold: 60.0
        }
    );
    assert!((l.max_dt - 60.5 / 2000.0).abs() < 1e-15);
    let l = loading("[loading]\nmode = \"simple-shear\"\nhistory = \"ramp-reverse\"\nshear = -0.5\nramp = \"2 s\"\nmax_dt = \"1 ms\"\n")
        .expect("valid");
    assert_eq!(
        l.history,
        History::RampReverse {
            value: -0.5,
            ramp: 2.0
        }
    );
    assert_eq!(l.max_dt, 1e-3);
}

#[test]
fn bad_loading_sections_name_file_line_and_key() {
    expect_err(
        loading("[loading]\nmode = \"torsion\"\nhistory = \"step\"\n"),
        &["l.toml:2", "loading.mode", "simple-shear"],
    );
    expect_err(
        loading(
            "[loading]\nmode = \"uniaxial\"\nhistory = \"step\"\nstretch = -1\nhold = \"1 s\"\n",
        ),
        &["l.toml:4", "loading.stretch"],
    );
    expect_err(
        loading("[loading]\nmode = \"uniaxial\"\nhistory = \"step\"\nstretch = 2\nhold = 1\n"),
        &["l.toml:5", "loading.hold", "no unit"],
    );
    expect_err(
        loading(
            "[loading]\nmode = \"uniaxial\"\nhistory = \"ramp-hold\"\nstretch = 2\nramp = \"0 s\"\nhold = \"1 s\"\n",
        ),
        &["l.toml:5", "loading.ramp"],
    );
    expect_err(
        loading("[loading]\nmode = \"uniaxial\"\nhistory = \"step\"\nshear = 2\nhold = \"1 s\"\n"),
        &["loading.stretch", "missing"],
    );
    expect_err(
        loading(
            "[loading]\nmode = \"uniaxial\"\nhistory = \"table\"\ntable = \"no-such-file.csv\"\n",
        ),
        &["l.toml:4", "loading.table", "no such file"],
    );
}

#[test]
fn bad_history_tables_name_file_row_and_column() {
    let dir = std::env::temp_dir().join(format!("nlvid-material-spec-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let case = |csv: &str, needles: &[&str]| {
        std::fs::write(dir.join("h.csv"), csv).expect("write");
        let r = loading_in(
            &dir,
            "[loading]\nmode = \"uniaxial\"\nhistory = \"table\"\ntable = \"h.csv\"\n",
        );
        expect_err(r, needles);
    };
    case(
        "t,stretch\n0,1\n",
        &["l.toml:4", "loading.table", "h.csv: row 1", "time_s"],
    );
    case(
        "time_s,lambda\n0,1\n",
        &["h.csv: row 1", "no `stretch` column"],
    );
    case(
        "time_m,stretch\n0,1\n",
        &["h.csv: row 1", "column `time_m`", "not a time unit"],
    );
    case(
        "time_s,stretch\n0,1\n1,abc\n",
        &["h.csv: row 3", "column `stretch`", "`abc`"],
    );
    case(
        "time_s,stretch\n0,1\n2,1.5\n1,1.5\n",
        &["h.csv: row 4", "before the previous row"],
    );
    case(
        "time_s,stretch\n0,1\n1,0\n",
        &["loading.table", "stretch must be finite and > 0"],
    );
    case("time_s,stretch\n", &["h.csv: no data rows"]);
    // A good table, in ms.
    std::fs::write(dir.join("h.csv"), "time_ms,stretch\n0,1\n500,2\n").expect("write");
    let l = loading_in(
        &dir,
        "[loading]\nmode = \"uniaxial\"\nhistory = \"table\"\ntable = \"h.csv\"\n",
    )
    .expect("valid");
    assert_eq!(l.history, History::Table(vec![(0.0, 1.0), (0.5, 2.0)]));
}
