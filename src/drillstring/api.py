"""The Python API for notebooks: load a case, run one drilling simulation, a Monte Carlo study, a
comparison of the two nonlinear models. The command line calls these functions (one set of defaults,
one set of checks) and only parses and formats. Each public function runs its dense linear algebra
single-threaded (:mod:`drillstring.blas_threads`), whatever the caller's BLAS settings.

>>> import drillstring
>>> ds = drillstring.simulate("reference", t_end=5.0)        # doctest: +SKIP
>>> ds.rate_of_penetration.sel(time=slice(2, None)).mean()  # doctest: +SKIP
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable, Mapping

import numpy as np

from drillstring.blas_threads import single_threaded_blas
from drillstring.case import Case, load_case
from drillstring.stochastic import DEFAULT_BASE_SAMPLES, DEFAULT_SAMPLES, DEFAULT_SEED
from drillstring.units import display_unit, unit_system

if TYPE_CHECKING:  # the simulating modules load with the functions that use them (light static, modes)
    import xarray as xr

#: Largest number of bootstrap resamples of a sensitivity run's confidence intervals.
MAX_RESAMPLES = 100_000


def as_case(case: Case | str | Path) -> Case:
    """A Case as is, or loaded from a built-in name or a TOML path. Anything else — a dict included (build
    a Case from one with :func:`drillstring.case.case_from_dict`) — raises TypeError naming ``case``."""
    if isinstance(case, Case):
        return case
    if isinstance(case, (str, Path)):
        return load_case(case)
    hint = " (build one from a dict with drillstring.case.case_from_dict)" if isinstance(case, Mapping) else ""
    raise TypeError(f"case = {type(case).__name__}: must be a Case, a built-in case name or a path to a TOML "
                    f"file{hint}")


def _tolerance(name: str, value) -> float | None:
    """An integration tolerance override: None, or a number in (0, 1)."""
    from drillstring.checks import real_number

    return None if value is None else real_number(name, value, low=0.0, high=1.0, low_open=True, high_open=True,
                                                   allowed="a number in (0, 1), e.g. 1e-6")


def _weight_on_bit(case: Case, value) -> float:
    """The ``weight_on_bit`` argument [N] overriding the case's, checked as the case's own (> 0, at most
    1e9 N, less than the string's weight with gravity on): TypeError or ValueError naming the argument."""
    from drillstring.checks import real_number

    value = real_number("weight_on_bit", value, unit="N", low=0.0, low_open=True)
    problem = case.weight_on_bit_problem(value)
    if problem:
        raise ValueError(f"weight_on_bit = {value!r} N: {problem}")
    return value


def _callable(name: str, value) -> None:
    if value is not None and not callable(value):
        raise TypeError(f"{name} = {value!r}: must be a callable or None")


@single_threaded_blas()
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
    """Simulate one drilling run of ``case`` (docs/model.md §9) and return its observables as a Dataset.

    Arguments left as None take the case's ``[simulation]`` values; ``weight_on_bit`` [N] overrides
    the static weight-on-bit. A run that stops early raises :class:`~drillstring.dynamics.simulate.SimulationError` whose
    ``.dataset`` holds what was computed (or, with ``raise_on_failure=False``, that Dataset is
    returned with ``attrs["status"] == "failed"``).
    """
    from drillstring.dynamics.rom import case_reduced_model
    from drillstring.dynamics.simulate import SimulationError, simulate_model
    from drillstring.results import run_dataset

    case = as_case(case)
    s = case.simulation
    window = _window(case, t_end, output_step)
    rtol, atol = _tolerance("rtol", rtol), _tolerance("atol", atol)
    if weight_on_bit is not None:
        weight_on_bit = _weight_on_bit(case, weight_on_bit)
    _callable("progress", progress)
    model = case_reduced_model(case, weight_on_bit=weight_on_bit)
    extra = {
        "weight_on_hook": model.static.weight_on_hook,
        "weight_on_bit": model.static.weight_on_bit,
        "top_speed": case.operation.top_speed,
        "top_drive": case.top_drive.controller,
        "bit_rock_law": case.bit_rock.law,
        "modes": f"{case.reduced_model.axial_modes} axial + rigid, {case.reduced_model.torsional_modes} "
                 f"torsional{' + rigid' if model.top_drive.drives else ''}, "
                 f"{model.family.count('lateral_y')} lateral per plane",
        "elements": model.static.mesh.n_elements,
        "lateral_modes": int(model.family.count("lateral_y")),
    }
    kwargs = dict(
        t_end=window.t_end,
        output_step=window.output_step,
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
        dataset = _with_derived(run_dataset(error.result, case_toml=case.to_toml(), extra_attrs=extra), model)
        if raise_on_failure:
            error.dataset = dataset
            raise
        return dataset
    return _with_derived(run_dataset(result, case_toml=case.to_toml(), extra_attrs=extra), model)


def _with_derived(dataset, model):
    """A run's Dataset with what its figure shows besides the observables: the ``hook_load`` [N] during a
    ramped start (:class:`~drillstring.forces.hook_load.HookLoadRamp`: the static hook load plus the weight
    not yet transferred) and, for a Detournay bit, the ``wear_flat_force`` [N] (the force on bit less the
    cutting force, :meth:`~drillstring.forces.detournay.DetournayParameters.cutting_force`); the
    ``depth_of_cut`` observable is dropped for the laws without one; with a downhole motor the
    ``differential_pressure`` [Pa] across it (:meth:`~drillstring.forces.motor.PositiveDisplacementMotor.
    differential_pressure`), without one its ``motor_speed`` and ``motor_torque`` observables are dropped."""
    from drillstring.quantities import LONG_NAMES, UNITS

    t = dataset["time"].values
    if model.hook_load.active:
        values = model.static.weight_on_hook - model.hook_load.force(t)
        dataset["hook_load"] = ("time", values, {"units": UNITS["hook_load"], "long_name": LONG_NAMES["hook_load"]})
    if model.bit_rock.delayed:
        cutting_force = getattr(model.bit_rock, "cutting_force", None)  # the law itself (component protocol)
        if cutting_force is not None:  # the Detournay law: the rest of the force on bit is the wear flats'
            force = dataset["force_on_bit"].values
            wear = np.where(force > 0.0, force - cutting_force(dataset["depth_of_cut"].values), 0.0)
            dataset["wear_flat_force"] = ("time", wear, {"units": UNITS["wear_flat_force"],
                                                         "long_name": LONG_NAMES["wear_flat_force"]})
    elif "depth_of_cut" in dataset:
        dataset = dataset.drop_vars("depth_of_cut")
    if model.motor is not None:  # a downhole motor: its differential pressure from its torque (its law, eq. (2))
        pressure = model.motor.differential_pressure(dataset["motor_torque"].values)
        dataset["differential_pressure"] = ("time", pressure, {"units": UNITS["differential_pressure"],
                                                               "long_name": LONG_NAMES["differential_pressure"]})
    else:
        dataset = dataset.drop_vars([name for name in ("motor_speed", "motor_torque") if name in dataset])
    return dataset


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
    "convergence": "Convergence: mean-square conv(n_s), each observable divided by its last value (left); maximum "
                   "and time-mean dispersion over records of growing length after the transient (right)",
    "realizations": "Per-realization cycle metrics after t = {t_transient:g} s: histograms, mean and nominal run",
}


def study_settings(case: Case, *, sigma=None, dispersion=None, parameters=None, correlation=None, model=None,
                   samples: int = DEFAULT_SAMPLES, seed: int = DEFAULT_SEED, t_end=None, output_step=None):
    """The validated settings of a Monte Carlo study of ``case`` (TypeError / ValueError naming the field or
    the parameter otherwise), and the case without its ``[uncertainty]`` table (the laws are in the settings).

    The random parameters: ``parameters`` (path -> law spec or table) with ``correlation`` (``{"parameters":
    [...], "matrix": [[...]]}``) when given, else the case's ``[uncertainty]`` table; plus the weight-on-hook,
    Normal of standard deviation ``sigma`` [N] or ``dispersion`` × its mean, when either is given (a
    shorthand for the law ``weight_on_hook = "normal mean=<hook load> std=<sigma>"``, declared first). With
    none of these, the default: the weight-on-hook Normal of σ = :data:`~drillstring.stochastic.DEFAULT_SIGMA`.
    ``model``: the model uncertainty, ``{"mass_dispersion": δ_M, "stiffness_dispersion": δ_K,
    "damping_dispersion": δ_D}`` (:mod:`~drillstring.stochastic.random_matrices`), else the case's
    ``[uncertainty.model]`` table, else none.
    """
    from drillstring.checks import real_number
    from drillstring.stochastic import DEFAULT_SIGMA
    from drillstring.stochastic.montecarlo import (
        StudySettings,
        check_study,
        nominal_weight_on_hook,
        weight_on_hook_normal,
    )
    from drillstring.stochastic.uncertainty import declared_uncertainty

    if sigma is not None and dispersion is not None:
        raise ValueError("give sigma [N] or dispersion (sigma / mean weight_on_hook), not both")
    if dispersion is not None:
        sigma = real_number("dispersion", dispersion, low=0.0, low_open=True) * nominal_weight_on_hook(case)
    if sigma is not None:
        sigma = real_number("sigma", sigma, unit="N", low=0.0, low_open=True)
    _mapping("parameters", parameters)
    _mapping("correlation", correlation)
    _mapping("model", model)
    from drillstring.stochastic.random_matrices import ModelDispersion

    dispersions = ModelDispersion.declared(case, model)
    first = dict([weight_on_hook_normal(case, sigma)]) if sigma is not None else None
    declared = declared_uncertainty(case, parameters, correlation, first=first, tolerance=1.0)
    if declared is None:
        first = dict([weight_on_hook_normal(case, DEFAULT_SIGMA)])
        declared = declared_uncertainty(case, None, None, first=first, tolerance=1.0)
    correlated, matrix = (), ()
    if declared.correlation is not None:
        correlated, matrix = declared.correlated, tuple(map(tuple, declared.correlation.tolist()))
    window = _window(case, t_end, output_step)
    bare = case.model_copy(update={"uncertainty": None})
    settings = StudySettings(samples=samples, seed=seed, t_end=window.t_end, output_step=window.output_step,
                             laws=tuple((p.path, p.law.to_spec()) for p in declared.parameters),
                             correlated=correlated, correlation=matrix,
                             model_dispersion=dispersions.as_tuple())
    check_study(bare, settings)
    return settings, bare


def _mapping(name: str, value) -> None:
    """Refuse (TypeError) ``value`` unless None or a mapping (a table: path -> law, or parameters/matrix)."""
    if value is not None and not isinstance(value, Mapping):
        raise TypeError(f"{name} = {type(value).__name__}: must be a dict (path -> law spec), e.g. "
                        "{'operation.top_speed': 'uniform 60 140 rpm'}")


def _window(case: Case, t_end=None, output_step=None, transient=None):
    """The run window (:func:`~drillstring.dynamics.simulate.run_window`) of ``case`` with the given overrides."""
    from drillstring.dynamics.simulate import run_window

    return run_window(case.simulation.t_end if t_end is None else t_end,
                      case.simulation.output_step if output_step is None else output_step, transient)


def _output_folder(out, prefix: str) -> Path:
    """The output folder, checked (ValueError naming ``out``), or a new temporary one when ``out`` is None."""
    import tempfile

    from drillstring.files import output_folder_problem

    if out is None:
        return Path(tempfile.mkdtemp(prefix=prefix))
    if not isinstance(out, (str, Path)):
        raise TypeError(f"out = {out!r}: must be a folder path (str or Path) or None")
    problem = output_folder_problem(out)
    if problem:
        raise ValueError(f"out = {str(out)!r}: {problem}")
    return Path(out)


def _engine(workers, scheduler, progress, note, worker_timeout):
    """The :class:`~drillstring.stochastic.execution.Engine` of a study, map or sensitivity run (checked)."""
    from drillstring.stochastic.execution import DASK_WORKER_TIMEOUT, Engine

    return Engine(workers=workers, scheduler=scheduler, progress=progress, note=note,
                  worker_timeout=DASK_WORKER_TIMEOUT if worker_timeout is None else worker_timeout)


@single_threaded_blas()
def monte_carlo_study(
    case: Case | str | Path = "reference",
    *,
    sigma: float | None = None,
    dispersion: float | None = None,
    parameters: Mapping[str, Any] | None = None,
    correlation: Mapping[str, Any] | None = None,
    model: Mapping[str, float] | None = None,
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
    stage: Callable[[str], None] | None = None,
) -> StudyOutcome:
    """Monte Carlo study of random case parameters (docs/model.md §11; by default a random weight-on-hook), with
    its files.

    The random parameters (:func:`study_settings`): each of ``parameters`` (case-parameter path -> law
    spec, e.g. ``{"fluid.inlet_velocity": "uniform 1.2 1.8 m/s"}``; laws by the Maximum Entropy Principle,
    :mod:`drillstring.stochastic.uncertainty`), correlated normals by ``correlation`` (``{"parameters":
    [...], "matrix": [[...]]}``), or the case's ``[uncertainty]`` table when ``parameters`` is None; and the
    weight-on-hook, Normal of standard deviation ``sigma`` [N] or ``dispersion`` × mean (at most one of
    them). Nothing declared: the weight-on-hook Normal of σ = :data:`~drillstring.stochastic.DEFAULT_SIGMA`.
    ``model``: nonparametric model uncertainty, ``{"mass_dispersion": δ_M, "stiffness_dispersion": δ_K,
    "damping_dispersion": δ_D}`` (random reduced matrices, :mod:`~drillstring.stochastic.random_matrices`;
    default the case's ``[uncertainty.model]``).
    ``samples`` realizations (>= 2) of ``t_end`` [s]
    run on ``workers`` local processes (default: one per core) or on the Dask cluster at ``scheduler``
    (an address, or a ``distributed.Client``). Summaries use ``t >= transient`` (default
    ``min(10 s, t_end/2)``; in [0, t_end)). ``progress(done, failed, total)`` follows the realizations;
    ``note(text)`` receives notes (a stale lock taken over); ``stage(text)``, what runs after the realizations
    ("reading the store", "statistics", "figures", "report").

    Everything is checked before anything runs (TypeError or ValueError naming the argument): the
    arguments, the run window and the study's size (:data:`~drillstring.stochastic.montecarlo.
    MAX_STUDY_BYTES`), the settings (a law that puts a probability above 1e-3 outside its parameter's
    range, e.g. a sigma that would put a weight-on-bit outside (0, string weight), included; a
    law that buckles more than one draw in a thousand is a result, not an error: ``summary["buckling"]``
    counts the buckled realizations, and ``note`` is told before the run when at least one is expected),
    ``out`` (must be a writable folder), the scheduler (:class:`~drillstring.stochastic.execution.
    SchedulerUnreachable`) and the lock on ``out`` (:class:`~drillstring.stochastic.locks.
    StudyLocked` while another study runs there; held until every file is written).

    In ``out`` (default: a temporary folder, and no files but the store): ``study.zarr`` (every
    realization, streamed; rerunning resumes), then, each written atomically, ``statistics.nc``,
    ``summary.json``, the figures ``envelopes.png``, ``dispersion.png``, ``convergence.png``, ``realizations.png`` and
    ``report.html``; figures and report in the unit system ``units`` (``"si"`` or ``"field"``; None:
    ``$DRILLSTRING_UNITS``, else si; JSON and NetCDF stay SI). Fewer than 2 finished realizations raise
    :class:`StudyFailed`.
    Scripts that use several local processes must call this under ``if __name__ == "__main__":``.
    """
    from drillstring.stochastic.montecarlo import buckling_note, run_study, study_buckling_margin

    units = unit_system(units, "units")  # a bad unit system is refused before anything runs
    settings, case = study_settings(as_case(case), sigma=sigma, dispersion=dispersion, parameters=parameters,
                                    correlation=correlation, model=model, samples=samples, seed=seed,
                                    t_end=t_end, output_step=output_step)
    t_transient = _window(case, settings.t_end, settings.output_step, transient).transient
    engine = _engine(workers, scheduler, progress, note, worker_timeout)
    folder = _output_folder(out, "drillstring-study-")
    buckling = study_buckling_margin(case, settings)
    if note is not None and buckling["warning"] and buckling["expected"] >= 1.0:
        # a result, not a misuse: said before the run only when a buckled realization is expected, and only
        # to a caller that takes notes (the summary counts them in any case)
        note(buckling_note(buckling, settings.samples, units))
    buckling = {k: v for k, v in buckling.items() if k not in ("lateral", "source")}
    finish = partial(_finish_study, case, settings, t_transient, buckling, folder if out is not None else None,
                     units, stage or (lambda text: None))
    run = run_study(case, settings, folder / "study.zarr", engine, finish=finish)
    return StudyOutcome(*run.result, run.already, run.note)


def _finish_study(case, settings, t_transient, buckling, folder, units, stage, run):
    """Under the study's lock: its statistics, summary and (in ``folder``, unless None) files; ``stage(text)``
    is told each step."""
    stage("reading the store")
    from drillstring.stochastic.analysis import load_study, study_statistics, study_summary
    from drillstring.stochastic.execution import computation_time

    raw = load_study(run.store.path)
    stage("statistics")
    failures = {str(k): str(v) for k, v in dict(raw.attrs.get("failures", {})).items()}
    try:
        stats = study_statistics(raw, t_transient=t_transient)
    except ValueError as error:
        listing = "; ".join(f"{k}: {v}" for k, v in list(failures.items())[:3])
        raise StudyFailed(f"{error} ({len(failures)} failure(s)"
                          f"{': ' + listing if listing else ''})") from None
    summary = study_summary(stats, t_transient=t_transient, boundary=_stability_boundary(case))
    sessions = run.store.sessions()
    wall_time, used = computation_time(sessions)
    if not sessions:  # a store written before sessions were recorded
        wall_time, used = run.wall_time, run.workers
    payload = dict(summary)
    payload["buckling"] = {**summary["buckling"], **buckling}
    payload.update({
        "case": case.name,
        "samples": settings.samples,
        "failures": failures,
        "wall_time": wall_time,
        "wall_time_this_run": run.wall_time,
        "realizations_this_run": run.computed,
        "realization_wall_time_total": float(np.nansum(raw["wall_time"].values)),
        "workers": used if isinstance(used, (int, str)) else str(used),
        "sessions": sessions,
    })
    files: dict[str, Path] = {}
    if folder is not None:
        files = _write_study_files(case, settings, stats, summary, payload, folder, t_transient, raw, units, stage)
    return stats, payload, files


def _stability_boundary(case: Case) -> dict | None:
    """:func:`stability_boundary`, None where steady drilling does not exist."""
    try:
        return stability_boundary(case)
    except ValueError:
        return None


def _write_study_files(case, settings, stats, summary, payload, folder: Path, t_transient,
                       raw=None, units: str | None = None, stage=lambda text: None) -> dict[str, Path]:
    """statistics.nc, the figures, summary.json (``payload`` gets ``files``), report.html (the
    statistics' ``summary`` and the run information from ``payload``) and interactive.html (with the first
    finished realizations of ``raw``, the study's raw Dataset); figures and report in the unit system ``units``."""

    from drillstring.files import strict_json, write_text_atomic
    from drillstring.interactive import REALIZATIONS_SHOWN, study_figures
    from drillstring.quantities import stored_observables
    from drillstring.report import INTERACTIVE_PAGE, write_report
    from drillstring.results import write_netcdf
    from drillstring.stochastic.analysis import current_figures, figures_key, record_figures
    from drillstring.stochastic.store import DONE

    paths = {"store": folder / "study.zarr", "summary": folder / "summary.json",
             "statistics": folder / "statistics.nc", "report": folder / "report.html",
             "interactive": folder / INTERACTIVE_PAGE}
    shown = None
    if raw is not None:
        finished = np.nonzero(raw.status.values == DONE)[0][:REALIZATIONS_SHOWN]
        shown = raw[list(stored_observables(raw))].isel(realization=finished)
    force = display_unit("force", units)
    write_netcdf(stats, paths["statistics"])
    key = figures_key(payload, settings, t_transient, units)
    figures = current_figures(folder, key)
    if figures is None:  # drawn again (importing Matplotlib only then)
        from drillstring.plots import plot_study

        stage("figures")
        figures = plot_study(stats, folder, t_transient, summary.get("time_convergence"), units=units)
        record_figures(folder, key, figures)
    stage("report")
    payload["files"] = {**{k: str(v) for k, v in paths.items()}, **{k: str(v) for k, v in figures.items()}}
    write_text_atomic(paths["summary"], strict_json(payload) + "\n")  # undefined values: null, never NaN
    run_info = {
        "realizations requested": settings.samples,
        "failures": payload["failures"],
        "computation wall time [s]": round(payload["wall_time"], 2),
        "buckled realizations (lowest lateral ω² < 0)": (
            f"{payload['buckling']['buckled_realizations']} of {payload['n_samples']}; critical weight-on-bit "
            f"{force(payload['buckling']['critical_weight_on_bit']):.5g} {force.label}, probability of a "
            f"buckled draw {payload['buckling']['probability']:.3g}"),
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
                 for k in ("envelopes", "dispersion", "convergence", "realizations") if k in figures},
        run_info=run_info,
        interactive=study_figures(stats, shown, units=units),
        units=units,
    )
    return {**paths, **figures}


