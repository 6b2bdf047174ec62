"""afmformats' data objects in nlvid (duck-typed: afmformats is optional).

With afmformats installed (scripts/test-python.sh installs it from PyPI when
it can), every public JPK test file is read by afmformats and by nlvid's own
reader: the curve made from afmformats' columns (`ForceCurve.from_columns`)
has the segments, kinds, times, force and heights nlvid's reader reads, and
the Hertz and Lee-Radok fits give the same values from either. Without
afmformats those tests are skipped with a message; the dict-of-columns tests
run regardless."""

import numpy as np
import pytest

import nlvid

DATA = "crates/afm/tests/data"
FILES = [
    "fmt-jpk-fd_spot3-0192.jpk-force",
    "fmt-jpk-fd_map2x2_extracted.jpk-force-map",
    "fmt-jpk-sr_cell1-0008.jpk-force",
    "fmt-jpk-cc_pr14-brain-2021.06.30.jpk-force",
    "fmt-jpk-fd_flipsign_2015.05.22-15.31.49.352.jpk-force",
]
MEASURED = ("strainGaugeHeight", "capacitiveSensorHeight", "measuredHeight")


@pytest.fixture(scope="module")
def afmformats():
    return pytest.importorskip(
        "afmformats",
        reason="afmformats is not installed in this venv (pip install afmformats); "
        "the comparison with nlvid's JPK reader is skipped",
    )


def measured_height(channels):
    for name in MEASURED:
        if name in channels:
            return channels[name]
    return channels["height"]


@pytest.mark.parametrize("name", FILES)
def test_afmformats_columns_are_what_nlvid_reads(root, afmformats, name):
    path = root / DATA / name
    theirs = afmformats.load_data(path)
    ours = nlvid.read_jpk(path)
    assert len(theirs) == len(ours)
    for a, o in zip(theirs[:2], ours[:2]):
        c = nlvid.ForceCurve.from_columns(a)
        assert len(c) == len(o)
        assert c.metadata["spring_constant_N_per_m"] == pytest.approx(
            o.metadata["spring_constant_N_per_m"], rel=1e-15
        )
        # Segment kinds inferred from the piezo height are the JPK headers'.
        assert [s["kind"] for s in c.segments] == [s["kind"] for s in o.segments]
        for sc, so in zip(c.segments, o.segments):
            np.testing.assert_allclose(sc["time"], so["time"], rtol=0, atol=1e-12)
            assert sc["duration"] == pytest.approx(so["duration"], rel=1e-9)
            f_c, f_o = sc["channels"]["vDeflection"], so["channels"]["vDeflection"]
            scale = np.abs(f_o).max()
            np.testing.assert_allclose(f_c, f_o, rtol=0, atol=5e-13 * scale)
            h_o = measured_height(so["channels"])
            np.testing.assert_allclose(
                sc["channels"]["measuredHeight"], h_o, rtol=0, atol=5e-13 * np.abs(h_o).max()
            )
            np.testing.assert_allclose(
                sc["channels"]["height"], so["channels"]["height"], rtol=0,
                atol=5e-13 * np.abs(so["channels"]["height"]).max(),
            )


@pytest.mark.parametrize("name", FILES[:2] + FILES[4:])
def test_hertz_on_an_afmformats_object_is_hertz_on_nlvid_reading(root, afmformats, name):
    path = root / DATA / name
    a, o = afmformats.load_data(path)[0], nlvid.read_jpk(path)[0]
    fa = nlvid.hertz(a, tip_radius="5 um")
    fo = nlvid.hertz(o, tip_radius="5 um")
    for k in ("youngs_modulus_Pa", "contact_point_m", "offset_N"):
        assert fa[k] == pytest.approx(fo[k], rel=1e-9, abs=1e-20), k
    assert fa["n_points"] == fo["n_points"]


def test_lee_radok_on_an_afmformats_object_is_lee_radok_on_nlvid_reading(root, afmformats):
    path = root / DATA / "fmt-jpk-sr_cell1-0008.jpk-force"
    a, o = afmformats.load_data(path)[0], nlvid.read_jpk(path)[0]
    fa = nlvid.lee_radok(a, tip_radius="5 um", terms=2)
    fo = nlvid.lee_radok(o, tip_radius="5 um", terms=2)
    for k in ("g0_Pa", "g_inf_Pa", "rmse_N", "contact_time_s"):
        assert fa[k] == pytest.approx(fo[k], rel=1e-6), k
    for ta, to in zip(fa["terms"], fo["terms"]):
        assert ta["tau_s"] == pytest.approx(to["tau_s"], rel=1e-6)
    np.testing.assert_allclose(fa["plot"]["model_nN"], fo["plot"]["model_nN"], rtol=1e-6)


def columns_of(curve):
    """A nlvid curve as a dict of afmformats-style columns (SI)."""
    cols = {"force": [], "height (measured)": [], "height (piezo)": [], "time": [], "segment": []}
    for k, s in enumerate(curve.segments):
        ch = s["channels"]
        cols["force"].append(ch["vDeflection"])
        cols["height (measured)"].append(measured_height(ch))
        cols["height (piezo)"].append(ch["height"])
        cols["time"].append(s["time"])
        cols["segment"].append(np.full(len(s["time"]), k, dtype=np.uint8))
    return {k: np.concatenate(v) for k, v in cols.items()}


def test_a_dict_of_columns_is_a_curve(root):
    (o,) = nlvid.read_jpk(root / DATA / "fmt-jpk-sr_cell1-0008.jpk-force")
    cols = columns_of(o)
    meta = {"spring constant": o.metadata["spring_constant_N_per_m"]}
    c = nlvid.ForceCurve.from_columns(cols, metadata=meta, source="dict")
    assert [s["kind"] for s in c.segments] == ["hold", "extend", "hold", "retract"]
    fo = nlvid.hertz(o, tip_radius="5 um")
    fc = nlvid.hertz(c, tip_radius="5 um")
    assert fc["youngs_modulus_Pa"] == fo["youngs_modulus_Pa"]


def test_bad_columns_raise_clear_errors(root):
    (o,) = nlvid.read_jpk(root / DATA / "fmt-jpk-fd_spot3-0192.jpk-force")
    cols = columns_of(o)
    with pytest.raises(nlvid.InputError, match="spring constant"):
        nlvid.hertz(cols, tip_radius="5 um")
    meta = {"spring constant": 0.04}
    with pytest.raises(nlvid.InputError, match="no column `force`"):
        nlvid.ForceCurve.from_columns({"time": cols["time"]}, metadata=meta)
    short = dict(cols, time=cols["time"][:-1])
    with pytest.raises(nlvid.InputError, match="one length"):
        nlvid.ForceCurve.from_columns(short, metadata=meta)
    bad = dict(cols, force=cols["force"].copy())
    bad["force"][7] = np.nan
    with pytest.raises(nlvid.InputError, match="index 7"):
        nlvid.ForceCurve.from_columns(bad, metadata=meta)
    shuffled = dict(cols, segment=cols["segment"][::-1].copy())
    with pytest.raises(nlvid.InputError, match="recording order"):
        nlvid.ForceCurve.from_columns(shuffled, metadata=meta)
    with pytest.raises(nlvid.InputError, match="afmformats"):
        nlvid.hertz(42, tip_radius="5 um")
