"""fit (arrays and files) against `nlvid --json fit` on the bundled demo
meta-model and a demo cell."""

import csv

import numpy as np
import pytest

import nlvid
from conftest import write_csv

K = 0.12  # N/m, [fit.calibration] of the study below


def study(root, tmp_path, extra=""):
    meta = root / "examples/demo/metamodel"
    p = tmp_path / "fit.toml"
    p.write_text(f"""
title = "fit of a demo cell"
[fit]
surrogate = "{meta / 'model.json'}"
meta = "{meta / 'meta.json'}"
check = "{meta / 'check.json'}"
inputs = "physical"
data = "afm"
starts = 3
seed = 7
{extra}
[fit.columns]
time = "time"
piezo = "piezo"
deflection = "deflection"

[fit.calibration]
spring_constant = "{K} N/m"

[fit.protocol]
rate = "2.3 um/s"
amplitude = "2.3 um"
displacement_tolerance = 0.2
""")
    return p


def cell(root, name):
    """A demo cell in SI: time s, piezo m, deflection m."""
    group = "A-stiff" if name.startswith("a") else "B-soft"
    with open(root / f"examples/demo/data/{group}/{name}.csv") as f:
        rows = list(csv.reader(f))[1:]
    a = np.array(rows, dtype=float)
    return a[:, 0], a[:, 1] * 1e-6, a[:, 2] * 1e-9


def arrays(t, z, d, label):
    # As the CLI reads an AFM CSV (crates/inverse/src/measured.rs): F = k d, delta = Z - d.
    return {"time": t, "displacement": z, "force": K * d, "indentation": z - d, "label": label}


SAME = ["parameters", "misfit_surrogate", "misfit_real", "surrogate_and_real_agree",
        "flags", "identifiability", "modulus", "fit"]


def test_arrays_fit_is_the_cli_fit(root, tmp_path, cli):
    st = study(root, tmp_path)
    t, z, d = cell(root, "a-stiff-01")
    data = tmp_path / "a-stiff-01.csv"
    write_csv(data, ["time [s]", "piezo [m]", "deflection [m]"], [t, z, d])
    ref = cli.run("fit", st, data)
    got = nlvid.fit(st, arrays(t, z, d, "a-stiff-01"))
    for k in SAME:
        assert got[k] == ref[k], k
    assert got["experiments"][0]["label"] == "a-stiff-01"
    # The demo's ground truth (examples/demo/ground_truth.csv): G0 within 10 %.
    g0 = next(p["value"] for p in got["parameters"] if p["name"] == "G0")
    assert abs(g0 / 1729.511909283039 - 1) < 0.1


def test_file_fit_is_the_cli_fit(root, tmp_path, cli):
    st = study(root, tmp_path)
    data = root / "examples/demo/data/B-soft/b-soft-02.csv"
    ref = cli.run("fit", st, data, "--starts", 2, "--seed", 3)
    got = nlvid.fit(nlvid.load_study(st), [str(data)], starts=2, seed=3)
    ref.pop("seconds"), got.pop("seconds")
    assert got == ref


def test_two_experiments_fitted_together(root, tmp_path, cli):
    st = study(root, tmp_path)
    curves, files = [], []
    for name in ("a-stiff-01", "a-stiff-02"):
        t, z, d = cell(root, name)
        files.append(tmp_path / f"{name}.csv")
        write_csv(files[-1], ["time [s]", "piezo [m]", "deflection [m]"], [t, z, d])
        curves.append(arrays(t, z, d, name))
    ref = cli.run("fit", st, *files)
    got = nlvid.fit(st, curves)
    for k in SAME:
        assert got[k] == ref[k], k
    assert len(got["experiments"]) == 2


def test_bad_arrays(root, tmp_path):
    st = study(root, tmp_path)
    t, z, d = cell(root, "a-stiff-01")
    good = arrays(t, z, d, "x")
    with pytest.raises(nlvid.InputError, match="one length"):
        nlvid.fit(st, {**good, "force": good["force"][:-1]})
    with pytest.raises(nlvid.InputError, match="missing `force`"):
        nlvid.fit(st, {k: v for k, v in good.items() if k != "force"})
    f = good["force"].copy()
    f[10] = np.nan
    with pytest.raises(nlvid.InputError, match="index 10"):
        nlvid.fit(st, {**good, "force": f})
    with pytest.raises(nlvid.InputError, match="increasing"):
        nlvid.fit(st, {**good, "time": good["time"][::-1].copy()})
    with pytest.raises(nlvid.InputError, match="unknown key"):
        nlvid.fit(st, {**good, "forces": good["force"]})
    with pytest.raises(TypeError, match="float64"):
        nlvid.fit(st, {**good, "time": good["time"].astype(np.float32)})
    # A protocol the data do not follow: the library's message, naming the curve.
    bad = study(root, tmp_path).read_text().replace('rate = "2.3 um/s"', 'rate = "0.5 um/s"')
    (tmp_path / "bad.toml").write_text(bad)
    with pytest.raises(nlvid.NlvidError):
        nlvid.fit(tmp_path / "bad.toml", good)
