"""The Python API for notebooks: load a case, run one drilling simulation, a Monte Carlo study, a
comparison of the two nonlinear models. The command line calls these functions (one set of defaults,
one set of checks) and only parses and formats.

>>> import drillstring
>>> ds = drillstring.simulate("reference", t_end=5.0)        # doctest: +SKIP
>>> ds.rate_of_penetration.sel(time=slice(2, None)).mean()  # doctest: +SKIP
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Mapping

import numpy as np
import xarray as xr

from drillstring.case import Case, load_case
from drillstring.dynamics.rom import case_reduced_model
from drillstring.dynamics.simulate import SimulationError, simulate_model
from drillstring.results import run_dataset
from drillstring.stochastic import DEFAULT_BASE_SAMPLES, DEFAULT_SAMPLES, DEFAULT_SEED
from drillstring.units import display_unit, unit_system


def as_case(case: Case | str | Path) -> Case:
    """A Case as is, or loaded from a built-in name or a TOML path."""
    return case if isinstance(case, Case) else load_case(case)


def simulate(
    case: Case | str | Path = "reference",
    *,
    t_end: float | None = None,
    output_step: float | None = None,
    rtol: float | None = None,
    atol: float | None = None,
    weight_on_bit: float | None = None,
    progress: Callable[[float], None] | None = None,
    raise_on_failure: bool = True,
) -> xr.Dataset:
    """Simulate one drilling run of ``case`` (SPEC §7) and return its observables as a Dataset.

    Arguments left as None take the case's ``[simulation]`` values; ``weight_on_bit`` [N] overrides
    the static weight-on-bit. A run that stops early raises :class:`SimulationError` whose
    ``.dataset`` holds what was computed (or, with ``raise_on_failure=False``, that Dataset is
    returned with ``attrs["status"] == "failed"``).
    """
    case = as_case(case)
    s = case.simulation
    model = case_reduced_model(case, weight_on_bit=weight_on_bit)
    extra = {
        "weight_on_hook": model.static.weight_on_hook,
        "weight_on_bit": model.static.weight_on_bit,
        "top_speed": case.operation.top_speed,
        "modes": f"{case.reduced_model.axial_modes} axial + rigid, {case.reduced_model.torsional_modes} "
                 f"torsional, {model.family.count('lateral_y')} lateral per plane",
        "elements": model.static.mesh.n_elements,
    }
    kwargs = dict(
        t_end=s.t_end if t_end is None else t_end,
        output_step=s.output_step if output_step is None else output_step,
        rtol=s.rtol if rtol is None else rtol,
        atol=s.atol if atol is None else atol,
        method=s.method,
        max_steps=s.max_steps,
        min_step=s.min_step,
        lateral_perturbation=case.initial.lateral_perturbation,
        seed=case.initial.seed,
        progress=progress,
    )
    try:
        result = simulate_model(model, **kwargs)
    except SimulationError as error:
        dataset = run_dataset(error.result, case_toml=case.to_toml(), extra_attrs=extra)
        if raise_on_failure:
            error.dataset = dataset
            raise
        return dataset
    return run_dataset(result, case_toml=case.to_toml(), extra_attrs=extra)


class StudyFailed(RuntimeError):
    """A study that ran but cannot give statistics (fewer than 2 realizations finished); the message
    lists the first failures, the store keeps everything."""


@dataclass
class StudyOutcome:
    """What :func:`monte_carlo_study` did.

    Attributes:
        statistics: the statistics Dataset (as returned by :func:`study`).
        summary: the JSON-ready summary (SI), as written to ``summary.json``: dispersions after the
            transient, the failures and their causes, ``wall_time`` (the computation time of the study,
            summed over the runs that computed realizations; a rerun of a finished study keeps it),
            ``wall_time_this_run``, ``workers``, ``sessions`` and ``files``.
        files: name -> path of each file written (empty when ``out`` is None).
        already: realizations that were in the store before this run (a resumed or finished study).
        note: a note for the user (a stale lock taken over), or None.
    """

    statistics: xr.Dataset
    summary: dict
    files: dict[str, Path]
    already: int
    note: str | None = None


#: Captions of the study figures in the report, by figure name.
_STUDY_CAPTIONS = {
    "envelopes": "95 % envelopes, mean and nominal response (deterministic run at the mean of every random "
                 "parameter)",
    "dispersion": "Dispersion of the response vs time (transient t < {t_transient:g} s shaded)",
    "convergence": "Mean-square convergence conv(n_s), each observable divided by its last value",
}


def study_settings(case: Case, *, sigma=None, dispersion=None, parameters=None, correlation=None,
                   samples: int = DEFAULT_SAMPLES, seed: int = DEFAULT_SEED, t_end=None, output_step=None):
    """The validated settings of a Monte Carlo study of ``case`` (ValueError naming the field or the
    parameter otherwise), and the case without its ``[uncertainty]`` table (the laws are in the settings).

    The random parameters: ``parameters`` (path -> law spec or table) with ``correlation`` (``{"parameters":
    [...], "matrix": [[...]]}``) when given, else the case's ``[uncertainty]`` table; plus the weight-on-hook,
    Normal of standard deviation ``sigma`` [N] or ``dispersion`` × its mean, when either is given. With none
    of these, the default: the weight-on-hook Normal of σ = :data:`~drillstring.stochastic.DEFAULT_SIGMA`.
    """
    from drillstring.stochastic import DEFAULT_SIGMA
    from drillstring.stochastic.montecarlo import StudySettings, check_study, nominal_weight_on_hook
    from drillstring.stochastic.parameters import WEIGHT_ON_HOOK
    from drillstring.stochastic.uncertainty import declared_uncertainty

    if sigma is not None and dispersion is not None:
        raise ValueError("give sigma [N] or dispersion (sigma / mean weight_on_hook), not both")
    if dispersion is not None:
        if not (isinstance(dispersion, (int, float)) and math.isfinite(dispersion) and dispersion > 0):
            raise ValueError(f"dispersion = {dispersion!r}: must be a finite number > 0")
        sigma = dispersion * nominal_weight_on_hook(case)
    if sigma is not None and not (isinstance(sigma, (int, float)) and not isinstance(sigma, bool)):
        raise ValueError(f"sigma = {sigma!r} N: must be a finite number > 0")
    first = None
    if sigma is not None and math.isfinite(sigma) and sigma > 0:
        first = {WEIGHT_ON_HOOK: {"law": "normal", "mean": nominal_weight_on_hook(case), "std": float(sigma)}}
    declared = declared_uncertainty(case, parameters, correlation, first=first, tolerance=1.0)
    laws, correlated, matrix = (), (), ()
    if declared is not None:
        laws = tuple((p.path, p.law.to_spec()) for p in declared.parameters if not (first and p.path in first))
        if declared.correlation is not None:
            correlated, matrix = declared.correlated, tuple(map(tuple, declared.correlation.tolist()))
    if sigma is None and not laws:
        sigma = DEFAULT_SIGMA
    bare = case.model_copy(update={"uncertainty": None})
    settings = StudySettings(
        samples=samples, sigma=float(sigma) if sigma is not None else None, seed=seed,
        t_end=case.simulation.t_end if t_end is None else t_end,
        output_step=case.simulation.output_step if output_step is None else output_step,
        laws=laws, correlated=correlated, correlation=matrix,
    )
    check_study(bare, settings)
    return settings, bare


def _transient(transient, t_end: float) -> float:
    from drillstring.dynamics.indicators import transient_end

    if transient is None:
        return transient_end(t_end)
    if not (isinstance(transient, (int, float)) and math.isfinite(transient) and 0 <= transient <= t_end):
        raise ValueError(f"transient = {transient!r} s: must be in [0, t_end = {t_end:g} s]")
    return float(transient)


def monte_carlo_study(
    case: Case | str | Path = "reference",
    *,
    sigma: float | None = None,
    dispersion: float | None = None,
    parameters: Mapping[str, Any] | None = None,
    correlation: Mapping[str, Any] | None = None,
    samples: int = DEFAULT_SAMPLES,
    seed: int = DEFAULT_SEED,
    out: str | Path | None = None,
    workers: int | None = None,
    scheduler=None,
    t_end: float | None = None,
    output_step: float | None = None,
    transient: float | None = None,
    progress: Callable[[int, int, int], None] | None = None,
    note: Callable[[str], None] | None = None,
    worker_timeout: float | None = None,
    units: str | None = None,
) -> StudyOutcome:
    """Monte Carlo study of random case parameters (SPEC §8; by default a random weight-on-hook), with
    its files.

    The random parameters (:func:`study_settings`): each of ``parameters`` (case-parameter path -> law
    spec, e.g. ``{"fluid.inlet_velocity": "uniform 1.2 1.8 m/s"}``; laws by the Maximum Entropy Principle,
    :mod:`drillstring.stochastic.uncertainty`), correlated normals by ``correlation`` (``{"parameters":
    [...], "matrix": [[...]]}``), or the case's ``[uncertainty]`` table when ``parameters`` is None; and the
    weight-on-hook, Normal of standard deviation ``sigma`` [N] or ``dispersion`` × mean (at most one of
    them). Nothing declared: the weight-on-hook Normal of σ = :data:`~drillstring.stochastic.DEFAULT_SIGMA`.
    ``samples`` realizations (>= 2) of ``t_end`` [s]
    run on ``workers`` local processes (default: one per core) or on the Dask cluster at ``scheduler``
    (an address, or a ``distributed.Client``). Summaries use ``t >= transient`` (default
    ``min(10 s, t_end/2)``). ``progress(done, failed, total)`` follows the realizations; ``note(text)``
    receives notes (a stale lock taken over).

    Everything is checked before anything runs: the settings (ValueError naming the field or the
    parameter; a law that puts a probability above 1e-3 outside its parameter's range, e.g. a sigma
    that would put a weight-on-bit outside (0, string weight), included; a weight-on-hook law that
    buckles more than one draw in a thousand is only noted, through ``note``),
    ``out`` (must be a writable folder), the scheduler (:class:`~drillstring.stochastic.montecarlo.
    SchedulerUnreachable`) and the lock on ``out`` (:class:`~drillstring.stochastic.locks.
    StudyLocked` while another study runs there; held until every file is written).

    In ``out`` (default: a temporary folder, and no files but the store): ``study.zarr`` (every
    realization, streamed; rerunning resumes), then, each written atomically, ``statistics.nc``,
    ``summary.json``, the figures ``envelopes.png``, ``dispersion.png``, ``convergence.png`` and
    ``report.html``; figures and report in the unit system ``units`` (``"si"`` or ``"field"``; None:
    ``$DRILLSTRING_UNITS``, else si; JSON and NetCDF stay SI). Fewer than 2 finished realizations raise
    :class:`StudyFailed`.
    Scripts that use several local processes must call this under ``if __name__ == "__main__":``.
    """
    import tempfile

    from drillstring.files import output_folder_problem
    from drillstring.stochastic.locks import StudyLock
    from drillstring.stochastic.analysis import load_study, study_statistics, study_summary
    from drillstring.stochastic.montecarlo import (
        DASK_WORKER_TIMEOUT,
        check_workers,
        computation_time,
        connect_scheduler,
        notify,
        run_study,
        study_buckling_margin,
    )

    units = unit_system(units, "units")  # a bad unit system is refused before anything runs
    settings, case = study_settings(as_case(case), sigma=sigma, dispersion=dispersion, parameters=parameters,
                                    correlation=correlation, samples=samples, seed=seed, t_end=t_end,
                                    output_step=output_step)
    t_transient = _transient(transient, settings.t_end)
    if out is not None:
        problem = output_folder_problem(out)
        if problem:
            raise ValueError(f"out = {str(out)!r}: {problem}")
    check_workers(workers, scheduler)
    buckling = study_buckling_margin(case, settings)
    if buckling["warning"]:
        notify(note, buckling["warning"])
    folder = Path(out) if out is not None else Path(tempfile.mkdtemp(prefix="drillstring-study-"))
    store = folder / "study.zarr"
    client = connect_scheduler(scheduler) if isinstance(scheduler, str) else scheduler
    try:
        with StudyLock(store) as guard:
            if guard.note:
                notify(note, guard.note)
            run = run_study(case, settings, store, workers=workers, scheduler=client, progress=progress,
                            note=note, worker_timeout=(DASK_WORKER_TIMEOUT if worker_timeout is None
                                                       else worker_timeout))
            raw = load_study(store)
            failures = {str(k): str(v) for k, v in dict(raw.attrs.get("failures", {})).items()}
            try:
                stats = study_statistics(raw, t_transient=t_transient)
            except ValueError as error:
                listing = "; ".join(f"{k}: {v}" for k, v in list(failures.items())[:3])
                raise StudyFailed(f"{error} ({len(failures)} failure(s)"
                                  f"{': ' + listing if listing else ''})") from None
            summary = study_summary(stats, t_transient=t_transient)
            sessions = run.store.sessions()
            wall_time, used = computation_time(sessions)
            if not sessions:  # a store written before sessions were recorded
                wall_time, used = run.wall_time, run.workers
            realization_time = float(np.nansum(raw["wall_time"].values))
            payload = dict(summary)
            payload["buckling"] = {**summary["buckling"], **buckling}
            payload.update({
                "case": case.name,
                "samples": settings.samples,
                "failures": failures,
                "wall_time": wall_time,
                "wall_time_this_run": run.wall_time,
                "realizations_this_run": run.computed,
                "realization_wall_time_total": realization_time,
                "workers": used if isinstance(used, (int, str)) else str(used),
                "sessions": sessions,
            })
            files: dict[str, Path] = {}
            if out is not None:
                files = _write_study_files(case, settings, stats, summary, payload, folder, t_transient, units)
    finally:
        if isinstance(scheduler, str) and client is not None:
            client.close()
    return StudyOutcome(stats, payload, files, run.completed + run.failed - run.computed,
                        guard.note or run.note)


def _write_study_files(case, settings, stats, summary, payload, folder: Path, t_transient,
                       units: str | None) -> dict[str, Path]:
    """statistics.nc, the figures, summary.json (``payload`` gets ``files``) and report.html (the
    statistics' ``summary`` and the run information from ``payload``)."""
    import json

    from drillstring.files import write_text_atomic
    from drillstring.plots import plot_study
    from drillstring.report import write_report
    from drillstring.results import write_netcdf

    paths = {"store": folder / "study.zarr", "summary": folder / "summary.json",
             "statistics": folder / "statistics.nc", "report": folder / "report.html"}
    force = display_unit("force", unit_system(units))
    write_netcdf(stats, paths["statistics"])
    figures = plot_study(stats, folder, t_transient, units=units)
    payload["files"] = {**{k: str(v) for k, v in paths.items()}, **{k: str(v) for k, v in figures.items()}}
    write_text_atomic(paths["summary"], json.dumps(payload, indent=2) + "\n")
    run_info = {
        "realizations requested": settings.samples,
        "failures": payload["failures"],
        "computation wall time [s]": round(payload["wall_time"], 2),
        "buckled realizations (lowest lateral ω² < 0)": (
            f"{payload['buckling']['buckled_realizations']} of {payload['n_samples']}; critical weight-on-bit "
            f"{force(payload['buckling']['critical_weight_on_bit']):.5g} {force.label}, probability of a buckled draw "
            f"{payload['buckling']['probability']:.3g}"),
        "total time of the realizations [s]": round(payload["realization_wall_time_total"], 2),
        "workers": payload["workers"],
    }
    if payload["realizations_this_run"] == 0 or len(payload["sessions"]) > 1:
        run_info["wall time of this run [s]"] = round(payload["wall_time_this_run"], 2)
        run_info["runs that computed realizations"] = len(payload["sessions"])
    run_info.update({
        "simulated time per realization [s]": settings.t_end,
        "output step [s]": settings.output_step,
        "store": str(paths["store"]),
    })
    write_report(
        paths["report"],
        title=f"Monte Carlo study: case '{case.name}', random {', '.join(stats.attrs['parameters'])}",
        case_toml=case.to_toml(),
        summary=summary,
        figures={_STUDY_CAPTIONS[k].format(t_transient=t_transient): figures[k]
                 for k in ("envelopes", "dispersion", "convergence")},
        run_info=run_info,
        units=units,
    )
    return {**paths, **figures}


def stability(case: Case | str | Path = "reference", *, weight_on_bit: float | None = None):
    """Steady drilling of ``case`` (closed form) and the eigenvalues of its reduced model linearised
    about it, bit–rock law included (:mod:`drillstring.dynamics.stability`).

    Returns a :class:`~drillstring.dynamics.stability.StabilityResult`: ``.stable``, ``.steady_state``
    (``rate_of_penetration`` [m/s], ``bit_speed`` [rad/s], ``torque_on_bit`` [N·m], ``force_on_bit``
    [N]), ``.modes`` sorted by frequency (``family``, ``frequency`` [Hz], ``damping_ratio``,
    ``growth_rate`` [1/s]), ``.leading`` and ``.to_dict()`` (JSON-ready). ``weight_on_bit`` [N]
    overrides the case's.
    """
    from drillstring.dynamics.stability import case_stability

    return case_stability(as_case(case), weight_on_bit=weight_on_bit)


def study(
    case: Case | str | Path = "reference",
    *,
    sigma: float | None = None,
    dispersion: float | None = None,
    parameters: Mapping[str, Any] | None = None,
    correlation: Mapping[str, Any] | None = None,
    samples: int = DEFAULT_SAMPLES,
    seed: int = DEFAULT_SEED,
    out: str | Path | None = None,
    workers: int | None = None,
    scheduler=None,
    t_end: float | None = None,
    output_step: float | None = None,
    transient: float | None = None,
    progress: Callable[[int, int, int], None] | None = None,
) -> xr.Dataset:
    """Monte Carlo study of random case parameters (SPEC §8); returns the statistics Dataset.

    The statistics of :func:`monte_carlo_study` (same arguments, same checks and files): laws of
    ``parameters`` (or the case's ``[uncertainty]`` table), at most one of ``sigma`` [N] or
    ``dispersion`` (σ / mean) for the weight-on-hook (default, nothing declared: σ = 5000 N); the
    drawn values are in ``input_values``; realizations stream to the Zarr
    store ``out``/study.zarr (a temporary folder when None), rerunning with the same ``out`` resumes.
    ``transient`` [s]: start of the steady window for the summaries and the per-realization vibration
    indicators (default ``min(10 s, t_end/2)``).
    Scripts that use several local processes must call this under ``if __name__ == "__main__":``.
    """
    return monte_carlo_study(
        case, sigma=sigma, dispersion=dispersion, parameters=parameters, correlation=correlation,
        samples=samples, seed=seed, out=out, workers=workers, scheduler=scheduler, t_end=t_end,
        output_step=output_step, transient=transient, progress=progress,
    ).statistics


#: The two nonlinear models compared by :func:`compare`, in the order returned: case 1, case 2.
COMPARED_MODELS = ("full", "bit_and_contact")
#: Scalar observables compared by :func:`compare` (the radial displacement is added per probe).
COMPARED_OBSERVABLES = ("rate_of_penetration", "bit_speed", "torque_on_bit", "force_on_bit")


def _ratio(numerator: float, denominator: float) -> float | None:
    """``numerator / denominator`` as a JSON-ready float, None when undefined (0/0, x/0, NaN)."""
    if not (math.isfinite(numerator) and math.isfinite(denominator)) or denominator == 0.0:
        return None
    return float(numerator / denominator)


def _finite_or_none(value: float) -> float | None:
    return float(value) if math.isfinite(value) else None


def _difference_numbers(full, reduced, steady) -> dict[str, float | None]:
    """Differences of one observable, case 1 (``full``) minus case 2 (``reduced``), SI units: the largest
    absolute difference over time, the RMS difference relative to the RMS of case 2, and the difference of
    the means over the ``steady`` samples (t after the transient), absolute and relative to case 2's."""
    full = np.asarray(full, dtype=float)
    reduced = np.asarray(reduced, dtype=float)
    delta = full - reduced
    mean_full = float(np.mean(full[steady]))
    mean_reduced = float(np.mean(reduced[steady]))
    return {
        "max_abs_difference": _finite_or_none(float(np.max(np.abs(delta)))),
        "rms_relative_difference": _ratio(float(np.sqrt(np.mean(delta**2))),
                                          float(np.sqrt(np.mean(reduced**2)))),
        "mean_full": _finite_or_none(mean_full),
        "mean_bit_and_contact": _finite_or_none(mean_reduced),
        "mean_difference": _finite_or_none(mean_full - mean_reduced),
        "mean_relative_difference": _ratio(mean_full - mean_reduced, abs(mean_reduced)),
    }


def compare(
    case: Case | str | Path = "reference",
    *,
    t_end: float | None = None,
    output_step: float | None = None,
    progress: Callable[[str, float], None] | None = None,
) -> tuple[xr.Dataset, xr.Dataset, dict]:
    """Run ``case`` with the full nonlinear model (case 1: kinetic- and strain-energy forces added) and with
    the bit–rock and contact forces only (case 2), everything else equal (SPEC §6), and compare them.

    Returns ``(full, bit_and_contact, differences)``: the two run Datasets and a JSON-ready dict (SI
    units) with, under ``observables``, for the rate of penetration, bit speed, torque- and force-on-bit
    and the radial displacement at each probe (``radial_displacement_<j>``, with its ``probe_x``):
    ``max_abs_difference`` over time, ``rms_relative_difference`` (RMS of the difference / RMS of case 2),
    the means after the transient (t >= min(10 s, t_end/2)) of each case, their ``mean_difference`` and
    ``mean_relative_difference`` (relative to |mean of case 2|; None when that mean is 0). Differences are
    case 1 minus case 2. ``wall_time`` holds the wall time [s] of each ``simulate`` call (model build and
    integration, measured around the call), ``ratio`` = full / bit_and_contact; ``solver_wall_time`` and
    ``n_rhs`` the integrator's own numbers. ``progress(model, t)`` is called with the model name
    ("full" or "bit_and_contact") and the simulated time [s]. A run that stops early raises
    :class:`SimulationError` (``.dataset`` the partial run, ``.nonlinear`` which model failed).
    """
    import time

    from drillstring.dynamics.indicators import transient_end

    case = as_case(case)
    runs: dict[str, xr.Dataset] = {}
    wall: dict[str, float] = {}
    for nonlinear in COMPARED_MODELS:
        variant = case.model_copy(update={"model": case.model.model_copy(update={"nonlinear": nonlinear})})
        report = None if progress is None else (lambda t, _m=nonlinear: progress(_m, t))
        start = time.perf_counter()
        try:
            runs[nonlinear] = simulate(variant, t_end=t_end, output_step=output_step, progress=report)
        except SimulationError as error:
            error.nonlinear = nonlinear
            raise
        wall[nonlinear] = time.perf_counter() - start
    full, reduced = runs["full"], runs["bit_and_contact"]

    t = np.asarray(full["time"].values, dtype=float)
    t_reduced = np.asarray(reduced["time"].values, dtype=float)

    def on_grid(values) -> np.ndarray:
        values = np.asarray(values, dtype=float)
        if t_reduced.shape == t.shape and np.allclose(t_reduced, t, rtol=0.0, atol=1e-12):
            return values
        return np.interp(t, t_reduced, values)

    t_final = float(t[-1])
    t_transient = transient_end(t_final)
    steady = t >= t_transient - 1e-9 * max(1.0, t_final)
    if not steady.any():
        steady = np.ones_like(t, dtype=bool)

    observables: dict[str, dict] = {}
    for name in COMPARED_OBSERVABLES:
        observables[name] = _difference_numbers(full[name].values, on_grid(reduced[name].values), steady)
    x = np.atleast_1d(np.asarray(full["x"].values, dtype=float))
    radial_full = np.asarray(full["radial_displacement"].values, dtype=float)
    radial_reduced = np.asarray(reduced["radial_displacement"].values, dtype=float)
    for j, position in enumerate(x):
        entry = {"probe_x": float(position)}
        entry.update(_difference_numbers(radial_full[:, j], on_grid(radial_reduced[:, j]), steady))
        observables[f"radial_displacement_{j}"] = entry

    def pair(key: str, cast=float) -> dict:
        return {m: cast(runs[m].attrs.get(key, float("nan"))) for m in COMPARED_MODELS}

    differences = {
        "case": case.name,
        "t_end": t_final,
        "t_transient": float(t_transient),
        "difference": "case 1 (full) minus case 2 (bit_and_contact)",
        "observables": observables,
        "wall_time": {**{m: float(wall[m]) for m in COMPARED_MODELS},
                      "ratio": _ratio(wall["full"], wall["bit_and_contact"])},
        "solver_wall_time": pair("solver_wall_time"),
        "n_rhs": pair("solver_n_rhs", int),
        "impacts": pair("impacts", int),
    }
    return full, reduced, differences


# --- operating maps and global sensitivity -------------------------------------------------------


def _engine_folder(out, workers, scheduler, prefix: str) -> Path:
    """The output folder (checked; a temporary one when ``out`` is None), after checking the workers."""
    import tempfile

    from drillstring.files import output_folder_problem
    from drillstring.stochastic.execution import check_workers

    if out is not None:
        problem = output_folder_problem(out)
        if problem:
            raise ValueError(f"out = {str(out)!r}: {problem}")
    check_workers(workers, scheduler)
    return Path(out) if out is not None else Path(tempfile.mkdtemp(prefix=prefix))


def _run_record(store, run, noun: str) -> dict:
    """Computation time and workers of a store's sessions, and this call's numbers (JSON-ready)."""
    from drillstring.stochastic.execution import computation_time

    sessions = store.sessions()
    wall_time, used = computation_time(sessions)
    return {
        "failures": store.failures(),
        "wall_time": wall_time,
        "wall_time_this_run": run.wall_time,
        f"{noun}_this_run": run.computed,
        "workers": used if isinstance(used, (int, str)) or used is None else str(used),
        "sessions": sessions,
    }


def _run_table(record: dict, noun: str) -> dict:
    """Rows of a report's "Run" table."""
    rows = {"failures": record["failures"], "computation wall time [s]": round(record["wall_time"], 2),
            "workers": record["workers"]}
    if record[f"{noun}_this_run"] == 0 or len(record["sessions"]) > 1:
        rows["wall time of this run [s]"] = round(record["wall_time_this_run"], 2)
        rows[f"runs that computed {noun}"] = len(record["sessions"])
    return rows


@dataclass
class MapOutcome:
    """What :func:`operating_map` did: the map Dataset, its JSON-ready summary (as in ``map.json``), the
    files written (name -> path) and the points that were in the store before this call."""

    dataset: xr.Dataset
    summary: dict
    files: dict[str, Path]
    already: int
    note: str | None = None


def map_settings(case: Case, *, top_speed=None, weight_on_bit=None, t_end=None, output_step=None, transient=None,
                 default_units: tuple[str, str] = ("", "")):
    """The validated :class:`~drillstring.stochastic.operating_map.MapSettings` of a map of ``case``: axes
    as sequences of SI numbers or grid strings (``"40 rpm:200 rpm:17"``, ``"100,120 kN"``; bare numbers in
    ``default_units`` or SI), default :data:`~drillstring.stochastic.DEFAULT_MAP_TOP_SPEED` ×
    :data:`~drillstring.stochastic.DEFAULT_MAP_WEIGHT_ON_BIT`."""
    from drillstring.case import DIMENSIONS
    from drillstring.stochastic import DEFAULT_MAP_TOP_SPEED, DEFAULT_MAP_WEIGHT_ON_BIT
    from drillstring.stochastic.operating_map import MapSettings, check_map, parse_axis

    dimension = {d.name: d for d in DIMENSIONS}
    speeds = parse_axis(DEFAULT_MAP_TOP_SPEED if top_speed is None else top_speed, dimension["angular speed"],
                        name="top_speed", default_unit=default_units[0])
    weights = parse_axis(DEFAULT_MAP_WEIGHT_ON_BIT if weight_on_bit is None else weight_on_bit, dimension["force"],
                         name="weight_on_bit", default_unit=default_units[1])
    settings = MapSettings(tuple(speeds), tuple(weights),
                           t_end=case.simulation.t_end if t_end is None else t_end,
                           output_step=case.simulation.output_step if output_step is None else output_step,
                           transient=transient)
    check_map(case, settings)
    return settings


def operating_map(
    case: Case | str | Path = "reference",
    *,
    top_speed=None,
    weight_on_bit=None,
    t_end: float | None = None,
    output_step: float | None = None,
    transient: float | None = None,
    out: str | Path | None = None,
    workers: int | None = None,
    scheduler=None,
    progress: Callable[[int, int, int], None] | None = None,
    note: Callable[[str], None] | None = None,
    worker_timeout: float | None = None,
    units: str | None = None,
) -> MapOutcome:
    """Operating map of ``case`` over top speed × weight-on-bit (:mod:`drillstring.stochastic.operating_map`):
    one simulation of ``t_end`` [s] per grid point, summarised after ``transient`` [s] (default
    ``min(10 s, t_end/2)``) by mean ROP, bit-speed oscillation, stick time, mean TOB and FOB, mechanical
    specific energy, largest radial displacement and impacts, with the linear stability of steady drilling
    (leading growth rate) and the buckling margin at each point.

    ``top_speed`` [rad/s] and ``weight_on_bit`` [N]: sequences of values or grid strings (``"40 rpm:200
    rpm:17"``, ``"A:B:N"``, ``"a,b,c"``; bare numbers SI), default 40–200 rpm (17) × 40–160 kN (13). Points
    run on ``workers`` local processes or the Dask cluster at ``scheduler``; the store ``out``/map.zarr is
    resumable. In ``out``: ``map.nc`` (dims ``top_speed``, ``weight_on_bit``; units in attributes),
    ``map.json`` (the summary), ``map.png`` and ``report.html`` (figure and report in the unit system ``units``,
    ``"si"`` or ``"field"``; None: ``$DRILLSTRING_UNITS``, else si). Checked before anything runs: the grid
    (every weight-on-bit below the string's weight), ``out``, the scheduler and the lock.
    Scripts that use several local processes must call this under ``if __name__ == "__main__":``.
    """
    import json

    from drillstring.files import write_text_atomic
    from drillstring.plots import plot_map
    from drillstring.report import write_map_report
    from drillstring.results import write_netcdf
    from drillstring.stochastic.execution import DASK_WORKER_TIMEOUT, connect_scheduler, notify
    from drillstring.stochastic.locks import StudyLock
    from drillstring.stochastic.operating_map import map_dataset, map_summary, run_map

    units = unit_system(units, "units")  # a bad unit system is refused before anything runs
    case = as_case(case).model_copy(update={"uncertainty": None})
    settings = map_settings(case, top_speed=top_speed, weight_on_bit=weight_on_bit, t_end=t_end,
                            output_step=output_step, transient=transient)
    folder = _engine_folder(out, workers, scheduler, "drillstring-map-")
    store_path = folder / "map.zarr"
    client = connect_scheduler(scheduler) if isinstance(scheduler, str) else scheduler
    try:
        with StudyLock(store_path, what="map") as guard:
            if guard.note:
                notify(note, guard.note)
            run = run_map(case, settings, store_path, workers=workers, scheduler=client, progress=progress,
                          note=note, worker_timeout=DASK_WORKER_TIMEOUT if worker_timeout is None else worker_timeout)
            ds = map_dataset(store_path)
            summary = {"case": case.name, **map_summary(ds), **_run_record(run.store, run, "points")}
            files: dict[str, Path] = {}
            if out is not None:
                files = {"store": store_path, "map": folder / "map.nc", "summary": folder / "map.json",
                         "figure": folder / "map.png", "report": folder / "report.html"}
                write_netcdf(ds, files["map"])
                plot_map(ds, files["figure"], units=units)
                summary["files"] = {k: str(v) for k, v in files.items()}
                write_text_atomic(files["summary"], json.dumps(summary, indent=2) + "\n")
                write_map_report(files["report"], title=f"Operating map: case '{case.name}'",
                                 case_toml=case.to_toml(), summary=summary,
                                 figures={"Mean ROP, bit-speed oscillation, mechanical specific energy and "
                                          "largest radial displacement over the map; black line: linear "
                                          "stability boundary of steady drilling (hatched: unstable); red "
                                          "dashed: lateral buckling limit; dots: simulated points": files["figure"]},
                                 run_info={**_run_table(summary, "points"), "store": str(store_path)},
                                 units=units)
    finally:
        if isinstance(scheduler, str) and client is not None:
            client.close()
    return MapOutcome(ds, summary, files, run.completed + run.failed - run.computed, guard.note or run.note)


@dataclass
class SensitivityOutcome:
    """What :func:`sensitivity` did: the Sobol' indices (a :class:`~drillstring.stochastic.sensitivity.
    SobolResult`), the JSON-ready payload (as in ``sensitivity.json``), the files written and the runs that
    were in the store before this call."""

    result: object
    payload: dict
    files: dict[str, Path]
    already: int
    note: str | None = None


def sensitivity(
    case: Case | str | Path = "reference",
    *,
    parameters: Mapping[str, Any] | None = None,
    samples: int = DEFAULT_BASE_SAMPLES,
    seed: int = 0,
    t_end: float | None = None,
    output_step: float | None = None,
    transient: float | None = None,
    confidence: float = 0.95,
    resamples: int = 1000,
    out: str | Path | None = None,
    workers: int | None = None,
    scheduler=None,
    progress: Callable[[int, int, int], None] | None = None,
    note: Callable[[str], None] | None = None,
    worker_timeout: float | None = None,
    units: str | None = None,
) -> SensitivityOutcome:
    """Global sensitivity of ``case``: first-order and total Sobol' indices, with bootstrap confidence
    intervals (level ``confidence``) and a convergence check at N/4, N/2, N, of the time-mean ROP,
    bit-speed oscillation, mean TOB and FOB and the standard deviations in time of ROP, TOB and FOB
    (:mod:`drillstring.stochastic.sensitivity_study`).

    The uncertain parameters: ``parameters`` (path -> law, independent), else the case's ``[uncertainty]``
    table. ``samples`` is the number of base samples N (a power of 2): N(k + 2) runs of ``t_end`` [s]
    on ``workers`` local processes or the Dask cluster at ``scheduler``; the store ``out``/sensitivity.zarr is
    resumable. In ``out``: ``sensitivity.json`` (per output: ``S1``, ``ST``, their intervals, per
    parameter; the convergence; the run), ``sobol.png``, ``sobol_convergence.png`` and ``report.html`` (its
    case table in the unit system ``units``, ``"si"`` or ``"field"``; None: ``$DRILLSTRING_UNITS``, else si).
    Scripts that use several local processes must call this under ``if __name__ == "__main__":``.
    """
    import json

    from drillstring.files import write_text_atomic
    from drillstring.plots import plot_sobol, plot_sobol_convergence
    from drillstring.report import write_sensitivity_report
    from drillstring.stochastic.execution import DASK_WORKER_TIMEOUT, connect_scheduler, notify
    from drillstring.stochastic.locks import StudyLock
    from drillstring.stochastic.sensitivity_study import (
        SENSITIVITY_OUTPUTS,
        SensitivitySettings,
        load_sensitivity,
        run_sensitivity,
    )
    from drillstring.stochastic.uncertainty import declared_uncertainty

    units = unit_system(units, "units")  # a bad unit system is refused before anything runs
    case = as_case(case)
    declared = declared_uncertainty(case, parameters)
    if declared is None:
        raise ValueError("no uncertain parameter: give parameters (path -> law), e.g. --param "
                         "operation.top_speed=\"uniform 60 140 rpm\", or an [uncertainty] table in the case")
    case = case.model_copy(update={"uncertainty": None})
    settings = SensitivitySettings(
        base_samples=samples, laws=tuple((p.path, p.law.to_spec()) for p in declared.parameters), seed=seed,
        t_end=case.simulation.t_end if t_end is None else t_end,
        output_step=case.simulation.output_step if output_step is None else output_step, transient=transient)
    if declared.correlation is not None:
        raise ValueError(f"Sobol' indices need independent parameters; {', '.join(declared.correlated)} are "
                         "correlated (drop the correlation, or use a Monte Carlo study for the joint law)")
    if not 0.0 < confidence < 1.0:
        raise ValueError(f"confidence = {confidence!r}: must be in (0, 1), e.g. 0.95")
    folder = _engine_folder(out, workers, scheduler, "drillstring-sensitivity-")
    store_path = folder / "sensitivity.zarr"
    client = connect_scheduler(scheduler) if isinstance(scheduler, str) else scheduler
    try:
        with StudyLock(store_path, what="sensitivity") as guard:
            if guard.note:
                notify(note, guard.note)
            run = run_sensitivity(case, settings, store_path, workers=workers, scheduler=client,
                                  progress=progress, note=note,
                                  worker_timeout=DASK_WORKER_TIMEOUT if worker_timeout is None else worker_timeout)
            data = load_sensitivity(store_path)
            result = data.indices(SENSITIVITY_OUTPUTS, confidence=confidence, resamples=resamples)
            record = _run_record(run.store, run, "runs")
            payload = {"case": case.name, **result.to_dict(), "t_end": settings.t_end,
                       "t_transient": settings.transient, "failed_runs": run.failed,
                       "run_wall_time_total": float(np.nansum(data.wall_time)), **record}
            files: dict[str, Path] = {}
            if out is not None:
                files = {"store": store_path, "indices": folder / "sensitivity.json",
                         "figure": folder / "sobol.png", "convergence": folder / "sobol_convergence.png",
                         "report": folder / "report.html"}
                plot_sobol(payload, files["figure"])
                plot_sobol_convergence(payload, files["convergence"])
                payload["files"] = {k: str(v) for k, v in files.items()}
                write_text_atomic(files["indices"], json.dumps(payload, indent=2, allow_nan=False) + "\n")
                write_sensitivity_report(
                    files["report"], title=f"Global sensitivity: case '{case.name}'", case_toml=case.to_toml(),
                    indices=payload,
                    figures={"First-order (S1) and total (ST) Sobol' indices with their confidence intervals":
                             files["figure"],
                             "The indices at N/4, N/2 and N base samples": files["convergence"]},
                    run_info={**_run_table(record, "runs"), "runs": result.runs,
                              "simulated time per run [s]": settings.t_end,
                              "outputs over": f"t ≥ {settings.transient:g} s", "store": str(store_path)},
                    units=units)
    finally:
        if isinstance(scheduler, str) and client is not None:
            client.close()
    return SensitivityOutcome(result, payload, files, run.completed + run.failed - run.computed,
                              guard.note or run.note)
