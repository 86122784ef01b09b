"""From a study's Zarr store to statistics and a JSON-ready summary (docs/model.md §11)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import xarray as xr

from drillstring.dynamics.indicators import (
    CYCLE_METRICS,
    DEFAULT_TRANSIENT,
    RENAMED_METRICS,
    TOP_DRIVE_METRICS,
    cycle_metrics,
    top_drive_metrics,
    transient_end,
)
from drillstring.quantities import LONG_NAMES, UNITS
from drillstring.stochastic.montecarlo import open_study_group, stored_observables
from drillstring.stochastic.locks import StudyLock
from drillstring.stochastic.runs import FAMILY_GROWTH_METRICS, REALIZATION_METRICS
from drillstring.stochastic.store import DONE, FAILED, StoreError, damage
from drillstring.stochastic.statistics import (
    dispersion,
    dispersion_summary,
    mean_square_convergence,
    realization_statistics,
    record_start,
)


def load_study(store_path: str | Path) -> xr.Dataset:
    """The raw study: every realization (dimension ``realization``), its status and draw, the nominal
    (deterministic, mean weight-on-hook) response, and the store's attributes.

    Refused while another process runs a study on the store (:class:`~drillstring.stochastic.
    locks.StudyLocked`: statistics are never computed from a store being written), and for a
    folder that is not a complete study store, or a damaged one (a missing or unreadable chunk, named;
    :class:`~drillstring.stochastic.store.StoreError`): a damaged store is never read as data."""
    with StudyLock(store_path, shared=True):
        group = open_study_group(store_path, mode="r")
        advice = "run the same study command again to recompute the damaged realizations"
        damaged = damage(group, decode=False)  # a missing chunk would read as NaN
        if damaged:
            raise StoreError(f"{store_path} is damaged ({'; '.join(damaged)}); {advice}")
        try:
            # read whole arrays, each in one Zarr call (its chunks concurrently), not through Dask's graph of
            # one task per chunk: 0.66 s instead of 1.95 s for a 500-realization reference study
            ds = xr.open_zarr(str(store_path), consolidated=False, chunks=None).load()
        except Exception as error:  # a chunk that does not decode (checksum, truncated file)
            found = "; ".join(damage(group)) or f"{type(error).__name__}: {error}"
            raise StoreError(f"{store_path} is damaged ({found}); {advice}") from None
    # stores written before the time means had the maps' spelling: the same arrays under their old names
    ds = ds.rename({old: new for old, new in RENAMED_METRICS.items() if old in ds and new not in ds})
    ds = ds.rename({f"nominal_{old}": f"nominal_{new}" for old, new in RENAMED_METRICS.items()
                    if f"nominal_{old}" in ds and f"nominal_{new}" not in ds})
    ds = ds.assign_coords(realization=np.arange(ds.sizes["realization"]))
    ds = ds.set_coords(["x"]) if "x" in ds.data_vars else ds
    for name in stored_observables(ds) + ("radial_displacement",):
        attrs = {"units": UNITS[name], "long_name": LONG_NAMES[name]}
        ds[name].attrs.update(attrs)
        ds[f"nominal_{name}"].attrs.update(attrs)
    return ds


#: Prefix of the per-realization results in the statistics (``realization_stick_slip_index``, ...): apart
#: from the pointwise statistics of the observables (``rate_of_penetration_mean`` is the mean over the
#: realizations at each time; ``realization_mean_rate_of_penetration`` each realization's time mean).
REALIZATION_PREFIX = "realization_"
#: The per-realization results summarised under ``realizations``: the cycle metrics and the bit-speed
#: oscillation (max − min)/2Ω of maps and sensitivity runs; with a top drive also the
#: :data:`~drillstring.dynamics.indicators.TOP_DRIVE_METRICS`.
SUMMARY_METRICS = (*CYCLE_METRICS, "bit_speed_oscillation", *TOP_DRIVE_METRICS)
#: Quantiles [%] of the per-realization distributions in the summary.
REALIZATION_QUANTILES = (2.5, 50.0, 97.5)
#: Length [s] by which the windows of the time convergence grow.
TIME_WINDOW = 10.0
#: Relative change of an observable's maximum dispersion between the last two records above which the
#: summary warns that it is not converged in time (2 % per 10 s: a maximum still drifting at that rate would
#: move by 20 % over 100 s more).
TIME_CONVERGENCE_THRESHOLD = 0.02


def _metric_names(raw: xr.Dataset) -> list[str]:
    """The per-realization metrics a study store holds: :data:`~drillstring.stochastic.runs.
    REALIZATION_METRICS`, the per-family growth rates (:data:`~drillstring.stochastic.runs.FAMILY_GROWTH_METRICS`,
    in stores written since they exist) and the :data:`~drillstring.dynamics.indicators.TOP_DRIVE_METRICS` of a
    case with a top drive."""
    return list(REALIZATION_METRICS) + [name for name in (*FAMILY_GROWTH_METRICS, *TOP_DRIVE_METRICS) if name in raw]


def _realization_metrics(raw: xr.Dataset, rows: np.ndarray, t_transient: float, prefix: str = "") -> dict:
    """The per-realization metrics (:func:`_metric_names`) of the realizations ``rows`` (or of the
    nominal run with ``prefix="nominal_"``) as the workers stored them; the cycle (and top-drive) metrics
    recomputed from the time histories, with each realization's own top speed and bit area, when
    ``t_transient`` differs from the window the workers used (the store's ``metrics_transient``)."""
    if "top_speed" not in raw:
        raise ValueError("the study store holds no per-realization cycle metrics (written by an older "
                         "drillstring version): rerun the study in a new folder")
    one = prefix == "nominal_"
    names = _metric_names(raw)
    values = {name: np.atleast_1d(np.asarray(raw[prefix + name].values, dtype=float))[0 if one else rows]
              for name in names}
    stored = raw.attrs.get("metrics_transient")
    if stored is not None and math.isclose(float(stored), t_transient, rel_tol=1e-12, abs_tol=1e-12):
        return values
    time = raw.time.values
    picked = [None] if one else list(rows)
    observables = stored_observables(raw)
    top_drive = any(name in TOP_DRIVE_METRICS for name in names)
    recomputed = []
    for j, top, area in zip(picked, np.atleast_1d(values["top_speed"]), np.atleast_1d(values["bit_area"])):
        histories = {name: raw[prefix + name].values if one else raw[name].values[j] for name in observables}
        row = cycle_metrics(time, histories, float(top), float(area), t_transient)
        if top_drive:
            row.update(top_drive_metrics(time, histories, t_transient))
        recomputed.append(row)
    for name in [name for name in names if name in CYCLE_METRICS or name in TOP_DRIVE_METRICS]:
        values[name] = np.array([row[name] for row in recomputed])
        if one:
            values[name] = values[name][0]
    return values


def study_statistics(raw: xr.Dataset, level: float = 0.95, t_transient: float | None = None) -> xr.Dataset:
    """Pointwise statistics over the finished realizations (failed ones excluded), the mean-square
    convergence ``conv(n_s)`` of each observable, and the nominal response.

    Variables: ``<v>_mean``, ``<v>_std``, ``<v>_lower``, ``<v>_upper`` (the ``level`` quantile envelope),
    ``<v>_dispersion`` (std/|mean|), ``<v>_nominal`` and ``<v>_convergence`` (dimension ``n_samples``),
    for ``v`` in the study observables and ``radial_displacement`` (per probe); and, per finished
    realization (dimension ``realization``), what its worker computed from its realized case, each named
    ``realization_<name>`` (:data:`~drillstring.stochastic.runs.REALIZATION_METRICS`: the cycle metrics after
    ``t_transient`` [s] (default ``min(10 s, t_end/2)``), its top speed, bit area and the leading
    ``growth_rate`` of steady drilling; and ``bit_speed_oscillation`` (max − min)/2Ω with its own Ω; the
    nominal run's value in each one's attribute ``nominal``) and the
    ``lowest_lateral_eigenvalue`` ω₁² [rad²/s²] of its prestressed string (negative: statically buckled;
    attribute ``buckled_realizations``). A study of a case with a top drive adds the observables
    ``quill_speed`` and ``surface_torque`` and the per-realization :data:`~drillstring.dynamics.indicators.
    TOP_DRIVE_METRICS`.
    """
    ok = raw.status.values == DONE
    names = list(stored_observables(raw)) + ["radial_displacement"]
    done = raw[names].isel(realization=np.nonzero(ok)[0])
    n_done = int(ok.sum())
    if n_done < 2:
        raise ValueError(f"only {n_done} finished realization(s): statistics need at least 2")
    stats = realization_statistics(done, dim="realization", level=level)
    time = raw.time.values
    for name in names:
        stats[f"{name}_nominal"] = raw[f"nominal_{name}"]
        samples = done[name].transpose("realization", "time", ...).values
        conv = mean_square_convergence(samples, time)
        stats[f"{name}_convergence"] = xr.DataArray(
            conv, dims="n_samples", coords={"n_samples": np.arange(1, n_done + 1)},
            attrs={"units": f"({UNITS[name]})^2 s",
                   "long_name": f"conv(n_s) = (1/n_s) sum_j int ||{name}_j||^2 dt"},
        )
    t_transient = transient_end(float(time[-1])) if t_transient is None else float(t_transient)
    rows = np.nonzero(ok)[0]
    metrics = _realization_metrics(raw, rows, t_transient)
    nominal = _realization_metrics(raw, rows, t_transient, prefix="nominal_")
    coords = {"realization": done.realization.values}
    for name, (unit, description) in {**REALIZATION_METRICS, **FAMILY_GROWTH_METRICS, **TOP_DRIVE_METRICS}.items():
        if name not in metrics:
            continue
        window = f" after t = {t_transient:g} s" if name in CYCLE_METRICS or name in TOP_DRIVE_METRICS else ""
        stats[REALIZATION_PREFIX + name] = xr.DataArray(
            metrics[name], dims="realization", coords=coords,
            attrs={"units": unit, "long_name": description + window, "nominal": float(nominal[name])})
    oscillation, nominal_oscillation = ((v["bit_speed_max"] - v["bit_speed_min"]) / (2.0 * v["top_speed"])
                                        for v in (metrics, nominal))
    stats[REALIZATION_PREFIX + "bit_speed_oscillation"] = xr.DataArray(
        oscillation, dims="realization", coords=coords,
        attrs={"units": "1", "nominal": float(nominal_oscillation),
               "long_name": f"bit-speed oscillation (max - min)/(2 top speed) after t = {t_transient:g} s"})
    lowest = (raw.lowest_lateral_eigenvalue.values[ok] if "lowest_lateral_eigenvalue" in raw
              else np.full(n_done, np.nan))
    stats["lowest_lateral_eigenvalue"] = xr.DataArray(
        lowest, dims="realization", coords={"realization": done.realization.values},
        attrs={"units": "rad^2/s^2", "long_name": "lowest lateral eigenvalue omega_1^2 (< 0: buckled)"},
    )
    paths = [str(p) for p in raw.attrs.get("parameters", [])]
    stats["input_values"] = xr.DataArray(
        np.asarray(raw.input_values.values, dtype=float)[ok], dims=("realization", "parameter"),
        coords={"realization": done.realization.values, "parameter": paths,
                "parameter_unit": ("parameter", [str(u) for u in raw.attrs.get("parameter_units", [])])},
        attrs={"long_name": "drawn values of the random parameters (SI units: see parameter_unit)"},
    )
    woh = raw.weight_on_hook.values[ok]
    wob = raw.weight_on_bit.values[ok]
    settings = dict(raw.attrs.get("settings", {}))
    mean_woh = float(raw.attrs.get("weight_on_hook_mean", np.nan))
    nominal_wob = float(raw.attrs.get("weight", np.nan)) - mean_woh
    sigma = _woh_std(raw.attrs)
    stats.attrs.update({
        "n_samples": n_done,
        "n_failed": int((raw.status.values == FAILED).sum()),
        "seed": int(settings.get("seed", -1)),
        # (δ_M, δ_K, δ_D) of the random reduced matrices (drillstring.stochastic.random_matrices); zeros: none
        "model_dispersion": [float(v) for v in settings.get("model_dispersion", (0.0, 0.0, 0.0))],
        "sigma": sigma,
        "weight_on_hook_mean": mean_woh,
        "weight_on_bit_nominal": nominal_wob,
        "weight_on_hook_dispersion": sigma / mean_woh,
        "weight_on_bit_dispersion": sigma / nominal_wob,
        "weight_on_hook_sample_mean": float(woh.mean()),
        "weight_on_hook_sample_std": float(woh.std(ddof=1)),
        "weight_on_bit_sample_std": float(wob.std(ddof=1)),
        "case": raw.attrs.get("case", ""),
        "t_transient": t_transient,
        "buckled_realizations": int(np.sum(lowest < 0.0)),
        **{key: list(raw.attrs.get(key, [])) for key in INPUT_ATTRIBUTES},
    })
    return stats


#: Attributes of a study store (and its statistics) describing the random parameters, one entry each.
INPUT_ATTRIBUTES = ("parameters", "laws", "parameter_units", "parameter_mean", "parameter_std")


def _woh_std(attrs) -> float:
    """The standard deviation [N] of the weight-on-hook's law, NaN when it is not random."""
    paths = [str(p) for p in attrs.get("parameters", [])]
    if "weight_on_hook" not in paths:
        return float("nan")
    return float(attrs["parameter_std"][paths.index("weight_on_hook")])


def input_dispersions(attrs) -> dict[str, float]:
    """Dispersion std/|mean| of each random parameter's law (those of mean 0 left out), and of the
    weight-on-bit when the weight-on-hook is random (``σ_WOH / (weight − mean WOH)``)."""
    out = {}
    for path, mean, std in zip(attrs.get("parameters", []), attrs.get("parameter_mean", []),
                               attrs.get("parameter_std", [])):
        if float(mean) != 0.0 and float(std) > 0.0:
            out[str(path)] = float(std) / abs(float(mean))
    sigma = _woh_std(attrs)
    if np.isfinite(sigma) and sigma > 0:
        out["weight_on_bit"] = sigma / float(attrs["weight_on_bit_nominal"])
    return out


def _inputs_summary(stats: xr.Dataset) -> dict[str, dict]:
    """Per random parameter: its law, unit (SI), mean, std and dispersion, and the sample's mean and std."""
    out = {}
    attrs = stats.attrs
    values = stats["input_values"].values if "input_values" in stats else np.zeros((0, 0))
    for j, path in enumerate(attrs.get("parameters", [])):
        mean, std = float(attrs["parameter_mean"][j]), float(attrs["parameter_std"][j])
        column = values[:, j] if values.size else np.array([np.nan])
        out[str(path)] = {
            "law": str(attrs["laws"][j]), "unit": str(attrs["parameter_units"][j]), "mean": mean, "std": std,
            "dispersion": std / abs(mean) if mean != 0.0 else None,
            "sample_mean": float(np.mean(column)),
            "sample_std": float(np.std(column, ddof=1)) if column.size > 1 else None,
        }
    return out


def _finite_or_none(value) -> float | None:
    value = float(value)
    return value if np.isfinite(value) else None


def distribution_summary(values) -> dict:
    """Mean, std (n − 1), dispersion std/|mean| (:func:`~drillstring.stochastic.statistics.dispersion`) and the
    :data:`REALIZATION_QUANTILES` (keys ``q2.5``, ``q50``, ``q97.5``) of the finite ``values``, with their
    count ``n``; None for what needs more values than there are."""
    x = np.asarray(values, dtype=float)
    x = x[np.isfinite(x)]
    out: dict = {"n": int(x.size), "mean": float(x.mean()) if x.size else None,
                 "std": float(x.std(ddof=1)) if x.size > 1 else None,
                 "dispersion": _finite_or_none(dispersion(x)) if x.size > 1 else None}
    quantiles = np.quantile(x, [q / 100.0 for q in REALIZATION_QUANTILES]) if x.size else [None] * 3
    out.update({f"q{q:g}": None if v is None else float(v) for q, v in zip(REALIZATION_QUANTILES, quantiles)})
    return out


def realizations_summary(stats: xr.Dataset) -> dict:
    """Per cycle metric (:data:`SUMMARY_METRICS`, unit SI): its distribution
    over the realizations (:func:`distribution_summary`), the nominal run's value and unit; plus
    ``stick_slip_realizations`` (stick time fraction > 0) and ``t_transient`` [s]."""
    out: dict = {}
    for name in SUMMARY_METRICS:
        values = stats.get(REALIZATION_PREFIX + name)
        if values is not None:
            out[name] = {**distribution_summary(values.values), "unit": values.attrs.get("units"),
                         "nominal": _finite_or_none(values.attrs.get("nominal", math.nan))}
    fraction = stats.get(REALIZATION_PREFIX + "stick_time_fraction")
    if fraction is not None:
        out["stick_slip_realizations"] = int((fraction.values > 0).sum())
    out["t_transient"] = float(stats.attrs.get("t_transient", math.nan))
    return out


def stability_summary(stats: xr.Dataset, boundary: dict | None = None) -> dict:
    """``unstable_fraction``: the share of the realizations (with a growth rate) whose steady drilling is
    unstable (leading growth rate > 0), their count, the distribution of the growth rate [1/s]
    (:func:`distribution_summary`) and the nominal run's; ``by_family``: the same per family of roots (axial,
    torsional, lateral: a buckled string's lateral divergence does not hide the torsional roots; absent in
    stores written before); ``boundary``: the nominal case's stability
    boundary along the weight-on-bit (:func:`~drillstring.dynamics.stability.weight_on_bit_boundary`) when
    given."""
    rates = stats.get(REALIZATION_PREFIX + "growth_rate")
    growth = np.asarray(rates.values, dtype=float) if rates is not None else np.zeros(0)
    finite = growth[np.isfinite(growth)]
    by_family = {}
    for name in FAMILY_GROWTH_METRICS:
        values = stats.get(REALIZATION_PREFIX + name)
        if values is None:  # a store written before the families were told apart
            continue
        own = np.asarray(values.values, dtype=float)
        own = own[np.isfinite(own)]
        by_family[name.removesuffix("_growth_rate")] = {
            "unstable_realizations": int(np.sum(own > 0.0)), "realizations_with_roots": int(own.size),
            "growth_rate": distribution_summary(own),
            "nominal_growth_rate": _finite_or_none(values.attrs.get("nominal", math.nan))}
    return {
        "unstable_fraction": float(np.mean(finite > 0.0)) if finite.size else None,
        "unstable_realizations": int(np.sum(finite > 0.0)),
        "realizations_with_growth_rate": int(finite.size),
        "growth_rate": distribution_summary(finite),
        "nominal_growth_rate": (_finite_or_none(rates.attrs.get("nominal", math.nan)) if rates is not None
                                else None),
        "by_family": by_family,
        "boundary": boundary,
    }


def time_convergence(stats: xr.Dataset, t_start: float, window: float = TIME_WINDOW,
                     threshold: float = TIME_CONVERGENCE_THRESHOLD) -> dict:
    """Convergence in time of the dispersion of each study observable: over growing records from
    ``t_start`` [s] (the end of the transient) to ``t_start + window``, ``t_start + 2 window``, ... (and the
    end of the record), the time-mean and the maximum of its dispersion (:func:`~drillstring.stochastic.
    statistics.dispersion_summary`), and ``change``: the relative change of each between the last two.

    ``warning``: one line when the maximum's change is above ``threshold`` (it still moves with the record
    length: a longer ``t_end`` is needed to tell where it settles), else None (also when the record holds
    fewer than two windows). The time mean's change is reported but not judged: over records of a few
    periods of an oscillating dispersion it moves by a few % with the records' phase alone (4.8 % for the
    torque-on-bit of the settled σ = 1000 N reference study between 10 and 20 s records), while the
    maximum of a settled oscillation no longer changes once a record holds a whole period."""
    time = np.asarray(stats.time.values, dtype=float)
    tolerance = 1e-9 * window
    ends = [float(t) for t in np.arange(t_start + window, time[-1] + tolerance, window)]
    if not ends or ends[-1] < time[-1] - tolerance:
        ends.append(float(time[-1]))
    out: dict = {"window": float(window), "threshold": float(threshold), "t_start": float(t_start),
                 "observables": {}}
    moving = []
    for name in stored_observables(stats):
        rows = []
        for end in ends:
            part = stats[[f"{name}_dispersion"]].sel(time=slice(None, end + tolerance))
            entry = dispersion_summary(part, [name], t_transient=t_start)[name]
            rows.append({"t_end": end, "dispersion_time_mean": entry["dispersion_time_mean"],
                         "dispersion_max": entry["dispersion_max"], "time_of_max": entry["time_of_max"]})
        change = {}
        for key in ("dispersion_time_mean", "dispersion_max"):
            last = [row[key] for row in rows[-2:]]
            change[key] = (abs(last[1] - last[0]) / abs(last[1]) if len(last) == 2 and None not in last
                           and last[1] != 0 else None)
        worst = change["dispersion_max"]
        if worst is not None and worst > threshold:
            moving.append(f"{name} {100 * worst:.3g} %")
        out["observables"][name] = {"windows": rows, "change": change}
    out["warning"] = None
    if moving:
        out["warning"] = (f"the dispersion is not converged in time: its maximum from t = {t_start:g} s to "
                          f"{ends[-2]:g} s and to {ends[-1]:g} s changed by more than {100 * threshold:g} % "
                          f"({', '.join(moving)}); run longer (a larger t_end) to see where it settles")
    return out


def study_summary(stats: xr.Dataset, t_transient: float = DEFAULT_TRANSIENT, boundary: dict | None = None) -> dict:
    """Per observable: time-mean and maximum dispersion after ``t_transient`` [s] and their ratios to
    the dispersion of each random parameter (and of the weight-on-bit when the weight-on-hook is random,
    :func:`input_dispersions`), and the same over the whole record
    (``whole_record``: from :func:`~drillstring.stochastic.statistics.record_start`, the first time the
    mean response is away from 0, as the reference study reports them); plus the study's size and
    input dispersions; the convergence of the dispersions with the record length (:func:`time_convergence`,
    records from ``t_transient``); the distributions of the per-realization cycle metrics
    (:func:`realizations_summary`) and the linear stability of the draws (:func:`stability_summary`, with
    the nominal case's ``boundary`` when given)."""
    inputs = input_dispersions(stats.attrs)
    observables = list(stored_observables(stats))
    per_variable = dispersion_summary(
        stats, observables, t_transient=t_transient, input_dispersion=inputs
    )
    time = stats.time.values
    for name in observables:
        start = record_start(time, stats[f"{name}_mean"].values, t_transient)
        whole = dispersion_summary(stats, [name], t_transient=start, input_dispersion=inputs)[name]
        per_variable[name]["whole_record"] = {
            key: whole[key] for key in ("dispersion_time_mean", "dispersion_max", "time_of_max", "t_start",
                                        "ratio_time_mean", "ratio_max")
        }
    convergence = {}
    for name in observables:
        conv = stats[f"{name}_convergence"].values
        half = len(conv) // 2
        # Relative change of conv(n_s) over the second half of the realizations.
        convergence[name] = float(abs(conv[-1] - conv[half]) / abs(conv[-1])) if half else None
    lowest = stats["lowest_lateral_eigenvalue"].values if "lowest_lateral_eigenvalue" in stats else np.zeros(0)
    return {
        "buckling": {
            "buckled_realizations": int(stats.attrs.get("buckled_realizations", 0)),
            "lowest_lateral_eigenvalue_min": float(lowest.min()) if lowest.size else None,
            "lowest_lateral_eigenvalue_max": float(lowest.max()) if lowest.size else None,
        },
        "n_samples": int(stats.attrs["n_samples"]),
        "n_failed": int(stats.attrs["n_failed"]),
        "seed": int(stats.attrs["seed"]),
        "model_dispersion": dict(zip(("mass", "stiffness", "damping"),
                                     map(float, stats.attrs.get("model_dispersion", (0.0, 0.0, 0.0))))),
        "sigma": _finite_or_none(stats.attrs["sigma"]),
        "weight_on_hook_mean": float(stats.attrs["weight_on_hook_mean"]),
        "weight_on_hook_dispersion": inputs.get("weight_on_hook"),
        "weight_on_bit_dispersion": inputs.get("weight_on_bit"),
        "inputs": _inputs_summary(stats),
        "input_dispersion": inputs,
        "t_transient": float(t_transient),
        "observables": per_variable,
        "convergence_change_second_half": convergence,
        "time_convergence": time_convergence(stats, t_transient),
        "start": start_summary(stats, t_transient),
        "realizations": realizations_summary(stats),
        "stability": stability_summary(stats, boundary),
    }


#: The file in a study's folder that says what its figures were drawn from (:func:`figures_key`).
FIGURES_KEY = ".figures-key.json"


def figures_key(payload: dict, settings, t_transient: float, units: str | None) -> str:
    """What a study's figures are drawn from: the realizations in the store (the summary ``payload``'s
    ``n_samples``, ``n_failed`` and ``sessions``, the runs that computed them), the ``settings``, the window
    ``t_transient`` [s], the unit system and the plotting code (the package's version, the size and time stamp
    of :mod:`drillstring.plots`). Equal keys: the figures on disk are current, and a rerun that computed
    nothing need not draw them again (:func:`current_figures`)."""
    import hashlib
    import importlib.util
    import json

    from drillstring._version import __version__

    origin = Path(importlib.util.find_spec("drillstring.plots").origin).stat()
    items = [__version__, origin.st_size, origin.st_mtime_ns, units, t_transient, repr(settings),
             payload["n_samples"], payload["n_failed"], payload["sessions"]]
    return hashlib.sha256(json.dumps(items, sort_keys=True, default=str).encode()).hexdigest()


def current_figures(folder: str | Path, key: str) -> dict[str, Path] | None:
    """The figures in ``folder`` (name -> path) if :func:`record_figures` recorded them with ``key`` and they
    are all there; None otherwise."""
    import json

    folder = Path(folder)
    try:
        record = json.loads((folder / FIGURES_KEY).read_text(encoding="utf-8"))
        figures = {name: folder / file for name, file in record["figures"].items()}
    except (OSError, ValueError, KeyError, TypeError, AttributeError):
        return None
    if record.get("key") != key or not figures or not all(path.is_file() for path in figures.values()):
        return None
    return figures


def record_figures(folder: str | Path, key: str, figures: dict[str, Path]) -> None:
    """Record (atomically, in :data:`FIGURES_KEY`) that ``figures`` (name -> path in ``folder``) were drawn
    from ``key``."""
    import json

    from drillstring.files import write_text_atomic

    record = {"key": key, "figures": {name: Path(path).name for name, path in figures.items()}}
    write_text_atomic(Path(folder) / FIGURES_KEY, json.dumps(record) + "\n")


def start_summary(stats: xr.Dataset, t_transient: float) -> dict:
    """When the nominal run's start-up has settled, against the summaries' window ``t_transient`` [s]
    (docs/model.md §8): ``settled``, :func:`~drillstring.dynamics.simulate.settling_time` of its bit speed
    from the end of the case's ramps (``ramp_end`` [s]: the weight ramp of ``initial.start = "ramp"`` and the
    top drive's set-point ramp; None: not settled by the end of the run) and, after a ramped start whose
    oscillation settles after ``t_transient`` or not at all, a ``warning``."""
    import tomllib

    from drillstring.dynamics.simulate import settling_time

    try:
        case = tomllib.loads(str(stats.attrs["case"]))
        speed = stats["bit_speed_nominal"].values
    except (KeyError, ValueError):
        return {"settled": None, "ramp_end": None, "warning": None}
    initial, top_drive = case.get("initial", {}), case.get("top_drive", {})
    ramp = initial.get("start") == "ramp"
    ramp_end = max(float(initial.get("weight_ramp_time", 0.0)) if ramp else 0.0,
                   float(top_drive.get("ramp_time", 0.0)))
    settled = settling_time(stats.time.values, speed, float(case.get("operation", {}).get("top_speed", 0.0)),
                            start=ramp_end)
    warning = None
    if ramp and not settled <= t_transient + 1e-9:
        when = (f"settles at t = {settled:.1f} s" if math.isfinite(settled) else
                f"has not settled by t = {float(stats.time.values[-1]):g} s")
        warning = (f"the nominal run's bit-speed oscillation {when} (measured: each period's range within 15 % of "
                   f"the last's), after the window's start t = {t_transient:g} s and the {ramp_end:g} s ramp: the "
                   "summaries mix the start-up with what follows" +
                   (f"; --transient {math.ceil(settled):g} starts them after it" if math.isfinite(settled) else
                    "; a longer --t-end shows where it goes"))
    return {"settled": settled if math.isfinite(settled) else None, "ramp_end": ramp_end, "warning": warning}
