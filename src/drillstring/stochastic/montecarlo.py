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

A study's store is locked while a study runs on it (a second study on the same store is refused at
once, a lock left by a killed study is taken over with a note), created atomically (built under a
temporary name, then renamed), and checked when opened (a folder that is not a complete study store is
refused with what is missing). Settings that would make realizations fail are refused before running:
fewer than 2 realizations, or a weight-on-hook law that puts a probability above
:data:`OUT_OF_RANGE_PROBABILITY` of the weight-on-bit outside (0, string weight).
"""

from __future__ import annotations

import concurrent.futures as cf
import datetime as _dt
import hashlib
import json
import math
import multiprocessing
import os
import shutil
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
from drillstring.stochastic.locks import StudyLock, StudyLocked  # noqa: F401  (re-exported)
from drillstring.stochastic.maxent import realization_generator, weight_on_hook_law

#: Observables kept for every realization (each (realization, time)); plus radial_displacement.
STUDY_OBSERVABLES = ("rate_of_penetration", "bit_speed", "torque_on_bit", "force_on_bit")
PENDING, DONE, FAILED = 0, 1, 2
NOMINAL = -1  # index of the deterministic run at the mean weight-on-hook
#: Fewest realizations of a study: the statistics (standard deviation, envelopes) need two.
MIN_SAMPLES = 2
#: Largest accepted probability that a drawn weight-on-bit falls outside (0, string weight), where the
#: realization cannot run. The Normal law is unbounded; 1e-3 lets a 1000-realization study expect about
#: one failed draw, and on the reference case (100 kN on the bit) accepts σ up to 32.4 kN.
OUT_OF_RANGE_PROBABILITY = 1e-3


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
        if not (isinstance(self.samples, int) and not isinstance(self.samples, bool)
                and self.samples >= MIN_SAMPLES):
            raise ValueError(f"samples = {self.samples!r}: must be an integer >= {MIN_SAMPLES} (the "
                             "statistics need at least 2 realizations)")
        if not (_is_real(self.sigma) and math.isfinite(self.sigma) and self.sigma > 0):
            raise ValueError(f"sigma = {self.sigma!r} N: must be a finite number > 0")
        if not (isinstance(self.seed, int) and not isinstance(self.seed, bool) and self.seed >= 0):
            raise ValueError(f"seed = {self.seed!r}: must be an integer >= 0")
        if not (_is_real(self.t_end) and math.isfinite(self.t_end) and self.t_end > 0):
            raise ValueError(f"t_end = {self.t_end!r} s: must be a finite number > 0")
        if not (_is_real(self.output_step) and 0 < self.output_step <= self.t_end):
            raise ValueError(f"output_step = {self.output_step!r} s: must be in (0, t_end = {self.t_end:g} s]")

    @property
    def time(self) -> np.ndarray:
        """The common output grid [s] (the integrator's grid: k·Δt, t_end included)."""
        return output_grid(self.t_end, self.output_step)


def _is_real(value) -> bool:
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool)


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
    lowest_lateral_eigenvalue: float = math.nan


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


def _normal_tail(z: float) -> float:
    """P(Z > z) for a standard Normal Z."""
    return 0.5 * math.erfc(z / math.sqrt(2.0))


def weight_on_bit_out_of_range_probability(case: Case, sigma: float) -> float:
    """Probability that a weight-on-hook drawn from the study's Normal law (mean
    :func:`nominal_weight_on_hook`, standard deviation ``sigma`` [N]) gives a weight-on-bit
    ``wob = weight − woh`` outside (0, weight), where no realization can run: with ``wob`` Normal of
    mean ``wob_0`` and standard deviation σ, ``P = Φ(−wob_0/σ) + Φ(−(weight − wob_0)/σ)``."""
    wob = case.operation.weight_on_bit
    return _normal_tail(wob / sigma) + _normal_tail((case.weight - wob) / sigma)


