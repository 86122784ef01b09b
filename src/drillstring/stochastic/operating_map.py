"""Operating map: drilling performance and vibration over a grid of top speed × weight-on-bit.

One simulation per grid point (the case with ``operation.top_speed`` and ``operation.weight_on_bit`` set,
:func:`~drillstring.stochastic.parameters.with_parameters`), summarised by the scalar outputs of
:mod:`drillstring.stochastic.runs` (mean ROP, bit-speed oscillation, stick time, mean TOB and FOB,
mechanical specific energy, largest radial displacement, impacts) and the linear stability of steady
drilling at that point (leading growth rate, closed-form steady state). The points run on the study engine
(:func:`~drillstring.stochastic.execution.run_tasks`: local processes or Dask, a resumable Zarr store, worker
deaths isolated) and depend only on the case and the settings, so an interrupted map resumes to the same
result.

The **buckling margin** ``wob_cr − wob`` uses the critical weight-on-bit of the case
(:func:`~drillstring.buckling.case_critical_weight_on_bit`), computed once: the prestressed lateral stiffness
depends on neither the weight-on-bit of the reference state nor the top speed (module docstring of
:mod:`drillstring.buckling`); for a case with ``[well]``, sinusoidal buckling along the well path
(:mod:`drillstring.well.buckling`, eq. (3)).

Grid axes are written ``A:B:N`` (N values from A to B, both included), ``a,b,c`` (a list) or ``a`` (one
value); each value is a number or a ``"value unit"`` string as in case files (``"40 rpm:200 rpm:17"``); a
unit written once after the last number (``"40:200:17 rpm"``, ``"100,120,140 kN"``) applies to every bare
number; bare numbers otherwise take ``default_unit`` (SI in the Python API).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from functools import partial
from pathlib import Path
from typing import Any, Callable, Sequence

import numpy as np
import xarray as xr

from drillstring.case import Case, Dimension, to_si
from drillstring.dynamics.simulate import run_window
from drillstring.stochastic.execution import Engine, StoreRun, TaskOutcome, run_locked
from drillstring.stochastic.locks import StudyLock
from drillstring.stochastic.parameters import with_parameters
from drillstring.dynamics.indicators import bit_area, has_top_drive
from drillstring.dynamics.stability import STABILITY_FAMILIES
from drillstring.stochastic.runs import (DERIVED_OUTPUTS, RUN_OUTPUTS, STABILITY_OUTPUTS, TOP_DRIVE_OUTPUTS,
                                        coexisting_cycles, compile_kernels, run_outputs, stored_outputs,
                                        with_top_drive_outputs)
from drillstring.stochastic.store import DONE, FAILED, ArraySpec, TaskStore

__all__ = [
    "MAP_AXES",
    "MAP_OUTPUTS",
    "MapSettings",
    "MapStore",
    "map_dataset",
    "map_summary",
    "parse_axis",
    "run_map",
]

#: The map's axes: case parameter path of each.
MAP_AXES = {"top_speed": "operation.top_speed", "weight_on_bit": "operation.weight_on_bit"}
#: Every output of a grid point: name -> (unit, description).
MAP_OUTPUTS = {**RUN_OUTPUTS, **STABILITY_OUTPUTS}

#: Largest number of grid points of one map.
MAX_POINTS = 100_000


# --- the grid ------------------------------------------------------------------------------------


def _split_unit(text: str) -> tuple[str, str]:
    """``"40 rpm"`` -> ``("40", "rpm")``; ``"40"`` -> ``("40", "")``."""
    parts = text.strip().split(None, 1)
    if not parts:
        return "", ""
    return parts[0], (parts[1].strip() if len(parts) > 1 else "")


def parse_axis(text: str | Sequence[float] | float, dimension: Dimension, *, name: str,
               default_unit: str = "") -> np.ndarray:
    """The values [SI] of one grid axis, sorted (see the module docstring for the grammar). A sequence of
    numbers is taken as SI. Raises ValueError (one line naming ``name``) for a malformed axis, a value that
    is not a positive number, or a value given twice."""
    shown = text if isinstance(text, str) else list(np.atleast_1d(text))
    if isinstance(text, str):
        values = _parse_axis_text(text, dimension, name, default_unit)
    else:
        try:
            values = np.atleast_1d(np.asarray(text, dtype=float))
        except (TypeError, ValueError):
            raise ValueError(f"{name} = {shown!r}: must be numbers [SI] or a grid like 'A:B:N'") from None
        if values.ndim != 1:
            raise ValueError(f"{name} = {shown!r}: must be a flat list of values")
    if values.size == 0:
        raise ValueError(f"{name} = {shown!r}: no value")
    if not np.all(np.isfinite(values)) or np.any(values <= 0):
        raise ValueError(f"{name} = {shown!r}: every value must be a finite number > 0")
    values = np.sort(values)
    if np.any(np.diff(values) <= 1e-12 * np.abs(values[1:])):
        raise ValueError(f"{name} = {shown!r}: a value is given twice")
    return values


def _parse_axis_text(text: str, dimension: Dimension, name: str, default_unit: str) -> np.ndarray:
    def si(item: str, unit: str) -> float:
        number, own = _split_unit(item)
        value = f"{number} {own or unit}".strip()
        try:
            return to_si(value if (own or unit) else float(number), dimension)
        except ValueError as error:
            raise ValueError(f"{name} = {text!r}: {error}") from None

    grammar = (f"{name} = {text!r}: write A:B:N (N values from A to B), a list a,b,c or one value, each a "
               "number or 'value unit'")
    if ":" in text:
        parts = text.split(":")
        if len(parts) != 3:
            raise ValueError(grammar)
        count_text, unit = _split_unit(parts[2])
        try:
            count = int(count_text)
        except ValueError:
            raise ValueError(f"{name} = {text!r}: N = {count_text!r} must be an integer >= 1") from None
        if count < 1:
            raise ValueError(f"{name} = {text!r}: N = {count} must be an integer >= 1")
        if count > MAX_POINTS:
            raise ValueError(f"{name} = {text!r}: N = {count} values, above the limit of {MAX_POINTS} grid points")
        unit = unit or default_unit
        start, stop = si(parts[0], unit), si(parts[1], unit)
        if count > 1 and not stop > start:
            raise ValueError(f"{name} = {text!r}: B must be greater than A")
        return np.linspace(start, stop, count) if count > 1 else np.array([start])
    items = [item for item in text.split(",")]
    if any(not item.strip() for item in items):
        raise ValueError(grammar)
    _, last_unit = _split_unit(items[-1])
    unit = last_unit or default_unit
    return np.array([si(item, unit) for item in items])


@dataclass(frozen=True)
class MapSettings:
    """What defines an operating map; a resumed map must have the same settings.

    Attributes:
        top_speed: top speeds of the grid [rad/s], increasing.
        weight_on_bit: weights-on-bit of the grid [N], increasing.
        t_end: simulated time per point [s].
        output_step: output step [s].
        transient: start of the window of the outputs [s].
    """

    top_speed: tuple[float, ...]
    weight_on_bit: tuple[float, ...]
    t_end: float = 30.0
    output_step: float = 0.01
    transient: float | None = None

    def __post_init__(self) -> None:
        for axis in MAP_AXES:
            values = tuple(float(v) for v in getattr(self, axis))
            if not values or not all(math.isfinite(v) and v > 0 for v in values) or any(
                    b <= a for a, b in zip(values, values[1:])):
                raise ValueError(f"{axis} = {values!r}: must be increasing finite values > 0")
            object.__setattr__(self, axis, values)
        if len(self.top_speed) * len(self.weight_on_bit) > MAX_POINTS:
            raise ValueError(f"the grid has {len(self.top_speed)} x {len(self.weight_on_bit)} = "
                             f"{len(self.top_speed) * len(self.weight_on_bit)} points, above the limit of {MAX_POINTS}")
        window = run_window(self.t_end, self.output_step, self.transient)
        for name in ("t_end", "output_step", "transient"):
            object.__setattr__(self, name, getattr(window, name))

    @property
    def shape(self) -> tuple[int, int]:
        return len(self.top_speed), len(self.weight_on_bit)

    @property
    def points(self) -> int:
        return self.shape[0] * self.shape[1]

    def point(self, index: int) -> tuple[float, float]:
        """(top speed [rad/s], weight-on-bit [N]) of point ``index`` (top speed major)."""
        i, j = divmod(index, self.shape[1])
        return self.top_speed[i], self.weight_on_bit[j]


def check_map(case: Case, settings: MapSettings) -> None:
    """Refuse (ValueError, one line, before any point runs) a grid whose weights-on-bit reach the string's
    weight, or any value of either axis that the case's field refuses (its range,
    :data:`drillstring.case.PHYSICAL_BOUNDS`: a top speed above 1e3 rad/s): no such point could run. The
    time window is checked by :class:`MapSettings` itself."""
    heaviest = max(settings.weight_on_bit)
    if case.model.gravity and heaviest >= case.weight:
        raise ValueError(f"weight_on_bit = {heaviest:.6g} N: every weight-on-bit of the map must be less than the "
                         f"string's weight, {case.weight:.6g} N")
    for axis, values, unit in (("top_speed", settings.top_speed, "rad/s"),
                               ("weight_on_bit", settings.weight_on_bit, "N")):
        for value in values:
            try:
                with_parameters(case, {MAP_AXES[axis]: value})
            except ValueError as error:
                reason = str(error).split(": ", 1)[-1]
                raise ValueError(f"{axis} = {value:.6g} {unit}: {reason} (a value of the map's grid; no point "
                                 "was run)") from None


# --- the store -----------------------------------------------------------------------------------


class MapStore(TaskStore):
    """A map's Zarr store: one row per grid point (top speed major), each output of :data:`MAP_OUTPUTS` (and
    the surface-torque amplitude with a top drive: :func:`~drillstring.stochastic.runs.with_top_drive_outputs`)."""

    kind = "map"
    row_dim = "point"
    noun = "points"
    differ = "case or settings differ: grid, t_end, output_step, transient"

    def __init__(self, path: str | Path, case: Case, settings: MapSettings, critical_weight_on_bit: float) -> None:
        layout = {
            "top_speed": ArraySpec(("top_speed",), data=np.array(settings.top_speed), attributes={"units": "rad/s"}),
            "weight_on_bit": ArraySpec(("weight_on_bit",), data=np.array(settings.weight_on_bit),
                                       attributes={"units": "N"}),
            **{name: ArraySpec(("point",), attributes={"units": unit, "long_name": text})
               for name, (unit, text) in with_top_drive_outputs(MAP_OUTPUTS, has_top_drive(case)).items()},
        }
        sizes = {"point": settings.points, "top_speed": settings.shape[0], "weight_on_bit": settings.shape[1]}
        attrs = {"critical_weight_on_bit": float(critical_weight_on_bit), "bit_area": bit_area(case),
                 "weight": case.weight}
        super().__init__(path, case_toml=case.to_toml(), settings=asdict(settings), layout=layout, sizes=sizes,
                         attrs=attrs)


# --- running -------------------------------------------------------------------------------------


def _point_task(case: Case, settings: MapSettings, item: tuple[int, float, float]):
    """The outcome of one grid point (never raises: a case the point cannot build fails with the cause)."""
    index, top_speed, weight_on_bit = item
    try:
        point_case = with_parameters(case, {MAP_AXES["top_speed"]: top_speed,
                                            MAP_AXES["weight_on_bit"]: weight_on_bit})
    except ValueError as error:
        return TaskOutcome(index, FAILED, str(error))
    return run_outputs(point_case, index, t_end=settings.t_end, output_step=settings.output_step,
                       t_transient=settings.transient, with_stability=True, with_top_drive=has_top_drive(case))


#: What :func:`run_map` did (:class:`~drillstring.stochastic.execution.StoreRun`: the store, points finished
#: and failed, wall time, workers, points computed by this call, a note or None).
MapRun = StoreRun


def run_map(case: Case, settings: MapSettings, store_path: str | Path, engine: Engine = Engine(), *,
            finish: Callable[[StoreRun], Any] | None = None) -> MapRun:
    """Run (or resume) every pending point of a map into its Zarr store on ``engine``, then ``finish(run)``
    under the store's lock (like :func:`~drillstring.stochastic.montecarlo.run_study`: settings checked,
    scheduler reached and the store locked before anything is created)."""
    from drillstring.buckling import case_critical_weight_on_bit

    check_map(case, settings)
    critical = case_critical_weight_on_bit(case)
    return run_locked(store_path, partial(MapStore, Path(store_path), case, settings, critical),
                      lambda store: [(i, (i, *settings.point(i))) for i in store.pending()],
                      partial(_point_task, case, settings), engine, prepare=partial(compile_kernels, case),
                      finish=finish, what="map", noun="grid points")


# --- the result ----------------------------------------------------------------------------------


def map_dataset(store_path: str | Path) -> xr.Dataset:
    """The map as a Dataset of dimensions ``top_speed`` [rad/s] × ``weight_on_bit`` [N]: every output of
    :data:`MAP_OUTPUTS` (units in attributes; with a top drive also ``surface_torque_amplitude`` [N m]:
    :data:`~drillstring.stochastic.runs.TOP_DRIVE_OUTPUTS`), ``status`` (1 done, 2 failed), ``wall_time`` [s] and
    ``buckling_margin`` = critical weight-on-bit − weight-on-bit [N]; attributes: the case (TOML), the
    settings, ``critical_weight_on_bit`` [N], ``bit_area`` [m²], the failures' causes. Refused while a map
    runs on the store (shared lock)."""
    with StudyLock(store_path, shared=True, what="map"):
        group = MapStore.open_group(store_path, mode="r")
        attrs = dict(group.attrs)
        top = np.asarray(group["top_speed"][:], dtype=float)
        wob = np.asarray(group["weight_on_bit"][:], dtype=float)
        shape = (top.size, wob.size)
        outputs = with_top_drive_outputs(MAP_OUTPUTS, any(name in attrs["layout"] for name in TOP_DRIVE_OUTPUTS))
        arrays = stored_outputs(group, attrs["layout"], (*outputs, "status", "wall_time"), shape)
    arrays["coexisting_cycles"] = np.where(arrays["status"] == DONE, coexisting_cycles(arrays), np.nan)
    outputs = {**outputs, **DERIVED_OUTPUTS}
    coords = {
        "top_speed": ("top_speed", top, {"units": "rad/s", "long_name": "top (rotary) speed"}),
        "weight_on_bit": ("weight_on_bit", wob, {"units": "N", "long_name": "static weight on bit"}),
    }
    data = {name: (("top_speed", "weight_on_bit"), arrays[name], {"units": unit, "long_name": text})
            for name, (unit, text) in outputs.items()}
    data["status"] = (("top_speed", "weight_on_bit"), arrays["status"].astype("i1"),
                      {"long_name": "0 pending, 1 done, 2 failed"})
    data["wall_time"] = (("top_speed", "weight_on_bit"), arrays["wall_time"], {"units": "s"})
    critical = float(attrs["critical_weight_on_bit"])
    data["buckling_margin"] = (("top_speed", "weight_on_bit"), np.broadcast_to(critical - wob, shape).copy(),
                               {"units": "N", "long_name": "critical weight on bit (lateral buckling) minus "
                                                            "weight on bit (< 0: buckled)"})
    ds = xr.Dataset(data, coords=coords)
    ds.attrs.update({
        **map_attributes(attrs, dict(attrs["settings"])),
        "n_points": int(top.size * wob.size),
        "n_done": int(np.sum(arrays["status"] == DONE)),
        "n_failed": int(np.sum(arrays["status"] == FAILED)),
        "failures": "; ".join(f"point {k}: {v}" for k, v in dict(attrs.get("failures", {})).items()),
    })
    return ds


def map_attributes(attrs: dict, window: dict) -> dict[str, Any]:
    """The Dataset attributes of every map (deterministic or probabilistic) from its store's ``attrs`` and the
    run ``window`` of its settings: the case (TOML), ``critical_weight_on_bit`` [N], ``bit_area`` [m²],
    ``t_end``, ``output_step``, ``t_transient`` [s]."""
    return {
        "case": attrs["case"],
        "critical_weight_on_bit": float(attrs["critical_weight_on_bit"]),
        "bit_area": float(attrs["bit_area"]),
        "t_end": float(window["t_end"]),
        "output_step": float(window["output_step"]),
        "t_transient": float(window["transient"]),
    }


def map_summary(ds: xr.Dataset) -> dict[str, Any]:
    """JSON-ready highlights of a map (SI): grid, counts, the point of largest mean ROP, the count of
    linearly stable points (every root) and, per family, of points whose roots of that family all decay
    (``linearly_stable_points_by_family``: stable and unstable counts), the points where a stick-slip cycle
    coexists with stable steady drilling (``coexisting_cycle_points``), the critical weight-on-bit."""
    rop = ds["mean_rate_of_penetration"].where(ds["status"] == DONE)
    best: dict[str, Any] | None = None
    if bool(np.isfinite(rop.values).any()):
        i, j = np.unravel_index(int(np.nanargmax(rop.values)), rop.shape)
        point = ds.isel(top_speed=i, weight_on_bit=j)
        best = {"top_speed": float(point.top_speed), "weight_on_bit": float(point.weight_on_bit),
                **{k: float(point[k]) for k in ("mean_rate_of_penetration", "bit_speed_oscillation",
                                                "mechanical_specific_energy", "growth_rate")}}
    growth = ds["growth_rate"].values
    defined = np.isfinite(growth)
    done = ds["status"].values == DONE
    by_family = {}
    for family in STABILITY_FAMILIES:
        rates = ds[f"{family}_growth_rate"].values
        by_family[family] = {"stable": int(np.sum(rates[np.isfinite(rates)] < 0.0)),
                             "unstable": int(np.sum(rates[np.isfinite(rates)] >= 0.0))}
    coexisting = ds["coexisting_cycles"].values
    return {
        "top_speed": [float(v) for v in ds.top_speed.values],
        "weight_on_bit": [float(v) for v in ds.weight_on_bit.values],
        "points": int(ds.attrs["n_points"]),
        "done": int(ds.attrs["n_done"]),
        "failed": int(ds.attrs["n_failed"]),
        "t_end": float(ds.attrs["t_end"]),
        "t_transient": float(ds.attrs["t_transient"]),
        "critical_weight_on_bit": float(ds.attrs["critical_weight_on_bit"]),
        "bit_area": float(ds.attrs["bit_area"]),
        "linearly_stable_points": int(np.sum(growth[defined] < 0.0)),
        "linearly_stable_points_by_family": by_family,
        "coexisting_cycle_points": int(np.nansum(coexisting > 0.0)),
        "points_without_steady_drilling": int(np.sum(~defined & done)),
        "stick_slip_points": int(np.nansum(ds["stick_time_fraction"].values > 0.0)),
        "largest_rate_of_penetration": best,
    }
