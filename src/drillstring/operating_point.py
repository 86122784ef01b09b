"""``drillstring.optimize``: the robust operating point of a case (:mod:`drillstring.stochastic.optimize`), its
results file, its figure and its store, as the notebook API and ``drillstring optimize`` see it."""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import partial
from pathlib import Path
from collections.abc import Mapping
from typing import Any

from drillstring.api.arguments import as_case, check_mapping, output_folder, point_uncertainty, run_record, run_table
from drillstring.api.settings import (ALL_FIELDS, DEFAULT_POINT_SAMPLES, RandomInputs, RunOptions, SearchOptions,
                                      SimulationWindow, gathered)
from drillstring.blas_threads import single_threaded_blas
from drillstring.case import Case
from drillstring.stochastic import DEFAULT_SEED
from drillstring.units import unit_system

__all__ = ["DEFAULT_POINT_SAMPLES", "OptimizeOutcome", "optimize", "optimization_settings", "parse_bounds"]

#: The fields of :class:`~drillstring.api.settings.RandomInputs` a search draws from at each point (as a
#: probabilistic map: no ``dispersion``).
SEARCH_INPUTS = ("parameters", "correlation", "sigma", "model")


@dataclass
class OptimizeOutcome:
    """What :func:`optimize` did: the JSON-ready ``summary`` (as in ``optimize.json``: the recommended point,
    its objective and probabilities with their errors, every design point), the ``dataset`` (realizations
    ``point × sample`` and the per-point estimates), the files written, the realizations already in the store
    before this call, a note (a stale lock taken over) or None."""

    summary: dict
    dataset: Any
    files: dict[str, Path]
    already: int
    note: str | None = None

    @property
    def feasible(self) -> bool:
        return bool(self.summary["feasible"])


def parse_bounds(case: Case, name: str, text, default_unit: str = "") -> tuple[str, float, float]:
    """``(path, low, high)`` [SI] of a decision variable ``name`` (an alias of
    :data:`~drillstring.stochastic.optimize.DECISION_ALIASES` or a case path) and its bounds: ``"A:B"`` with a
    unit after each value or once after the last (``"60 rpm:140 rpm"``, ``"80:120 kN"``; bare numbers in
    ``default_unit``, else SI) or a pair of SI numbers. ValueError (one line naming the variable) otherwise."""
    from drillstring.case import to_si
    from drillstring.stochastic.operating_map import _split_unit
    from drillstring.stochastic.optimize import decision_path
    from drillstring.stochastic.parameters import WEIGHT_ON_HOOK, ParameterError, case_parameter

    path = decision_path(str(name))
    try:
        dimension = None if path == WEIGHT_ON_HOOK else case_parameter(case, path).dimension
    except ParameterError as error:
        raise ValueError(f"decision variable {path}: the case cannot vary it ({error})") from None
    if path == WEIGHT_ON_HOOK:
        from drillstring.units import FORCE as dimension
    if isinstance(text, str):
        parts = text.split(":")
        if len(parts) != 2:
            raise ValueError(f"{path} = {text!r}: write the bounds as LOW:HIGH, e.g. '60 rpm:140 rpm' or '80:120 kN'")
        _, last_unit = _split_unit(parts[1])
        values = []
        for part in parts:
            number, unit = _split_unit(part)
            unit = unit or last_unit or default_unit
            try:
                values.append(float(to_si(f"{number} {unit}" if unit else float(number), dimension)))
            except ValueError as error:
                raise ValueError(f"{path} = {text!r}: {error}") from None
        low, high = values
    else:
        try:
            low, high = (float(v) for v in text)
        except (TypeError, ValueError):
            raise ValueError(f"{path} = {text!r}: bounds must be 'LOW:HIGH' or a pair of numbers [SI]") from None
    if not (math.isfinite(low) and math.isfinite(high)):
        raise ValueError(f"{path} = {text!r}: bounds must be finite")
    if not low < high:
        raise ValueError(f"{path} = {text!r}: bounds reversed or equal (LOW must be less than HIGH)")
    return path, low, high


