"""Operating maps over top speed × weight-on-bit (deterministic or probabilistic) and global sensitivity
(Sobol' indices), with their files."""

from __future__ import annotations

from dataclasses import dataclass
from functools import partial
from pathlib import Path
from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np

from drillstring.api.arguments import as_case, output_folder, point_uncertainty, run_record, run_table
from drillstring.api.settings import ALL_FIELDS, RandomInputs, RunOptions, SimulationWindow, gathered
from drillstring.blas_threads import single_threaded_blas
from drillstring.case import Case
from drillstring.stochastic import DEFAULT_BASE_SAMPLES, DEFAULT_SEED
from drillstring.units import unit_system

if TYPE_CHECKING:  # the simulating modules load with the functions that use them (light static, modes)
    import xarray as xr


#: The fields of :class:`~drillstring.api.settings.RandomInputs` a map draws from (its weight-on-hook's σ is about
#: each point's own hook load: no ``dispersion``).
MAP_INPUTS = ("parameters", "correlation", "sigma", "model")

#: Largest number of bootstrap resamples of a sensitivity run's confidence intervals.
MAX_RESAMPLES = 100_000


@dataclass
class MapOutcome:
    """What :func:`operating_map` did: the map Dataset, its JSON-ready summary (as in ``map.json``), the
    files written (name -> path) and the points that were in the store before this call."""

    dataset: xr.Dataset
    summary: dict
    files: dict[str, Path]
    already: int
    note: str | None = None


