"""Monte Carlo study of a random weight-on-hook (SPEC §8): realizations, parallel execution, Zarr
streaming and resume.

Each realization ``s`` draws a weight-on-hook from the Maximum-Entropy law with its own random stream
(:func:`~drillstring.stochastic.maxent.realization_generator`, keyed by ``(seed, s)`` only), derives the
consistent weight-on-bit ``wob = weight − woh``, recomputes the static state, the prestress and the
modes, integrates the time response and returns the observables on the common output grid.

Realizations run in local processes by default, or on a Dask distributed cluster when a scheduler
address is given. Results stream into a Zarr store as each one finishes: its data first, then its
status flag, so an interrupted study (Ctrl-C, killed process, lost worker) resumes with the same
command and skips finished realizations; since each realization depends only on ``(seed, s)`` the
resumed result equals an uninterrupted one. A realization that fails is stored with its cause and
excluded from the statistics.
"""

from __future__ import annotations

import concurrent.futures as cf
import hashlib
import json
import math
import multiprocessing
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Callable, Iterable

import numpy as np
import zarr

from drillstring import __version__
from drillstring.case import Case
from drillstring.dynamics.rom import case_reduced_model
from drillstring.dynamics.simulate import (
    SimulationError,
    SimulationResult,
    output_grid,
    simulate_model,
)
from drillstring.stochastic.maxent import realization_generator, weight_on_hook_law

#: Observables kept for every realization (each (realization, time)); plus radial_displacement.
STUDY_OBSERVABLES = ("rate_of_penetration", "bit_speed", "torque_on_bit", "force_on_bit")
PENDING, DONE, FAILED = 0, 1, 2
NOMINAL = -1  # index of the deterministic run at the mean weight-on-hook


@dataclass(frozen=True)
class StudySettings:
    """What defines a study's realizations; a resumed study must have the same settings.

    Attributes:
        samples: number of realizations n_s.
        sigma: standard deviation of the weight-on-hook [N].
        seed: root seed of the realizations' random streams.
        t_end: simulated time per realization [s].
        output_step: output step [s].
    """

    samples: int
    sigma: float
    seed: int = 0
    t_end: float = 30.0
    output_step: float = 0.01

    def __post_init__(self) -> None:
        if not (isinstance(self.samples, int) and self.samples >= 1):
            raise ValueError(f"samples = {self.samples!r}: must be an integer >= 1")
        if not (math.isfinite(self.sigma) and self.sigma > 0):
            raise ValueError(f"sigma = {self.sigma!r} N: must be a finite number > 0")
        if not (isinstance(self.seed, int) and self.seed >= 0):
            raise ValueError(f"seed = {self.seed!r}: must be an integer >= 0")
        if not self.t_end > 0:
            raise ValueError(f"t_end = {self.t_end!r} s: must be > 0")
        if not 0 < self.output_step <= self.t_end:
            raise ValueError(f"output_step = {self.output_step!r} s: must be in (0, t_end]")

    @property
    def time(self) -> np.ndarray:
        """The common output grid [s] (the integrator's grid: k·Δt, t_end included)."""
        return output_grid(self.t_end, self.output_step)


@dataclass
class RealizationOutcome:
    """What one realization returns to the driver (picklable)."""

    index: int
    weight_on_hook: float
    weight_on_bit: float
    status: int
    message: str
    observables: dict[str, np.ndarray] = field(default_factory=dict)
    radial_displacement: np.ndarray | None = None
    wall_time: float = 0.0
    n_rhs: int = 0


def nominal_weight_on_hook(case: Case) -> float:
    """Mean weight-on-hook [N]: the case's static hook load, weight − weight_on_bit."""
    return case.weight - case.operation.weight_on_bit


def draw_weight_on_hook(case: Case, settings: StudySettings, index: int) -> float:
    """The weight-on-hook [N] of realization ``index`` (the mean for :data:`NOMINAL`)."""
    mean = nominal_weight_on_hook(case)
    if index == NOMINAL:
        return mean
    law = weight_on_hook_law(mean, sigma=settings.sigma)
    return float(law.sample(realization_generator(settings.seed, index)))