def largest_accepted_sigma(case: Case, probability: float = OUT_OF_RANGE_PROBABILITY) -> float:
    """The σ [N] at which :func:`weight_on_bit_out_of_range_probability` equals ``probability``
    (the probability grows with σ; bisection on a log scale to 1e-9 relative)."""
    low, high = 1e-9 * case.weight, case.weight
    while weight_on_bit_out_of_range_probability(case, high) < probability:
        high *= 2.0
    for _ in range(200):
        middle = math.sqrt(low * high)
        if weight_on_bit_out_of_range_probability(case, middle) < probability:
            low = middle
        else:
            high = middle
        if high / low < 1.0 + 1e-9:
            break
    return low


#: Above this probability of a buckled draw (weight-on-bit beyond the critical one), a study warns before
#: it runs: about one realization in a thousand (σ = 5000 N on the reference case gives 2.35e-3).
BUCKLING_WARNING_PROBABILITY = 1e-3


def study_buckling_margin(case: Case, settings: StudySettings) -> dict:
    """The lateral buckling margin of a study's draws (SI): ``critical_weight_on_bit`` [N] of the case
    (:func:`drillstring.buckling.case_buckling_margin`), ``probability`` that a weight-on-hook drawn from the
    study's law buckles the string (:func:`drillstring.buckling.buckling_probability`), ``expected``
    buckled realizations (probability × samples) and ``warning``: a one-line note when the probability is
    above :data:`BUCKLING_WARNING_PROBABILITY`, else None."""
    from drillstring.buckling import buckling_probability, case_buckling_margin

    margin = case_buckling_margin(case)
    law = weight_on_hook_law(nominal_weight_on_hook(case), sigma=settings.sigma)
    probability = buckling_probability(law, case.weight, margin.critical_weight_on_bit)
    warning = None
    if probability > BUCKLING_WARNING_PROBABILITY:
        warning = (f"sigma = {settings.sigma:.6g} N puts the weight-on-bit above the critical "
                   f"{margin.critical_weight_on_bit / 1e3:.5g} kN (lateral buckling) with probability "
                   f"{probability:.3g}: about {probability * settings.samples:.3g} of the {settings.samples} "
                   f"realizations will be buckled strings (bowed to the wall); their count is in the summary")
    return {"critical_weight_on_bit": float(margin.critical_weight_on_bit), "probability": float(probability),
            "expected": float(probability * settings.samples), "warning": warning}


def check_study(case: Case, settings: StudySettings) -> None:
    """Refuse (ValueError naming sigma) settings whose draws would often be impossible: a probability
    above :data:`OUT_OF_RANGE_PROBABILITY` of a weight-on-bit outside (0, string weight)."""
    p = weight_on_bit_out_of_range_probability(case, settings.sigma)
    if p > OUT_OF_RANGE_PROBABILITY:
        raise ValueError(
            f"sigma = {settings.sigma:.6g} N: with the weight-on-hook Normal around "
            f"{nominal_weight_on_hook(case) / 1e3:.6g} kN, the weight-on-bit falls outside (0, "
            f"{case.weight / 1e3:.6g} kN) (the string's weight) with probability {p:.3g}, above "
            f"{OUT_OF_RANGE_PROBABILITY:g}: such realizations cannot run; sigma must be at most "
            f"{largest_accepted_sigma(case) / 1e3:.4g} kN for this case"
        )


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
        outcome.lowest_lateral_eigenvalue = model.lowest_lateral_eigenvalue
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


class StudyStoreError(ValueError):
    """A folder that is not a (complete, readable) drillstring study store."""


#: Arrays every study store holds: name -> dimension names.
STORE_ARRAYS = {
    "time": ("time",), "x": ("probe",),
    "weight_on_hook": ("realization",), "weight_on_bit": ("realization",),
    "wall_time": ("realization",), "status": ("realization",),
    "lowest_lateral_eigenvalue": ("realization",),
    **{name: ("realization", "time") for name in STUDY_OBSERVABLES},
    **{f"nominal_{name}": ("time",) for name in STUDY_OBSERVABLES},
    "radial_displacement": ("realization", "time", "probe"),
    "nominal_radial_displacement": ("time", "probe"),
    "nominal_status": ("one",),
}


