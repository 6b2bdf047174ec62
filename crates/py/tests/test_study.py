"""load_study / parse_study against `nlvid --json check`."""

import pytest

import nlvid

STUDIES = [
    "examples/metamodel/afm-fe.toml",
    "examples/metamodel/membrane.toml",
    "examples/study/capsule-compression.toml",
    "examples/demo/study.toml",
]


@pytest.mark.parametrize("rel", STUDIES)
def test_check_report_is_the_cli_document(root, cli, rel):
    st = nlvid.load_study(root / rel)
    assert st.check_report() == cli.run("check", root / rel)


def test_values_in_si(tmp_path):
    p = tmp_path / "s.toml"
    p.write_text('[geometry]\nradius = "12.22 um"\n[protocol]\nkind = "ramp-hold"\n'
                 'displacement = "0.6 mm"\nspeed = "5 mm/s"\nhold = "3 s"\n')
    d = nlvid.load_study(p).as_dict()
    assert d["geometry.radius"] == pytest.approx(12.22e-6, rel=1e-15)
    assert d["protocol.speed"] == pytest.approx(5e-3, rel=1e-15)


def test_bad_unit_names_file_line_key_like_the_cli(tmp_path, cli):
    p = tmp_path / "bad.toml"
    p.write_text('[protocol]\nkind = "ramp-hold"\ndisplacement = "0.6 mm"\n'
                 'speed = "5 mm"\nhold = "3 s"\n')
    with pytest.raises(nlvid.StudyError) as e:
        nlvid.load_study(p)
    assert str(e.value) == cli.error("check", p)
    assert e.value.line == 4
    assert e.value.key == "protocol.speed"
    assert e.value.file == str(p)
    assert isinstance(e.value, nlvid.NlvidError)


def test_syntax_error_and_missing_file(tmp_path, cli):
    p = tmp_path / "syntax.toml"
    p.write_text("[a]\nx = = 1\n")
    with pytest.raises(nlvid.StudyError) as e:
        nlvid.load_study(p)
    assert e.value.line == 2 and e.value.key is None
    assert str(e.value) == cli.error("check", p)
    with pytest.raises(nlvid.StudyError) as e:
        nlvid.load_study(tmp_path / "missing.toml")
    assert str(e.value) == cli.error("check", tmp_path / "missing.toml")


def test_non_finite_number_is_an_error_with_its_key(tmp_path, cli):
    p = tmp_path / "nan.toml"
    p.write_text("[x]\na = 1.0\nb = nan\n")
    with pytest.raises(nlvid.StudyError) as e:
        nlvid.load_study(p)
    assert str(e.value) == cli.error("check", p)
    assert (e.value.line, e.value.key) == (3, "x.b")


def test_parse_study_and_strict(tmp_path):
    st = nlvid.parse_study('[a]\nlength = "3 furlongs"\n', name="inline.toml")
    assert st.name == "inline.toml" and len(st.warnings) == 1
    with pytest.raises(nlvid.StudyError, match="strict"):
        nlvid.parse_study('[a]\nlength = "3 furlongs"\n', strict=True)
    with pytest.raises(TypeError):
        nlvid.simulate(42)
