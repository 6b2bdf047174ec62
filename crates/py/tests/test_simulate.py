"""simulate against `nlvid --json simulate` (cell FE, 3D capsule FE) and
`nlvid --json membrane` on the same study files."""

import numpy as np
import pytest

import nlvid

AFM_FE = """
title = "small afm-fe cell"
[forward]
model = "afm-fe"
height = "12.22 um"
diameter = "28.88 um"
probe_radius = "2.5 um"
spring_constant = "0.12 N/m"
mesh = "coons"
elements_per_side = 6
mesh_bias = 4.0
bulk_ratio = 1000
hold_step_max = "0.5 s"
points = 30

[protocol]
kind = "afm"
engage_force = "0.48 nN"
engage_time = "1 s"
cycle_rates = ["10 um/s"]
depth = "0.5 um"
retract = "0.25 um"
final_rate = "10 um/s"
hold = "1 s"

[parameters]
G0 = "1 kPa"
g1 = 0.3
g2 = 0.2
tau1 = "0.1 s"
tau2 = "5 s"
"""

MEMBRANE = """
[forward]
model = "membrane"
radius = "1.5 mm"
wall_thickness = "40 um"
nodes = 48
points = 61

[protocol]
kind = "ramp-hold"
displacement = "0.6 mm"
speed = "5 mm/s"
hold = "3 s"

[parameters]
G10 = "3 kPa"
gamma0 = 0.3
g1_long_term = 0.8
g2_long_term = 0.8
tau1 = "0.1 s"
tau2 = "2 s"
"""

# The 3D capsule of thesis §4.3 on a coarse mesh (0.6 mm elements, 2 layers
# through the wall) and a short ramp-hold, so the run takes seconds; the
# parameters are §4.4.3's RH set (crates/forward/tests/it/capsule_fe.rs).
CAPSULE_FE = """
title = "coarse capsule-fe"
[forward]
model = "capsule-fe"
axes = ["9.96 mm", "6.51 mm", "6.51 mm"]
wall_thickness = ["0.62 mm", "0.4 mm", "0.4 mm"]
element_size = "0.6 mm"
layers = 2
min_steps = 8
points = 25

[protocol]
kind = "ramp-hold"
target = "1 mm"
rate = "5 mm/s"
hold = "0.4 s"

[parameters]
C1 = "21.2546 MPa"
alpha = 0.3720
g1 = 0.7674
g2 = 0.1546
tau1 = "0.0623 s"
tau2 = "1.3936 s"
"""


def curve_matches(py_curve, cli_curve):
    assert np.array_equal(py_curve["time"], np.array(cli_curve["time_s"]))
    for name, unit in py_curve["units"].items():
        if name == "time":
            continue
        header = name if unit in ("1", "") else f"{name}_{unit.replace('/', '_per_')}"
        assert np.array_equal(py_curve[name], np.array(cli_curve[header])), name


def test_cell_fe_run_is_the_cli_run(tmp_path, cli):
    p = tmp_path / "cell.toml"
    p.write_text(AFM_FE)
    r = nlvid.simulate(p)
    c = cli.run("simulate", p, "-o", tmp_path / "cell.csv")
    assert r["model"] == c["model"] == "afm-fe"
    assert r["parameters"] == c["parameters"]
    assert r["provenance"] == c["provenance"]
    curve_matches(r["curve"], c["curve"])
    for k in ("peak_force_N", "final_force_N", "min_force_N", "final"):
        assert r[k] == c[k], k
    assert r["solver"]["steps"] == c["solver"]["steps"]
    # Physics sanity independent of the CLI: the probe pushes (force > 0 at the peak).
    assert r["peak_force_N"] > 0 and r["curve"]["force"].dtype == np.float64


def test_capsule_fe_run_is_the_cli_run(tmp_path, cli):
    p = tmp_path / "capsule-fe.toml"
    p.write_text(CAPSULE_FE)
    r = nlvid.simulate(p)
    c = cli.run("simulate", p, "-o", tmp_path / "capsule.csv")
    assert r["model"] == c["model"] == "capsule-fe"
    assert r["parameters"] == c["parameters"]
    assert r["provenance"] == c["provenance"]
    curve_matches(r["curve"], c["curve"])
    for k in ("peak_force_N", "final_force_N", "min_force_N", "final"):
        assert r[k] == c[k], k
    curve = r["curve"]
    t, f = curve["time"], curve["force"]
    assert f.dtype == np.float64 and len(t) == 25
    # Independent of the CLI: the grid spans the program (ramp 1 mm at
    # 5 mm/s = 0.2 s, then 0.4 s), the capsule starts unloaded, the hold
    # relaxes, and the incompressible oil keeps the capsule's volume.
    assert t[0] == 0.0 and t[-1] == pytest.approx(0.6, rel=1e-12)
    assert f[0] == 0.0 and f.max() > 0 and f[-1] < f.max()
    v = curve["volume"]
    assert np.all(np.abs(v / v[0] - 1) < 1e-9)


def test_membrane_run_is_the_cli_run(tmp_path, cli):
    p = tmp_path / "capsule.toml"
    p.write_text(MEMBRANE)
    r = nlvid.simulate(p)
    c = cli.run("membrane", p, "--out", tmp_path / "out")
    assert r["parameters"] == c["parameters"]
    curve_matches(r["curve"], c["curve"])
    assert r["peak_force_N"] == c["peak_force_N"]
    (t, prof), = r["profiles"]
    assert t == pytest.approx(0.12 + 3.0)  # ramp 0.6 mm at 5 mm/s, then 3 s hold
    assert len(prof["psi_rad"]) > 0


def test_run_failure_is_the_cli_message(tmp_path, cli):
    # docs/cli/membrane.md: with gamma0 = 0.1, g_long_term = 0.5 the capsule wrinkles.
    p = tmp_path / "wrinkles.toml"
    p.write_text(MEMBRANE.replace("gamma0 = 0.3", "gamma0 = 0.1")
                 .replace("g1_long_term = 0.8", "g1_long_term = 0.5")
                 .replace("g2_long_term = 0.8", "g2_long_term = 0.5"))
    with pytest.raises(nlvid.NlvidError, match="wrinkl") as e:
        nlvid.simulate(p)
    assert str(e.value) == cli.error("simulate", p)


def test_study_errors_raise_with_key(tmp_path, cli):
    p = tmp_path / "bad.toml"
    p.write_text(MEMBRANE.replace('G10 = "3 kPa"', 'G10 = "3 kPa/s"'))
    with pytest.raises(nlvid.StudyError) as e:
        nlvid.simulate(p)
    assert e.value.key == "parameters.G10"
    assert str(e.value) == cli.error("simulate", p)


def test_profile_times_need_units(tmp_path):
    p = tmp_path / "capsule.toml"
    p.write_text(MEMBRANE)
    with pytest.raises(nlvid.InputError, match="unit"):
        nlvid.simulate(p, profile_times=[0.5])
    with pytest.raises(ValueError, match="no unit"):
        nlvid.simulate(p, profile_times=["0.5"])