def open_study_group(path: str | Path, mode: str = "r") -> zarr.Group:
    """Open the study store at ``path``, checking that it is one: a Zarr group with a study
    fingerprint and every array of :data:`STORE_ARRAYS` with consistent sizes. Raises
    :class:`StudyStoreError` saying what is wrong otherwise."""
    path = Path(path)
    advice = "delete it (or use another --out folder) to start over"
    if not path.is_dir():
        raise StudyStoreError(f"{path} is not a drillstring study store (no such folder)")
    if not (path / "zarr.json").is_file():
        raise StudyStoreError(f"{path} is not a drillstring study store (no zarr.json); {advice}")
    try:
        group = zarr.open_group(str(path), mode=mode)
        attrs = dict(group.attrs)
    except Exception as error:  # any unreadable metadata: one line, not a traceback
        raise StudyStoreError(f"{path} is not a readable Zarr store ({type(error).__name__}: {error}); "
                              f"{advice}") from None
    missing_attrs = [k for k in ("fingerprint", "settings", "case") if k not in attrs]
    if missing_attrs:
        raise StudyStoreError(f"{path} is not a drillstring study store (no {', '.join(missing_attrs)} "
                              f"attribute); {advice}")
    try:
        names = set(group.array_keys())
    except Exception as error:
        raise StudyStoreError(f"{path} is not a readable Zarr store ({type(error).__name__}: {error}); "
                              f"{advice}") from None
    missing = [name for name in STORE_ARRAYS if name not in names]
    if missing:
        raise StudyStoreError(f"{path} is not a complete drillstring study store (missing array(s): "
                              f"{', '.join(missing)}); {advice}")
    try:
        sizes = {"realization": int(attrs["settings"]["samples"]), "time": group["time"].shape[0],
                 "probe": group["x"].shape[0], "one": 1}
        for name, dims in STORE_ARRAYS.items():
            expected = tuple(sizes[d] for d in dims)
            if tuple(group[name].shape) != expected:
                raise StudyStoreError(f"{path} is not a consistent drillstring study store (array {name} "
                                      f"has shape {tuple(group[name].shape)}, expected {expected}); {advice}")
    except (KeyError, TypeError, ValueError) as error:
        if isinstance(error, StudyStoreError):
            raise
        raise StudyStoreError(f"{path} is not a consistent drillstring study store ({error}); {advice}") from None
    return group


class StudyStore:
    """A study's Zarr store: one row per realization, a status flag written after the data.

    A new store is built under a temporary name and renamed into place once complete; an existing one
    is checked (:func:`open_study_group`) and must hold the same study (case and settings). Writers
    hold its :class:`StudyLock` (as :func:`run_study` does)."""

    def __init__(self, path: str | Path, case: Case, settings: StudySettings) -> None:
        self.path = Path(path)
        self.case = case
        self.settings = settings
        fingerprint = _fingerprint(case, settings)
        if self.path.exists() and not (self.path.is_dir() and not any(self.path.iterdir())):
            self.group = open_study_group(self.path, mode="a")
            if self.group.attrs.get("fingerprint") != fingerprint:
                raise ValueError(
                    f"{self.path} holds a different study (case or settings differ: samples, sigma, "
                    f"seed, t_end, output_step); use another --out folder or delete it to start over"
                )
            return
        self.path.parent.mkdir(parents=True, exist_ok=True)
        for leftover in self.path.parent.glob(f".{self.path.name}.*.tmp"):  # from a killed creation
            shutil.rmtree(leftover, ignore_errors=True)
        temporary = self.path.with_name(f".{self.path.name}.{os.getpid()}.tmp")
        try:
            self._create(temporary, case, settings, fingerprint)
            if self.path.exists():  # an empty folder
                self.path.rmdir()
            os.rename(temporary, self.path)
        except BaseException:
            shutil.rmtree(temporary, ignore_errors=True)
            raise
        self.group = zarr.open_group(str(self.path), mode="a")

    @staticmethod
    def _create(path: Path, case: Case, settings: StudySettings, fingerprint: str) -> None:
        n_s, time_grid = settings.samples, settings.time
        n_t, n_p = len(time_grid), len(case.mesh.probes)
        g = zarr.open_group(str(path), mode="w")
        g.attrs.update({
            "fingerprint": fingerprint,
            "drillstring_version": __version__,
            "case": case.to_toml(),
            "settings": asdict(settings),
            "weight_on_hook_mean": nominal_weight_on_hook(case),
            "weight": case.weight,
            "failures": {},
            "sessions": [],
        })
        g.create_array("time", data=time_grid, dimension_names=["time"],
                       attributes={"units": "s"})
        g.create_array("x", data=np.asarray(case.mesh.probes, dtype=float),
                       dimension_names=["probe"], attributes={"units": "m"})
        for name, dtype, fill in (("weight_on_hook", "f8", np.nan), ("weight_on_bit", "f8", np.nan),
                                  ("wall_time", "f8", np.nan), ("lowest_lateral_eigenvalue", "f8", np.nan),
                                  ("status", "i1", PENDING)):
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
        for name in ("weight_on_hook", "weight_on_bit", "wall_time", "lowest_lateral_eigenvalue"):
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

    def record_session(self, started: str, wall_time: float, realizations: int,
                       workers: int | str) -> None:
        """Append one run that computed ``realizations`` (> 0) in ``wall_time`` [s] to the store's
        ``sessions``: the study's computation time is their sum, whatever reruns follow."""
        sessions = list(self.group.attrs.get("sessions", []))
        sessions.append({"started": started, "wall_time": float(wall_time),
                         "realizations": int(realizations), "workers": workers})
        self.group.attrs["sessions"] = sessions

    def sessions(self) -> list[dict]:
        return list(self.group.attrs.get("sessions", []))


