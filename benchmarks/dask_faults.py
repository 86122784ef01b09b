"""Dask faults with the real command and the default timeouts (docs/verification.md, "Faults").

For each fault — every worker killed (SIGKILL), every worker stopped (SIGSTOP), the scheduler killed, the
scheduler stopped — a study of 40 realizations of 5 s on the coarse reference string runs on a loopback
cluster (a scheduler and 2 workers without nannies, each its own process on 127.0.0.1); once 3
realizations are stored the fault is made, and the time from the fault to the command's end, its exit
code, its stderr (progress bar left out) and the realizations stored are printed as one JSON line; then
the same command on a new cluster, which must resume to the end. About 2 minutes per fault.

    PYTHONPATH=src python benchmarks/dask_faults.py ["workers killed" ...]
"""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import zarr

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "stochastic"))
from test_dask_faults import Cluster  # noqa: E402  (the tests' loopback cluster of real processes)

FAULTS = ("workers killed", "workers stopped", "scheduler killed", "scheduler stopped")


def _stored(out: Path) -> int:
    return int(np.sum(zarr.open_group(str(out / "study.zarr"), mode="r")["status"][...] == 1))


def _stderr(text: str) -> list[str]:
    return [line for line in text.splitlines() if line.strip() and "━" not in line]


def run(fault: str, case: Path, folder: Path) -> None:
    out = folder / fault.replace(" ", "-")
    study = [sys.executable, "-m", "drillstring.cli", "study", str(case), "--samples", "40", "--t-end", "5",
             "--out", str(out)]
    cluster = Cluster(2)
    try:
        proc = subprocess.Popen([*study, "--scheduler", cluster.address], stdout=subprocess.PIPE,
                                stderr=subprocess.PIPE, text=True)
        at = None
        while proc.poll() is None and at is None:
            time.sleep(0.5)
            try:
                ready = _stored(out) >= 3
            except Exception:  # the store is not there yet
                continue
            if ready:
                which = cluster.workers if fault.startswith("workers") else [cluster.scheduler]
                cluster.signal(which, signal.SIGKILL if fault.endswith("killed") else signal.SIGSTOP)
                at = time.monotonic()
        _, stderr = proc.communicate(timeout=600)
        print(json.dumps({"fault": fault, "exit": proc.returncode,
                          "seconds_after_fault": None if at is None else round(time.monotonic() - at, 1),
                          "stored": _stored(out), "stderr": _stderr(stderr)}), flush=True)
    finally:
        cluster.close()
    cluster = Cluster(2)
    try:
        start = time.monotonic()
        again = subprocess.run([*study, "--scheduler", cluster.address], capture_output=True, text=True, timeout=900)
        print(json.dumps({"fault": fault, "rerun_exit": again.returncode, "seconds": round(time.monotonic() - start, 1),
                          "stored": _stored(out), "stderr": _stderr(again.stderr)}), flush=True)
    finally:
        cluster.close()


def main() -> None:
    from drillstring.case import load_case

    case = load_case("reference")
    case = case.model_copy(update={"mesh": case.mesh.model_copy(update={"max_element_length": 40.0}),
                                   "reduced_model": case.reduced_model.model_copy(update={"lateral_cutoff": 0.0})})
    with tempfile.TemporaryDirectory(prefix="drillstring-dask-faults-") as folder:
        path = Path(folder) / "coarse.toml"
        path.write_text(case.to_toml(), encoding="utf-8")
        for fault in sys.argv[1:] or FAULTS:
            run(fault, path, Path(folder))


if __name__ == "__main__":
    main()