def optimization_settings(case: Case, *, variables, objective="rate_of_penetration", constraints=None,
                          search: SearchOptions | None = None, seed=DEFAULT_SEED, inputs: RandomInputs | None = None,
                          window: SimulationWindow | None = None, default_units: Mapping[str, str] | None = None,
                          **keywords):
    """The validated :class:`~drillstring.stochastic.optimize.OptimizationSettings` of a search of ``case``
    (arguments as :func:`optimize`)."""
    from drillstring.stochastic.optimize import DEFAULT_BATCH, OptimizationSettings, check_optimization

    search, inputs, window = gathered("optimization_settings", keywords,
                                      {"search": search, "inputs": inputs, "window": window},
                                      {**ALL_FIELDS, "inputs": SEARCH_INPUTS})
    check_mapping("variables", variables)
    check_mapping("constraints", constraints)
    if not variables:
        raise ValueError("variables: give at least one decision variable with its bounds, e.g. "
                         "{'top_speed': '60 rpm:140 rpm'}")
    units = dict(default_units or {})
    bounded = tuple(parse_bounds(case, name, text, units.get(name, "")) for name, text in variables.items())
    sigma, uncertainty = point_uncertainty(case, inputs)
    window = window.on(case)
    initial = max(4, 4 * len(bounded)) if search.initial is None else search.initial
    points = 2 * initial if search.points is None else search.points
    settings = OptimizationSettings(
        variables=bounded, objective=objective, constraints=tuple((constraints or {}).items()),
        samples=search.samples, points=points, initial=initial,
        batch=DEFAULT_BATCH if search.batch is None else search.batch, seed=seed, t_end=window.t_end,
        output_step=window.output_step, transient=window.transient, sigma=sigma, uncertainty=uncertainty,
        probability_mean=search.probability_mean)
    check_optimization(case.model_copy(update={"uncertainty": None}), settings)
    return settings


@single_threaded_blas()
def optimize(
    case: Case | str | Path = "reference",
    *,
    variables: Mapping[str, Any],
    objective: str = "rate_of_penetration",
    constraints: Mapping[str, float] | None = None,
    search: SearchOptions | None = None,
    seed: int = DEFAULT_SEED,
    inputs: RandomInputs | None = None,
    window: SimulationWindow | None = None,
    run: RunOptions | None = None,
    default_units: Mapping[str, str] | None = None,
    **keywords,
) -> OptimizeOutcome:
    """The robust operating point of ``case`` (:mod:`drillstring.stochastic.optimize`).

    The settings come as objects (:mod:`drillstring.api.settings`): ``search``
    (:class:`~drillstring.api.settings.SearchOptions`: ``samples``, ``points``, ``initial``, ``batch``,
    ``probability_mean``), ``inputs`` (``sigma``, ``parameters``, ``correlation``, ``model``), ``window``
    (``t_end``, ``output_step``, ``transient``) and ``run`` (``out``, ``workers``, ``scheduler``, ``progress``,
    ``note``, ``worker_timeout``, ``units``); or, as before, each field as a keyword of its own (refused when its
    object is given too).

    ``variables``: decision variable -> bounds, ``{"top_speed": "60 rpm:140 rpm", "weight_on_bit": "80 kN:120
    kN"}`` (aliases ``top_speed``, ``weight_on_bit``, ``weight_on_hook``, ``proportional_gain``,
    ``integral_gain``, or any case path; bounds ``"LOW:HIGH"`` with units, or a pair of SI numbers).
    ``objective``: ``rate_of_penetration`` (expected, maximised), ``rate_of_penetration_qNN`` (its NN % quantile,
    maximised) or ``mechanical_specific_energy`` (expected, minimised). ``constraints``: event -> bound,
    ``P(event) ≤ bound`` (``{"stick_slip": 0.05, "buckling": 0.01, "surface_torque_amplitude>8000": 0.01}``).
    ``samples`` realizations per design point, ``points`` design points in all (default twice ``initial``,
    itself 4 per variable, at least 4); after the initial design, ``batch`` points (default
    :data:`~drillstring.stochastic.optimize.DEFAULT_BATCH`) are chosen together and their realizations run in
    one pass of the engine; ``probability_mean`` is the prior mean of the constraints' surrogates,
    ``"constant"`` or ``"linear"`` (a fitted plane, where the processes return far from the data). The
    uncertainty at each point is a probabilistic map's
    (:func:`~drillstring.api.operating_map` with ``samples``: ``sigma``, ``parameters``, ``correlation``,
    ``model``, ``seed``; nothing declared: the weight-on-hook with σ = 5 kN). Runs of ``t_end`` [s] (default the
    case's), outputs after ``transient``.

    Writes ``out``/optimize.zarr (resumable), optimize.json (the summary), optimize.nc (the realizations and
    per-point estimates), optimize.png (the feasible region over the first two variables, the answer
    marked; axes in the unit system ``units``) and report.html (the search, the answer, every design point).
    Infeasible constraints are not an exception: the outcome's
    ``feasible`` is False and its recommended point is the least-infeasible one.
    """
    from drillstring.stochastic.optimize import run_optimization

    search, inputs, window, run = gathered(
        "optimize", keywords, {"search": search, "inputs": inputs, "window": window, "run": run},
        {**ALL_FIELDS, "inputs": SEARCH_INPUTS})
    units = unit_system(run.units, "units")
    case = as_case(case)
    settings = optimization_settings(case, variables=variables, objective=objective, constraints=constraints,
                                     search=search, seed=seed, inputs=inputs, window=window,
                                     default_units=default_units)
    engine = run.engine()
    case = case.model_copy(update={"uncertainty": None})
    folder = output_folder(run.out, "drillstring-optimize-")
    done = run_optimization(case, settings, folder / "optimize.zarr", engine,
                            finish=partial(_finish, case, settings, folder if run.out is not None else None, units))
    summary, dataset, files = done.result
    return OptimizeOutcome(summary, dataset, files, done.already, done.note)


