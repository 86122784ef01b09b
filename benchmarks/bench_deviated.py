"""Benchmark: one realization of the deviated case (its well's statics, the along-string friction) against the
reference case's, in the same run (issue 34).

For each of ``reference`` (as written), ``deviated`` (as written: the stiff-string statics, Coulomb friction at
its nodes on the wall) and ``deviated`` without the friction (the same model, ``string_friction`` None), in this
process with the Numba cache warm (a first short run of each compiles or loads the kernels):

- ``build``: ``case_reduced_model(case)`` (statics, linear system, modes, damping, the kernels' data) [s, CPU];
- ``run``: ``simulate_model`` over ``--t-end`` seconds with the case's method and tolerances [s, CPU], its
  steps and right-hand-side evaluations, and the CPU time per right-hand-side evaluation.

The best of ``--repeat`` runs is kept; ratios are against the reference case of the same run.

Then a Monte Carlo study of ``--samples`` realizations (default 100; 0 skips it) of each of ``reference`` and
``deviated`` (the default law: the weight-on-hook Normal, σ = 5 kN), ``--t-end`` seconds each, on
``--workers`` local processes (default 1: in this process), into a temporary folder: the study's computation
time (``summary["wall_time"]``: the realizations, nominal run included), the whole call's wall and CPU time
(statistics, figures and report too), the time per realization and the note on its models (the reference
study's parametric model, built once; the deviated study rebuilds every realization: its well's statics is not
parametrised). Run from the repository root:

    PYTHONPATH=src python benchmarks/bench_deviated.py [--t-end 5] [--repeat 3] [--samples 100] [--workers 1]
"""

from __future__ import annotations

import argparse
import dataclasses
import tempfile
import time
from pathlib import Path

from drillstring.case import load_case
from drillstring.dynamics.rom import case_reduced_model
from drillstring.dynamics.simulate import simulate_model


def _cpu(function):
    start = time.process_time()
    value = function()
    return time.process_time() - start, value


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--t-end", type=float, default=5.0, help="simulated time [s]")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--samples", type=int, default=100, help="realizations of each study (0: no study)")
    parser.add_argument("--workers", type=int, default=1, help="local processes of each study")
    options = parser.parse_args()
    rows = {}
    for label, name, friction in (("reference", "reference", True), ("deviated", "deviated", True),
                                  ("deviated, no friction", "deviated", False)):
        case = load_case(name)
        builds, model = [], None
        for _ in range(options.repeat if friction else 1):
            seconds, model = _cpu(lambda case=case: case_reduced_model(case))
            builds.append(seconds)
        if not friction:
            model = dataclasses.replace(model, string_friction=None)
        s = case.simulation

        def run(t_end, model=model, s=s):
            return simulate_model(model, t_end=t_end, output_step=s.output_step, method=s.method, rtol=s.rtol,
                                  atol=s.atol)

        run(0.05)  # compile or load the kernels
        runs = [_cpu(lambda: run(options.t_end)) for _ in range(options.repeat)]
        seconds, result = min(runs, key=lambda r: r[0])
        rows[label] = (min(builds) if friction else float("nan"), seconds, result.stats["n_steps"],
                       result.stats["n_rhs"], model.size, len(model.friction_stations))
    base = rows["reference"]
    print(f"{options.t_end:g} s simulated, best of {options.repeat}, CPU seconds")
    print(f"{'case':<24}{'modes':>6}{'stations':>9}{'build [s]':>10}{'run [s]':>9}{'x ref':>7}{'steps':>8}{'rhs':>8}"
          f"{'us/rhs':>8}{'x ref':>7}")
    for label, (build, run, steps, rhs, size, stations) in rows.items():
        per = run / rhs * 1e6
        print(f"{label:<24}{size:>6}{stations:>9}{build:>10.2f}{run:>9.3f}{run / base[1]:>7.2f}{steps:>8}{rhs:>8}"
              f"{per:>8.1f}{per / (base[1] / base[3] * 1e6):>7.2f}")
    if options.samples:
        _studies(options)


def _studies(options) -> None:
    """The two studies of the module docstring, in this run, and their ratio."""
    from drillstring import api

    rows = {}
    for name in ("reference", "deviated"):
        notes: list[str] = []
        with tempfile.TemporaryDirectory(prefix=f"bench-deviated-{name}-") as folder:
            start, cpu = time.perf_counter(), time.process_time()
            outcome = api.monte_carlo_study(load_case(name), samples=options.samples, t_end=options.t_end,
                                            workers=options.workers, out=Path(folder) / "study", note=notes.append)
            rows[name] = (outcome.summary["wall_time"], time.perf_counter() - start, time.process_time() - cpu,
                          outcome.summary["n_failed"],
                          next((n for n in notes if "rebuilt" in n), "parametric model, built once"))
    print(f"\nstudies: {options.samples} realizations of {options.t_end:g} s, {options.workers} worker(s), wall s")
    print(f"{'case':<12}{'study [s]':>10}{'x ref':>7}{'per real. [s]':>14}{'call [s]':>10}{'CPU [s]':>9}"
          f"{'failed':>7}  models")
    for name, (study, call, cpu, failed, note) in rows.items():
        print(f"{name:<12}{study:>10.1f}{study / rows['reference'][0]:>7.2f}{study / options.samples:>14.3f}"
              f"{call:>10.1f}{cpu:>9.1f}{failed:>7}  {note}")


if __name__ == "__main__":
    main()
