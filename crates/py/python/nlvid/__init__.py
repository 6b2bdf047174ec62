"""nlvid from Python: studies, forward runs, Kriging meta-models, NLV fits,
JPK files, Hertz and Lee-Radok fits, cohort tables and group comparisons.

The functions wrap the library calls of the ``nlvid`` command line (each
docstring names its subcommand), so results are the CLI's. Arrays are numpy
float64 in SI units (s, m, N, Pa); quantities given as scalars carry their
unit in a string (``tip_radius="5 um"``). ``hertz`` and ``lee_radok`` also
take afmformats' data objects (``afmformats.load_data(path)[0]``) or dicts of
their columns, duck-typed (``ForceCurve.from_columns``). Errors raise ``NlvidError``
(``StudyError`` with ``file``/``line``/``column``/``key`` for study files,
``InputError`` — also a ``ValueError`` — or ``TypeError`` for bad arguments).
"""

from ._nlvid import (  # noqa: F401
    __version__,
    NlvidError,
    StudyError,
    InputError,
    Study,
    load_study,
    parse_study,
    simulate,
    MetaModel,
    fit,
    ForceCurve,
    read_jpk,
    hertz,
    lee_radok,
    fit_hertz,
    fit_lee_radok,
    read_results,
    compare,
    run_cohort,
)

__all__ = [
    "NlvidError",
    "StudyError",
    "InputError",
    "Study",
    "load_study",
    "parse_study",
    "simulate",
    "MetaModel",
    "fit",
    "ForceCurve",
    "read_jpk",
    "hertz",
    "lee_radok",
    "fit_hertz",
    "fit_lee_radok",
    "read_results",
    "results_frame",
    "compare",
    "run_cohort",
]


def results_frame(path):
    """The per-cell results table as a pandas DataFrame (one row per used
    cell: cell, group, line, G0 [Pa], g1, tau1 [s], ...); needs pandas.
    Without pandas, use ``read_results`` (a dict of numpy arrays)."""
    try:
        import pandas as pd
    except ImportError as e:  # pragma: no cover - depends on the environment
        raise ImportError(
            "results_frame needs pandas (pip install pandas); "
            "read_results(path) gives the same columns as numpy arrays"
        ) from e
    t = read_results(path)
    cols = ["cell", "group", "line", "G0"]
    for k in range(1, t["terms"] + 1):
        cols += [f"g{k}", f"tau{k}"]
    return pd.DataFrame({c: t[c] for c in cols})
