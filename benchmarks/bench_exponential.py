"""The exponential step (``erk32``) against DOPRI5 and the IMEX ``ark43`` at equal accuracy, per built-in case.

For each case (``reference``, ``contact``, case 1 = ``reference`` with ``nonlinear = "full"``, ``stick_slip``,
``aarsnes2019``, ``motor``): a tight DOPRI5 run (rtol/1000, atol likewise) is the yardstick; every method runs at
each rtol of ``--rtols`` (multiples of the case's rtol, atol scaled with it), and the error of its records
(max |Δ| / max |x| over ROP, bit speed, TOB, FOB) against the yardstick is printed with its right-hand sides,
steps and solver CPU time (one core, best of ``--repeat``). "At equal accuracy": for each method the cheapest
of its runs whose records error is at most DOPRI5's at the case's rtol (×1.5); the ratios are against DOPRI5
at the case's rtol, measured in the same process. ``--compile`` adds the cold compile time [s] of the step loop
per method (a fresh Numba cache in a child process, ``compile_time`` of a 0.01 s run), for the case 2 model;
``--law-in-a`` runs the exponential step with the bit law's linearisation at the run's start in ``A`` (the
measured alternative, :data:`drillstring.dynamics.steps.exponential.LINEARISED_LAW`); ``--refresh S`` with it runs
the exponential step as a sequence of :func:`~drillstring.dynamics.compiled.advance` calls of ``S`` seconds each,
so that ``A`` holds the law's linearisation at the start of each (an experiment: the state of a continued run
carries the controller, but the bit's history is the model's start's, right only for a law without delay).

    PYTHONPATH=src python benchmarks/bench_exponential.py [--cases reference,contact] [--t-end 5] [--compile]
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import json  # noqa: E402
import resource  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

from drillstring.case import load_case  # noqa: E402
from drillstring.dynamics.rom import case_reduced_model  # noqa: E402
from drillstring.dynamics.simulate import simulate_model  # noqa: E402

RECORDS = ("rate_of_penetration", "bit_speed", "torque_on_bit", "force_on_bit")
CASES = {"reference": ("reference", None), "contact": ("contact", None), "case1": ("reference", "full"),
         "stick_slip": ("stick_slip", None), "aarsnes2019": ("aarsnes2019", None), "motor": ("motor", None)}


def run(model, case, method: str, rtol: float, t_end: float, repeat: int):
    s = case.simulation
    best, best_cpu = None, np.inf
    for _ in range(repeat):
        start = time.process_time()
        result = simulate_model(model, t_end=t_end, output_step=s.output_step, rtol=rtol,
                                atol=s.atol * rtol / s.rtol, method=method, raise_on_failure=False,
                                lateral_perturbation=case.initial.lateral_perturbation, seed=case.initial.seed,
                                max_steps=20_000_000)
        cpu = time.process_time() - start  # the kernels compiled beforehand (main): a cache hit costs ~ms
        if cpu < best_cpu:
            best, best_cpu = result, cpu
    return best, best_cpu


def segmented(model, case, rtol: float, t_end: float, seconds: float):
    """The exponential step in ``advance`` calls of ``seconds`` each (``--refresh``): (observables by name,
    CPU [s], stats summed)."""
    from drillstring.dynamics.compiled import RunState, SolverSettings, advance
    from drillstring.dynamics.rom import OBSERVABLES

    s = case.simulation
    grid = np.arange(0.0, t_end + 1e-12, s.output_step)
    state = RunState.start(model, model.initial_state(case.initial.lateral_perturbation, case.initial.seed))
    solver = SolverSettings("erk32", rtol, s.atol * rtol / s.rtol, max_steps=20_000_000)
    rows, stats = [], {"n_rhs": 0, "n_accepted": 0, "n_rejected": 0, "status": "success"}
    start = time.process_time()
    for edge in np.append(np.arange(seconds, t_end, seconds), t_end):
        times = grid[(grid >= state.t) & (grid <= edge)] if not rows else grid[(grid > state.t) & (grid <= edge)]
        run = advance(model, solver, state, float(edge), output_times=times)
        rows.append(run.outputs)
        for key in ("n_rhs", "n_accepted", "n_rejected"):
            stats[key] += run.stats[key]
        if not run.success:
            stats["status"] = "failed"
            break
        state = run.state
    cpu = time.process_time() - start
    out = np.vstack(rows)
    return {name: out[:, k] for k, name in enumerate(OBSERVABLES)}, cpu, stats


class _Observed:
    def __init__(self, time_axis, observables):
        self.time, self.observables = time_axis, observables


def records(a, b) -> float:
    n = min(len(a.time), len(b.time))
    if n == 0:
        return float("nan")
    return max(float(np.max(np.abs(a.observables[k][:n] - b.observables[k][:n]))
                     / max(np.max(np.abs(b.observables[k][:n])), 1e-300)) for k in RECORDS)


def cold_compile(method: str) -> tuple[float, float]:
    """compile_time [s] of a 0.01 s reference run with ``method`` in a fresh Numba cache (child process), and
    the child's whole CPU time [s] (user + system: the machine is shared, wall times under load mislead)."""
    code = ("import json; from drillstring.case import load_case; from drillstring.dynamics.rom import "
            "case_reduced_model; from drillstring.dynamics.simulate import simulate_model; c = load_case('reference');"
            f" r = simulate_model(case_reduced_model(c), t_end=0.01, output_step=0.01, method={method!r});"
            " print(json.dumps(r.stats['compile_time']))")
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache)
        out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return float(json.loads(out.stdout.strip().splitlines()[-1])), cpu


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--cases", default=",".join(CASES))
    parser.add_argument("--methods", default="dopri5,ark43,erk32")
    parser.add_argument("--rtols", default="1,0.1", help="multiples of the case's rtol")
    parser.add_argument("--t-end", type=float, default=None, help="default: the case's")
    parser.add_argument("--repeat", type=int, default=2)
    parser.add_argument("--compile", action="store_true")
    parser.add_argument("--refresh", type=float, default=None, help="seconds per advance call (with --law-in-a)")
    parser.add_argument("--law-in-a", action="store_true",
                        help="the measured alternative: the bit law's linearisation at each run's start in A")
    args = parser.parse_args()
    if args.law_in_a:
        from drillstring.dynamics.steps import exponential

        exponential.LINEARISED_LAW = True
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})  # one core
    methods = args.methods.split(",")
    factors = [float(x) for x in args.rtols.split(",")]
    if args.compile:
        for _ in range(args.repeat):  # the methods alternating
            for method in methods:
                wall, cpu = cold_compile(method)
                print(f"cold compile (reference, case 2) {method}: compile_time {wall:.1f} s, process CPU {cpu:.1f} s",
                      flush=True)
    for label in args.cases.split(","):
        name, nonlinear = CASES[label]
        case = load_case(name)
        t_end = args.t_end or case.simulation.t_end
        model = case_reduced_model(case, nonlinear=nonlinear)
        rtol = case.simulation.rtol
        for method in methods:  # compile outside the timing
            simulate_model(model, t_end=0.01, output_step=0.01, method=method, raise_on_failure=False)
        tight, _ = run(model, case, "dopri5", rtol / 1000, t_end, 1)
        print(f"case {label} ({model.nonlinear}), {model.size} modal coordinates, t_end = {t_end:g} s, case rtol "
              f"{rtol:g}; yardstick dopri5 at rtol/1000 ({tight.stats['n_accepted']} steps); one core, best of "
              f"{args.repeat}", flush=True)
        rows = {}
        for method in methods:
            for factor in factors:
                result, cpu = run(model, case, method, rtol * factor, t_end, args.repeat)
                st = result.stats
                error = records(result, tight)
                rows[(method, factor)] = (cpu, error, st)
                status = "" if st["status"] == "success" else f"  FAILED: {result.message[:100]}"
                print(f"  {method:7s} rtol {rtol * factor:7.1e}: CPU {cpu:7.3f} s  RHS {st['n_rhs']:>9d}  steps "
                      f"{st['n_accepted']:>8d}+{st['n_rejected']:<5d} records error {error:.2e}{status}", flush=True)
        extra = [f"erk32/{args.refresh:g}s"] if args.refresh else []
        if args.refresh:
            for factor in factors:
                observed, cpu, st = segmented(model, case, rtol * factor, t_end, args.refresh)
                result = _Observed(np.arange(len(observed[RECORDS[0]])) * case.simulation.output_step, observed)
                error = records(result, tight)
                rows[(f"erk32/{args.refresh:g}s", factor)] = (cpu, error, st)
                print(f"  erk32, A re-linearised every {args.refresh:g} s, rtol {rtol * factor:7.1e}: CPU {cpu:7.3f} s "
                      f" RHS {st['n_rhs']:>9d}  steps {st['n_accepted']:>8d}+{st['n_rejected']:<5d} records error "
                      f"{error:.2e} {st['status']}", flush=True)
        base_cpu, base_error, _ = rows[("dopri5", 1.0)] if ("dopri5", 1.0) in rows else (np.nan, np.nan, None)
        for method in methods + extra:
            fits = [(cpu, f, e) for (m, f), (cpu, e, st) in rows.items()
                    if m == method and st["status"] == "success" and e <= 1.5 * base_error]
            if fits:
                cpu, f, e = min(fits)
                print(f"  at equal accuracy {method}: rtol x{f:g}, CPU {cpu:.3f} s, {base_cpu / cpu:.2f}x dopri5")
            else:
                print(f"  at equal accuracy {method}: no run as accurate as dopri5 at the case's rtol")


if __name__ == "__main__":
    main()
