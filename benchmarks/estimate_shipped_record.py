"""The estimator on the record shipped with the stick_slip case against its hidden truth (docs/estimation.md,
"The shipped record"): coverage of the 90 % bands, RMS errors, the surface-only guess's, the parameters, the wall
time (the model's build and compilation included).

    python benchmarks/estimate_shipped_record.py MODE DURATION MEMBERS [setting=value ...]

MODE: ``10hz`` (the record as shipped) or ``1hz`` (every 10th sample); DURATION: the first seconds of the record;
the settings: EstimatorSettings fields over the defaults. ``SAVE=path.npz`` in the environment saves the means
and quantiles."""
import sys
import time

import numpy as np

from drillstring.api.estimates import builtin_record
from drillstring.case import load_case
from drillstring.estimation.ensemble import (
    case_estimator_settings,
    estimate,
)
from drillstring.estimation.reading import read_surface_record
from drillstring.estimation.surface import SurfaceRecord
from drillstring.estimation.synthetic import read_truth

c = load_case('stick_slip')
rp, tp = builtin_record('stick_slip')
r = read_surface_record(rp, case=c)
mode, dur, N = sys.argv[1], float(sys.argv[2]), int(sys.argv[3])
over = {}
for a in sys.argv[4:]:
    k, v = a.split("=")
    over[k] = type(getattr(case_estimator_settings(c), k))(v) if not v.isalpha() else v
step = 10 if mode == "1hz" else 1
keep = np.arange(0, len(r.time), step)
keep = keep[r.time[keep] <= dur + 1e-9]
ch = {k: v[keep] for k, v in r.channels.items()}
fl = {k: v[keep] for k, v in r.flags.items()}
r2 = SurfaceRecord(r.time[keep], ch, fl, "x")
s = case_estimator_settings(c, ensemble_size=N, **over)
t0 = time.perf_counter()
res = estimate(c, r2, s)
wall = time.perf_counter() - t0
_, t = read_truth(tp)
print("settings", over, "N", N, "wall", round(wall, 1), "rtf", round(wall / dur, 2), "replaced", res.replaced.sum())
for k in ("bit_speed", "torque_on_bit", "force_on_bit", "rate_of_penetration", "weight_on_bit_bias", "a5"):
    lo, hi = res.band(k)
    if k in t:
        tr = np.interp(res.time, t["time"], t[k])
        err = res.mean[k] - tr
        rm = np.sqrt(np.nanmean(err**2))
        print(f"{k:22s} mean {np.nanmean(res.mean[k]):11.4g} truth {np.mean(tr):11.4g} cov {res.coverage(k, tr):.2f} "
              f"cov>10 {res.coverage(k, tr, 10.0):.2f} rmse {rm:.4g} bandw {np.nanmean(hi-lo):.4g}")
    else:
        print(f"{k:22s} mean {np.nanmean(res.mean[k]):11.4g} last {res.mean[k][-1]:.4g} band_last {lo[-1]:.4g}..{hi[-1]:.4g}")
tr = np.interp(res.time, t["time"], t["bit_speed"])
top = np.interp(res.time, t["time"], t["top_speed"])
print("surface-only guess rmse bit speed", np.sqrt(np.mean((top - tr)**2)))
for a, b in [(0, 5), (5, 10), (10, 20), (20, 40), (40, 60), (60, 80)]:
    m = (res.time >= a) & (res.time < b)
    if m.any():
        print(f"  [{a},{b}) bias {np.nanmean(res.mean['weight_on_bit_bias'][m]):9.0f} fob {np.nanmean(res.mean['force_on_bit'][m]):9.0f} "
              f"rop {np.nanmean(res.mean['rate_of_penetration'][m])*3600:7.2f} a5 {np.nanmean(res.mean['a5'][m]):7.0f} "
              f"bs_rmse {np.sqrt(np.nanmean((res.mean['bit_speed'][m]-tr[m])**2)):.2f}")
if len(sys.argv) > 1 and "SAVE" in __import__("os").environ:
    np.savez(__import__("os").environ["SAVE"], time=res.time, **{k+"_mean": v for k, v in res.mean.items()},
             **{k+"_q": v for k, v in res.quantiles.items()}, **{"pred_"+k: v for k, v in res.predicted_mean.items()})
