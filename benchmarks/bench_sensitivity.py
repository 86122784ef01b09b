"""Benchmark: a 3-parameter Sobol' study of the reference case with N = 1024 base samples (5 120 runs of
20 s), on local processes and on a local Dask cluster.

Parameters: the driller's three controls, uniform: weight-on-hook 1033.4–1093.4 kN (weight-on-bit
70–130 kN, across the lateral buckling limit at 114 kN), fluid inlet velocity 1–2 m/s and top speed
60–140 rpm (docs/sensitivity.md answers the reference study's question with eight parameters). Prints the wall time, runs per second, the speed-up over the serial cost of the runs
projected from a random sample run one after the other in this process (the baseline, measured in the same
run), the sum of the runs' own times over the wall time (the parallelism achieved), the load average (the
machine is shared), and the indices with their largest change from N/2 to N. Goal: <= 30 min on the project's 2-core
machine. Run:

    .venv/bin/python benchmarks/bench_sensitivity.py [--samples 1024] [--t-end 20] [--dask] [--sample 8]
        [--method ark43] [--rebuild]
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

from _engine import cores, load_average, local_dask_cluster, serial_cost, timed_in_folder  # before NumPy

from drillstring import api
from drillstring.case import load_case
from drillstring.stochastic.sensitivity_study import SensitivitySettings, _row_task, sensitivity_design
from drillstring.stochastic.study_model import REBUILD_VARIABLE

LAWS = {"weight_on_hook": "uniform 1033.4 1093.4 kN", "fluid.inlet_velocity": "uniform 1 2 m/s",
        "operation.top_speed": "uniform 60 140 rpm"}


def timed(case, samples, t_end, keep: Path | None = None, **engine):
    return timed_in_folder(
        "bench_sensitivity_", lambda folder: api.sensitivity(
            case, parameters=LAWS, samples=samples, t_end=t_end, out=folder, **engine),
        keep, ("sensitivity.json", "sobol.png", "sobol_convergence.png", "report.html"))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--samples", type=int, default=1024, help="base samples N (power of 2)")
    parser.add_argument("--t-end", type=float, default=20.0)
    parser.add_argument("--sample", type=int, default=8, help="runs made serially for the baseline")
    parser.add_argument("--dask", action="store_true", help="also time a local Dask cluster (2 workers)")
    parser.add_argument("--keep", type=Path, default=None, help="copy the local run's files to this folder")
    parser.add_argument("--method", default=None, help="simulation.method for every run (default: the case's)")
    parser.add_argument("--rebuild", action="store_true",
                        help="rebuild every run's model (the recipe before the design's parametric model)")
    args = parser.parse_args()
    case = load_case("reference")
    if args.method is not None:
        case = case.model_copy(update={"simulation": case.simulation.model_copy(update={"method": args.method})})
    print(load_average("start"))
    settings = SensitivitySettings(args.samples, tuple(LAWS.items()), t_end=args.t_end)
    design = sensitivity_design(case, settings)
    # the serial baseline: every run's model rebuilt (the recipe before the parametric model)
    os.environ[REBUILD_VARIABLE] = "1"
    per_run, sampled = serial_cost(lambda i: _row_task(case, design.uncertainty, settings, (i, design.values[i])),
                                   design.runs, args.sample)
    if args.rebuild:
        print(f"every run's model rebuilt ({REBUILD_VARIABLE}=1, inherited by the workers)")
    else:
        del os.environ[REBUILD_VARIABLE]
    serial = per_run * design.runs
    print(f"Sobol' study: 3 parameters, N = {args.samples}, {design.runs} runs of {args.t_end:g} s, {cores()} cores,"
          f" method {case.simulation.method};"
          f" serial cost {per_run:.3f} s per run (sample of {sampled}) -> {serial / 60:.1f} min projected serially")
    rows = [("local processes (one per core)", *timed(case, args.samples, args.t_end, args.keep))]
    if args.dask:
        with local_dask_cluster() as address:
            rows.append(("local Dask cluster, 2 workers", *timed(case, args.samples, args.t_end, scheduler=address)))
    for label, wall, outcome in rows:
        p = outcome.payload
        busy = p["run_wall_time_total"]
        print(f"  {label:32s} {wall / 60:6.1f} min  {design.runs / wall:6.2f} runs/s  speed-up {serial / wall:4.2f}x"
              f" over the serial projection; sum of the runs' own times {busy / 60:.1f} min = {busy / wall:.2f} x the "
              f"wall time  (failed {p['failed_runs']}; goal <= 30 min: {'met' if wall <= 1800 else 'NOT met'})")
    result = rows[0][2].result
    for o, name in enumerate(result.outputs):
        change = result.convergence_change(name)
        s1 = ", ".join(f"{p.split('.')[-1]} {v:.3f}" for p, v in zip(result.parameters, result.S1[o]))
        st = ", ".join(f"{v:.3f}" for v in result.ST[o])
        print(f"  {name:28s} S1: {s1}; ST: {st}; max change N/2 -> N {change[-1]:.3f}")


if __name__ == "__main__":
    main()
    print(load_average("end"))
