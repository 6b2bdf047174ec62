"""read_jpk, hertz, lee_radok against `nlvid --json inspect` on the public
JPK curves of crates/afm/tests/data; fit_hertz and fit_lee_radok against
closed forms; nanite's published Hertz moduli (nanite_hertz.csv)."""

import csv
import math

import numpy as np
import pytest

import nlvid

DATA = "crates/afm/tests/data"
FILES = [
    "fmt-jpk-sr_cell1-0008.jpk-force",
    "fmt-jpk-fd_spot3-0192.jpk-force",
    "fmt-jpk-fd_map2x2_extracted.jpk-force-map",
    "fmt-jpk-fd_2020.02.07-16.29.05.036.jpk-qi-data",
    "fmt-jpk-fd_flipsign_2015.05.22-15.31.49.352.jpk-force",
    "fmt-jpk-cc_pr14-brain-2021.06.30.jpk-force",
]


@pytest.mark.parametrize("name", FILES)
def test_read_jpk_is_the_cli_reading(root, cli, name):
    path = root / DATA / name
    curves = nlvid.read_jpk(path)
    for i, c in enumerate(curves[:2]):
        ref = cli.run("inspect", path, "--samples", "--curve", i)
        assert c.summary(samples=True) == ref
        seg = c.segments[0]
        assert seg["time"].dtype == np.float64
        assert len(seg["time"]) == len(next(iter(seg["channels"].values())))
        assert c.metadata["curves_in_file"] == len(curves)


def test_calibration_published_values(root):
    # crates/afm/tests/data/README.md: k = 1.0677 N/m, sensitivity 110.28 nm/V.
    (c,) = nlvid.read_jpk(root / DATA / "fmt-jpk-sr_cell1-0008.jpk-force")
    m = c.metadata
    assert m["spring_constant_N_per_m"] == pytest.approx(1.0677, rel=1e-4)
    assert m["sensitivity_m_per_V"] == pytest.approx(110.28e-9, rel=1e-4)
    kinds = [s["kind"] for s in c.segments]
    assert kinds[1:3] == ["extend", "hold"]
    (o,) = nlvid.read_jpk(root / DATA / "fmt-jpk-sr_cell1-0008.jpk-force",
                          spring_constant="0.5 N/m")
    assert o.metadata["spring_constant_N_per_m"] == 0.5
    assert o.metadata["spring_constant_source"] == "override"


def nanite_rows(root):
    with open(root / DATA / "nanite_hertz.csv") as f:
        rows = [r for r in csv.DictReader(l for l in f if not l.startswith("#"))]
    return [r for r in rows if "!" not in r["file"]]


def test_hertz_is_the_cli_fit_and_agrees_with_nanite(root, cli):
    for r in nanite_rows(root):
        path = root / DATA / r["file"]
        i = int(r["curve"] or 0)
        radius = f"{float(r['radius_m']) * 1e9:g} nm"
        curve = nlvid.read_jpk(path)[i]
        f = nlvid.hertz(curve, tip_radius=radius)
        ref = cli.run("inspect", path, "--curve", i, "--fit", "hertz", "--tip-radius", radius)["fit"]
        assert {k: f[k] for k in ref} == ref, r["file"]
        # nanite 4.2.3 (lmfit) on the same points: within its own stopping accuracy.
        e_nanite = float(r["E_nanite_Pa"])
        assert abs(f["youngs_modulus_Pa"] / e_nanite - 1) < 2e-4, (r["file"], i)
        assert f["n_points"] == int(r["points"])


def test_lee_radok_is_the_cli_fit(root, cli):
    path = root / DATA / "fmt-jpk-sr_cell1-0008.jpk-force"
    (curve,) = nlvid.read_jpk(path)
    f = nlvid.lee_radok(curve, tip_radius="5 um", terms=2)
    ref = cli.run("inspect", path, "--fit", "lee-radok", "--tip-radius", "5 um", "--terms", 2)["fit"]
    assert {k: f[k] for k in ref} == ref
    assert f["g0_Pa"] > f["g_inf_Pa"] > 0


def test_fit_hertz_recovers_a_closed_form_curve():
    # Eq. 1.1, paraboloid: F = 4/3 E/(1-nu^2) sqrt(R) delta^1.5 plus an offset.
    E, R, nu, sc, b = 2.0e3, 5e-6, 0.5, 3e-6, 1e-11
    s = np.linspace(4e-6, 1e-6, 400)
    delta = np.clip(sc - s, 0, None)
    F = b + 4.0 / 3.0 * E / (1 - nu**2) * math.sqrt(R) * delta**1.5
    f = nlvid.fit_hertz(s, F, tip_radius="5 um", poisson=nu)
    assert f["youngs_modulus_Pa"] == pytest.approx(E, rel=1e-6)
    assert f["contact_point_m"] == pytest.approx(sc, rel=1e-6)
    assert f["offset_N"] == pytest.approx(b, rel=1e-4)


def test_fit_lee_radok_recovers_an_elastic_ramp():
    # No relaxation: G(t) = G0, so Lee-Radok reduces to Hertz with E = 3 G0
    # (nu = 0.5): F = 16/3 G0 sqrt(R) delta^1.5 on a ramp delta = v t.
    G0, R, v = 500.0, 5e-6, 1e-6
    t = np.linspace(0.0, 2.0, 201)
    delta = v * t
    F = 16.0 / 3.0 * G0 * math.sqrt(R) * delta**1.5
    f = nlvid.fit_lee_radok(t, delta, F, tip_radius="5 um", terms=1)
    assert f["g0_Pa"] == pytest.approx(G0, rel=1e-3)
    assert f["range_normalised_rmse"] < 1e-3


def test_bad_inputs(root):
    s = np.linspace(4e-6, 1e-6, 50)
    with pytest.raises(nlvid.InputError, match="unit"):
        nlvid.fit_hertz(s, s, tip_radius=5e-6)
    with pytest.raises(ValueError, match="no unit"):
        nlvid.fit_hertz(s, s, tip_radius="5")
    with pytest.raises(nlvid.InputError, match="length"):
        nlvid.fit_hertz(s, s, tip_radius="5 kPa")
    with pytest.raises(nlvid.InputError, match="one length"):
        nlvid.fit_hertz(s, s[:-1], tip_radius="5 um")
    bad = s.copy()
    bad[7] = np.inf
    with pytest.raises(nlvid.InputError, match="index 7"):
        nlvid.fit_hertz(s, bad, tip_radius="5 um")
    with pytest.raises(TypeError, match="float64"):
        nlvid.fit_hertz(s.astype(np.int32), s, tip_radius="5 um")
    with pytest.raises(nlvid.NlvidError, match="reading"):
        nlvid.read_jpk(root / "README.md")
    (c,) = nlvid.read_jpk(root / DATA / "fmt-jpk-fd_spot3-0192.jpk-force")
    with pytest.raises(nlvid.InputError, match="contact"):
        nlvid.hertz(c, tip_radius="40 nm", contact="magic")
