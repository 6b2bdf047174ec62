"""Fit nlvid's prepared approach points with nanite's paraboloidal Hertz model.

Input: the JSON lines of `cargo run -p nlvid-afm --example hertz_points -- R FILE...`
(separation s in m and baseline-corrected force F in N of each curve, exactly as nlvid
fits them). For every curve this fits nanite's `hertz_para` model (E, contact_point and
baseline free; R and nu = 0.5 fixed) to those points with nanite's residual function,
unweighted (`weight_cp=0`: plain least squares, nlvid's objective), by lmfit `leastsq`
as nanite's IndentationFitter does. As nanite's `correct_tip_offset` preprocessing does,
the x axis is shifted so that nanite's own contact-point estimate
(`nanite.poc.compute_poc`, deviation from baseline) lies at 0, which is also the initial
contact point; E and baseline start from nanite's defaults. (A constant shift of x moves
the fitted contact point by the same amount and changes nothing else; without it,
lmfit's finite-difference steps are badly scaled and `leastsq` stops up to 0.6 % short
of the optimum on two map curves.) The fitted contact point is shifted back.

Printed per curve: nanite's E, contact point, baseline and sum of squared residuals
(SSE), nlvid's E and SSE (both SSEs from nanite's residual function), and the relative
difference of E.

Usage: python nanite_hertz.py points.jsonl > nanite_hertz.csv
"""
import json
import sys

import lmfit
import nanite
import nanite.model
import nanite.poc
import numpy as np

md = nanite.model.models_available["hertz_para"]


def params(radius, e=None, cp=None, baseline=None):
    p = md.get_parameter_defaults()
    p["R"].set(value=radius)
    p["nu"].set(value=0.5)
    for key, value in [("E", e), ("contact_point", cp), ("baseline", baseline)]:
        if value is not None:
            p[key].set(value=value)
    return p


def sse(p, s, f):
    return float((md.residual(p, s, f, 0) ** 2).sum())


print(f"# nanite {nanite.__version__}, lmfit {lmfit.__version__}, numpy {np.__version__}")
print("file,curve,radius_m,points,E_nanite_Pa,contact_point_nanite_m,baseline_nanite_N,"
      "sse_nanite_N2,E_nlvid_Pa,sse_nlvid_N2,rel_diff")
for line in open(sys.argv[1]):
    d = json.loads(line)
    s = np.array(d["separation"])
    f = np.array(d["force"])
    x0 = s[nanite.poc.compute_poc(f, method="deviation_from_baseline")]
    fit = lmfit.minimize(fcn=md.residual, params=params(d["radius"], cp=0.0),
                         method="leastsq", args=(s - x0, f, 0))
    e = fit.params["E"].value
    cp = float(fit.params["contact_point"].value + x0)
    b = fit.params["baseline"].value
    name = d["file"].split("/")[-1]
    curve = "" if d["curve"] is None else d["curve"]
    ours = params(d["radius"], d["E"], d["contact_point"], d["offset"])
    print(f"{name},{curve},{d['radius']:.6g},{len(s)},{e!r},{cp!r},{b!r},"
          f"{sse(params(d['radius'], e, cp, b), s, f)!r},{d['E']!r},{sse(ours, s, f)!r},"
          f"{(d['E'] - e) / e:.3e}")