def computation_time(sessions: list[dict]) -> tuple[float, int | str | None]:
    """(total wall time [s] of the runs that computed realizations, the workers of the last one)."""
    total = float(sum(float(s.get("wall_time", 0.0)) for s in sessions))
    return total, (sessions[-1].get("workers") if sessions else None)


# --- execution -----------------------------------------------------------------------------------


class StudyInterrupted(RuntimeError):
    """The study was interrupted; what finished is in the store and a rerun resumes."""


class StudyWorkersLost(RuntimeError):
    """No worker is left to compute the study (Dask workers gone, worker processes that cannot start);
    what finished is in the store and a rerun resumes."""


class SchedulerUnreachable(ValueError):
    """The ``scheduler`` address does not lead to a Dask scheduler (refused, no answer, another
    protocol, malformed address)."""


@dataclass
class StudyRun:
    """What :func:`run_study` did.

    Attributes:
        completed, failed: realizations finished and failed in the store (all runs together).
        wall_time: wall time of this call [s].
        computed: realizations computed by this call (0 when the study was already finished).
        workers: what this call ran on (local process count or scheduler address).
        note: a note for the user (e.g. a stale lock taken over), or None.
    """

    store: StudyStore
    completed: int
    failed: int
    wall_time: float
    workers: int | str
    computed: int = 0
    note: str | None = None


ProgressCallback = Callable[[int, int, int], None]  # (done, failed, total)

#: Seconds a Dask study waits with no worker in the cluster before stopping (resumably).
DASK_WORKER_TIMEOUT = 30.0
#: Seconds allowed to each step of reaching a Dask scheduler (TCP connection, the server's greeting,
#: its identity, the client's registration): an address that is no scheduler fails at one of the first
#: three, so within 12 s.
SCHEDULER_TIMEOUT = 4.0


def _local_workers(workers: int | None) -> int:
    return max(1, workers or multiprocessing.cpu_count())


