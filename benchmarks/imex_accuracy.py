"""Work and accuracy of the implicit–explicit steps (``ark43``, ``ark32``) against compiled DOPRI5, per case.

For each case: DOPRI5 at the case's tolerances (the baseline: its wall time, right-hand sides, steps) and at
rtol/10 (its own error, the yardstick of "equal accuracy"); then each IMEX method at the rtols given, with its
wall time, right-hand sides, steps and Jacobians (the stiff part, once per step from a new state), the
speed-up against the baseline measured in the same run, and two accuracies against the baseline: the largest
relative deviation of the cycle metrics (:func:`drillstring.dynamics.indicators.cycle_metrics`, after the
transient) and of the observables' records (max |Δ| / max |x| of ROP, bit speed, TOB, FOB). Run:

    PYTHONPATH=src python benchmarks/imex_accuracy.py reference aarsnes2019 [--t-end 30] [--rtols 1e-6,1e-5]
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import math  # noqa: E402

import numpy as np  # noqa: E402

from drillstring.case import load_case  # noqa: E402
from drillstring.dynamics.indicators import bit_area, cycle_metrics, transient_end  # noqa: E402
from drillstring.dynamics.rom import case_reduced_model  # noqa: E402
from drillstring.dynamics.simulate import simulate_model  # noqa: E402

RECORDS = ("rate_of_penetration", "bit_speed", "torque_on_bit", "force_on_bit")


def run(model, case, method: str, rtol: float, t_end: float, repeat: int):
    s = case.simulation
    best = None
    for _ in range(repeat):
        result = simulate_model(model, t_end=t_end, output_step=s.output_step, rtol=rtol,
                                atol=s.atol * rtol / s.rtol, method=method, raise_on_failure=False,
                                lateral_perturbation=case.initial.lateral_perturbation, seed=case.initial.seed)
        if best is None or result.stats["wall_time"] < best.stats["wall_time"]:
            best = result
    return best


def metrics(result, case, t_end: float) -> dict[str, float]:
    return cycle_metrics(result.time, result.observables, case.operation.top_speed, bit_area(case),
                         transient_end(t_end))


def deviation(a: dict, b: dict) -> tuple[float, str]:
    """The largest relative deviation of the metrics both have finite (relative to the larger magnitude)."""
    worst, name = 0.0, ""
    for key in a:
        x, y = a[key], b[key]
        if not (math.isfinite(x) and math.isfinite(y)) or max(abs(x), abs(y)) == 0.0:
            continue
        d = abs(x - y) / max(abs(x), abs(y))
        if d > worst:
            worst, name = d, key
    return worst, name


def records(a, b) -> float:
    n = min(len(a.time), len(b.time))
    return max(float(np.max(np.abs(a.observables[k][:n] - b.observables[k][:n])) / np.max(np.abs(b.observables[k][:n])))
               for k in RECORDS)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("cases", nargs="+")
    parser.add_argument("--t-end", type=float, default=None, help="default: the case's")
    parser.add_argument("--rtols", default="1e-6,1e-5", help="the IMEX methods' rtols (atol scaled with them)")
    parser.add_argument("--methods", default="ark43,ark32")
    parser.add_argument("--nonlinear", choices=("bit_and_contact", "full"), default=None)
    parser.add_argument("--repeat", type=int, default=2)
    args = parser.parse_args()
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})  # one core
    for name in args.cases:
        case = load_case(name)
        t_end = args.t_end or case.simulation.t_end
        model = case_reduced_model(case, nonlinear=args.nonlinear)
        rtol = case.simulation.rtol
        base = run(model, case, "dopri5", rtol, t_end, args.repeat)
        tight = run(model, case, "dopri5", rtol / 10, t_end, 1)
        reference = metrics(base, case, t_end)
        own, own_name = deviation(metrics(tight, case, t_end), reference)
        st = base.stats
        print(f"case {name} ({model.nonlinear}), {model.size} modal coordinates, t_end = {t_end:g} s, "
              f"case rtol = {rtol:g}, atol = {case.simulation.atol:g}; one core, best of {args.repeat}")
        print(f"  dopri5 rtol {rtol:g}: {st['wall_time']:.3f} s, RHS {st['n_rhs']}, steps {st['n_accepted']}+"
              f"{st['n_rejected']}; dopri5 at rtol/10 differs by {own:.2%} ({own_name}) in the cycle metrics, "
              f"{records(tight, base):.2e} in the records", flush=True)
        for method in args.methods.split(","):
            for r in (float(x) for x in args.rtols.split(",")):
                result = run(model, case, method, r, t_end, args.repeat)
                s = result.stats
                worst, worst_name = deviation(metrics(result, case, t_end), reference)
                status = "" if result.status == "success" else f" FAILED: {result.message[:160]}"
                print(f"  {method} rtol {r:g}: {s['wall_time']:.3f} s, RHS {s['n_rhs']}, Jacobians "
                      f"{s.get('n_jacobians', 0)}, steps {s['n_accepted']}+{s['n_rejected']}; speed-up vs dopri5: "
                      f"{st['wall_time'] / s['wall_time']:.1f}x; cycle metrics within {worst:.2%} ({worst_name}), "
                      f"records {records(result, base):.2e}{status}", flush=True)


if __name__ == "__main__":
    main()
