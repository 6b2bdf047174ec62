//! Every kind of bad input gives an error naming file, line, column and key.
//! Expected lines and columns are counted by hand from the texts below.
#![allow(clippy::unwrap_used)] // test helpers outside #[test] fns

use nlvid_study::{Bounds, Dimension, ErrorKind, Section, Study, StudyError};

fn section(text: &str, name: &str) -> Section {
    Study::parse("bad.toml", text)
        .unwrap()
        .section(name)
        .unwrap()
}

fn msg(r: Result<impl std::fmt::Debug, StudyError>) -> String {
    r.unwrap_err().to_string()
}

#[test]
fn unknown_key_is_reported_with_its_line_and_the_expected_keys() {
    let text = "[geometry]\nradius = \"1 um\"\nradisu = \"2 um\"\n";
    let mut s = section(text, "geometry");
    s.req_quantity("radius", Dimension::LENGTH, Bounds::positive())
        .unwrap();
    assert_eq!(
        msg(s.finish()),
        "bad.toml:3:1: key `geometry.radisu`: unknown key: did you mean `radius`? (expected one of: radius)"
    );
}

#[test]
fn unknown_top_level_section_is_reported() {
    let text = "[geometry]\nradius = \"1 um\"\n\n[protocl]\nspeed = \"1 um/s\"\n";
    let mut study = Study::parse("bad.toml", text).unwrap();
    let mut g = study.section("geometry").unwrap();
    g.req_quantity("radius", Dimension::LENGTH, ..).unwrap();
    g.finish().unwrap();
    let _ = study.opt_section("protocol").unwrap();
    assert_eq!(
        msg(study.finish()),
        "bad.toml:4:2: key `protocl`: unknown key: did you mean `protocol`? (expected one of: geometry, protocol)"
    );
}

#[test]
fn missing_unit_names_the_expected_dimension_and_an_example() {
    let text = "[g]\n\nradius = 12.22\n";
    let e = section(text, "g").req_quantity("radius", Dimension::LENGTH, ..);
    let e = e.unwrap_err();
    assert!(matches!(e.kind(), Some(ErrorKind::MissingUnit { .. })));
    assert_eq!(
        e.to_string(),
        "bad.toml:3:10: key `g.radius`: `12.22` has no unit; expected a length (m), e.g. \"12.22 um\""
    );
    // A unit-less string is the same mistake.
    let text = "[g]\nradius = \"12.22\"\n";
    assert_eq!(
        msg(section(text, "g").req_quantity("radius", Dimension::LENGTH, ..)),
        "bad.toml:2:10: key `g.radius`: `12.22` has no unit; expected a length (m), e.g. \"12.22 um\""
    );
    // Integers too.
    let text = "[g]\nhold = 50\n";
    assert_eq!(
        msg(section(text, "g").req_quantity("hold", Dimension::TIME, ..)),
        "bad.toml:2:8: key `g.hold`: `50` has no unit; expected a time (s), e.g. \"50 s\""
    );
}

#[test]
fn wrong_dimension_names_both_dimensions() {
    let text = "[material]\nC1 = \"0.12 N/m\"\n";
    assert_eq!(
        msg(section(text, "material").req_quantity("C1", Dimension::PRESSURE, Bounds::positive())),
        "bad.toml:2:6: key `material.C1`: `0.12 N/m` is a force per length (N/m), expected a pressure or stress (Pa)"
    );
}

#[test]
fn unknown_unit_is_named() {
    let text = "[p]\nspeed = \"5 mm/sec\"\n";
    let m = msg(section(text, "p").req_quantity("speed", Dimension::VELOCITY, ..));
    assert!(
        m.starts_with("bad.toml:2:9: key `p.speed`: cannot read `5 mm/sec`: unknown unit `sec`"),
        "{m}"
    );
}

#[test]
fn nan_and_infinity_are_rejected_as_strings_and_as_toml_floats() {
    let text = "[p]\na = \"NaN s\"\nb = nan\nc = -inf\nd = \"1e400 m\"\n";
    let mut s = section(text, "p");
    assert_eq!(
        msg(s.req_quantity("a", Dimension::TIME, ..)),
        "bad.toml:2:5: key `p.a`: `NaN s` is not a finite number"
    );
    assert_eq!(
        msg(s.req_f64("b", ..)),
        "bad.toml:3:5: key `p.b`: `NaN` is not a finite number"
    );
    // A dimensioned key given a non-finite bare float: non-finiteness is reported first.
    assert_eq!(
        msg(s.req_quantity("c", Dimension::LENGTH, ..)),
        "bad.toml:4:5: key `p.c`: `-inf` is not a finite number"
    );
    assert_eq!(
        msg(s.req_quantity("d", Dimension::LENGTH, ..)),
        "bad.toml:5:5: key `p.d`: `1e400 m` is not a finite number"
    );
}