def run_realization(case: Case, settings: StudySettings, index: int) -> RealizationOutcome:
    """Draw, solve and simulate realization ``index``; never raises for a failed realization."""
    start = time.perf_counter()
    woh = draw_weight_on_hook(case, settings, index)
    wob = case.weight - woh
    outcome = RealizationOutcome(index, woh, wob, FAILED, "")
    n_t = len(settings.time)
    try:
        if not 0.0 < wob < case.weight:
            raise ValueError(
                f"drawn weight_on_hook = {woh:.6g} N gives weight_on_bit = {wob:.6g} N, outside "
                f"(0, {case.weight:.6g}) N"
            )
        model = case_reduced_model(case, weight_on_bit=wob)
        s = case.simulation
        kwargs = dict(t_end=settings.t_end, output_step=settings.output_step, rtol=s.rtol,
                      atol=s.atol, method=s.method, max_steps=s.max_steps, min_step=s.min_step,
                      lateral_perturbation=case.initial.lateral_perturbation, seed=case.initial.seed)
        try:
            result: SimulationResult = simulate_model(model, **kwargs)
            outcome.status = DONE
        except SimulationError as error:
            result = error.result
            outcome.message = str(error)
        k = len(result.time)
        for name in STUDY_OBSERVABLES:
            values = np.full(n_t, np.nan)
            values[:k] = result.observables[name]
            outcome.observables[name] = values
        radial = np.full((n_t, result.radial_displacement.shape[1]), np.nan)
        radial[:k] = result.radial_displacement
        outcome.radial_displacement = radial
        outcome.n_rhs = int(result.stats.get("n_rhs", 0))
    except Exception as error:  # any failure is recorded with its cause, never dropped
        outcome.status = FAILED
        outcome.message = f"{type(error).__name__}: {error}"
    outcome.wall_time = time.perf_counter() - start
    return outcome


# --- the Zarr store ------------------------------------------------------------------------------