def run_study(
    case: Case,
    settings: StudySettings,
    store_path: str | Path,
    *,
    workers: int | None = None,
    scheduler=None,
    progress: ProgressCallback | None = None,
    note: Callable[[str], None] | None = None,
    worker_timeout: float = DASK_WORKER_TIMEOUT,
) -> StudyRun:
    """Run (or resume) every pending realization of a study into its Zarr store.

    Before anything is created: the settings are checked against the case (:func:`check_study`), a
    scheduler is reached (:class:`SchedulerUnreachable` within about 12 s), and the store is locked
    (:class:`StudyLocked` if another study runs on it).

    Args:
        workers: local processes (default: one per core); 1 runs in this process.
        scheduler: address of a Dask distributed scheduler (``tcp://host:8786``), or a connected
            ``distributed.Client`` (left open); when given, the realizations run on that cluster's
            workers instead of local processes.
        progress: called as ``progress(done, failed, total)`` after each realization.
        note: called with a one-line note for the user (a stale lock taken over); default: a warning.
        worker_timeout: seconds a Dask study waits with no worker left before raising
            :class:`StudyWorkersLost`.
    """
    check_workers(workers, scheduler)
    check_study(case, settings)
    client = connect_scheduler(scheduler) if isinstance(scheduler, str) else scheduler
    try:
        with StudyLock(store_path) as guard:
            if guard.note:
                notify(note, guard.note)
            address = None if client is None else str(getattr(client.scheduler, "address", scheduler))
            run = _run_locked(case, settings, Path(store_path), workers, client, address, progress,
                              worker_timeout)
            run.note = guard.note
            return run
    finally:
        if isinstance(scheduler, str) and client is not None:
            client.close()


def check_workers(workers: int | None, scheduler=None) -> None:
    """Refuse (ValueError) a worker count that is not an integer >= 1, or workers with a scheduler."""
    if workers is not None and not (isinstance(workers, int) and not isinstance(workers, bool)
                                    and workers >= 1):
        raise ValueError(f"workers = {workers!r}: must be an integer >= 1")
    if workers is not None and scheduler is not None:
        raise ValueError("give workers (local processes) or scheduler (Dask cluster), not both")


def notify(note: Callable[[str], None] | None, text: str) -> None:
    """Give ``text`` to ``note``, or issue it as a RuntimeWarning when there is no ``note``."""
    if note is None:
        import warnings

        warnings.warn(text, RuntimeWarning, stacklevel=3)
    else:
        note(text)


def _run_locked(case, settings, store_path, workers, client, scheduler, progress, worker_timeout):
    store = StudyStore(store_path, case, settings)
    indices = ([] if store.nominal_done() else [NOMINAL]) + store.pending()
    status = store.status()
    done, failed = int(np.sum(status == DONE)), int(np.sum(status == FAILED))
    total = settings.samples
    started = _dt.datetime.now().astimezone().isoformat(timespec="seconds")
    start = time.perf_counter()
    computed = 0

    def record(outcome: RealizationOutcome) -> None:
        nonlocal done, failed, computed
        store.write(outcome)
        if outcome.index != NOMINAL:
            computed += 1
            if outcome.status == DONE:
                done += 1
            else:
                failed += 1
        if progress:
            progress(done, failed, total)

    if scheduler:
        used: int | str = scheduler
    elif _local_workers(workers) == 1 or len(indices) <= 1:
        used = 1
    else:
        used = _local_workers(workers)
    if progress:
        progress(done, failed, total)
    try:
        if indices and not scheduler:
            _compile_kernels(case)
        if client is not None:
            _run_dask(client, scheduler, case, settings, indices, record, worker_timeout)
        elif used == 1:
            for i in indices:
                record(run_realization(case, settings, i))
        else:
            _run_processes(case, settings, indices, used, record)
    except KeyboardInterrupt as error:
        raise StudyInterrupted(
            f"study interrupted after {done + failed} of {total} realizations; they are saved in "
            f"{store.path}; run the same command again to resume"
        ) from error
    finally:
        elapsed = time.perf_counter() - start
        if computed:
            store.record_session(started, elapsed, computed, used)
    return StudyRun(store, done, failed, elapsed, used, computed)


def _compile_kernels(case: Case) -> None:
    """Compile the simulation kernels once, here (announced on stderr the first time), so that local
    worker processes only load them from Numba's cache and no realization's time includes compiling."""
    from drillstring.dynamics.compiled import prepare_kernels

    try:
        model = case_reduced_model(case)
    except Exception:  # the realizations record why; the kernels then compile in the first of them
        return
    prepare_kernels(model, case.simulation.method)


