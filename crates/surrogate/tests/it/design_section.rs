//! The study's `[design]` and `[build]` sections: units converted, the
//! domain in the model's parameter order, constraints mapped by name, the
//! designs identical to those of the hand-built domain; bad sections give
//! errors naming file, line and key.

#![allow(clippy::unwrap_used)]

use nlvid_model::Domain;
use nlvid_study::Study;
use nlvid_surrogate::Admissibility;
use nlvid_surrogate::doe::{DesignSettings, training_and_checking};

fn names() -> Vec<String> {
    ["G0", "g1", "g2", "tau1", "tau2"]
        .map(String::from)
        .to_vec()
}
fn units() -> Vec<String> {
    ["Pa", "1", "1", "s", "s"].map(String::from).to_vec()
}

const DESIGN: &str = r#"[design]
n_train = 24
n_check = 9
seed = 5
ese_iterations = 5

[design.parameters]
tau2 = { range = ["2 s", "40 s"], log = true }
G0 = { range = ["80 Pa", "4 kPa"], log = true }
g1 = { range = [0.01, 1.0] }
g2 = { range = ["1 %", "100 %"] }
tau1 = { range = ["10 ms", "2 s"], log = true }

[[design.constraint]]
coefficients = { g2 = 1, g1 = 1 }
at_most = 0.99
"#;

fn read(text: &str) -> Result<DesignSettings, String> {
    let mut st = Study::parse("d.toml", text).unwrap();
    let mut s = st.section("design").map_err(|e| e.to_string())?;
    let d = DesignSettings::from_section(&mut s, &names(), &units()).map_err(|e| e.to_string())?;
    s.finish().map_err(|e| e.to_string())?;
    Ok(d)
}

#[test]
fn design_section_gives_the_hand_built_domain_and_its_designs() {
    let d = read(DESIGN).unwrap();
    // The Table 5.3 domain built by hand (nlvid_model).
    let want = Domain::table_5_3(0.01).unwrap();
    // Unit conversion may differ from the literal in the last bit.
    assert_eq!(d.domain.len(), 5);
    for (a, b) in d.domain.params().iter().zip(want.params()) {
        assert_eq!((&a.name, &a.unit, a.scale), (&b.name, &b.unit, b.scale));
        assert!((a.lower - b.lower).abs() <= 1e-15 * b.lower.abs());
        assert!((a.upper - b.upper).abs() <= 1e-15 * b.upper.abs());
    }
    assert_eq!(d.domain.constraints().len(), 1);
    let (c, w) = (&d.domain.constraints()[0], &want.constraints()[0]);
    assert_eq!((&c.coefficients, c.rhs), (&w.coefficients, w.rhs));
    assert_eq!(
        (d.n_train, d.n_check, d.seed, d.ese_iterations),
        (24, 9, 5, 5)
    );
    let (train, check) = d.designs().unwrap();
    let (t2, c2) = training_and_checking(&d.domain, 24, 9, 5, 5, 1e-6).unwrap();
    assert_eq!((train.clone(), check.clone()), (t2, c2));
    assert_eq!((train.len(), check.len()), (24, 9));
    for x in train.iter().chain(&check) {
        assert!(x[1] + x[2] <= 0.99, "{x:?}");
        assert!(x[0] >= 80.0 * (1.0 - 1e-12) && x[0] <= 4000.0 * (1.0 + 1e-12));
    }
    for c in &check {
        assert!(!train.contains(c));
    }
}

#[test]
fn ese_off_and_no_checking_set() {
    let text = DESIGN
        .replace("ese_iterations = 5", "ese = false")
        .replace("n_check = 9\n", "");
    let d = read(&text).unwrap();
    assert_eq!((d.ese_iterations, d.n_check), (0, 0));
    let (train, check) = d.designs().unwrap();
    assert_eq!((train.len(), check.len()), (24, 0));
}

#[test]
fn bad_design_sections_name_file_line_and_key() {
    let cases: [(String, &str); 6] = [
        // a parameter of the model is missing
        (
            DESIGN.replace("g1 = { range = [0.01, 1.0] }\n", ""),
            "design.parameters.g1",
        ),
        // an unknown parameter (typo)
        (DESIGN.replace("g1 = {", "g_1 = {"), "design.parameters.g1"),
        // wrong unit
        (
            DESIGN.replace("\"80 Pa\"", "\"80 s\""),
            "design.parameters.G0.range",
        ),
        // log axis through zero
        (
            DESIGN.replace(
                "g1 = { range = [0.01, 1.0] }",
                "g1 = { range = [0.0, 1.0], log = true }",
            ),
            "design.parameters.g1.log",
        ),
        // constraint on an unknown parameter
        (
            DESIGN.replace("{ g2 = 1, g1 = 1 }", "{ g2 = 1, g3 = 1 }"),
            "design.constraint[0].coefficients.g3",
        ),
        // n_train missing
        (DESIGN.replace("n_train = 24\n", ""), "design.n_train"),
    ];
    for (text, key) in cases {
        let e = read(&text).unwrap_err();
        assert!(
            e.contains("d.toml:") && e.contains(key),
            "expected `{key}` in: {e}"
        );
    }
    // An extra parameter the model does not have.
    let e = read(&DESIGN.replace(
        "[[design.constraint]]",
        "G1 = { range = [1, 2] }\n\n[[design.constraint]]",
    ))
    .unwrap_err();
    assert!(
        e.contains("d.toml:14") && e.contains("design.parameters.G1"),
        "{e}"
    );
}

