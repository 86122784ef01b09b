"""Benchmark (issue 22, the component protocol): the cold compile and one reference realization of this tree
against a baseline tree (e.g. ``main`` at a9da97a), in the same run: each measurement in a fresh process with
an empty Numba cache, pinned to one core, the trees alternating round by round so that a change of machine
load hits both. Wall and CPU (process) times are both reported: on a loaded machine the CPU time, which
leaves out the time the process waits for the core, is the steadier figure. Run:

    .venv/bin/python benchmarks/bench_protocol.py --baseline /path/to/base [--rounds 4] [--repeat 5]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import time
from pathlib import Path

from _engine import load_average, run_in_tree  # sets one thread per library, as in the workers


def worker(repeat: int) -> dict:
    """In this process (fresh Numba cache): the first run's compile (wall and CPU seconds), then the best of
    ``repeat`` reference realizations (model build excluded)."""
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[-1]})
    from drillstring.case import load_case
    from drillstring.dynamics.rom import case_reduced_model
    from drillstring.dynamics.simulate import simulate_model

    case = load_case("reference")
    s = case.simulation
    model = case_reduced_model(case)
    wall, cpu = time.perf_counter(), time.process_time()
    first = simulate_model(model, t_end=0.1, output_step=0.01, lateral_perturbation=0.0)
    out = {"compile_wall": time.perf_counter() - wall, "compile_cpu": time.process_time() - cpu,
           "compile_time": float(first.stats.get("compile_time", 0.0))}
    walls, cpus = [], []
    for _ in range(repeat):
        wall, cpu = time.perf_counter(), time.process_time()
        result = simulate_model(model, t_end=s.t_end, output_step=s.output_step, rtol=s.rtol, atol=s.atol,
                                lateral_perturbation=case.initial.lateral_perturbation, seed=case.initial.seed)
        walls.append(time.perf_counter() - wall)
        cpus.append(time.process_time() - cpu)
    out.update(run_wall=min(walls), run_cpu=min(cpus), n_rhs=int(result.stats["n_rhs"]))
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--baseline", type=Path)
    parser.add_argument("--rounds", type=int, default=4)
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.worker:
        print(json.dumps(worker(args.repeat)))
        return
    trees = {"this tree": Path(__file__).resolve().parents[1], "baseline": args.baseline.resolve()}
    results: dict[str, list[dict]] = {name: [] for name in trees}
    print(load_average("start"), flush=True)
    for _ in range(args.rounds):
        for name, tree in trees.items():
            results[name].append(run_in_tree(__file__, tree, ["--worker", "--repeat", str(args.repeat)]))
    print(load_average("end"))
    keys = ("compile_wall", "compile_cpu", "run_wall", "run_cpu")
    summary = {name: {k: (min(r[k] for r in rounds), statistics.median(r[k] for r in rounds)) for k in keys}
               for name, rounds in results.items()}
    for name, rounds in results.items():
        print(f"{name} ({rounds[0]['n_rhs']:,} RHS evaluations per realization):")
        for k in keys:
            print(f"  {k:13s} min {summary[name][k][0]:7.3f} s  median {summary[name][k][1]:7.3f} s  "
                  f"({', '.join(f'{r[k]:.3f}' for r in rounds)})")
    print("ratio this tree / baseline (min, median):")
    for k in keys:
        here, base = summary["this tree"][k], summary["baseline"][k]
        print(f"  {k:13s} {here[0] / base[0]:.3f}  {here[1] / base[1]:.3f}")


if __name__ == "__main__":
    main()