#: Thread counts for worker processes: one process per core, each single-threaded, so linear
#: algebra libraries do not oversubscribe the cores.
WORKER_ENVIRONMENT = {"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1",
                      "NUMBA_NUM_THREADS": "1"}

#: In a worker process: the shared flags "realization started" (slot index + 1; slot 0 the nominal run).
_STARTED = None


def _worker_start(parent_pid: int, started=None) -> None:
    """Worker initializer: keep the shared "started" flags, and exit as soon as the study's process is
    gone (killed, not just interrupted), instead of computing realizations nobody will record."""
    import threading

    global _STARTED
    _STARTED = started

    def watch() -> None:
        while True:
            time.sleep(1.0)
            if os.getppid() != parent_pid:
                os._exit(0)

    threading.Thread(target=watch, daemon=True).start()


def _tracked(task: Callable, case, settings, index: int):
    """Run ``task`` in a worker after flagging ``index`` as started (a plain store into shared memory:
    no lock that a killed worker could leave held)."""
    if _STARTED is not None:
        _STARTED[index + 1] = 1
    return task(case, settings, index)


def _run_processes(case, settings, indices: Iterable[int], workers: int, record,
                   task: Callable = run_realization) -> None:
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


def _worker_died(case, settings, index: int) -> RealizationOutcome:
    return RealizationOutcome(
        index, draw_weight_on_hook(case, settings, index), math.nan, FAILED,
        "worker process died (killed or crashed) while computing this realization alone")


def _process_loop(context, case, settings, remaining, workers, record, parent_pid, task) -> None:
    """Run ``remaining`` on a pool of ``workers`` processes.

    If a worker dies (killed, out of memory, crash) the pool breaks and every running realization is
    lost with it. The realizations that had started and not returned (at most one per worker) are set
    aside as suspects; the others go on in a fresh pool of ``workers`` processes. At the end each
    suspect runs alone in its own single-process pool (up to ``workers`` such pools at once): the one
    that kills its worker there is recorded as failed with that cause, the innocent ones finish
    normally. A pool that breaks before any realization started (workers that cannot start) raises
    :class:`StudyWorkersLost`.
    """
    slots = max(remaining, default=-1) + 2
    started = context.Array("b", slots, lock=False)
    suspects: list[int] = []
    recorded: set[int] = set()
    while remaining:
        for i in range(slots):
            started[i] = 0
        pool = cf.ProcessPoolExecutor(max_workers=min(workers, len(remaining)), mp_context=context,
                                      initializer=_worker_start, initargs=(parent_pid, started))
        broken = False
        try:
            futures = {pool.submit(_tracked, task, case, settings, i): i for i in remaining}
            for future in cf.as_completed(futures):
                error = future.exception()
                if error is None:
                    record(future.result())
                    recorded.add(futures[future])
                elif isinstance(error, cf.process.BrokenProcessPool):
                    broken = True
                else:
                    raise error
        finally:
            pool.shutdown(wait=False, cancel_futures=True)
        in_flight = [i for i in remaining if started[i + 1] and i not in recorded]
        if broken and not in_flight:
            raise StudyWorkersLost("local worker processes died before computing any realization "
                                   "(they cannot start); finished realizations are saved, rerun to resume")
        suspects.extend(in_flight)
        remaining = [i for i in remaining if i not in recorded and i not in in_flight]
    for first in range(0, len(suspects), workers):
        batch = suspects[first:first + workers]
        pools = [cf.ProcessPoolExecutor(max_workers=1, mp_context=context, initializer=_worker_start,
                                        initargs=(parent_pid, None)) for _ in batch]
        try:
            futures = {p.submit(task, case, settings, i): i for p, i in zip(pools, batch)}
            for future in cf.as_completed(futures):
                error = future.exception()
                if error is None:
                    record(future.result())
                elif isinstance(error, cf.process.BrokenProcessPool):
                    record(_worker_died(case, settings, futures[future]))
                else:
                    raise error
        finally:
            for p in pools:
                p.shutdown(wait=False, cancel_futures=True)