def map_settings(case: Case, *, top_speed=None, weight_on_bit=None, window: SimulationWindow | None = None,
                 default_units: tuple[str, str] = ("", ""), **keywords):
    """The validated :class:`~drillstring.stochastic.operating_map.MapSettings` of a map of ``case``: axes
    as sequences of SI numbers or grid strings (``"40 rpm:200 rpm:17"``, ``"100,120 kN"``; bare numbers in
    ``default_units`` or SI), default :data:`~drillstring.stochastic.DEFAULT_MAP_TOP_SPEED` ×
    :data:`~drillstring.stochastic.DEFAULT_MAP_WEIGHT_ON_BIT`; the run window ``window`` (a
    :class:`~drillstring.api.settings.SimulationWindow`, or its fields as keywords)."""
    from drillstring.case import DIMENSIONS
    from drillstring.stochastic import DEFAULT_MAP_TOP_SPEED, DEFAULT_MAP_WEIGHT_ON_BIT
    from drillstring.stochastic.operating_map import MapSettings, check_map, parse_axis

    dimension = {d.name: d for d in DIMENSIONS}
    speeds = parse_axis(DEFAULT_MAP_TOP_SPEED if top_speed is None else top_speed, dimension["angular speed"],
                        name="top_speed", default_unit=default_units[0])
    weights = parse_axis(DEFAULT_MAP_WEIGHT_ON_BIT if weight_on_bit is None else weight_on_bit, dimension["force"],
                         name="weight_on_bit", default_unit=default_units[1])
    (window,) = gathered("map_settings", keywords, {"window": window}, ALL_FIELDS)
    window = window.on(case)
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
    samples: int | None = None,
    seed: int = DEFAULT_SEED,
    inputs: RandomInputs | None = None,
    window: SimulationWindow | None = None,
    run: RunOptions | None = None,
    **keywords,
) -> MapOutcome:
    """Operating map of ``case`` over top speed × weight-on-bit (:mod:`drillstring.stochastic.operating_map`):
    one simulation of ``t_end`` [s] per grid point, summarised after ``transient`` [s] (default
    ``min(10 s, t_end/2)``) by mean ROP, bit-speed oscillation, stick time, mean TOB and FOB, mechanical
    specific energy, largest radial displacement and impacts, with the linear stability of steady drilling
    (leading growth rate) and the buckling margin at each point.

    The settings come as objects (:mod:`drillstring.api.settings`): ``window`` (``t_end``, ``output_step``,
    ``transient``), ``run`` (``out``, ``workers``, ``scheduler``, ``progress``, ``note``, ``worker_timeout``,
    ``units``) and ``inputs`` (``sigma``, ``parameters``, ``correlation``, ``model``); or, as before, each field as a
    keyword of its own (refused when its object is given too).

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

    inputs, window, run = gathered("operating_map", keywords, {"inputs": inputs, "window": window, "run": run},
                                   {**ALL_FIELDS, "inputs": MAP_INPUTS})
    units = unit_system(run.units, "units")  # a bad unit system is refused before anything runs
    case = as_case(case)
    settings = map_settings(case, top_speed=top_speed, weight_on_bit=weight_on_bit, window=window)
    engine = run.engine()
    if samples is not None:
        from drillstring.stochastic.probabilistic_map import run_sampled_map

        sampled = sampled_map_settings(case, settings, samples=samples, inputs=inputs, seed=seed)
        return _run_map(run_sampled_map, _finish_sampled_map, case, sampled, engine, run.out, units)
    if inputs.declared():
        raise ValueError("sigma, parameters, correlation and model declare the uncertainty of a probabilistic map: "
                         "give samples (realizations per point) too")
    return _run_map(run_map, _finish_map, case, settings, engine, run.out, units)


def _run_map(runner, finish, case, settings, engine, out, units) -> MapOutcome:
    """Run a map of ``case`` (its ``[uncertainty]`` table dropped: the laws are in ``settings``) with ``runner``
    (:func:`~drillstring.stochastic.operating_map.run_map` or :func:`~drillstring.stochastic.probabilistic_map.
    run_sampled_map`) into ``out``/map.zarr (``out`` None: a temporary folder, and no files but the store), then
    ``finish(case, folder, units, run)`` under its lock."""
    case = case.model_copy(update={"uncertainty": None})
    folder = output_folder(out, "drillstring-map-")
    run = runner(case, settings, folder / "map.zarr", engine,
                 finish=partial(finish, case, folder if out is not None else None, units))
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
    return _map_files(case, folder, run, _MapKind(
        map_dataset, map_summary, "points", figures, partial(write_map_report, units=units),
        f"Operating map: case '{case.name}'", partial(map_figures, units=units)))


@dataclass(frozen=True)
class _MapKind:
    """What a kind of map writes: its Dataset (``dataset(store)``), summary (``summarize(ds)``), the ``noun`` of
    its runs, the ``figures`` (key -> (file name, plot function, caption)), the ``report`` (``report(path,
    title=..., case_toml=..., summary=..., figures=..., run_info=..., interactive=...)``) with its ``title``, and
    its ``interactive(ds)`` figures."""

    dataset: Callable
    summarize: Callable
    noun: str
    figures: dict
    report: Callable
    title: str
    interactive: Callable


def _map_files(case, folder, run, kind: _MapKind):
    """A map's Dataset, summary (with the run's record) and, in ``folder`` unless None, ``map.nc``, ``map.json``,
    the figures and the report with its interactive figures beside it (what ``kind`` says)."""
    from drillstring.files import strict_json, write_text_atomic
    from drillstring.report import INTERACTIVE_PAGE
    from drillstring.results import write_netcdf

    dataset, summarize, noun, figures = kind.dataset, kind.summarize, kind.noun, kind.figures
    report, title, interactive = kind.report, kind.title, kind.interactive

    store_path = run.store.path
    ds = dataset(store_path)
    summary = {"case": case.name, **summarize(ds), **run_record(run.store, run, noun)}
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
               run_info={**run_table(summary, noun), "store": str(store_path)}, interactive=interactive(ds))
    return ds, summary, files


def sampled_map_settings(case, grid, *, samples, inputs: RandomInputs, seed):
    """The settings of a probabilistic map of ``case`` on ``grid`` (:func:`operating_map` with ``samples``; the
    uncertainty of ``inputs`` by :func:`~drillstring.api.arguments.point_uncertainty`)."""
    from drillstring.stochastic.probabilistic_map import SampledMapSettings

    sigma, uncertainty = point_uncertainty(case, inputs)
    return SampledMapSettings(grid, samples=samples, seed=seed, sigma=sigma, uncertainty=uncertainty)


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
    return _map_files(case, folder, run, _MapKind(
        sampled_map_dataset, sampled_map_summary, "realizations", figures,
        partial(write_probability_map_report, units=units), f"Probabilistic operating map: case '{case.name}'",
        partial(probability_map_figures, units=units)))


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
    samples: int = DEFAULT_BASE_SAMPLES,
    seed: int = 0,
    confidence: float = 0.95,
    resamples: int = 1000,
    inputs: RandomInputs | None = None,
    window: SimulationWindow | None = None,
    run: RunOptions | None = None,
    **keywords,
) -> SensitivityOutcome:
    """Global sensitivity of ``case``: first-order and total Sobol' indices, with bootstrap confidence
    intervals (level ``confidence``) and a convergence check at N/4, N/2, N, of the time-mean ROP,
    bit-speed oscillation, mean TOB and FOB and the standard deviations in time of ROP, TOB and FOB
    (:mod:`drillstring.stochastic.sensitivity_study`).

    The settings come as objects (:mod:`drillstring.api.settings`): ``inputs`` (only its ``parameters``),
    ``window`` and ``run``; or, as before, each field as a keyword of its own (refused when its object is given too).
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
    from drillstring.stochastic.uncertainty_settings import UncertaintySettings

    inputs, window, run = gathered("sensitivity", keywords, {"inputs": inputs, "window": window, "run": run},
                                   {**ALL_FIELDS, "inputs": ("parameters",)})
    parameters = inputs.parameters
    units = unit_system(run.units, "units")  # a bad unit system is refused before anything runs
    case = as_case(case)
    confidence = real_number("confidence", confidence, low=0.0, high=1.0, low_open=True, high_open=True,
                             allowed="a number in (0, 1), e.g. 0.95")
    resamples = integer("resamples", resamples, low=1, high=MAX_RESAMPLES)
    window = window.on(case)
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
        base_samples=samples, uncertainty=UncertaintySettings.of(declared), seed=check_seed(seed),
        t_end=window.t_end, output_step=window.output_step, transient=window.transient)
    folder = output_folder(run.out, "drillstring-sensitivity-")
    done = run_sensitivity(case, settings, folder / "sensitivity.zarr", run.engine(),
                           finish=partial(_finish_sensitivity, case, settings, confidence, resamples,
                                          folder if run.out is not None else None, units))
    return SensitivityOutcome(*done.result, done.already, done.note)


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
    record = run_record(run.store, run, "runs")
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
            run_info={**run_table(record, "runs"), "runs": result.runs,
                      "simulated time per run [s]": settings.t_end,
                      "outputs over": f"t ≥ {settings.transient:g} s", "store": str(store_path)},
            interactive=sensitivity_figures(payload), units=units)
    return result, payload, files