def _finish(case, settings, folder, units, run):
    """Under the store's lock: the summary, the dataset and (in ``folder`` unless None) the files."""
    from drillstring.files import strict_json, write_text_atomic
    from drillstring.outputs.optimize_plots import decision_unit, objective_unit, plot_optimization
    from drillstring.report import write_optimization_report
    from drillstring.results import write_netcdf
    from drillstring.stochastic.optimize import optimization_result

    result = optimization_result(run.store)
    summary = {"case": case.name, **{k: v for k, v in result.items() if k not in ("surrogates", "problem")},
               **run_record(run.store, run, "realizations")}
    dataset = _dataset(run.store, settings, result)
    files: dict[str, Path] = {}
    if folder is not None:
        files = {"store": run.store.path, "summary": folder / "optimize.json", "results": folder / "optimize.nc",
                 "figure": folder / "optimize.png", "report": folder / "report.html"}
        write_netcdf(dataset, files["results"])
        plot_optimization(case, result, files["figure"], units=units)
        summary["files"] = {k: str(v) for k, v in files.items()}
        write_text_atomic(files["summary"], strict_json(summary) + "\n")
        write_optimization_report(
            files["report"], title=f"Robust operating point: case '{case.name}'", case_toml=case.to_toml(),
            summary=summary, units=units, variable_units=[decision_unit(case, v, units) for v in summary["variables"]],
            objective_unit=objective_unit(summary["objective"], units)[0],
            figures={"The surrogate's objective over the decision variables, each chance constraint's boundary, "
                     "the region where one fails hatched, the design points and the answer": files["figure"]},
            run_info={**run_table(summary, "realizations"), "store": str(run.store.path)})
    return summary, dataset, files


def _dataset(store, settings, result):
    """Realizations (``point × sample``) of every stored output, design values and per-point estimates."""
    import numpy as np
    import xarray as xr

    s, n = settings.samples, settings.points
    data = {}
    for name in store.group:
        array = np.asarray(store.group[name][...])
        if array.ndim == 1 and array.size == n * s:
            data[name] = (("point", "sample"), array.reshape(n, s), dict(store.group[name].attrs))
    data["design_values"] = (("point", "variable"), np.asarray(result["design"], dtype=float))
    data["objective_estimate"] = (("point",), np.asarray(result["estimates"]["objective"], dtype=float),
                                  {"long_name": f"Monte Carlo estimate of the objective {settings.objective} [SI]"})
    data["probability_estimates"] = (("point", "constraint"),
                                     np.asarray(result["estimates"]["probabilities"], dtype=float).reshape(n, -1))
    data["samples_done"] = (("point",), np.asarray(result["estimates"]["count"]))
    ds = xr.Dataset(data, coords={"variable": [p for p, _, _ in settings.variables],
                                  "constraint": [e for e, _ in settings.constraints]})
    ds.attrs.update({"case": store.group.attrs["case"], "objective": settings.objective,
                     "recommended_point": int(result["recommended"]["point"]), "feasible": int(result["feasible"])})
    return ds
