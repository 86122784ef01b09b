"""Benchmark: start-up cost of the command line, end to end from the shell.

Measures, each in a fresh interpreter started the way a user starts the ``drillstring`` command:

- ``cold simulate``: ``drillstring simulate reference --t-end 1`` with an empty Numba cache
  (a fresh ``NUMBA_CACHE_DIR``): the first-ever run, kernels compiled; whether a compilation
  message appeared on stderr;
- ``warm simulate``: ``drillstring simulate reference`` (the case's 30 s) with the cache filled:
  total wall time, the solver's own wall time (from ``--json``) and the difference (imports, model
  build, NetCDF, figure);
- ``warm modes``: ``drillstring modes reference``;
- ``import``: ``python -c "import drillstring.cli"``;
- ``load case``: ``python -c`` importing ``drillstring.case`` and loading the reference case (its unit
  strings read by pint: the import and registry of the unit library, issue 18).

With ``--baseline REF`` the same measurements are made, in the same run, on the source tree of the git
revision ``REF`` (extracted with ``git archive`` to a temporary folder), so the two columns are
comparable on a noisy machine. Run from the repository root:

    .venv/bin/python benchmarks/bench_startup.py [--repeat 3] [--baseline 6036199]

Goals (issue 12): cold <= 15 s with a visible message; warm simulate <= 2 s beyond the solver time;
warm modes <= 1.5 s.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tarfile
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
# What the ``drillstring`` console script runs: ``cli.run`` (Dask hidden from the commands that do not use
# it) where the tree has it, else ``cli.app`` (older revisions).
CLI = ("import sys; from drillstring import cli; sys.argv[0] = 'drillstring'; "
       "getattr(cli, 'run', cli.app)()")


def _children_cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def _run(src: Path, args: list[str], cache: Path, cwd: Path) -> tuple[float, float, subprocess.CompletedProcess]:
    """Run ``drillstring ARGS`` with the package from ``src``; returns (wall [s], CPU [s], process)."""
    env = dict(os.environ, PYTHONPATH=str(src), NUMBA_CACHE_DIR=str(cache))
    cpu = _children_cpu()
    start = time.perf_counter()
    done = subprocess.run([sys.executable, "-c", CLI, *args], env=env, cwd=cwd, capture_output=True,
                          text=True)
    wall = time.perf_counter() - start
    if done.returncode != 0:
        raise RuntimeError(f"drillstring {' '.join(args)} failed ({done.returncode}):\n{done.stderr}")
    return wall, _children_cpu() - cpu, done


def _python_time(src: Path, cache: Path, code: str) -> float:
    """Wall time of ``python -c code`` with the package from ``src`` [s]."""
    env = dict(os.environ, PYTHONPATH=str(src), NUMBA_CACHE_DIR=str(cache))
    start = time.perf_counter()
    subprocess.run([sys.executable, "-c", code], env=env, check=True)
    return time.perf_counter() - start


def measure(src: Path, repeat: int) -> dict[str, float | str]:
    """All figures for the source tree ``src`` (the folder holding the ``drillstring`` package)."""
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        cache = work / "numba-cache"
        out = ["--out", str(work / "run.nc"), "--plot", str(work / "run.png")]
        cold, cold_cpu, done = _run(src, ["simulate", "reference", "--t-end", "1", *out], cache, work)
        message = next((line.strip() for line in done.stderr.splitlines() if "compil" in line.lower()), "")
        warm, warm_cpu, solver, modes, modes_cpu, imports, loads = [], [], [], [], [], [], []
        for _ in range(repeat):
            wall, cpu, done = _run(src, ["simulate", "reference", "--json", *out], cache, work)
            warm.append(wall)
            warm_cpu.append(cpu)
            solver.append(float(json.loads(done.stdout)["wall_time"]))
            wall, cpu, _ = _run(src, ["modes", "reference"], cache, work)
            modes.append(wall)
            modes_cpu.append(cpu)
            imports.append(_python_time(src, cache, "import drillstring.cli"))
            loads.append(_python_time(src, cache, "from drillstring.case import load_case; load_case('reference')"))
    median = statistics.median
    return {
        "cold simulate --t-end 1 [s]": cold,
        "  CPU [s]": cold_cpu,
        "compilation message": message or "(none)",
        "warm simulate reference [s]": median(warm),
        "  of which solver [s]": median(solver),
        "  beyond the solver [s]": median(w - s for w, s in zip(warm, solver)),
        "  CPU beyond the solver [s]": median(c - s for c, s in zip(warm_cpu, solver)),
        "warm modes reference [s]": median(modes),
        "  CPU [s] ": median(modes_cpu),
        "import drillstring.cli [s]": median(imports),
        "import + load_case('reference') [s]": median(loads),
    }


def _extract(revision: str, folder: Path) -> Path:
    archive = folder / "tree.tar"
    subprocess.run(["git", "-C", str(ROOT), "archive", "--format=tar", "-o", str(archive), revision, "src"],
                   check=True)
    with tarfile.open(archive) as tar:
        tar.extractall(folder, filter="data")
    return folder / "src"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeat", type=int, default=3, help="warm runs per figure (median)")
    parser.add_argument("--baseline", metavar="REF", help="also measure this git revision, for comparison")
    args = parser.parse_args()
    columns = {}
    with tempfile.TemporaryDirectory() as tmp:
        if args.baseline:
            columns[f"baseline {args.baseline}"] = measure(_extract(args.baseline, Path(tmp)), args.repeat)
        columns["this tree"] = measure(ROOT / "src", args.repeat)
    goals = {"cold simulate --t-end 1 [s]": "<= 15", "  beyond the solver [s]": "<= 2",
             "warm modes reference [s]": "<= 1.5"}
    print(f"drillstring start-up, {os.cpu_count()} cores, load {os.getloadavg()[0]:.2f}, "
          f"median of {args.repeat} warm runs (CPU: user + system time of the process, less sensitive "
          f"to other load than wall time)")
    names = list(next(iter(columns.values())))
    width = max(len(n) for n in names)
    print(f"{'':<{width}}  " + "  ".join(f"{c:>16}" for c in columns) + "  goal")
    for name in names:
        cells = []
        for figures in columns.values():
            value = figures[name]
            cells.append(f"{value:>16.2f}" if isinstance(value, float) else f"{value[:16]:>16}")
        print(f"{name:<{width}}  " + "  ".join(cells) + f"  {goals.get(name, '')}")
    for label, figures in columns.items():
        print(f"compilation message ({label}): {figures['compilation message']}")


if __name__ == "__main__":
    main()