@single_threaded_blas()
def static(case: Case | str | Path = "reference"):
    """The prestressed static state of ``case`` and its lateral buckling margin.

    Returns ``(state, margin)``: a :class:`~drillstring.statics.StaticState` (``weight``,
    ``weight_on_hook``, ``weight_on_bit`` [N], ``neutral_point_height`` [m], the mesh and the axial
    force ``axial_force`` [N] at its nodes, tension positive) and a :class:`~drillstring.buckling.
    BucklingMargin` (``critical_weight_on_bit`` [N], ``buckled``)."""
    from drillstring.buckling import case_buckling_margin
    from drillstring.statics import case_static_state

    case = as_case(case)
    state = case_static_state(case)
    return state, case_buckling_margin(case, state)


#: Largest number of modes per family :func:`modes` computes.
MAX_MODES = 1000


@single_threaded_blas()
def modes(case: Case | str | Path = "reference", *, count: int = 10):
    """The ``count`` lowest natural modes per family (axial with its rigid mode, torsional, lateral per plane)
    of the prestressed string of ``case`` with its drilling fluid, and its lateral buckling margin. With a
    downhole motor the torsional modes are those of the string released at its rotor
    (:func:`drillstring.rotor.released_modes`; the first, at 0 Hz, the string below turning relative to the
    string above).

    Returns ``(modes, margin)``: :class:`~drillstring.modal.Modes` (``.axial.frequencies`` [Hz], ...) and a
    :class:`~drillstring.buckling.BucklingMargin`. ``count``: an integer in [1, :data:`MAX_MODES`]."""
    from drillstring.buckling import buckling_margin
    from drillstring.checks import integer
    from drillstring.modal import case_linear_system, compute_modes
    from drillstring.statics import case_static_state

    from drillstring.rotor import released_modes

    count = integer("count", count, low=1, high=MAX_MODES)
    case = as_case(case)
    system = case_linear_system(case, case_static_state(case))
    if case.motor is not None:  # the torsion released at the rotor: its first mode the string below turning
        return released_modes(system, case.motor.position, count, count, count)[0], buckling_margin(system)
    return compute_modes(system, axial=count, torsional=count, lateral=count), buckling_margin(system)


