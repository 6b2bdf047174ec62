//! Whole-file behaviour: hash stability, SI view, paths, readers for stages.
#![allow(clippy::unwrap_used)] // test helpers outside #[test] fns

use nlvid_study::{Bounds, Dimension, FromSection, LeafValue, Section, Study, StudyError};

#[test]
fn hash_ignores_comments_order_and_spelling_but_not_values() {
    let a = "# capsule\n[g]\nr = \"1 um\"\nn = 1000.0\n[p]\nv = \"5 mm/s\"\n";
    let b = "[p]\nv = \"5 mm/s\"  # speed\n\n[g]\nn = 1e3\nr = \"1 um\"\n";
    let c = "g = { r = \"1 um\", n = 1_000.0 }\np.v = \"5 mm/s\"\n";
    let d = "[g]\nr = \"1 um\"\nn = 1000.0\n[p]\nv = \"6 mm/s\"\n";
    let h = |t: &str| *Study::parse("x.toml", t).unwrap().hash();
    assert_eq!(h(a), h(b));
    assert_eq!(h(a), h(c));
    assert_ne!(h(a), h(d));
    assert_eq!(h(a).to_string().len(), 64);
    assert_eq!(h(a).short().len(), 12);
}

#[test]
fn hash_of_empty_study_is_sha256_of_the_documented_canonical_text() {
    // Canonical text of an empty file: the tag line then "{}" (see StudyHash docs).
    // Reference digest computed independently: printf 'nlvid-study-v1\n{}' | sha256sum
    let h = Study::parse("e.toml", "").unwrap().hash().to_string();
    assert_eq!(h, EMPTY_DIGEST);
}
const EMPTY_DIGEST: &str = include_str!("../empty_digest.txt");

#[test]
fn leaves_show_quantities_in_si_with_lines() {
    let t =
        "title = \"demo\"\n[g]\nr = \"12.22 um\"\nnu = 0.3\nn = 4\ntau = [\"1 s\", \"10 ms\"]\n";
    let study = Study::parse("x.toml", t).unwrap();
    let leaves = study.leaves();
    let keys: Vec<&str> = leaves.iter().map(|l| l.key.as_str()).collect();
    assert_eq!(
        keys,
        ["title", "g.r", "g.nu", "g.n", "g.tau[0]", "g.tau[1]"]
    );
    assert_eq!(leaves[0].value, LeafValue::Text("demo".into()));
    match &leaves[1].value {
        LeafValue::Quantity { si, .. } => {
            assert_eq!(si.dim, Dimension::LENGTH);
            assert!((si.value - 12.22e-6).abs() < 1e-18);
        }
        v => panic!("{v:?}"),
    }
    assert_eq!(leaves[1].line, 3);
    assert_eq!(leaves[3].value, LeafValue::Integer(4));
    assert_eq!(leaves[5].line, 6);
}

#[test]
fn paths_resolve_against_the_study_directory() {
    let dir = std::env::temp_dir().join(format!("nlvid-study-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("curve.csv"), "time_s\n0\n").unwrap();
    let file = dir.join("s.toml");
    std::fs::write(
        &file,
        "[data]\ncurve = \"curve.csv\"\nmissing = \"nope.csv\"\n",
    )
    .unwrap();
    let mut study = Study::load(&file).unwrap();
    let mut d = study.section("data").unwrap();
    assert_eq!(d.req_input_file("curve").unwrap(), dir.join("curve.csv"));
    let e = d.req_input_file("missing").unwrap_err().to_string();
    assert!(
        e.contains(":3:11: key `data.missing`: no such file:"),
        "{e}"
    );
    assert!(e.contains("nope.csv"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[derive(Debug, PartialEq)]
struct Prony {
    g: Vec<f64>,
    tau: Vec<f64>,
}

impl FromSection for Prony {
    fn from_section(s: &mut Section) -> Result<Self, StudyError> {
        let g = s.req_f64s("g", 0.0..=1.0)?;
        let tau = s.req_quantities("tau", Dimension::TIME, Bounds::positive())?;
        if g.len() != tau.len() {
            return Err(s.invalid(
                "tau",
                format!("{} relaxation times for {} weights", tau.len(), g.len()),
            ));
        }
        Ok(Self { g, tau })
    }
}

#[test]
fn stage_structs_read_nested_sections_and_report_their_own_checks() {
    let t = "[material.prony]\ng = [0.3, \"20 %\"]\ntau = [\"0.5 s\", \"2 min\"]\n";
    let mut study = Study::parse("x.toml", t).unwrap();
    let mut m = study.section("material").unwrap();
    let p: Prony = m.read("prony").unwrap();
    m.finish().unwrap();
    study.finish().unwrap();
    assert_eq!(p.g, vec![0.3, 0.2]);
    assert_eq!(p.tau, vec![0.5, 120.0]);

    let t = "[material.prony]\ng = [0.3]\ntau = [\"0.5 s\", \"2 min\"]\n";
    let mut study = Study::parse("x.toml", t).unwrap();
    let e = study
        .section("material")
        .unwrap()
        .read::<Prony>("prony")
        .unwrap_err();
    assert_eq!(
        e.to_string(),
        "x.toml:3:7: key `material.prony.tau`: 2 relaxation times for 1 weights"
    );
}
