"""Benchmark: the model build from a user's script beside a busy second process, BLAS threads as NumPy
loads them (one per core) against drillstring's limit (:mod:`drillstring.blas_threads`, issue 26).

A user's script imports NumPy without ``OPENBLAS_NUM_THREADS``: OpenBLAS then runs one thread per core.
When another process keeps a core busy, the threads of each small dense problem (``scipy.linalg.eigh`` on a
few hundred DOFs per mode family) wait for each other. Measured here, in one process and the same run:

- ``threads as loaded``: the reference case's reduced model built (``case_reduced_model``: statics, modes of
  each family, projections) with the BLAS threads NumPy started with;
- ``single-threaded``: the same inside :func:`~drillstring.blas_threads.single_threaded_blas`, what every
  function of :mod:`drillstring.api` does;
- ``api.modes``: the public function itself (decorated), for reference.

With ``--busy N`` (default 1), N processes spin on the CPU the whole time (a second user, a study's
worker). Run from the repository root, without the thread variables set:

    env -u OPENBLAS_NUM_THREADS -u OMP_NUM_THREADS .venv/bin/python benchmarks/bench_blas_threads.py [--repeat 5]
"""

from __future__ import annotations

import argparse
import multiprocessing
import os
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))


def _spin(stop) -> None:  # a busy second process
    x = 0
    while not stop.is_set():
        for _ in range(100_000):
            x += 1


def _times(call, repeat: int) -> list[float]:
    out = []
    for _ in range(repeat):
        start = time.perf_counter()
        call()
        out.append(time.perf_counter() - start)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--busy", type=int, default=1, help="busy processes beside the benchmark")
    parser.add_argument("--case", default="reference")
    args = parser.parse_args()
    for name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        if name in os.environ:
            print(f"note: {name}={os.environ[name]} is set: NumPy loaded with it, the comparison is moot")

    from threadpoolctl import threadpool_info

    from drillstring import api
    from drillstring.blas_threads import single_threaded_blas
    from drillstring.case import load_case
    from drillstring.dynamics.rom import case_reduced_model

    case = load_case(args.case)
    case_reduced_model(case)  # imports, kernels: out of the timing
    loaded = sorted({info["num_threads"] for info in threadpool_info() if info["user_api"] == "blas"})
    print(f"{os.cpu_count()} cores; BLAS threads as loaded: {loaded}; busy processes: {args.busy}")

    def limited() -> None:
        with single_threaded_blas():
            case_reduced_model(case)

    stop = multiprocessing.Event()
    spinners = [multiprocessing.Process(target=_spin, args=(stop,), daemon=True) for _ in range(args.busy)]
    for process in spinners:
        process.start()
    time.sleep(0.5)
    try:
        rows = {}
        for _ in range(2):  # interleaved, so that both see the same machine
            for label, call in (("threads as loaded", lambda: case_reduced_model(case)),
                                ("single-threaded", limited),
                                ("api.modes", lambda: api.modes(case))):
                rows.setdefault(label, []).extend(_times(call, max(1, args.repeat // 2)))
    finally:
        stop.set()
        for process in spinners:
            process.join()
    base = statistics.median(rows["threads as loaded"])
    print(f"{'':20s} {'median [s]':>11s} {'best [s]':>9s} {'speed-up':>9s}")
    for label, values in rows.items():
        median = statistics.median(values)
        print(f"{label:20s} {median:11.3f} {min(values):9.3f} {base / median:8.1f}x")


if __name__ == "__main__":
    main()
