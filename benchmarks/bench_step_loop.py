"""Benchmark and check of the step/loop split of the compiled integrator (issue 22, item 2), against a baseline
source tree (e.g. ``main`` exported to a temporary folder), in the same run.

Each tree runs in a fresh process with an empty Numba cache, pinned to one core; the trees alternate so that a
change of machine load hits both. Each worker reports the cold compile time (the first run's
``compile_time``), the best wall time of a reference realization (30 s, model built outside the timing), and
— in the first round — every output array of short runs of ``reference``, ``stick_slip``, ``contact`` and
``aarsnes2019`` (on-bottom start, and its own ramped start) with their step counts, which are then compared
between the trees bit for bit. Run:

    git -C /path/to/main archive <commit> | tar -x -C /tmp/base
    .venv/bin/python benchmarks/bench_step_loop.py --baseline /tmp/base [--rounds 2] [--repeat 3]
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
import time
from pathlib import Path

from _engine import run_in_tree  # sets one thread per library, as in the workers

import numpy as np  # noqa: E402

#: (case, start, t_end [s]) of the identity runs.
RUNS = (("reference", None, 10.0), ("stick_slip", None, 10.0), ("contact", None, 5.0),
        ("aarsnes2019", "on_bottom", 5.0), ("aarsnes2019", "ramp", 12.0))


def _identity_runs(folder: Path) -> dict:
    from drillstring.api import simulate
    from drillstring.case import load_case

    stats = {}
    for name, start, t_end in RUNS:
        case = load_case(name)
        if start is not None:
            case = case.model_copy(update={"initial": case.initial.model_copy(update={"start": start})})
        ds = simulate(case, t_end=t_end)
        key = f"{name}-{start or 'own'}"
        np.savez(folder / f"{key}.npz", **{v: ds[v].values for v in ds.data_vars},
                 **{f"coord_{c}": ds[c].values for c in ds.coords if np.issubdtype(ds[c].dtype, np.number)})
        stats[key] = {k: ds.attrs[f"solver_{k}"] for k in ("n_accepted", "n_rejected", "n_rhs", "status")}
    return stats


def worker(folder: str | None, repeat: int) -> dict:
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})
    from drillstring.case import load_case
    from drillstring.dynamics.rom import case_reduced_model
    from drillstring.dynamics.simulate import simulate_model

    case = load_case("reference")
    s = case.simulation
    model = case_reduced_model(case)
    cpu = time.process_time()
    first = simulate_model(model, t_end=0.1, output_step=0.01, lateral_perturbation=0.0)
    out: dict = {"compile_time": float(first.stats["compile_time"]), "compile_cpu": time.process_time() - cpu}
    kwargs = dict(t_end=s.t_end, output_step=s.output_step, rtol=s.rtol, atol=s.atol,
                  lateral_perturbation=case.initial.lateral_perturbation, seed=case.initial.seed)
    walls, cpus = [], []
    for _ in range(repeat):
        start, cpu = time.perf_counter(), time.process_time()
        result = simulate_model(model, **kwargs)
        walls.append(time.perf_counter() - start)
        cpus.append(time.process_time() - cpu)
    out["realization"], out["realization_cpu"] = min(walls), min(cpus)
    out["n_rhs"] = int(result.stats["n_rhs"])
    if folder:
        out["identity"] = _identity_runs(Path(folder))
    return out


def _compare(a: Path, b: Path, stats_a: dict, stats_b: dict) -> None:
    print("identity (every output array, bit for bit; step counts):")
    for key in stats_a:
        x, y = np.load(a / f"{key}.npz"), np.load(b / f"{key}.npz")
        worst, names, same = 0.0, sorted(x.files), set(x.files) == set(y.files)
        for v in names:
            if v not in y.files or x[v].shape != y[v].shape:
                same = False
                continue
            if not np.array_equal(x[v], y[v], equal_nan=True):
                same = False
                scale = np.nanmax(np.abs(y[v])) or 1.0
                worst = max(worst, float(np.nanmax(np.abs(x[v] - y[v])) / scale))
        counts = stats_a[key] == stats_b[key]
        print(f"  {key:24s} {len(names)} arrays {'identical' if same else f'DIFFER (max rel {worst:.2e})'}; "
              f"steps {stats_a[key]['n_accepted']} accepted, {stats_a[key]['n_rejected']} rejected, "
              f"{stats_a[key]['n_rhs']} RHS: {'equal' if counts else f'DIFFER from {stats_b[key]}'}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--baseline", type=Path, help="source tree to compare with (required)")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--worker", default=None, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.worker is not None:
        print(json.dumps(worker(args.worker or None, args.repeat)))
        return
    if args.baseline is None:
        parser.error("--baseline is required")
    trees = {"this tree": Path(__file__).resolve().parents[1], "baseline": args.baseline.resolve()}
    results: dict[str, list[dict]] = {name: [] for name in trees}
    with tempfile.TemporaryDirectory() as scratch:
        folders = {name: Path(scratch) / str(i) for i, name in enumerate(trees)}
        for round_ in range(args.rounds):
            for name, tree in trees.items():
                folder = ""
                if round_ == 0:
                    folders[name].mkdir()
                    folder = str(folders[name])
                results[name].append(run_in_tree(__file__, tree, ["--worker", folder, "--repeat", str(args.repeat)]))
        print(f"reference case, one core, fresh Numba cache per process; best of {args.rounds} rounds x "
              f"{args.repeat} realizations (30 s)")
        # wall times, and the process's CPU times (less sensitive to other work on a shared machine)
        best = {name: {key: min(r[key] for r in rounds) for key in ("compile_time", "compile_cpu", "realization",
                                                                   "realization_cpu")}
                for name, rounds in results.items()}
        for name, b in best.items():
            print(f"  {name:10s} cold compile {b['compile_time']:6.2f} s wall, {b['compile_cpu']:6.2f} s CPU; "
                  f"realization {b['realization']:.3f} s wall, {b['realization_cpu']:.3f} s CPU "
                  f"({results[name][0]['n_rhs']:,} RHS)")
        ratio = {key: best["this tree"][key] / best["baseline"][key] for key in best["baseline"]}
        print(f"  ratio this/baseline: cold compile {ratio['compile_time']:.3f} wall, {ratio['compile_cpu']:.3f} CPU; "
              f"realization {ratio['realization']:.3f} wall, {ratio['realization_cpu']:.3f} CPU")
        print(f"  load average at the end (1, 5, 15 min): " + ", ".join(f"{v:.2f}" for v in os.getloadavg()))
        _compare(folders["this tree"], folders["baseline"], results["this tree"][0]["identity"],
                 results["baseline"][0]["identity"])


if __name__ == "__main__":
    main()
