"""Benchmark: Monte Carlo throughput of the reference study (sigma = 5000 N, case 2).

Runs the same realizations with 1 and 2 local worker processes (and optionally a local Dask
cluster), prints realizations per second per core and the projected wall time of a 500-realization
study; the per-realization cost of the reference path (NumPy RHS + Python integrator) is measured in
the same process as the baseline. Run:

    .venv/bin/python benchmarks/bench_study.py [--samples 40] [--dask] [--method ark43] [--workers 1,2]
"""

from __future__ import annotations

import argparse
import os
import shutil
import tempfile
import time
from pathlib import Path

from drillstring.case import load_case
from drillstring.dynamics.rom import case_reduced_model
from drillstring.dynamics.simulate import simulate_model
from drillstring.stochastic.execution import Engine
from drillstring.stochastic.montecarlo import StudySettings, run_study, weight_on_hook_normal


def timed_study(case, settings, workers=None, scheduler=None):
    folder = Path(tempfile.mkdtemp(prefix="bench_study_"))
    try:
        start = time.perf_counter()
        run = run_study(case, settings, folder / "study.zarr", Engine(workers=workers, scheduler=scheduler))
        return time.perf_counter() - start, run
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--samples", type=int, default=40)
    parser.add_argument("--dask", action="store_true", help="also time a local Dask cluster")
    parser.add_argument("--method", default=None, help="simulation.method for every run (default: the case's)")
    parser.add_argument("--workers", default="1,2", help="local process counts to time")
    parser.add_argument("--no-reference-path", action="store_true", help="skip timing the NumPy reference path")
    args = parser.parse_args()
    case = load_case("reference")
    if args.method is not None:
        case = case.model_copy(update={"simulation": case.simulation.model_copy(update={"method": args.method})})
    settings = StudySettings(samples=args.samples, seed=0, laws=(weight_on_hook_normal(case, 5000.0),),
                             t_end=case.simulation.t_end, output_step=case.simulation.output_step)
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()

    # per-realization cost, fast path vs reference path, same process
    start = time.perf_counter()
    model = case_reduced_model(case, weight_on_bit=101e3)
    build = time.perf_counter() - start
    kwargs = dict(t_end=settings.t_end, output_step=settings.output_step, method=case.simulation.method)
    simulate_model(model, **kwargs)
    start = time.perf_counter()
    simulate_model(model, engine="compiled", **kwargs)
    fast = time.perf_counter() - start
    line = f"one realization: model build {build:.3f} s + integration {fast:.3f} s (fast path)"
    if not args.no_reference_path:
        start = time.perf_counter()
        simulate_model(model, engine="reference", **kwargs)
        slow = time.perf_counter() - start
        line += f"; reference path integration {slow:.3f} s ({slow / fast:.1f}x slower)"
    print(line)

    rows = []
    for workers in (int(w) for w in args.workers.split(",")):
        wall, run = timed_study(case, settings, workers=workers)
        rows.append((f"{workers} local process(es)", workers, wall, run))
    if args.dask:
        from distributed import LocalCluster

        with LocalCluster(n_workers=2, threads_per_worker=1, dashboard_address=None) as cluster:
            wall, run = timed_study(case, settings, scheduler=cluster.scheduler_address)
        rows.append(("local Dask cluster, 2 workers", 2, wall, run))
    print(f"{args.samples} realizations + 1 nominal run, sigma = 5000 N, t_end = {settings.t_end} s,"
          f" {cores} cores, method {case.simulation.method}")
    for label, workers, wall, run in rows:
        rate = (args.samples + 1) / wall
        print(f"  {label:32s} {wall:7.2f} s  {rate:6.2f} realizations/s  {rate / workers:6.2f} per core"
              f"  -> 500 realizations in {501 / rate / 60:5.2f} min  (failed {run.failed})")
    base = rows[0][2]
    for label, _, wall, _ in rows[1:]:
        print(f"  speed-up of {label} over 1 process: {base / wall:.2f}x")


if __name__ == "__main__":
    main()
