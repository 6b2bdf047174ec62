"""read_results, compare against `nlvid --json compare`; run_cohort against
`nlvid --json cohort` on four demo cells."""

import numpy as np
import pytest

import nlvid

TABLE = """group,cell,G0 [kPa],g1,tau1 [s],g2,tau2 [ms],status,reason
A,a1,1.2,0.3,0.5,0.2,9000,ok,
A,a2,1.5,0.25,0.6,0.25,11000,,
A,a3,1.1,0.35,0.4,0.2,10000,ok,
A,a4,1.4,0.3,0.45,0.3,8000,failed,did not converge
B,b1,0.6,0.4,0.3,0.2,7000,ok,
B,b2,0.7,0.45,0.35,0.25,6000,ok,
B,b3,0.5,0.4,0.25,0.2,9000,ok,
"""


@pytest.fixture()
def table(tmp_path):
    p = tmp_path / "results.csv"
    p.write_text(TABLE)
    return p


def test_read_results_in_si(table):
    t = nlvid.read_results(table)
    assert t["cell"] == ["a1", "a2", "a3", "b1", "b2", "b3"]
    assert t["group"] == ["A"] * 3 + ["B"] * 3
    np.testing.assert_array_equal(t["G0"], [1200.0, 1500.0, 1100.0, 600.0, 700.0, 500.0])
    np.testing.assert_allclose(t["tau2"], [9.0, 11.0, 10.0, 7.0, 6.0, 9.0], rtol=1e-15)
    assert t["terms"] == 2 and t["excluded"][0]["cell"] == "a4"
    assert list(t["line"]) == [2, 3, 4, 6, 7, 8]


def test_compare_is_the_cli_comparison(table, tmp_path, cli):
    out = tmp_path / "out"
    ref = cli.run("compare", table, "--t-end", "10 s", "--points", 11, "--out-dir", out)
    ref_csv = (out / "results.groups.csv").read_text()
    got = nlvid.compare(table, t_end="10 s", points=11, out_dir=out)
    curves = got.pop("curves")
    assert got == ref
    # G(0) of group A is the mean of its used cells' G0.
    assert curves["A"]["G_mean"][0] == pytest.approx(np.mean([1200, 1500, 1100]), rel=1e-12)
    assert len(curves["p_G"]) == 11
    assert (out / "results.groups.csv").read_text() == ref_csv


def test_compare_bad_arguments(table):
    with pytest.raises(nlvid.NlvidError, match="method"):
        nlvid.compare(table, method="bayes")
    with pytest.raises(nlvid.InputError, match="no unit"):
        nlvid.compare(table, t_end="52")
    with pytest.raises(nlvid.NlvidError, match="exactly two"):
        nlvid.compare(table, groups=["A"])


def test_run_cohort_is_the_cli_cohort(root, tmp_path, cli):
    manifest = tmp_path / "manifest.csv"
    data = root / "examples/demo/data"
    manifest.write_text("group,file\n" + "".join(
        f"{g},{data / g / f}.csv\n" for g, f in
        [("A-stiff", "a-stiff-01"), ("A-stiff", "a-stiff-02"),
         ("B-soft", "b-soft-01"), ("B-soft", "b-soft-02")]))
    study = root / "examples/demo/study.toml"
    got = nlvid.run_cohort(study, manifest, out=tmp_path / "py")
    cli.run("cohort", study, manifest, "--out", tmp_path / "cli")
    assert (tmp_path / "py" / "results.csv").read_text() == \
        (tmp_path / "cli" / "results.csv").read_text()
    assert got["results"]["group"] == ["A-stiff", "A-stiff", "B-soft", "B-soft"]
