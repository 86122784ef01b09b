"""From a study's Zarr store to statistics and a JSON-ready summary (SPEC §8)."""

from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
import xarray as xr

from drillstring.dynamics.indicators import DEFAULT_TRANSIENT, drilling_indicators, transient_end
from drillstring.quantities import LONG_NAMES, UNITS
from drillstring.stochastic.montecarlo import STUDY_OBSERVABLES, open_study_group
from drillstring.stochastic.locks import StudyLock
from drillstring.stochastic.store import DONE, FAILED
from drillstring.stochastic.statistics import (
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
    folder that is not a complete study store (:class:`~drillstring.stochastic.store.
    StoreError`)."""
    with StudyLock(store_path, shared=True):
        open_study_group(store_path, mode="r")
        ds = xr.open_zarr(str(store_path), consolidated=False).load()
    ds = ds.assign_coords(realization=np.arange(ds.sizes["realization"]))
    ds = ds.set_coords(["x"]) if "x" in ds.data_vars else ds
    for name in STUDY_OBSERVABLES + ("radial_displacement",):
        attrs = {"units": UNITS[name], "long_name": LONG_NAMES[name]}
        ds[name].attrs.update(attrs)
        ds[f"nominal_{name}"].attrs.update(attrs)
    return ds


#: Vibration indicators recorded per realization (:mod:`drillstring.dynamics.indicators`).
REALIZATION_INDICATORS = ("bit_speed_oscillation", "stick_time_fraction")


def study_statistics(raw: xr.Dataset, level: float = 0.95, t_transient: float | None = None) -> xr.Dataset:
    """Pointwise statistics over the finished realizations (failed ones excluded), the mean-square
    convergence ``conv(n_s)`` of each observable, and the nominal response.

    Variables: ``<v>_mean``, ``<v>_std``, ``<v>_lower``, ``<v>_upper`` (the ``level`` quantile envelope),
    ``<v>_dispersion`` (std/|mean|), ``<v>_nominal`` and ``<v>_convergence`` (dimension ``n_samples``),
    for ``v`` in the study observables and ``radial_displacement`` (per probe); and, per finished
    realization (dimension ``realization``), the vibration indicators ``bit_speed_oscillation`` and
    ``stick_time_fraction`` after ``t_transient`` [s] (default ``min(10 s, t_end/2)``) and the
    ``lowest_lateral_eigenvalue`` ω₁² [rad²/s²] of its prestressed string (negative: statically buckled;
    attribute ``buckled_realizations``).
    """
    ok = raw.status.values == DONE
    names = list(STUDY_OBSERVABLES) + ["radial_displacement"]
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
    top_speed = float(tomllib.loads(raw.attrs["case"])["operation"]["top_speed"])
    rows = [drilling_indicators(time, done.rate_of_penetration.values[j], done.bit_speed.values[j], top_speed,
                                t_transient) for j in range(n_done)]
    for name in REALIZATION_INDICATORS:
        stats[name] = xr.DataArray(
            np.array([row[name] for row in rows], dtype=float), dims="realization",
            coords={"realization": done.realization.values},
            attrs={"units": "1", "long_name": f"{name.replace('_', ' ')} after t = {t_transient:g} s"},
        )
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
        "top_speed": top_speed,
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


def study_summary(stats: xr.Dataset, t_transient: float = DEFAULT_TRANSIENT) -> dict:
    """Per observable: time-mean and maximum dispersion after ``t_transient`` [s] and their ratios to
    the dispersion of each random parameter (and of the weight-on-bit when the weight-on-hook is random,
    :func:`input_dispersions`), and the same over the whole record
    (``whole_record``: from :func:`~drillstring.stochastic.statistics.record_start`, the first time the
    mean response is away from 0, as the reference study reports them); plus the study's size and
    input dispersions."""
    inputs = input_dispersions(stats.attrs)
    per_variable = dispersion_summary(
        stats, list(STUDY_OBSERVABLES), t_transient=t_transient, input_dispersion=inputs
    )
    time = stats.time.values
    for name in STUDY_OBSERVABLES:
        start = record_start(time, stats[f"{name}_mean"].values, t_transient)
        whole = dispersion_summary(stats, [name], t_transient=start, input_dispersion=inputs)[name]
        per_variable[name]["whole_record"] = {
            key: whole[key] for key in ("dispersion_time_mean", "dispersion_max", "time_of_max", "t_start",
                                        "ratio_time_mean", "ratio_max")
        }
    convergence = {}
    for name in STUDY_OBSERVABLES:
        conv = stats[f"{name}_convergence"].values
        half = len(conv) // 2
        # Relative change of conv(n_s) over the second half of the realizations.
        convergence[name] = float(abs(conv[-1] - conv[half]) / abs(conv[-1])) if half else None
    indicators = {}
    for name in REALIZATION_INDICATORS:
        if name in stats:
            values = stats[name].values
            indicators[name] = {"mean": float(values.mean()), "std": float(values.std(ddof=1)),
                                "min": float(values.min()), "max": float(values.max())}
    if "stick_time_fraction" in stats:
        indicators["stick_slip_realizations"] = int((stats["stick_time_fraction"].values > 0).sum())
        indicators["t_transient"] = float(stats.attrs.get("t_transient", t_transient))
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
        "sigma": _finite_or_none(stats.attrs["sigma"]),
        "weight_on_hook_mean": float(stats.attrs["weight_on_hook_mean"]),
        "weight_on_hook_dispersion": inputs.get("weight_on_hook"),
        "weight_on_bit_dispersion": inputs.get("weight_on_bit"),
        "inputs": _inputs_summary(stats),
        "input_dispersion": inputs,
        "t_transient": float(t_transient),
        "observables": per_variable,
        "convergence_change_second_half": convergence,
        "indicators": indicators,
    }
