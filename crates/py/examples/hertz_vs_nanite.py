"""Hertz fits of the public JPK curves (crates/afm/tests/data) with nlvid
and, when installed, with nanite, side by side.

    python crates/py/examples/hertz_vs_nanite.py

nanite (pip install nanite afmformats) is optional: without it the nanite
columns are skipped with a message. Both fit the paraboloidal Hertz model
(eq. 1.1, Poisson ratio 0.5) with E, contact point and baseline free, on the
approach segment; each program uses its own preprocessing (nanite: tip
position correction and its contact-point estimate; nlvid: the baseline
deviation contact estimate of `nlvid inspect --fit hertz`).
"""

import sys
import time
from pathlib import Path

import nlvid

DATA = Path(__file__).resolve().parents[3] / "crates/afm/tests/data"
CURVES = [  # (file, probe radius) as in crates/afm/tests/data/nanite_hertz.csv
    ("fmt-jpk-fd_spot3-0192.jpk-force", 40e-9),
    ("fmt-jpk-fd_map2x2_extracted.jpk-force-map", 5e-6),
    ("fmt-jpk-fd_2020.02.07-16.29.05.036.jpk-qi-data", 5e-6),
    ("fmt-jpk-fd_flipsign_2015.05.22-15.31.49.352.jpk-force", 5e-6),
    ("fmt-jpk-cc_pr14-brain-2021.06.30.jpk-force", 5e-6),
    ("fmt-jpk-sr_cell1-0008.jpk-force", 5e-6),
]


def nanite_fit(path, index, radius):
    """E (Pa) of nanite's hertz_para fit of one curve, or None on failure."""
    import nanite

    group = nanite.IndentationGroup(str(path))
    idnt = group[index]
    idnt.apply_preprocessing(
        ["compute_tip_position", "correct_force_offset", "correct_tip_offset"]
    )
    params = idnt.get_initial_fit_parameters(model_key="hertz_para")
    params["R"].set(value=radius)
    params["nu"].set(value=0.5)
    idnt.fit_model(model_key="hertz_para", params_initial=params, range_type="absolute",
                   segment="approach", weight_cp=0)
    return idnt.fit_properties["params_fitted"]["E"].value


def main():
    try:
        import nanite  # noqa: F401
        have_nanite = True
    except ImportError:
        have_nanite = False
        print("nanite is not installed (pip install nanite afmformats): "
              "showing nlvid only", file=sys.stderr)
    print(f"{'file':52s} {'curve':>5s} {'R (m)':>8s} {'E nlvid (Pa)':>14s} {'ms':>7s}"
          + (f" {'E nanite (Pa)':>14s} {'ms':>7s} {'rel. diff':>10s}" if have_nanite else ""))
    for name, radius in CURVES:
        curves = nlvid.read_jpk(DATA / name)
        for i, curve in enumerate(curves[:2]):
            t0 = time.perf_counter()
            try:
                e = nlvid.hertz(curve, tip_radius=f"{radius * 1e9:g} nm")["youngs_modulus_Pa"]
            except nlvid.NlvidError as err:
                print(f"{name:52s} {i:5d} nlvid failed: {err}")
                continue
            ms = (time.perf_counter() - t0) * 1e3
            line = f"{name:52s} {i:5d} {radius:8.1e} {e:14.6g} {ms:7.1f}"
            if have_nanite:
                t0 = time.perf_counter()
                try:
                    en = nanite_fit(DATA / name, i, radius)
                    msn = (time.perf_counter() - t0) * 1e3
                    line += f" {en:14.6g} {msn:7.1f} {e / en - 1:10.2e}"
                except Exception as err:  # nanite cannot read or fit every file
                    line += f" nanite failed: {type(err).__name__}: {err}"
            print(line)


if __name__ == "__main__":
    main()
