"""Benchmark: cold compile time and the cost of one reference realization with the imposed top speed and with
each top-drive controller, against a baseline source tree (e.g. ``main`` checked out in a temporary worktree),
in the same run. Each measurement runs in a fresh process with an empty Numba cache (cold compile), pinned to
one core; the trees alternate so that a change of machine load hits both. Run:

    git worktree add /tmp/base <commit>
    .venv/bin/python benchmarks/bench_top_drive.py --baseline /tmp/base [--repeat 3] [--rounds 2]

The controllers on ``reference``: ``pi`` with stiff gains (k_p = 1e5 N·m·s/rad, k_i = 3e6 N·m/rad), and
``soft_torque`` and ``z_torque`` with their tuned gains.
"""

from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path

from _engine import run_in_tree  # sets one thread per library, as in the workers

CONTROLLERS = {
    "imposed_speed": {"controller": "imposed_speed"},
    "pi": {"controller": "pi", "proportional_gain": 1e5, "integral_gain": 3e6},
    "soft_torque": {"controller": "soft_torque", "proportional_gain": None, "integral_gain": None},
    "z_torque": {"controller": "z_torque", "proportional_gain": None, "integral_gain": None},
}


def worker(controllers: list[str], repeat: int) -> dict:
    """In this process (fresh Numba cache): the first run's compile time, then the best wall time of each
    controller's reference run (model build excluded)."""
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})
    from drillstring.case import load_case
    from drillstring.dynamics.rom import case_reduced_model
    from drillstring.dynamics.simulate import simulate_model

    base = load_case("reference")
    s = base.simulation
    kwargs = dict(t_end=s.t_end, output_step=s.output_step, rtol=s.rtol, atol=s.atol,
                  lateral_perturbation=base.initial.lateral_perturbation, seed=base.initial.seed)
    out: dict = {"compile_time": None, "runs": {}}
    for name in controllers:
        case = base if name == "imposed_speed" else base.model_copy(  # the baseline may have no [top_drive]
            update={"top_drive": base.top_drive.model_copy(update=CONTROLLERS[name])})
        model = case_reduced_model(case)
        start = time.perf_counter()
        first = simulate_model(model, t_end=0.1, output_step=0.01, lateral_perturbation=0.0)
        if out["compile_time"] is None:
            out["compile_time"] = float(first.stats.get("compile_time", 0.0))
            out["first_call"] = time.perf_counter() - start
        walls, result = [], None
        for _ in range(repeat):
            start = time.perf_counter()
            result = simulate_model(model, **kwargs)
            walls.append(time.perf_counter() - start)
        out["runs"][name] = {"wall": min(walls), "n_rhs": int(result.stats["n_rhs"]),
                             "bit_speed_min": float(result.observables["bit_speed"][result.time >= 10].min()),
                             "bit_speed_max": float(result.observables["bit_speed"][result.time >= 10].max())}
    return out


def run_tree(tree: Path, controllers: list[str], repeat: int) -> dict:
    return run_in_tree(__file__, tree, ["--worker", ",".join(controllers), "--repeat", str(repeat)])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--baseline", type=Path, required=False, help="source tree to compare with")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--worker", default=None, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.worker is not None:
        print(json.dumps(worker(args.worker.split(","), args.repeat)))
        return
    here = Path(__file__).resolve().parents[1]
    trees = {"this tree": (here, list(CONTROLLERS))}
    if args.baseline is not None:
        trees["baseline"] = (args.baseline.resolve(), ["imposed_speed"])
    results: dict[str, list[dict]] = {name: [] for name in trees}
    for _ in range(args.rounds):
        for name, (tree, controllers) in trees.items():
            results[name].append(run_tree(tree, controllers, args.repeat))
    print(f"reference case, one core, fresh Numba cache per process; best of {args.rounds} rounds x {args.repeat}")
    for name, rounds in results.items():
        compile_time = min(r["compile_time"] for r in rounds)
        print(f"{name}: cold compile {compile_time:.2f} s")
        for controller in rounds[0]["runs"]:
            best = min((r["runs"][controller] for r in rounds), key=lambda run: run["wall"])
            print(f"  {controller:14s} realization {best['wall']:.3f} s, {best['n_rhs']:,} RHS evaluations, "
                  f"bit speed {best['bit_speed_min'] * 30 / 3.141592653589793:.1f}-"
                  f"{best['bit_speed_max'] * 30 / 3.141592653589793:.1f} rpm (t >= 10 s)")


if __name__ == "__main__":
    main()
