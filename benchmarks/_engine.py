"""What the engine benchmarks (studies, maps, sensitivity runs) share: one BLAS thread in the benchmark's
own process, a job timed in a temporary folder, the serial baseline from a random sample of tasks, the
load average and a local Dask cluster.

Import this module before NumPy: it sets the thread counts, as in the worker processes, so that the serial
baseline measured in the benchmark's process is comparable with the workers' own times.
"""

from __future__ import annotations

import os

os.environ.update({"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1",
                   "NUMBA_NUM_THREADS": "1"})

import shutil  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from contextlib import contextmanager  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any, Callable  # noqa: E402

import numpy as np  # noqa: E402


def run_in_tree(script: str, tree: Path, arguments: list[str]) -> dict:
    """Run ``python script *arguments`` with the package of the source tree ``tree`` (``tree/src`` first on
    the path), an empty Numba cache (cold compile) and one thread per library; returns the JSON object its
    last line of output prints. A failed worker stops the benchmark with its error output."""
    import json
    import subprocess
    import sys

    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, PYTHONPATH=str(tree / "src"), NUMBA_CACHE_DIR=cache, OMP_NUM_THREADS="1",
                   OPENBLAS_NUM_THREADS="1", MKL_NUM_THREADS="1", NUMBA_NUM_THREADS="1")
        done = subprocess.run([sys.executable, script, *arguments], env=env, capture_output=True, text=True)
    if done.returncode:
        raise SystemExit(f"the worker in {tree} failed:\n{done.stderr}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def timed_in_folder(prefix: str, run: Callable[[Path], Any], keep: Path | None = None,
                    files: tuple[str, ...] = ()) -> tuple[float, Any]:
    """Run ``run(folder)`` in a new temporary folder, deleted afterwards; returns (wall time [s], its
    result). With ``keep``, the ``files`` of the folder are copied there first (e.g. for the documentation's
    figures)."""
    folder = Path(tempfile.mkdtemp(prefix=prefix))
    try:
        start = time.perf_counter()
        outcome = run(folder)
        wall = time.perf_counter() - start
        if keep is not None:
            keep.mkdir(parents=True, exist_ok=True)
            for name in files:
                shutil.copy(folder / name, keep / name)
        return wall, outcome
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def serial_cost(task: Callable[[int], Any], count: int, sample: int) -> tuple[float, int]:
    """Mean time [s] of ``task(i)`` over a random sample of ``sample`` of the ``count`` tasks, run one
    after the other in this process after one warm-up call (Numba); returns (seconds per task, sample size)."""
    task(0)
    picks = np.random.default_rng(0).choice(count, size=min(sample, count), replace=False)
    start = time.perf_counter()
    for i in picks:
        task(int(i))
    return (time.perf_counter() - start) / len(picks), len(picks)


def cores() -> int:
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()


def load_average(when: str) -> str:
    return f"load average at {when} (1, 5, 15 min): " + ", ".join(f"{v:.2f}" for v in os.getloadavg())


@contextmanager
def local_dask_cluster():
    """The address of a local Dask cluster of 2 single-threaded worker processes."""
    from distributed import LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        yield cluster.scheduler_address
