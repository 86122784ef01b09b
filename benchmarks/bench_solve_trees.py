"""The solve of one realization timed for two source trees in one run (e.g. ``main`` exported to a temporary
folder against this tree), so that the ratio is fair on a shared, noisy machine.

Each round runs one worker process per tree, the trees alternating (so a change of the machine's load hits
both), each pinned to one core with one thread per library. A worker builds each case's model (outside the
timing), runs it once (the kernels compiled or loaded from the tree's own Numba cache, kept between rounds:
the first round of a tree compiles cold, or every round with ``--cold``; the compile time of each compiling
run is reported, in wall time and as the CPU time of that first run), then times ``--repeat`` solves (the
CPU time of ``simulate_model``, steadier than wall time on a loaded machine; with ``--clock times`` the solver's
``wall_time``, the compiled step loop; neither includes the model build). Printed per case: the median and
the best solve of each tree over all rounds and repeats, the ratio of the medians, and the step counts of
both trees (they must be equal: the outputs of the trees are compared bit for bit by
``benchmarks/protocol_equality.py``). Run:

    git -C /path/to/main archive <commit> | tar -x -C /tmp/base
    .venv/bin/python benchmarks/bench_solve_trees.py --baseline /tmp/base [--rounds 3] [--repeat 3]
        [--cases reference,contact,case1]

The cases: a built-in case's name (its own run length), or ``case1``, the ``reference`` case with
``model.nonlinear = "full"`` over ``--case1-t-end`` seconds.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

THREADS = {"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1", "NUMBA_NUM_THREADS": "1"}
os.environ.update(THREADS)


def worker(cases: list[str], repeat: int, case1_t_end: float, method: str | None = None) -> dict:
    """Build and solve each case in this process (the tree on ``PYTHONPATH``); the solve times [s]."""
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {max(os.sched_getaffinity(0))})
    from drillstring.case import load_case
    from drillstring.dynamics.rom import case_reduced_model
    from drillstring.dynamics.simulate import simulate_model

    out = {}
    for name in cases:
        case = load_case("reference" if name == "case1" else name)
        s = case.simulation
        model = case_reduced_model(case, nonlinear="full" if name == "case1" else None)
        kwargs = {"t_end": case1_t_end if name == "case1" else s.t_end, "output_step": s.output_step,
                  "rtol": s.rtol, "atol": s.atol, "method": method or s.method,
                  "lateral_perturbation": case.initial.lateral_perturbation, "seed": case.initial.seed}
        cpu_start = time.process_time()
        first = simulate_model(model, **kwargs)
        first_cpu = time.process_time() - cpu_start
        times, cpu = [], []
        for _ in range(repeat):
            start = time.process_time()
            result = simulate_model(model, **kwargs)
            cpu.append(time.process_time() - start)
            times.append(result.stats["wall_time"])
        out[name] = {"times": times, "cpu": cpu, "compile_time": first.stats["compile_time"],
                     "first_cpu": first_cpu,
                     "compiled": bool(first.stats["compiled"]),
                     "counts": [int(result.stats[k]) for k in ("n_rhs", "n_accepted", "n_rejected")]}
    return out


def _run(tree: Path, cache: Path, arguments: list[str]) -> dict:
    env = dict(os.environ, PYTHONPATH=str(tree / "src"), NUMBA_CACHE_DIR=str(cache), **THREADS)
    done = subprocess.run([sys.executable, __file__, *arguments], env=env, capture_output=True, text=True,
                          check=False)
    if done.returncode:
        raise SystemExit(f"the worker in {tree} failed:\n{done.stderr}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--baseline", type=Path, help="the source tree to compare with (required)")
    parser.add_argument("--tree", type=Path, default=Path(__file__).resolve().parents[1],
                        help="the source tree measured (default: this one)")
    parser.add_argument("--cases", default="reference,contact,case1")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--case1-t-end", type=float, default=10.0)
    parser.add_argument("--method", default=None, help="the integration method of every case (default: each case's)")
    parser.add_argument("--clock", choices=("cpu", "times"), default="cpu",
                        help="cpu: the CPU time of the process over a run (default; steadier under load), times: "
                             "the solver's wall_time")
    parser.add_argument("--cold", action="store_true",
                        help="an empty Numba cache for every round (each round compiles cold), not one per tree")
    parser.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    cases = [c for c in args.cases.split(",") if c]
    if args.worker:
        print(json.dumps(worker(cases, args.repeat, args.case1_t_end, args.method)))
        return
    if args.baseline is None:
        parser.error("--baseline is required")
    trees = {"tree": args.tree.resolve(), "baseline": args.baseline.resolve()}
    arguments = ["--worker", "--cases", ",".join(cases), "--repeat", str(args.repeat),
                 "--case1-t-end", str(args.case1_t_end)] + (["--method", args.method] if args.method else [])
    results: dict[str, list[dict]] = {label: [] for label in trees}
    with tempfile.TemporaryDirectory() as caches:
        for r in range(args.rounds):
            order = list(trees) if r % 2 == 0 else list(reversed(trees))
            for label in order:
                cache = Path(caches) / (f"{label}-{r}" if args.cold else label)
                results[label].append(_run(trees[label], cache, arguments))
                print(f"round {r + 1}: {label} done", file=sys.stderr, flush=True)
    clock = "CPU time of simulate_model" if args.clock == "cpu" else "the solver's wall_time"
    print(f"solve times [s] ({clock}), {args.rounds} rounds x {args.repeat} repeats per tree, one core; load average "
          + ", ".join(f"{v:.2f}" for v in os.getloadavg()))
    print(f"  tree: {trees['tree']}\n  baseline: {trees['baseline']}")
    for name in cases:
        row = {}
        for label in trees:
            times = [t for res in results[label] for t in res[name][args.clock]]
            cold = [(res[name]["compile_time"], res[name]["first_cpu"]) for res in results[label]
                    if res[name]["compiled"]]
            row[label] = (statistics.median(times), min(times), results[label][0][name]["counts"], cold)
        (med, best, counts, cold), (bmed, bbest, bcounts, bcold) = row["tree"], row["baseline"]
        same = "equal" if counts == bcounts else f"DIFFER (baseline {bcounts})"
        print(f"{name:10s} baseline median {bmed:.4f} best {bbest:.4f} | tree median {med:.4f} best {best:.4f} | "
              f"ratio of medians {bmed / med:.2f}x, of bests {bbest / best:.2f}x | RHS, accepted, rejected "
              f"{counts}: {same}")
        if cold and bcold:
            print(f"{'':10s} compiling runs: compile_time (wall) baseline "
                  + ", ".join(f"{c[0]:.1f}" for c in bcold) + " s, tree " + ", ".join(f"{c[0]:.1f}" for c in cold)
                  + " s; CPU of the first run (compile + one solve) baseline "
                  + ", ".join(f"{c[1]:.1f}" for c in bcold) + " s, tree " + ", ".join(f"{c[1]:.1f}" for c in cold)
                  + f" s: median ratio tree/baseline {statistics.median(c[1] for c in cold) / statistics.median(c[1] for c in bcold):.2f}")


if __name__ == "__main__":
    main()