# --- Dask ----------------------------------------------------------------------------------------


def _receive(sock, n: int) -> bytes:
    data = b""
    while len(data) < n:
        chunk = sock.recv(n - len(data))
        if not chunk:
            raise ConnectionError("closed the connection")
        data += chunk
    return data


def _probe_tcp_scheduler(address: str, host: str, port: int, timeout: float) -> None:
    """Check that ``host:port`` answers as a Dask server: a TCP connection within ``timeout`` and,
    within ``timeout`` more, the greeting every Dask server sends first (an 8-byte length, then a
    msgpack handshake). Raises :class:`SchedulerUnreachable`."""
    import socket
    import struct

    def refuse(why: str) -> SchedulerUnreachable:
        return SchedulerUnreachable(f"scheduler = {address!r}: {why}")

    try:
        sock = socket.create_connection((host, port), timeout=timeout)
    except ConnectionRefusedError:
        raise refuse("connection refused (no server listens on that port)") from None
    except socket.gaierror as error:
        raise refuse(f"unknown host {host!r} ({error.strerror})") from None
    except TimeoutError:
        raise refuse(f"no answer within {timeout:g} s (unreachable address or filtered port)") from None
    except OSError as error:
        raise refuse(f"cannot connect ({error.strerror or error})") from None
    with sock:
        sock.settimeout(timeout)
        not_dask = "the server there does not speak the Dask protocol (not a Dask scheduler)"
        try:
            (length,) = struct.unpack("<Q", _receive(sock, 8))
            if not 0 < length <= 1 << 20:
                raise refuse(not_dask)
            payload = _receive(sock, length)
        except TimeoutError:
            raise refuse(f"the server there sent no Dask greeting within {timeout:g} s "
                         "(not a Dask scheduler)") from None
        except (ConnectionError, OSError):
            raise refuse(f"{not_dask}: it closed the connection") from None
    try:
        import msgpack
        from distributed.protocol.utils import unpack_frames

        greetings = [msgpack.loads(bytes(frame)) for frame in unpack_frames(payload)]
    except Exception:
        raise refuse(not_dask) from None
    if not any(isinstance(g, dict) and "pickle-protocol" in g for g in greetings):
        raise refuse(not_dask)


def _server_type(address: str, timeout: float) -> str:
    """The type of the Dask server at ``address`` ("Scheduler", "Worker", "Nanny", ...) from its
    ``identity``, within ``timeout`` seconds (in a thread of its own, so that it also works where an
    event loop is already running, as in a notebook)."""
    import asyncio
    from concurrent.futures import ThreadPoolExecutor

    from distributed.core import rpc

    async def identity() -> dict:
        async with rpc(address, timeout=timeout) as server:
            return await asyncio.wait_for(server.identity(), timeout)

    def ask() -> str:
        try:
            info = asyncio.run(asyncio.wait_for(identity(), timeout))
        except (TimeoutError, asyncio.TimeoutError):
            raise SchedulerUnreachable(f"scheduler = {address!r}: no answer to a Dask request within "
                                       f"{timeout:g} s") from None
        except Exception as error:
            message = str(error).splitlines()[0] if str(error) else type(error).__name__
            raise SchedulerUnreachable(f"scheduler = {address!r}: cannot connect ({message})") from None
        return str(info.get("type", "server of unknown type")) if isinstance(info, dict) else "server"

    with ThreadPoolExecutor(max_workers=1) as pool:
        return pool.submit(ask).result()


