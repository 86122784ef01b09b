"""Monte Carlo studies of random case parameters (docs/model.md §11) with their files: statistics, summary,
figures and report."""

from __future__ import annotations

from dataclasses import dataclass
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from drillstring.api.arguments import as_case, case_window, keywords_of, output_folder
from drillstring.api.settings import ALL_FIELDS, RandomInputs, RunOptions, SimulationWindow, gathered
from drillstring.api.runs import stability_boundary
from drillstring.blas_threads import single_threaded_blas
from drillstring.case import Case
from drillstring.stochastic import DEFAULT_SAMPLES, DEFAULT_SEED
from drillstring.units import display_unit, unit_system

if TYPE_CHECKING:  # the simulating modules load with the functions that use them (light static, modes)
    import xarray as xr


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


def study_settings(case: Case, *, inputs: RandomInputs | None = None, samples: int = DEFAULT_SAMPLES,
                   seed: int = DEFAULT_SEED, window: SimulationWindow | None = None, **keywords):
    """The validated settings of a Monte Carlo study of ``case`` (TypeError / ValueError naming the field or
    the parameter otherwise), and the case without its ``[uncertainty]`` table (the laws are in the settings).

    The random parameters (``inputs``, a :class:`~drillstring.api.settings.RandomInputs`, or its fields as
    keywords): ``parameters`` (path -> law spec or table) with ``correlation`` (``{"parameters":
    [...], "matrix": [[...]]}``) when given, else the case's ``[uncertainty]`` table; plus the weight-on-hook,
    Normal of standard deviation ``sigma`` [N] or ``dispersion`` × its mean, when either is given (a
    shorthand for the law ``weight_on_hook = "normal mean=<hook load> std=<sigma>"``, declared first). With
    none of these, the default: the weight-on-hook Normal of σ = :data:`~drillstring.stochastic.DEFAULT_SIGMA`.
    ``model``: the model uncertainty, ``{"mass_dispersion": δ_M, "stiffness_dispersion": δ_K,
    "damping_dispersion": δ_D}`` (:mod:`~drillstring.stochastic.random_matrices`), else the case's
    ``[uncertainty.model]`` table, else none. ``window``: the run's ``t_end`` and ``output_step`` [s] (its
    ``transient`` is the summaries', not the settings').
    """
    from drillstring.stochastic import DEFAULT_SIGMA
    from drillstring.stochastic.montecarlo import (
        StudySettings,
        check_study,
        nominal_weight_on_hook,
        weight_on_hook_normal,
    )
    from drillstring.stochastic.random_matrices import ModelDispersion
    from drillstring.stochastic.uncertainty import declared_uncertainty
    from drillstring.stochastic.uncertainty_settings import UncertaintySettings

    inputs, window = gathered("study_settings", keywords, {"inputs": inputs, "window": window},
                              {**ALL_FIELDS, "window": ("t_end", "output_step")})
    sigma = inputs.sigma
    if inputs.dispersion is not None:
        sigma = inputs.dispersion * nominal_weight_on_hook(case)
    dispersions = ModelDispersion.declared(case, inputs.model)
    first = dict([weight_on_hook_normal(case, sigma)]) if sigma is not None else None
    declared = declared_uncertainty(case, inputs.parameters, inputs.correlation, first=first, tolerance=1.0)
    if declared is None:
        first = dict([weight_on_hook_normal(case, DEFAULT_SIGMA)])
        declared = declared_uncertainty(case, None, None, first=first, tolerance=1.0)
    window = case_window(case, window.t_end, window.output_step)
    bare = case.model_copy(update={"uncertainty": None})
    settings = StudySettings(samples=samples, seed=seed, t_end=window.t_end, output_step=window.output_step,
                             uncertainty=UncertaintySettings.of(declared, dispersions))
    check_study(bare, settings)
    return settings, bare


