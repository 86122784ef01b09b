"""Trial of another explicit pair on a case's realization: Tsitouras 5(4) (Ch. Tsitouras, "Runge–Kutta pairs of
order 5(4) satisfying only the first column simplifying assumption", Comput. Math. Appl. 62 (2011) 770–775; the
coefficients of its Table 1, the error weights as published with the last one's sign as in its eq. for b̂; its
order conditions checked over every rooted tree with the tests' ``order_defect``) against
DOPRI5, both in the compiled loop, at a sweep of relative tolerances (the absolute tolerance scaled with it), one
core. Per method and tolerance: accepted and rejected steps, right-hand sides, the best CPU time of the solve, and
the records' largest difference (ROP, bit speed, TOB, FOB, relative to each record's largest magnitude) from
DOPRI5 at rtol 1e-9. The trial pair's dense output is the cubic Hermite interpolant (3rd order, as BS32's),
not Tsitouras's own 4th-order extension: a trial of the step count, not a method the package offers
(docs/performance.md, "The solve at the physical limit"). Run:

    .venv/bin/python benchmarks/trial_tsit5.py [--case reference] [--rtols 1e-6,3e-6,1e-5,1e-4] [--repeat 3]
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "dynamics"))
from test_runge_kutta import order_defect  # noqa: E402  (the tests' order conditions over all rooted trees)

RECORDS = ("rate_of_penetration", "bit_speed", "torque_on_bit", "force_on_bit")


def tsitouras_54():
    """The Tsitouras 5(4) pair as a validated :class:`ButcherTableau` (FSAL; b̂ = b − error weights)."""
    import numpy as np

    from drillstring.dynamics.tableaus import ButcherTableau

    c = np.array([0.0, 0.161, 0.327, 0.9, 0.9800255409045097, 1.0, 1.0])
    inner = [[], [], [0.3354806554923570], [-6.359448489975075, 4.362295432869581],
             [-11.74888356406283, 7.495539342889836, -0.09249506636175525],
             [-12.92096931784711, 8.159367898576159, -0.07158497328140100, -0.02826905039406838]]
    b = np.array([0.0, 0.01, 0.4798896504144996, 1.379008574103742, -3.290069515436081, 2.324710524099774, 0.0])
    b[0] = 1.0 - b[1:].sum()
    a = np.zeros((7, 7))
    for i in range(1, 6):
        a[i, 1:1 + len(inner[i])] = inner[i]
        a[i, 0] = c[i] - a[i, 1:].sum()
    a[6, :6] = b[:6]
    error = np.array([-0.00178001105222577714, -0.0008164344596567469, 0.007880878010261995,
                      -0.1447110071732629, 0.5823571654525552, -0.45808210592918697, 1.0 / 66.0])
    hermite = {"h10": [1.0, -2.0, 1.0], "h01": [0.0, 3.0, -2.0], "h11": [0.0, -1.0, 1.0]}
    dense = np.outer(b, hermite["h01"])
    dense[0] += hermite["h10"]
    dense[6] += hermite["h11"]
    return ButcherTableau(name="tsit5_trial", c=c, a=a, b=b, b_hat=b - error, order=5, error_order=4, fsal=True,
                          dense=dense)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--case", default="reference")
    parser.add_argument("--rtols", default="1e-6,3e-6,1e-5,1e-4")
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {max(os.sched_getaffinity(0))})
    import numpy as np

    from drillstring.case import load_case
    from drillstring.dynamics import tableaus
    from drillstring.dynamics.compiled import RunState, SolverSettings, advance
    from drillstring.dynamics.rom import OBSERVABLE_COLUMN, case_reduced_model

    trial = tsitouras_54()
    for weights, order in ((trial.b, trial.order), (trial.b_hat, trial.error_order)):  # every rooted tree
        defects = [order_defect(trial, weights, q) for q in range(1, order + 2)]
        print(f"order-{order} weights: largest order-condition defect up to order {order} "
              f"{max(defects[:-1]):.1e}, at order {order + 1} {defects[-1]:.1e}")
    tableaus.TABLEAUS[trial.name] = trial  # the trial's name, for this process only

    case = load_case(args.case)
    s = case.simulation
    model = case_reduced_model(case)
    y0 = model.initial_state(case.initial.lateral_perturbation, case.initial.seed)
    grid = np.arange(0.0, s.t_end + 0.5 * s.output_step, s.output_step)

    def run(method: str, rtol: float):
        solver = SolverSettings(method=method, rtol=rtol, atol=s.atol * rtol / s.rtol)
        result = advance(model, solver, RunState.start(model, y0), s.t_end, output_times=grid)
        cpu = []
        for _ in range(args.repeat):
            start = time.process_time()
            advance(model, solver, RunState.start(model, y0), s.t_end, output_times=grid)
            cpu.append(time.process_time() - start)
        return result, min(cpu)

    tight = run("dopri5", 1e-9)[0].outputs
    print(f"case {args.case}, t_end {s.t_end} s, one core, best CPU of {args.repeat}; records vs DOPRI5 at rtol 1e-9")
    print("method        rtol     accepted  rejected  RHS      CPU [s]  records")
    for method in ("dopri5", trial.name):
        for rtol in sorted(float(r) for r in args.rtols.split(",")):
            result, cpu = run(method, rtol)
            worst = max(float(np.max(np.abs(result.outputs[:, OBSERVABLE_COLUMN[n]] - tight[:, OBSERVABLE_COLUMN[n]]))
                              / (np.max(np.abs(tight[:, OBSERVABLE_COLUMN[n]])) or 1.0)) for n in RECORDS)
            st = result.stats
            print(f"{method:13s} {rtol:<8.0e} {st['n_accepted']:<9d} {st['n_rejected']:<9d} {st['n_rhs']:<8d} "
                  f"{cpu:<8.4f} {worst:.1e}")


if __name__ == "__main__":
    main()
