"""MetaModel.predict / check against `nlvid --json surrogate predict | check`
on the bundled demo meta-model (examples/demo/metamodel)."""

import csv

import numpy as np
import pytest

import nlvid
from conftest import write_csv

NAMES = ["G0", "g1", "g2", "tau1", "tau2"]


@pytest.fixture(scope="module")
def demo(root):
    d = root / "examples/demo/metamodel"
    return nlvid.MetaModel.load(d / "model.json", meta=d / "meta.json")


@pytest.fixture(scope="module")
def points(root):
    with open(root / "examples/demo/ground_truth.csv") as f:
        rows = list(csv.DictReader(f))
    cols = ["G0_Pa", "g1", "g2", "tau1_s", "tau2_s"]
    return np.array([[float(r[c]) for c in cols] for r in rows])


def test_shape_and_grid(demo, root):
    assert demo.dim == 5 and demo.n_outputs == len(demo.times)
    # The FE demo grid starts at t = 0 (the hertz-prony one at 0.1 s).
    assert demo.times[0] >= 0 and np.all(np.diff(demo.times) > 0)


def test_predict_with_mse_is_the_cli_prediction(demo, points, tmp_path, cli, root):
    x = tmp_path / "x.csv"
    write_csv(x, NAMES, points.T)
    y, mse = demo.predict(points, mse=True)
    c = cli.run("surrogate", "predict", root / "examples/demo/metamodel/model.json", "--x", x, "--mse")
    names = c["outputs"]
    assert names == demo.output_names
    ref_y = np.array([[p["y"][n] for n in names] for p in c["points"]])
    ref_mse = np.array([[p["mse"][n] for n in names] for p in c["points"]])
    assert np.array_equal(y, ref_y) and np.array_equal(mse, ref_mse)
    assert y.shape == (len(points), demo.n_outputs) and np.all(mse >= 0)
    # One point as a 1-d array, and without MSE: the same numbers.
    assert np.array_equal(demo.predict(points[3])[0], y[3])


def test_non_contiguous_input_gives_the_same_prediction(demo, points):
    wide = np.zeros((len(points), 10))
    wide[:, ::2] = points
    view = wide[:, ::2]
    assert not view.flags["C_CONTIGUOUS"]
    assert np.array_equal(demo.predict(view), demo.predict(points))


def test_check_is_eq_4_4_and_the_cli_summary(demo, points, tmp_path, cli, root):
    y = demo.predict(points)
    k = np.arange(y.shape[1])
    ref = y * (1.0 + 0.01 * np.sin(0.1 * k))[None, :]
    s = demo.check(points, ref)
    # Eq. 4.4 computed here independently.
    expected = np.sqrt(np.mean((ref - y) ** 2, axis=1)) / (ref.max(axis=1) - ref.min(axis=1))
    np.testing.assert_allclose(s["rmse"], expected, rtol=1e-9)
    assert s["max"] == pytest.approx(expected.max(), rel=1e-9)
    x, yc = tmp_path / "x.csv", tmp_path / "y.csv"
    write_csv(x, NAMES, points.T)
    write_csv(yc, demo.output_names, ref.T)
    c = cli.run("surrogate", "check", root / "examples/demo/metamodel/model.json",
                "--x", x, "--y", yc, "--summary", tmp_path / "summary.json")
    assert list(s["rmse"]) == c["rmse"]
    for key in ("min", "median", "max", "worst", "median_case"):
        assert s[key] == c[key], key


def test_bad_inputs_raise_clear_exceptions(demo, points):
    with pytest.raises(TypeError, match="float64"):
        demo.predict(points.astype(np.int64))
    with pytest.raises(TypeError, match="float64"):
        demo.predict(points.astype(np.float32))
    with pytest.raises(TypeError, match="float64"):
        demo.predict(points.tolist())
    bad = points.copy()
    bad[2, 1] = np.nan
    with pytest.raises(nlvid.InputError, match="not finite"):
        demo.predict(bad)
    with pytest.raises(ValueError, match="5"):
        demo.predict(points[:, :4])
    with pytest.raises(nlvid.InputError, match="checking"):
        demo.check(points, demo.predict(points)[:3])
    with pytest.raises(nlvid.InputError, match="dimension"):
        demo.predict(np.zeros((2, 2, 5)))
    with pytest.raises(nlvid.NlvidError):
        nlvid.MetaModel.load("/nonexistent/model.json")