def connect_scheduler(address: str, timeout: float = SCHEDULER_TIMEOUT):
    """A :class:`distributed.Client` connected to the scheduler at ``address``, or
    :class:`SchedulerUnreachable` (one line) within about ``3 × timeout`` seconds: a TCP address is
    first probed by hand (:func:`_probe_tcp_scheduler`), since the client waits forever for the
    greeting of a server that is not a Dask server; then the server must say it is a scheduler (not a
    worker or nanny)."""
    from distributed import Client
    from distributed.comm import parse_address
    from distributed.comm.addressing import parse_host_port

    if not isinstance(address, str) or not address.strip():
        raise SchedulerUnreachable(f"scheduler = {address!r}: give an address like tcp://host:8786")
    try:
        scheme, location = parse_address(address.strip())
        if scheme == "tcp":
            host, port = parse_host_port(location, 8786)
    except (ValueError, TypeError) as error:
        raise SchedulerUnreachable(f"scheduler = {address!r}: not an address like tcp://host:8786 "
                                   f"({error})") from None
    if scheme == "tcp":
        _probe_tcp_scheduler(address, host, int(port), timeout)
    kind = _server_type(address.strip(), timeout)
    if kind != "Scheduler":
        raise SchedulerUnreachable(f"scheduler = {address!r}: that is a Dask {kind}, not a scheduler "
                                   "(give the scheduler's address, e.g. tcp://host:8786)")
    try:
        return Client(address.strip(), timeout=timeout, set_as_default=False)
    except Exception as error:  # one line, whatever went wrong on the way
        message = str(error).splitlines()[0] if str(error) else type(error).__name__
        raise SchedulerUnreachable(f"scheduler = {address!r}: cannot connect ({message})") from None


def _run_dask(client, scheduler: str, case, settings, indices: list[int], record,
              worker_timeout: float) -> None:
    """Run ``indices`` on the cluster of ``client``. A realization whose workers keep dying
    (``KilledWorker``) is recorded as failed with that cause; a cluster left without any worker for
    ``worker_timeout`` seconds, or a lost scheduler, raises :class:`StudyWorkersLost`."""
    from distributed.scheduler import KilledWorker

    if not indices:
        return
    futures = client.map(run_realization, [case] * len(indices), [settings] * len(indices), indices,
                         pure=False)
    index_of = {future.key: i for future, i in zip(futures, indices)}
    pending = list(futures)
    alone_since: float | None = None
    checked = time.monotonic()

    def lost(why: str) -> StudyWorkersLost:
        return StudyWorkersLost(f"{why}; the finished realizations are saved, rerun the same command "
                                f"(with workers available) to resume")

    try:
        while pending:
            finished = []
            for future in pending:  # statuses are updated by the client's event loop
                status = future.status
                if status == "finished":
                    try:
                        outcome = future.result(timeout=worker_timeout)
                    except TimeoutError:  # its result left with its worker: the scheduler recomputes it
                        continue
                    finished.append(future)
                    record(outcome)
                elif status == "error":
                    finished.append(future)
                    error = future.exception()
                    i = index_of[future.key]
                    if not isinstance(error, KilledWorker):
                        raise lost(f"the Dask cluster at {scheduler} could not compute realization {i} "
                                   f"({type(error).__name__}: {error})")
                    record(RealizationOutcome(
                        i, draw_weight_on_hook(case, settings, i), math.nan, FAILED,
                        f"Dask workers died (killed or crashed) while computing this realization: {error}"))
                elif status == "cancelled":
                    raise lost(f"the Dask scheduler at {scheduler} cancelled the study's tasks")
                # "pending", or "lost" (its result left with its worker; recomputed): wait
            if finished:
                done_now = set(map(id, finished))
                pending = [f for f in pending if id(f) not in done_now]
                alone_since, checked = None, time.monotonic()
                continue
            time.sleep(0.05)
            if pending and time.monotonic() - checked > 1.0:  # no progress: is any worker left?
                checked = time.monotonic()
                try:
                    n_workers = len(client.nthreads())
                except Exception as error:
                    raise lost(f"lost the Dask scheduler at {scheduler} ({type(error).__name__})") from None
                if n_workers:
                    alone_since = None
                elif alone_since is None:
                    alone_since = time.monotonic()
                elif time.monotonic() - alone_since > worker_timeout:
                    raise lost(f"the Dask cluster at {scheduler} has had no worker for "
                               f"{worker_timeout:g} s")
    finally:
        if pending:
            try:
                client.cancel(list(pending))
            except Exception:  # the scheduler may be gone: nothing left to cancel there
                pass
