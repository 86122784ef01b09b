"""Where the first compilation goes: the compiled functions of one case's first run, each with its own (self)
and its inclusive compile time, from Numba's compile events, in a fresh process with an empty Numba cache,
pinned to one core. Run:

    .venv/bin/python benchmarks/compile_profile.py [CASE] [--top 25]

Numba compiles a function's callees first (nested events); a function's self time is its inclusive time less
its callees'. Every compiled function that calls the right-hand side links a copy of the right-hand side's
whole call tree, which Numba optimizes and generates again: such a function shows a self time of 1–1.5 s
however small its own body (docs/performance.md, "Start-up").
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile


def worker(case_name: str, top: int) -> None:
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[-1]})
    import time

    from numba.core import event

    from drillstring.case import load_case
    from drillstring.dynamics.rom import case_reduced_model
    from drillstring.dynamics.simulate import simulate_model

    recorder = event.RecordingListener()
    event.register("numba:compile", recorder)
    model = case_reduced_model(load_case(case_name))
    wall, cpu = time.perf_counter(), time.process_time()
    simulate_model(model, t_end=0.1, output_step=0.01, lateral_perturbation=0.0)
    wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
    open_events: list[list[float]] = []  # [start, time of the callees]
    rows = []
    for stamp, ev in recorder.buffer:
        if ev.is_start:
            open_events.append([stamp, 0.0])
            continue
        start, callees = open_events.pop()
        inclusive = stamp - start
        if open_events:
            open_events[-1][1] += inclusive
        function = ev.data["dispatcher"].py_func
        rows.append((inclusive - callees, inclusive, f"{function.__module__}.{function.__qualname__}"))
    print(f"{case_name}: first run {wall:.2f} s wall, {cpu:.2f} s CPU; {len(rows)} functions compiled")
    print("   self  inclusive [s]  function")
    for own, inclusive, name in sorted(rows, reverse=True)[:top]:
        print(f"{own:7.3f}  {inclusive:9.3f}      {name}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("case", nargs="?", default="reference")
    parser.add_argument("--top", type=int, default=25)
    parser.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.worker:
        worker(args.case, args.top)
        return
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1",
                   MKL_NUM_THREADS="1", NUMBA_NUM_THREADS="1")
        subprocess.run([sys.executable, __file__, args.case, "--top", str(args.top), "--worker"], env=env,
                       check=True)


if __name__ == "__main__":
    main()