@single_threaded_blas()
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

    case = as_case(case)
    if weight_on_bit is not None:
        weight_on_bit = _weight_on_bit(case, weight_on_bit)
    return case_stability(case, weight_on_bit=weight_on_bit)


@single_threaded_blas()
def campbell(case: Case | str | Path = "reference", *, top_speed=None, blades: int | None = None,
             default_unit: str = "", progress: Callable[[int, int], None] | None = None):
    """The Campbell diagram of ``case`` (:mod:`drillstring.critical_speeds`): natural frequencies of the axial,
    torsional and lateral (forward and backward whirl) families against the rotary speed, prestressed at
    the case's weight-on-bit, with the drilling fluid and the gyroscopic terms; the excitation lines 1×
    and ``blades`` × (default :data:`~drillstring.critical_speeds.DEFAULT_BLADES`) and their critical speeds.

    ``top_speed``: the speeds, SI numbers [rad/s] or a grid string (``"5 rpm:300 rpm:60"``, bare numbers
    in ``default_unit`` or SI), default :data:`~drillstring.critical_speeds.DEFAULT_CAMPBELL_TOP_SPEED`. Returns a
    :class:`~drillstring.critical_speeds.CampbellDiagram` (``.to_dict()`` is JSON-ready). Raises ValueError (one
    line naming the argument) for a bad grid, more than :data:`~drillstring.critical_speeds.MAX_CAMPBELL_SPEEDS`
    speeds or a blade count outside [1, :data:`~drillstring.critical_speeds.MAX_BLADES`] (before any work),
    TypeError for a blade count that is not an integer. ``progress(done, total)`` is called after each exact
    solution of the lateral whirl (``total``: an upper bound; a diagram of 3,000 speeds needs about 20)."""
    from drillstring.case import DIMENSIONS
    from drillstring.checks import integer
    from drillstring.critical_speeds import (
        DEFAULT_BLADES,
        DEFAULT_CAMPBELL_TOP_SPEED,
        MAX_BLADES,
        case_campbell,
        check_speed_count,
    )
    from drillstring.stochastic.operating_map import parse_axis

    the_case = as_case(case)
    blades = integer("blades", DEFAULT_BLADES if blades is None else blades, low=1, high=MAX_BLADES)
    _callable("progress", progress)
    dimension = {d.name: d for d in DIMENSIONS}["angular speed"]
    speeds = parse_axis(DEFAULT_CAMPBELL_TOP_SPEED if top_speed is None else top_speed, dimension,
                        name="top_speed", default_unit=default_unit)
    check_speed_count(len(speeds), name=f"top_speed = {top_speed!r}" if isinstance(top_speed, str) else "top_speed")
    return case_campbell(the_case, speeds, blades, progress=progress)