def _fingerprint(case: Case, settings: StudySettings) -> str:
    text = case.to_toml() + json.dumps(asdict(settings), sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


class StudyStore:
    """A study's Zarr store: one row per realization, a status flag written after the data."""

    def __init__(self, path: str | Path, case: Case, settings: StudySettings) -> None:
        self.path = Path(path)
        self.case = case
        self.settings = settings
        fingerprint = _fingerprint(case, settings)
        n_s, time_grid = settings.samples, settings.time
        n_t, n_p = len(time_grid), len(case.mesh.probes)
        if (self.path / "zarr.json").exists():
            self.group = zarr.open_group(str(self.path), mode="a")
            found = self.group.attrs.get("fingerprint")
            if found != fingerprint:
                raise ValueError(
                    f"{self.path} holds a different study (case or settings differ: samples, sigma, "
                    f"seed, t_end, output_step); use another --out folder or delete it to start over"
                )
            return
        self.path.parent.mkdir(parents=True, exist_ok=True)
        g = zarr.open_group(str(self.path), mode="w")
        g.attrs.update({
            "fingerprint": fingerprint,
            "drillstring_version": __version__,
            "case": case.to_toml(),
            "settings": asdict(settings),
            "weight_on_hook_mean": nominal_weight_on_hook(case),
            "weight": case.weight,
            "failures": {},
        })
        g.create_array("time", data=time_grid, dimension_names=["time"],
                       attributes={"units": "s"})
        g.create_array("x", data=np.asarray(case.mesh.probes, dtype=float),
                       dimension_names=["probe"], attributes={"units": "m"})
        for name, dtype, fill in (("weight_on_hook", "f8", np.nan), ("weight_on_bit", "f8", np.nan),
                                  ("wall_time", "f8", np.nan), ("status", "i1", PENDING)):
            g.create_array(name, shape=(n_s,), chunks=(n_s,), dtype=dtype, fill_value=fill,
                           dimension_names=["realization"])
        for name in STUDY_OBSERVABLES:
            g.create_array(name, shape=(n_s, n_t), chunks=(1, n_t), dtype="f8", fill_value=np.nan,
                           dimension_names=["realization", "time"])
            g.create_array(f"nominal_{name}", shape=(n_t,), chunks=(n_t,), dtype="f8",
                           fill_value=np.nan, dimension_names=["time"])
        g.create_array("radial_displacement", shape=(n_s, n_t, n_p), chunks=(1, n_t, n_p),
                       dtype="f8", fill_value=np.nan, dimension_names=["realization", "time", "probe"])
        g.create_array("nominal_radial_displacement", shape=(n_t, n_p), chunks=(n_t, n_p),
                       dtype="f8", fill_value=np.nan, dimension_names=["time", "probe"])
        g.create_array("nominal_status", shape=(1,), dtype="i1", fill_value=PENDING,
                       dimension_names=["one"])
        self.group = g

    # per-realization rows (small arrays rewritten whole: one chunk, one writer)
    def status(self) -> np.ndarray:
        return self.group["status"][:]

    def nominal_done(self) -> bool:
        return int(self.group["nominal_status"][0]) != PENDING

    def pending(self) -> list[int]:
        return [int(i) for i in np.nonzero(self.status() == PENDING)[0]]

    def write(self, outcome: RealizationOutcome) -> None:
        g, i = self.group, outcome.index
        if i == NOMINAL:
            if outcome.radial_displacement is not None:
                for name in STUDY_OBSERVABLES:
                    g[f"nominal_{name}"][:] = outcome.observables[name]
                g["nominal_radial_displacement"][:] = outcome.radial_displacement
            if outcome.status != DONE:
                self._record_failure("nominal", outcome.message)
            g["nominal_status"][0] = outcome.status
            return
        if outcome.radial_displacement is not None:
            for name in STUDY_OBSERVABLES:
                g[name][i, :] = outcome.observables[name]
            g["radial_displacement"][i] = outcome.radial_displacement
        for name in ("weight_on_hook", "weight_on_bit", "wall_time"):
            row = g[name][:]
            row[i] = getattr(outcome, name)
            g[name][:] = row
        if outcome.status != DONE:
            self._record_failure(str(i), outcome.message)
        status = g["status"][:]
        status[i] = outcome.status  # last: a realization counts only once its data is in
        g["status"][:] = status

    def _record_failure(self, key: str, message: str) -> None:
        failures = dict(self.group.attrs.get("failures", {}))
        failures[key] = message
        self.group.attrs["failures"] = failures

    def failures(self) -> dict[str, str]:
        return dict(self.group.attrs.get("failures", {}))


# --- execution -----------------------------------------------------------------------------------


class StudyInterrupted(RuntimeError):
    """The study was interrupted; what finished is in the store and a rerun resumes."""


@dataclass
class StudyRun:
    """What :func:`run_study` did."""

    store: StudyStore
    completed: int
    failed: int
    wall_time: float
    workers: int | str


ProgressCallback = Callable[[int, int, int], None]  # (done, failed, total)


def _local_workers(workers: int | None) -> int:
    return max(1, workers or multiprocessing.cpu_count())


def run_study(
    case: Case,
    settings: StudySettings,
    store_path: str | Path,
    *,
    workers: int | None = None,
    scheduler: str | None = None,
    progress: ProgressCallback | None = None,
) -> StudyRun:
    """Run (or resume) every pending realization of a study into its Zarr store.

    Args:
        workers: local processes (default: one per core); 1 runs in this process.
        scheduler: address of a Dask distributed scheduler (``tcp://host:8786``); when given, the
            realizations run on that cluster's workers instead of local processes.
        progress: called as ``progress(done, failed, total)`` after each realization.
    """
    store = StudyStore(store_path, case, settings)
    indices = ([] if store.nominal_done() else [NOMINAL]) + store.pending()
    status = store.status()
    done, failed = int(np.sum(status == DONE)), int(np.sum(status == FAILED))
    total = settings.samples
    start = time.perf_counter()

    def record(outcome: RealizationOutcome) -> None:
        nonlocal done, failed
        store.write(outcome)
        if outcome.index != NOMINAL:
            if outcome.status == DONE:
                done += 1
            else:
                failed += 1
        if progress:
            progress(done, failed, total)

    if progress:
        progress(done, failed, total)
    try:
        if scheduler:
            _run_dask(case, settings, indices, scheduler, record)
            used: int | str = scheduler
        elif _local_workers(workers) == 1 or len(indices) <= 1:
            for i in indices:
                record(run_realization(case, settings, i))
            used = 1
        else:
            used = _local_workers(workers)
            _run_processes(case, settings, indices, used, record)
    except KeyboardInterrupt as error:
        raise StudyInterrupted(
            f"study interrupted after {done + failed} of {total} realizations; they are saved in "
            f"{store.path}; run the same command again to resume"
        ) from error
    return StudyRun(store, done, failed, time.perf_counter() - start, used)


#: Thread counts for worker processes: one process per core, each single-threaded, so linear
#: algebra libraries do not oversubscribe the cores.
WORKER_ENVIRONMENT = {"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1",
                      "NUMBA_NUM_THREADS": "1"}


def _worker_start(parent_pid: int) -> None:
    """Worker initializer: exit as soon as the study's process is gone (killed, not just
    interrupted), instead of computing realizations nobody will record."""
    import os
    import threading

    def watch() -> None:
        while True:
            time.sleep(1.0)
            if os.getppid() != parent_pid:
                os._exit(0)

    threading.Thread(target=watch, daemon=True).start()


def _run_processes(case, settings, indices: Iterable[int], workers: int, record,
                   task: Callable = run_realization) -> None:
    import os

    context = multiprocessing.get_context("spawn")
    remaining = list(indices)
    saved = {k: os.environ.get(k) for k in WORKER_ENVIRONMENT}
    os.environ.update(WORKER_ENVIRONMENT)  # inherited by the spawned workers only at start-up
    try:
        _process_loop(context, case, settings, remaining, workers, record, os.getpid(), task)
    finally:
        for key, value in saved.items():
            if value is None:
                os.environ.pop(key, None)
            else:
                os.environ[key] = value


def _process_loop(context, case, settings, remaining, workers, record, parent_pid, task) -> None:
    """Run ``remaining`` on a process pool. If a worker dies (killed, out of memory, crash), the pool
    is restarted for the rest; if it dies again before any realization finished, the remaining
    realizations run one per single-worker pool, so a realization that kills its worker is recorded
    as failed with that cause instead of being retried forever."""
    isolate = False
    while remaining:
        before = len(remaining)
        batch = remaining[:1] if isolate else list(remaining)
        pool = cf.ProcessPoolExecutor(max_workers=1 if isolate else workers, mp_context=context,
                                      initializer=_worker_start, initargs=(parent_pid,))
        try:
            futures = {pool.submit(task, case, settings, i): i for i in batch}
            for future in cf.as_completed(futures):
                record(future.result())
                remaining.remove(futures[future])
        except cf.process.BrokenProcessPool:
            if isolate:
                index = batch[0]
                record(RealizationOutcome(
                    index, draw_weight_on_hook(case, settings, index), math.nan, FAILED,
                    "worker process died (killed or crashed) while computing this realization"))
                remaining.remove(index)
            elif len(remaining) == before:
                isolate = True
        finally:
            pool.shutdown(wait=False, cancel_futures=True)


def _run_dask(case, settings, indices: list[int], scheduler: str, record) -> None:
    from distributed import Client, as_completed

    with Client(scheduler) as client:
        futures = client.map(run_realization, [case] * len(indices), [settings] * len(indices),
                             indices, pure=False)
        for future in as_completed(futures):
            record(future.result())