#[test]
fn build_section_filters_in_si() {
    let mut st = Study::parse(
        "b.toml",
        "[build]\nmin_peak_force = \"4 nN\"\nreject_non_repulsive = true\n",
    )
    .unwrap();
    let mut s = st.section("build").unwrap();
    let a = Admissibility::from_section(&mut s, 3).unwrap();
    s.finish().unwrap();
    assert!((a.min_peak_force.unwrap() - 4e-9).abs() < 1e-24);
    assert!(a.reject_non_repulsive);
    assert_eq!(a.contact_index, 3);
    let mut st = Study::parse("b.toml", "[build]\nmin_peak_force = \"4 nm\"\n").unwrap();
    let mut s = st.section("build").unwrap();
    let e = Admissibility::from_section(&mut s, 0)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("b.toml:2") && e.contains("build.min_peak_force"),
        "{e}"
    );
}

/// The bundled demo meta-model (`examples/demo/metamodel/`) was built from
/// `examples/demo/metamodel.toml` before the parameter domain moved to
/// `nlvid_model`: its training design — hence the study hash of its run
/// store, which a resumed build compares — is reproduced bit for bit, and
/// the domain stored in its `meta.json` is the one of its `[design]`.
#[test]
fn the_bundled_demo_design_reproduces_its_study_hash_and_domain() {
    let demo = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/demo");
    let mut study = Study::load(demo.join("metamodel.toml")).unwrap();
    let model = nlvid_forward::from_study(&mut study).unwrap();
    let mut ds = study.section("design").unwrap();
    let d =
        DesignSettings::from_section(&mut ds, &model.parameter_names(), &model.parameter_units())
            .unwrap();
    ds.finish().unwrap();
    let (train, _) = d.designs().unwrap();
    let meta = nlvid_surrogate::StoreMeta::new(
        model.parameter_names(),
        model.parameter_units(),
        model.time_grid().to_vec(),
        train,
        model.identity(),
    );
    let committed: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(demo.join("metamodel/meta.json")).unwrap())
            .unwrap();
    assert_eq!(meta.study_hash, committed["study_hash"].as_str().unwrap());
    let stored: Domain = serde_json::from_value(committed["domain"].clone()).unwrap();
    assert_eq!(stored, d.domain);
}

/// The capsule example study (`examples/metamodel/capsule-rh.toml`) reads
/// to the `capsule-fe` model and its `[design]` to Table 4.1's domain
/// (`Domain::table_4_1`), with the thesis's N = 492 and M = 92; every design
/// point satisfies g1 + g2 ≤ 0.99.
#[test]
fn the_capsule_study_designs_over_table_4_1() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples/metamodel/capsule-rh.toml");
    let mut study = Study::load(&path).unwrap();
    let model = nlvid_forward::from_study(&mut study).unwrap();
    let mut ds = study.section("design").unwrap();
    let d =
        DesignSettings::from_section(&mut ds, &model.parameter_names(), &model.parameter_units())
            .unwrap();
    ds.finish().unwrap();
    assert_eq!(d.domain, Domain::table_4_1(0.01).unwrap());
    let (train, check) = d.designs().unwrap();
    assert_eq!((train.len(), check.len()), (492, 92));
    assert!(
        train
            .iter()
            .chain(&check)
            .all(|x| d.domain.contains(x, 1e-12))
    );
}

#[test]
fn infill_subsection_is_read_and_checked() {
    let with = |extra: &str| format!("{DESIGN}\n[design.infill]\n{extra}");
    let d = read(&with(
        "initial = 12\nbatch = 4\ntarget_max_error = 0.01\nproportional_to = \"G0\"\n",
    ))
    .unwrap();
    let i = d.infill.clone().unwrap();
    assert_eq!(
        (i.initial, i.batch, i.target_max_error, i.proportional_to),
        (12, 4, Some(0.01), Some(0))
    );
    assert_eq!((i.candidates, i.pca_energy), (4000, Some(1.0 - 1e-6)));
    // The training design is the starting Latin hypercube; the checking
    // design is the one without infill.
    let (train, check) = d.designs().unwrap();
    let plain = read(DESIGN).unwrap();
    assert_eq!(train.len(), 12);
    assert_eq!(check, plain.designs().unwrap().1);
    for (text, key) in [
        (with("batch = 4\n"), "design.infill.initial"),
        (with("initial = 25\n"), "design.infill.initial"),
        (
            with("initial = 12\nproportional_to = \"E\"\n"),
            "design.infill.proportional_to",
        ),
        (
            with("initial = 12\ntarget_max_error = 0\n"),
            "design.infill.target_max_error",
        ),
        (with("initial = 12\nbatches = 3\n"), "design.infill.batches"),
    ] {
        let e = read(&text).unwrap_err();
        assert!(
            e.contains("d.toml:") && e.contains(key),
            "expected `{key}` in: {e}"
        );
    }
}
