"""Benchmark: a long string on a fine mesh, end to end from the shell (issue 19).

The reference case's string made 10 km long (9800 m of drill pipe over its 200 m of drill collar, the
stabilizer at 9800 m, the probe at 9960 m) and meshed with 1 m elements (10 000 elements, 60 006 DOFs),
against the reference case itself (160 elements) as the baseline of the same run. For each, in a fresh
interpreter started as a user starts the ``drillstring`` command, with the Numba cache already filled:

- ``modes``: ``drillstring modes CASE --count 10``;
- ``simulate``: ``drillstring simulate CASE --t-end 0.5 --json``, whose own figures split the wall time
  into the solver's and the rest (the model's set-up: statics, modes, damping, reduced model; the files).

Each is reported as its wall time [s] and the peak resident memory of its process [MiB] (``wait4``).
Run from the repository root:

    .venv/bin/python benchmarks/bench_long_string.py [--repeat 1]
"""

from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CLI = "import sys; from drillstring import cli; sys.argv[0] = 'drillstring'; cli.run()"
REFERENCE = ROOT / "src" / "drillstring" / "cases" / "reference.toml"


def long_case_text(length: float = 10_000.0, element: float = 1.0) -> str:
    """The reference case with its drill pipe lengthened to make the string ``length`` [m] long, meshed
    with elements of at most ``element`` [m]."""
    pipe = length - 200.0
    text = REFERENCE.read_text()
    for old, new in (('name = "reference"', 'name = "long"'),
                     ('length = "1400 m"', f'length = "{pipe:g} m"'),
                     ('position = "1400 m"', f'position = "{pipe:g} m"'),
                     ('max_element_length = "10 m"', f'max_element_length = "{element:g} m"'),
                     ('probes = ["1560 m"]', f'probes = ["{length - 40.0:g} m"]')):
        if old not in text:
            raise RuntimeError(f"the reference case no longer has {old!r}")
        text = text.replace(old, new, 1)
    return re.sub(r'^description = .*$', f'description = "{length / 1e3:g} km string, {element:g} m elements"',
                  text, count=1, flags=re.M)


def run_measured(args: list[str], cwd: Path) -> tuple[float, float, str]:
    """``drillstring ARGS`` in a fresh interpreter: (wall [s], peak resident memory [MiB], stdout)."""
    env = dict(os.environ, PYTHONPATH=str(ROOT / "src"))
    with tempfile.TemporaryFile("w+") as out, tempfile.TemporaryFile("w+") as err:
        start = time.perf_counter()
        process = subprocess.Popen([sys.executable, "-c", CLI, *args], cwd=cwd, env=env, stdout=out,
                                   stderr=err, text=True)
        _, status, usage = os.wait4(process.pid, 0)
        wall = time.perf_counter() - start
        process.returncode = os.waitstatus_to_exitcode(status)
        out.seek(0)
        err.seek(0)
        if process.returncode != 0:
            raise RuntimeError(f"drillstring {' '.join(args)} failed ({process.returncode}):\n{err.read()}")
        return wall, usage.ru_maxrss / 1024.0, out.read()  # ru_maxrss in KiB on Linux


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=1, help="runs of each command (the fastest is kept)")
    parser.add_argument("--length", type=float, default=10_000.0, help="string length [m]")
    parser.add_argument("--element", type=float, default=1.0, help="largest element [m]")
    options = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        work = Path(folder)
        long_case = work / "long.toml"
        long_case.write_text(long_case_text(options.length, options.element))
        run_measured(["simulate", "reference", "--t-end", "0.1", "--json"], work)  # fill the kernel cache
        print(f"{'case':<28} {'command':<22} {'wall [s]':>9} {'solver [s]':>11} {'set-up [s]':>11} "
              f"{'peak RSS [MiB]':>15}")
        for label, case in (("reference (160 elements)", "reference"),
                            (f"{options.length / 1e3:g} km, {options.element:g} m elements", str(long_case))):
            best: dict[str, tuple] = {}
            for _ in range(options.repeat):
                wall, rss, _ = run_measured(["modes", case, "--count", "10"], work)
                if "modes" not in best or wall < best["modes"][0]:
                    best["modes"] = (wall, None, rss)
                wall, rss, out = run_measured(["simulate", case, "--t-end", "0.5", "--json", "--out",
                                               str(work / "run.nc"), "--plot", str(work / "run.png")], work)
                solver = json.loads(out)["wall_time"]
                if "simulate" not in best or wall < best["simulate"][0]:
                    best["simulate"] = (wall, solver, rss)
            for command, (wall, solver, rss) in best.items():
                name = "modes --count 10" if command == "modes" else "simulate --t-end 0.5"
                solver_text = "" if solver is None else f"{solver:.2f}"
                setup_text = "" if solver is None else f"{wall - solver:.2f}"
                print(f"{label:<28} {name:<22} {wall:>9.2f} {solver_text:>11} {setup_text:>11} {rss:>15.0f}",
                      flush=True)


if __name__ == "__main__":
    main()
