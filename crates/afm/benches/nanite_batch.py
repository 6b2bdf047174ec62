"""nanite's side of the batch benchmark (docs/theory/afm.md, issue 14).

Paraboloidal Hertz fit (R given, nu = 0.5) of every curve of every JPK file in the given
folders, with nanite's usual pipeline: load (afmformats), preprocessing
`compute_tip_position`, `correct_force_offset`, `correct_tip_offset`, then
`fit_model(model_key="hertz_para")` over the approach segment. `-j N` processes
(multiprocessing), one task per file. Prints one CSV row per curve and a summary line on
stderr.

Usage: python nanite_batch.py [-j N] R_M FOLDER...
"""
import argparse
import multiprocessing
import pathlib
import sys
import time

import nanite

PRE = ["compute_tip_position", "correct_force_offset", "correct_tip_offset"]
SUFFIXES = (".jpk-force", ".jpk-force-map", ".jpk-qi-data", ".jpk-qi-series")


def fit_file(args):
    path, radius = args
    rows = []
    try:
        group = nanite.load_group(path)
    except BaseException as e:  # afmformats' MissingMetaDataError is a BaseException
        return [(str(path), "", f"error: {e}")]
    for idnt in group:
        try:
            idnt.apply_preprocessing(PRE)
            params = idnt.get_initial_fit_parameters(model_key="hertz_para")
            params["R"].set(value=radius)
            params["nu"].set(value=0.5)
            idnt.fit_model(model_key="hertz_para", params_initial=params)
            e = idnt.fit_properties["params_fitted"]["E"].value
            rows.append((str(path), idnt.metadata["enum"], repr(e)))
        except BaseException as e:
            rows.append((str(path), idnt.metadata.get("enum", ""), f"error: {e}"))
    return rows


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("-j", type=int, default=1)
    ap.add_argument("radius", type=float)
    ap.add_argument("folders", nargs="+")
    a = ap.parse_args()
    files = sorted(p for f in a.folders for p in pathlib.Path(f).rglob("*")
                   if p.name.lower().endswith(SUFFIXES))
    t0 = time.time()
    with multiprocessing.Pool(a.j) as pool:
        results = pool.map(fit_file, [(p, a.radius) for p in files], chunksize=4)
    n = 0
    print("file,curve,E_Pa")
    for rows in results:
        for r in rows:
            print(",".join(str(x) for x in r))
            n += 1
    print(f"{n} curves in {time.time() - t0:.3f} s on {a.j} processes",
          file=sys.stderr)


if __name__ == "__main__":
    main()