#[test]
fn out_of_range_shows_value_and_bounds_in_si() {
    let text = "[g]\nradius = \"-1.5 mm\"\nnu = 0.7\n";
    let mut s = section(text, "g");
    assert_eq!(
        msg(s.req_quantity("radius", Dimension::LENGTH, Bounds::positive())),
        "bad.toml:2:10: key `g.radius`: -0.0015 m (from `-1.5 mm`) is out of range: must be > 0 m"
    );
    assert_eq!(
        msg(s.req_f64("nu", 0.0..=0.5)),
        "bad.toml:3:6: key `g.nu`: 0.7 is out of range: must be in [0, 0.5]"
    );
}

#[test]
fn missing_required_key_points_at_the_table_header() {
    let text = "title = \"x\"\n\n[geometry]\nheight = \"5 um\"\n";
    let mut s = section(text, "geometry");
    let e = s.req_quantity("radius", Dimension::LENGTH, ..).unwrap_err();
    assert!(matches!(e.kind(), Some(ErrorKind::MissingKey { .. })));
    assert_eq!(
        e.to_string(),
        "bad.toml:3:2: key `geometry.radius`: missing required key (a length (m), e.g. \"1 um\")"
    );
    // A missing section is reported at the top of the file.
    let mut study = Study::parse("bad.toml", text).unwrap();
    assert_eq!(
        msg(study.section("protocol")),
        "bad.toml:1:1: key `protocol`: missing required key (a table)"
    );
}

#[test]
fn wrong_types_are_named() {
    let text = "[a]\nn = 2.5\nflag = \"yes\"\nname = 3\nr = true\nsub = 1\nlist = \"1 s\"\n";
    let mut s = section(text, "a");
    assert_eq!(
        msg(s.req_usize("n", ..)),
        "bad.toml:2:5: key `a.n`: expected a non-negative integer, found a float"
    );
    assert_eq!(
        msg(s.req_bool("flag")),
        "bad.toml:3:8: key `a.flag`: expected true or false, found a string"
    );
    assert_eq!(
        msg(s.req_str("name")),
        "bad.toml:4:8: key `a.name`: expected a string, found an integer"
    );
    assert_eq!(
        msg(s.req_quantity("r", Dimension::LENGTH, ..)),
        "bad.toml:5:5: key `a.r`: expected a quantity string such as \"1 um\", found a boolean"
    );
    assert_eq!(
        msg(s.subsection("sub")),
        "bad.toml:6:7: key `a.sub`: expected a table, found an integer"
    );
    assert_eq!(
        msg(s.req_quantities("list", Dimension::TIME, ..)),
        "bad.toml:7:8: key `a.list`: expected an array of time (s), found a string"
    );
}

#[test]
fn bad_choice_lists_the_allowed_values() {
    let text = "[m]\nmodel = \"qvl\"\n";
    #[derive(Clone, Copy, Debug)]
    enum M {
        Qlv,
        Pr,
    }
    let e = section(text, "m").req_enum("model", &[("qlv", M::Qlv), ("pipkin-rogers", M::Pr)]);
    assert_eq!(
        msg(e),
        "bad.toml:2:9: key `m.model`: `qvl` is not one of: qlv, pipkin-rogers"
    );
}

#[test]
fn array_elements_are_named_by_index() {
    let text = "[m]\ntau = [\"1 s\", \"10 ms\", \"3 m\"]\n";
    assert_eq!(
        msg(section(text, "m").req_quantities("tau", Dimension::TIME, Bounds::positive())),
        "bad.toml:2:24: key `m.tau[2]`: `3 m` is a length (m), expected a time (s)"
    );
}