@single_threaded_blas()
def monte_carlo_study(
    case: Case | str | Path = "reference",
    *,
    inputs: RandomInputs | None = None,
    samples: int = DEFAULT_SAMPLES,
    seed: int = DEFAULT_SEED,
    window: SimulationWindow | None = None,
    run: RunOptions | None = None,
    **keywords,
) -> StudyOutcome:
    """Monte Carlo study of random case parameters (docs/model.md §11; by default a random weight-on-hook), with
    its files.

    The settings come as objects (:mod:`drillstring.api.settings`): ``inputs``
    (:class:`~drillstring.api.settings.RandomInputs`), ``window``
    (:class:`~drillstring.api.settings.SimulationWindow`), ``run`` (:class:`~drillstring.api.settings.RunOptions`);
    or, as before, each of their fields as a keyword of its own (``sigma=..., t_end=..., workers=...``): a keyword
    none of them has, or a field given both ways, is refused (TypeError).

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

    inputs, window, run = gathered("monte_carlo_study", keywords, {"inputs": inputs, "window": window, "run": run},
                                   ALL_FIELDS)
    out, note, units = run.out, run.note, unit_system(run.units, "units")  # a bad unit system: refused now
    settings, case = study_settings(as_case(case), inputs=inputs, samples=samples, seed=seed,
                                    t_end=window.t_end, output_step=window.output_step)
    t_transient = case_window(case, settings.t_end, settings.output_step, window.transient).transient
    engine = run.engine()
    folder = output_folder(out, "drillstring-study-")
    buckling = study_buckling_margin(case, settings)
    if note is not None and buckling["warning"] and buckling["expected"] >= 1.0:
        # a result, not a misuse: said before the run only when a buckled realization is expected, and only
        # to a caller that takes notes (the summary counts them in any case)
        note(buckling_note(buckling, settings.samples, units))
    buckling = {k: v for k, v in buckling.items() if k not in ("lateral", "source")}
    finish = partial(_finish_study, case, settings, t_transient, buckling, folder if out is not None else None,
                     units, run.stage or (lambda text: None))
    done = run_study(case, settings, folder / "study.zarr", engine, finish=finish)
    return StudyOutcome(*done.result, done.already, done.note)


def _finish_study(case, settings, t_transient, buckling, folder, units, stage, run):
    """Under the study's lock: its statistics, summary and (in ``folder``, unless None) files; ``stage(text)``
    is told each step."""
    from drillstring.outputs.beside import ProcessBeside

    # the figures' process, its imports starting now: only where this run already spawned local worker processes
    # (a script then runs under ``if __name__ == "__main__":``, which a spawned process needs)
    beside_ok = folder is not None and isinstance(run.workers, int) and run.workers > 1
    with ProcessBeside(enabled=beside_ok) as beside:
        return _finish_study_beside(case, settings, t_transient, buckling, folder, units, stage, run, beside)


def _finish_study_beside(case, settings, t_transient, buckling, folder, units, stage, run, beside):
    """:func:`_finish_study` with the figures drawn by ``beside`` (:class:`~drillstring.outputs.beside.
    ProcessBeside`) while the stability boundary and the other files are computed and written here."""
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
    sessions = run.store.sessions()
    figures = None
    if folder is not None:
        figures = _study_figures(settings, stats, sessions, folder, t_transient, units, stage, beside)
    summary = study_summary(stats, t_transient=t_transient, boundary=_stability_boundary(case))
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
        files = _write_study_files(case, settings, stats, summary, payload, folder, t_transient, raw, units, stage,
                                   figures)
    return stats, payload, files


def _study_figures(settings, stats, sessions, folder: Path, t_transient, units, stage, beside):
    """A callable giving the study's figures (name -> path): those in ``folder`` if they were drawn from the same
    realizations, settings, window, units and plotting code (:func:`~drillstring.stochastic.analysis.figures_key`),
    else drawn by ``beside`` (:class:`~drillstring.outputs.beside.ProcessBeside`) and recorded when asked for."""
    from drillstring.stochastic.analysis import current_figures, figures_key, record_figures, time_convergence

    key = figures_key({"n_samples": int(stats.attrs["n_samples"]), "n_failed": int(stats.attrs["n_failed"]),
                       "sessions": sessions}, settings, t_transient, units)
    found = current_figures(folder, key)
    if found is not None:
        return lambda: found
    from drillstring.outputs.study_plots import plot_study

    stage("figures")
    drawn = beside.submit(plot_study, stats, folder, t_transient, time_convergence(stats, t_transient), units=units)

    def figures() -> dict[str, Path]:
        result = drawn()
        record_figures(folder, key, result)
        return result

    return figures


def _stability_boundary(case: Case) -> dict | None:
    """:func:`stability_boundary`, None where steady drilling does not exist."""
    try:
        return stability_boundary(case)
    except ValueError:
        return None


def _write_study_files(case, settings, stats, summary, payload, folder: Path, t_transient, raw, units: str | None,
                       stage, figures) -> dict[str, Path]:
    """statistics.nc, summary.json (``payload`` gets ``files``), report.html (the statistics' ``summary``, the
    figures given by the callable ``figures`` (:func:`_study_figures`) and the run information from ``payload``)
    and interactive.html (with the first finished realizations of ``raw``, the study's raw Dataset); report in the
    unit system ``units``."""

    from drillstring.files import strict_json, write_text_atomic
    from drillstring.interactive import REALIZATIONS_SHOWN, study_figures
    from drillstring.quantities import stored_observables
    from drillstring.report import INTERACTIVE_PAGE, write_report
    from drillstring.results import write_netcdf
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
    interactive = study_figures(stats, shown, units=units)
    figures = figures()  # waits for the drawing
    stage("report")
    payload["files"] = {**{k: str(v) for k, v in paths.items()}, **{k: str(v) for k, v in figures.items()}}
    write_text_atomic(paths["summary"], strict_json(payload) + "\n")  # undefined values: null, never NaN
    run_info = {
        "realizations requested": settings.samples,
        "failures": payload["failures"],
        "computation wall time [s]": round(payload["wall_time"], 2),
        "buckled realizations (lowest lateral ω² < 0)": (
            f"{payload['buckling']['buckled_realizations']} of {payload['n_samples']}; critical weight-on-bit "
            f"{force(payload['buckling']['critical_weight_on_bit']):.5g} {force.label}"
            + (f" ({payload['buckling']['criterion']})" if "criterion" in payload["buckling"] else "")
            + f", probability of a buckled draw {payload['buckling']['probability']:.3g}"),
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
        interactive=interactive,
        units=units,
    )
    return {**paths, **figures}


@single_threaded_blas()
@keywords_of(monte_carlo_study)
def study(case: Case | str | Path = "reference", **options) -> xr.Dataset:
    """Monte Carlo study of random case parameters (docs/model.md §11); returns the statistics Dataset.

    The statistics of :func:`monte_carlo_study` (its arguments, settings objects or their fields as keywords; the
    same checks and files): laws of
    ``parameters`` (or the case's ``[uncertainty]`` table), at most one of ``sigma`` [N] or
    ``dispersion`` (σ / mean) for the weight-on-hook (default, nothing declared: σ = 5000 N); the
    drawn values are in ``input_values``; realizations stream to the Zarr
    store ``out``/study.zarr (a temporary folder when None), rerunning with the same ``out`` resumes.
    ``transient`` [s]: start of the steady window for the summaries and the per-realization vibration
    indicators (default ``min(10 s, t_end/2)``).
    Scripts that use several local processes must call this under ``if __name__ == "__main__":``.
    """
    return monte_carlo_study(case, **options).statistics