@single_threaded_blas()
def stability_boundary(case: Case | str | Path = "reference") -> dict:
    """The stability boundary of steady drilling along the weight-on-bit at the case's top speed (SI):
    ``weight_on_bit`` [N] where the leading growth rate crosses 0 nearest the case's weight-on-bit (None
    when it does not between 0 and the string's weight), ``top_speed`` [rad/s], ``nominal_weight_on_bit``
    [N] and ``nominal_growth_rate`` [1/s] (:func:`~drillstring.dynamics.stability.weight_on_bit_boundary`).
    ValueError when the case itself has no steady drilling."""
    from drillstring.dynamics.stability import weight_on_bit_boundary

    return weight_on_bit_boundary(as_case(case))


@single_threaded_blas()
def study(
    case: Case | str | Path = "reference",
    *,
    sigma: float | None = None,
    dispersion: float | None = None,
    parameters: Mapping[str, Any] | None = None,
    correlation: Mapping[str, Any] | None = None,
    model: Mapping[str, float] | None = None,
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
    """Monte Carlo study of random case parameters (docs/model.md §11); returns the statistics Dataset.

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
        case, sigma=sigma, dispersion=dispersion, parameters=parameters, correlation=correlation, model=model,
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


@single_threaded_blas()
def compare(
    case: Case | str | Path = "reference",
    *,
    t_end: float | None = None,
    output_step: float | None = None,
    progress: Callable[[str, float], None] | None = None,
) -> tuple[xr.Dataset, xr.Dataset, dict]:
    """Run ``case`` with the full nonlinear model (case 1: kinetic- and strain-energy forces added) and with
    the bit–rock and contact forces only (case 2), everything else equal (docs/model.md §5), and compare them.

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
    :class:`~drillstring.dynamics.simulate.SimulationError` (``.dataset`` the partial run, ``.nonlinear`` which model failed).
    """
    import time

    from drillstring.dynamics.indicators import transient_end
    from drillstring.dynamics.simulate import SimulationError

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
    window = _window(case, t_end, output_step, transient)
    settings = MapSettings(tuple(speeds), tuple(weights), t_end=window.t_end, output_step=window.output_step,
                           transient=window.transient)
    check_map(case, settings)
    return settings


@single_threaded_blas()
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
    samples: int | None = None,
    sigma: float | None = None,
    parameters: Mapping[str, Any] | None = None,
    correlation: Mapping[str, Any] | None = None,
    seed: int = DEFAULT_SEED,
    units: str | None = None,
    model: Mapping[str, float] | None = None,
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
    ``map.json`` (the summary), ``map.png``, ``stability.png`` (per-family growth rates) and ``report.html``
    (figures and report in the unit system ``units``,
    ``"si"`` or ``"field"``; None: ``$DRILLSTRING_UNITS``, else si). Checked before anything runs: the grid
    (every weight-on-bit below the string's weight), ``out``, the scheduler and the lock.
    Scripts that use several local processes must call this under ``if __name__ == "__main__":``.

    With ``samples`` (>= 2) the map is probabilistic (:mod:`drillstring.stochastic.probabilistic_map`):
    ``samples`` realizations per point of the declared uncertainty — the weight-on-hook Normal around each
    point's hook load of standard deviation ``sigma`` [N], and ``parameters`` (path -> law) with
    ``correlation``, else the case's ``[uncertainty]`` table; nothing declared: ``sigma`` =
    :data:`~drillstring.stochastic.DEFAULT_SIGMA` —, drawn from the streams ``(seed, sample)``; per point the
    probabilities of stick-slip, buckling, wall impact and unstable steady drilling and quantiles of the ROP and
    of the stick-slip index; files ``map.nc``, ``map.json``, ``probabilities.png``, ``quantiles.png``,
    ``report.html`` and ``interactive.html``. ``model``: random reduced matrices (``{"stiffness_dispersion":
    δ_K, ...}``, :mod:`~drillstring.stochastic.random_matrices`; default the case's ``[uncertainty.model]``),
    sample ``j`` drawing them from ``model_generator(seed, j)`` at every point. Without ``samples``, ``sigma``,
    ``parameters``, ``correlation``, ``model`` and ``seed`` are unused (giving one of the first four is
    refused) and the map is deterministic.
    """
    from drillstring.stochastic.operating_map import run_map

    units = unit_system(units, "units")  # a bad unit system is refused before anything runs
    case = as_case(case)
    settings = map_settings(case, top_speed=top_speed, weight_on_bit=weight_on_bit, t_end=t_end,
                            output_step=output_step, transient=transient)
    engine = _engine(workers, scheduler, progress, note, worker_timeout)
    if samples is not None:
        return _sampled_map(case, settings, engine, out, samples=samples, sigma=sigma, parameters=parameters,
                            correlation=correlation, model=model, seed=seed, units=units)
    if sigma is not None or parameters is not None or correlation is not None or model is not None:
        raise ValueError("sigma, parameters, correlation and model declare the uncertainty of a probabilistic map: "
                         "give samples (realizations per point) too")
    case = case.model_copy(update={"uncertainty": None})
    folder = _output_folder(out, "drillstring-map-")
    run = run_map(case, settings, folder / "map.zarr", engine,
                  finish=partial(_finish_map, case, folder if out is not None else None, units))
    return MapOutcome(*run.result, run.already, run.note)


def _finish_map(case, folder, units, run):
    """Under the map's lock: its Dataset, summary and (in ``folder``, unless None) files."""
    from drillstring.interactive import map_figures
    from drillstring.plots import plot_map, plot_map_stability
    from drillstring.report import write_map_report
    from drillstring.stochastic.operating_map import map_dataset, map_summary

    figures = {"figure": ("map.png", partial(plot_map, units=units),
                          "Mean ROP, bit-speed oscillation, mechanical specific energy and largest radial displacement "
                          "over the map; black line: linear stability boundary of steady drilling (hatched: unstable); "
                          "red dashed: lateral buckling limit; dots: simulated points; open orange circles: "
                          "stick-slip although steady drilling is linearly stable (coexisting cycles)"),
               "stability": ("stability.png", partial(plot_map_stability, units=units),
                             "Growth rate of the leading torsional, axial and lateral root of steady drilling over "
                             "the map (blue decays, red grows; black: the family's boundary): the torsional and axial "
                             "windows are not hidden by a buckled string's lateral root")}
    return _map_files(case, folder, run, map_dataset, map_summary, "points", figures,
                      partial(write_map_report, units=units),
                      f"Operating map: case '{case.name}'", partial(map_figures, units=units))


def _map_files(case, folder, run, dataset, summarize, noun: str, figures: dict, report, title: str, interactive):
    """A map's Dataset (``dataset(store)``), summary (``summarize(ds)`` with the run's record) and, in ``folder``
    unless None, ``map.nc``, ``map.json``, the ``figures`` (key -> (file name, plot function, caption)) and
    the ``report`` (``report(path, title=..., case_toml=..., summary=..., figures=..., run_info=...,
    interactive=...)``) with its ``interactive(ds)`` figures beside it."""
    from drillstring.files import strict_json, write_text_atomic
    from drillstring.report import INTERACTIVE_PAGE
    from drillstring.results import write_netcdf

    store_path = run.store.path
    ds = dataset(store_path)
    summary = {"case": case.name, **summarize(ds), **_run_record(run.store, run, noun)}
    files: dict[str, Path] = {}
    if folder is not None:
        files = {"store": store_path, "map": folder / "map.nc", "summary": folder / "map.json",
                 **{key: folder / name for key, (name, _, _) in figures.items()}, "report": folder / "report.html",
                 "interactive": folder / INTERACTIVE_PAGE}
        write_netcdf(ds, files["map"])
        for key, (_, plot, _) in figures.items():
            plot(ds, files[key])
        summary["files"] = {k: str(v) for k, v in files.items()}
        write_text_atomic(files["summary"], strict_json(summary) + "\n")  # undefined values: null
        report(files["report"], title=title, case_toml=case.to_toml(), summary=summary,
               figures={caption: files[key] for key, (_, _, caption) in figures.items()},
               run_info={**_run_table(summary, noun), "store": str(store_path)}, interactive=interactive(ds))
    return ds, summary, files


def _point_uncertainty(case, parameters, correlation, model, sigma):
    """What the realizations at each point of a map or a search draw: ``(sigma, laws, correlated, correlation
    matrix, model dispersions)`` for the settings of :mod:`drillstring.stochastic.probabilistic_map` and
    :mod:`drillstring.stochastic.optimize`; the weight-on-hook's default σ when no parameter is declared."""
    from drillstring.stochastic import DEFAULT_SIGMA
    from drillstring.stochastic.random_matrices import ModelDispersion
    from drillstring.stochastic.uncertainty import declared_uncertainty

    dispersions = ModelDispersion.declared(case, model)
    declared = declared_uncertainty(case, parameters, correlation, tolerance=1.0)
    if declared is None and sigma is None:
        sigma = DEFAULT_SIGMA
    laws, correlated, matrix = (), (), ()
    if declared is not None:
        laws = tuple((p.path, p.law.to_spec()) for p in declared.parameters)
        if declared.correlation is not None:
            correlated, matrix = declared.correlated, tuple(map(tuple, declared.correlation.tolist()))
    return sigma, laws, correlated, matrix, dispersions


def _sampled_map(case, grid, engine, out, *, samples, sigma, parameters, correlation, model, seed,
                 units) -> MapOutcome:
    """A probabilistic map (:func:`operating_map` with ``samples``), its figures and report in ``units``."""
    from drillstring.stochastic.probabilistic_map import SampledMapSettings, run_sampled_map

    _mapping("parameters", parameters)
    _mapping("correlation", correlation)
    _mapping("model", model)
    sigma, laws, correlated, matrix, dispersions = _point_uncertainty(case, parameters, correlation, model, sigma)
    settings = SampledMapSettings(grid, samples=samples, seed=seed, sigma=sigma, laws=laws, correlated=correlated,
                                  correlation=matrix, model_dispersion=dispersions.as_tuple())
    case = case.model_copy(update={"uncertainty": None})
    folder = _output_folder(out, "drillstring-map-")
    run = run_sampled_map(case, settings, folder / "map.zarr", engine,
                          finish=partial(_finish_sampled_map, case, folder if out is not None else None, units))
    return MapOutcome(*run.result, run.already, run.note)


def _finish_sampled_map(case, folder, units, run):
    """Under the map's lock: the probabilistic map's Dataset, summary and (in ``folder``, unless None) files, in
    the unit system ``units``."""
    from drillstring.interactive import probability_map_figures
    from drillstring.plots import plot_probability_map, plot_quantile_map
    from drillstring.report import write_probability_map_report
    from drillstring.stochastic.probabilistic_map import sampled_map_dataset, sampled_map_summary

    figures = {"figure": ("probabilities.png", partial(plot_probability_map, units=units),
                          "Probabilities of stick-slip, of a buckled string, of wall impact, of unstable steady "
                          "drilling (any root, a torsional root, an axial root), of stick-slip although steady "
                          "drilling is linearly stable (coexisting cycles) and of bit bounce over the map, each from "
                          "the point's realizations; red dashed: the nominal lateral buckling limit; dots: the points"),
               "quantiles": ("quantiles.png", partial(plot_quantile_map, units=units),
                             "2.5, 50 and 97.5 % quantiles of the mean ROP and of the stick-slip index over each "
                             "point's realizations")}
    return _map_files(case, folder, run, sampled_map_dataset, sampled_map_summary, "realizations", figures,
                      partial(write_probability_map_report, units=units),
                      f"Probabilistic operating map: case '{case.name}'", partial(probability_map_figures, units=units))


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


@single_threaded_blas()
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
    from drillstring.checks import integer, real_number
    from drillstring.checks import seed as check_seed
    from drillstring.stochastic.sensitivity_study import SensitivitySettings, run_sensitivity
    from drillstring.stochastic.uncertainty import declared_uncertainty

    units = unit_system(units, "units")  # a bad unit system is refused before anything runs
    case = as_case(case)
    _mapping("parameters", parameters)
    confidence = real_number("confidence", confidence, low=0.0, high=1.0, low_open=True, high_open=True,
                             allowed="a number in (0, 1), e.g. 0.95")
    resamples = integer("resamples", resamples, low=1, high=MAX_RESAMPLES)
    window = _window(case, t_end, output_step, transient)
    if parameters is None and case.uncertainty is not None and case.uncertainty.model is not None \
            and any(case.uncertainty.model.model_dump().values()):
        raise ValueError("[uncertainty.model] of the case: Sobol' sensitivity runs do not draw random reduced "
                         "matrices (a random matrix is no point of the unit hypercube); give the parameters "
                         "(--param PATH=LAW), or run a study or a probabilistic map for the model uncertainty")
    declared = declared_uncertainty(case, parameters)
    if declared is None:
        raise ValueError("no uncertain parameter: give parameters (path -> law), e.g. --param "
                         "operation.top_speed=\"uniform 60 140 rpm\", or an [uncertainty] table in the case")
    if declared.correlation is not None:
        raise ValueError(f"Sobol' indices need independent parameters; {', '.join(declared.correlated)} are "
                         "correlated (drop the correlation, or use a Monte Carlo study for the joint law)")
    case = case.model_copy(update={"uncertainty": None})
    settings = SensitivitySettings(
        base_samples=samples, laws=tuple((p.path, p.law.to_spec()) for p in declared.parameters),
        seed=check_seed(seed), t_end=window.t_end, output_step=window.output_step, transient=window.transient)
    engine = _engine(workers, scheduler, progress, note, worker_timeout)
    folder = _output_folder(out, "drillstring-sensitivity-")
    run = run_sensitivity(case, settings, folder / "sensitivity.zarr", engine,
                          finish=partial(_finish_sensitivity, case, settings, confidence, resamples,
                                         folder if out is not None else None, units))
    return SensitivityOutcome(*run.result, run.already, run.note)


def _finish_sensitivity(case, settings, confidence, resamples, folder, units, run):
    """Under the sensitivity run's lock: its Sobol' indices, payload and (in ``folder``, unless None) files."""
    import json

    from drillstring.files import write_text_atomic
    from drillstring.interactive import sensitivity_figures
    from drillstring.plots import plot_sobol, plot_sobol_convergence
    from drillstring.report import INTERACTIVE_PAGE, write_sensitivity_report
    from drillstring.stochastic.sensitivity_study import SENSITIVITY_OUTPUTS, load_sensitivity

    store_path = run.store.path
    data = load_sensitivity(store_path)
    result = data.indices(SENSITIVITY_OUTPUTS, confidence=confidence, resamples=resamples)
    record = _run_record(run.store, run, "runs")
    payload = {"case": case.name, **result.to_dict(), "t_end": settings.t_end,
               "t_transient": settings.transient, "failed_runs": run.failed,
               "run_wall_time_total": float(np.nansum(data.wall_time)), **record}
    files: dict[str, Path] = {}
    if folder is not None:
        files = {"store": store_path, "indices": folder / "sensitivity.json",
                 "figure": folder / "sobol.png", "convergence": folder / "sobol_convergence.png",
                 "report": folder / "report.html", "interactive": folder / INTERACTIVE_PAGE}
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
            interactive=sensitivity_figures(payload), units=units)
    return result, payload, files