#[test]
fn errors_in_arrays_of_tables_name_the_element() {
    let text = "[[experiment]]\nspeed = \"1 um/s\"\n\n[[experiment]]\nspeed = \"1 um\"\n";
    let mut study = Study::parse("bad.toml", text).unwrap();
    let mut ex = study.root().tables("experiment").unwrap();
    assert_eq!(ex.len(), 2);
    ex[0]
        .req_quantity("speed", Dimension::VELOCITY, ..)
        .unwrap();
    assert_eq!(
        msg(ex[1].req_quantity("speed", Dimension::VELOCITY, ..)),
        "bad.toml:5:9: key `experiment[1].speed`: `1 um` is a length (m), expected a velocity (m/s)"
    );
}

#[test]
fn toml_syntax_errors_have_a_line() {
    let text = "[g]\nradius = \"1 um\n";
    let e = Study::parse("bad.toml", text).unwrap_err();
    assert!(matches!(e, StudyError::Syntax { .. }));
    assert!(e.to_string().starts_with("bad.toml:2:"), "{e}");
    let text = "[g]\na = 1\na = 2\n";
    let e = Study::parse("bad.toml", text).unwrap_err();
    assert!(e.to_string().starts_with("bad.toml:3:"), "{e}");
}

#[test]
fn unreadable_file_names_the_path() {
    let e = Study::load("/nonexistent/nowhere.toml").unwrap_err();
    assert!(
        e.to_string()
            .starts_with("/nonexistent/nowhere.toml: cannot read study file"),
        "{e}"
    );
}

#[test]
fn stage_checks_are_located_at_the_key() {
    let text = "[g]\nouter = \"1 um\"\ninner = \"2 um\"\n";
    let mut s = section(text, "g");
    let outer = s.req_quantity("outer", Dimension::LENGTH, ..).unwrap();
    let inner = s.req_quantity("inner", Dimension::LENGTH, ..).unwrap();
    assert!(inner > outer);
    assert_eq!(
        s.invalid("inner", "must be smaller than `outer`")
            .to_string(),
        "bad.toml:3:9: key `g.inner`: must be smaller than `outer`"
    );
}

#[test]
fn unknown_keys_in_nested_tables_are_reported_on_finish() {
    let text =
        "[material]\nmodel = \"qlv\"\n[material.prony]\ng = [0.5]\ntau = [\"1 s\"]\ntua = 3\n";
    let mut study = Study::parse("bad.toml", text).unwrap();
    let mut m = study.section("material").unwrap();
    m.req_str("model").unwrap();
    let mut p = m.subsection("prony").unwrap();
    m.finish().unwrap();
    p.req_f64s("g", 0.0..=1.0).unwrap();
    p.req_quantities("tau", Dimension::TIME, Bounds::positive())
        .unwrap();
    assert_eq!(
        msg(p.finish()),
        "bad.toml:6:1: key `material.prony.tua`: unknown key: did you mean `tau`? (expected one of: g, tau)"
    );
}

#[test]
fn ranges_need_two_ordered_values_of_the_right_dimension() {
    let text = "[bounds]\nC1 = [\"1 kPa\", \"10 kPa\"]\nC2 = [\"10 kPa\", \"1 kPa\"]\ntau = [\"1 s\"]\ng = [0.1, \"2 s\"]\n";
    let mut s = section(text, "bounds");
    assert_eq!(
        s.req_range("C1", Dimension::PRESSURE, Bounds::positive())
            .unwrap(),
        (1000.0, 10000.0)
    );
    assert_eq!(
        msg(s.req_range("C2", Dimension::PRESSURE, Bounds::positive())),
        "bad.toml:3:6: key `bounds.C2`: lower end must be below upper end"
    );
    assert_eq!(
        msg(s.req_range("tau", Dimension::TIME, Bounds::positive())),
        "bad.toml:4:7: key `bounds.tau`: expected [lower, upper] (2 values), found 1 value(s)"
    );
    assert_eq!(
        msg(s.req_range("g", Dimension::NONE, 0.0..=1.0)),
        "bad.toml:5:11: key `bounds.g[1]`: `2 s` is a time (s), expected a dimensionless number"
    );
}

#[test]
fn a_renamed_key_names_its_replacement_and_its_line() {
    let s = section("[m]\nx = 1\nold = \"2 Pa\"\n", "m");
    let e = msg(s
        .renamed("old", "new", "it meant half of `new`")
        .map(|_| ()));
    assert!(e.contains("bad.toml:3"), "{e}");
    assert!(
        e.contains("m.old") && e.contains("write `new`") && e.contains("half of"),
        "{e}"
    );
    assert!(s.renamed("absent", "new", "").is_ok());
}
