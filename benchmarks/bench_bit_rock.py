"""Benchmark: the cost of one realization with the Detournay bit–rock law against the Tucker–Wang law on the
same string, and of the Tucker–Wang reference realization against a baseline source tree (e.g. the commit
before the Detournay law, checked out in a temporary worktree), in the same run. Each tree's measurements run
in a fresh process with an empty Numba cache, pinned to one core; the trees alternate over the rounds so that
a change of machine load hits both. Run:

    git worktree add /tmp/base <commit>
    .venv/bin/python benchmarks/bench_bit_rock.py [--baseline /tmp/base] [--repeat 3] [--rounds 2]

Runs (30 s each, the case's own tolerances and output step, model build excluded):

- ``reference/tucker_wang``: the reference realization (the reference start);
- ``aarsnes2019/detournay``: the published case as it is (ramped start, stick-slip);
- ``aarsnes2019/tucker_wang``: the same string and start with the Tucker–Wang law (its reference coefficients);
- ``aarsnes2019/detournay_on_bottom``: the Detournay law started on the steady bottom.
"""

from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path

from _engine import run_in_tree  # sets one thread per library, as in the workers

RUNS = {
    "reference/tucker_wang": ("reference", {}),
    "aarsnes2019/detournay": ("aarsnes2019", {}),
    "aarsnes2019/tucker_wang": ("aarsnes2019", {"bit_rock": {"law": "tucker_wang"}}),
    "aarsnes2019/detournay_on_bottom": ("aarsnes2019", {"initial": {"start": "on_bottom"}}),
}


def worker(names: list[str], repeat: int) -> dict:
    """In this process (fresh Numba cache): the best wall time of each run (model build excluded)."""
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})
    from drillstring.case import load_case
    from drillstring.dynamics.rom import case_reduced_model
    from drillstring.dynamics.simulate import simulate_model

    out: dict = {}
    for name in names:
        case_name, tables = RUNS[name]
        case = load_case(case_name)
        case = case.model_copy(update={k: getattr(case, k).model_copy(update=v) for k, v in tables.items()})
        s = case.simulation
        model = case_reduced_model(case)
        simulate_model(model, t_end=0.05, output_step=0.01, lateral_perturbation=0.0)  # compile
        walls, result = [], None
        for _ in range(repeat):
            start = time.perf_counter()
            result = simulate_model(model, t_end=30.0, output_step=s.output_step, rtol=s.rtol, atol=s.atol,
                                    lateral_perturbation=case.initial.lateral_perturbation, seed=case.initial.seed,
                                    raise_on_failure=False)
            walls.append(time.perf_counter() - start)
        out[name] = {"wall": min(walls), "n_rhs": int(result.stats["n_rhs"]),
                     "n_accepted": int(result.stats["n_accepted"]), "status": result.status}
    return out


def run_tree(tree: Path, names: list[str], repeat: int) -> dict:
    return run_in_tree(__file__, tree, ["--worker", ",".join(names), "--repeat", str(repeat)])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--baseline", type=Path, help="source tree to compare the Tucker–Wang reference run with")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--worker")
    args = parser.parse_args()
    if args.worker:
        print(json.dumps(worker(args.worker.split(","), args.repeat)))
        return
    here = Path(__file__).resolve().parents[1]
    best: dict[str, dict] = {}
    for _ in range(args.rounds):
        for label, tree, names in [("this tree", here, list(RUNS))] + (
                [("baseline", args.baseline, ["reference/tucker_wang"])] if args.baseline else []):
            for name, run in run_tree(tree, names, args.repeat).items():
                key = f"{label}: {name}"
                if key not in best or run["wall"] < best[key]["wall"]:
                    best[key] = run
    print(f"{'run':52s} {'wall [s]':>9s} {'rhs calls':>11s} {'steps':>9s}  status")
    for key, run in best.items():
        print(f"{key:52s} {run['wall']:9.2f} {run['n_rhs']:11,d} {run['n_accepted']:9,d}  {run['status']}")
    tw = best["this tree: aarsnes2019/tucker_wang"]["wall"]
    print(f"\nDetournay / Tucker–Wang on the aarsnes2019 string, ramped start: "
          f"{best['this tree: aarsnes2019/detournay']['wall'] / tw:.2f}; started on the steady bottom: "
          f"{best['this tree: aarsnes2019/detournay_on_bottom']['wall'] / tw:.2f}")
    if args.baseline:
        print(f"reference realization, this tree / baseline: "
              f"{best['this tree: reference/tucker_wang']['wall'] / best['baseline: reference/tucker_wang']['wall']:.3f}")


if __name__ == "__main__":
    main()
