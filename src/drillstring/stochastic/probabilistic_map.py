"""Probabilistic operating map: at each point of a top speed × weight-on-bit grid, ``samples`` realizations
of the declared uncertain parameters, and per point the probabilities of stick-slip, of a buckled string,
of wall impact and of unstable steady drilling, with quantiles of the ROP and of the stick-slip index.

**The uncertainty at a point.** Point ``(Ω, wob)`` is the case with ``operation.top_speed = Ω`` and
``operation.weight_on_bit = wob`` (as in :mod:`~drillstring.stochastic.operating_map`). A ``sigma`` declares
the weight-on-hook Normal around that point's hook load, ``weight − wob``, of standard deviation ``sigma``
[N]: since ``weight_on_bit = weight − weight_on_hook``, the weight-on-bit of the point's realizations is
Normal of mean ``wob`` and standard deviation ``sigma``. Every other declared law (``laws``: case-parameter
path -> law spec, :mod:`~drillstring.stochastic.uncertainty`; optionally a correlation of normal ones) is the
same at every point. Laws of the grid's own parameters (``operation.top_speed``, ``operation.weight_on_bit``,
``weight_on_hook``) are refused: the grid sets them (the weight-on-hook's uncertainty is ``sigma``).

**Random streams.** Realization ``s`` of every point maps the stream :func:`~drillstring.stochastic.maxent.
realization_generator` ``(seed, s)`` through the point's law (:meth:`~drillstring.stochastic.uncertainty.
Uncertainty.draw`): common random numbers across the grid, so the differences between points are not blurred
by independent draws, and each realization depends only on ``(seed, s)``, the laws and its point (not on
workers, order or resumption: an interrupted map resumes to the same result).

**Per realization** (:func:`~drillstring.stochastic.runs.run_outputs` on the realized case, with the linear
stability of steady drilling and :data:`~drillstring.stochastic.runs.REALIZATION_OUTPUTS`) the store keeps
:data:`SAMPLE_OUTPUTS`, the drawn values and the realized weight-on-bit. **Per point**, over its finished
realizations (n of them; failed ones are excluded and listed):

=============================  =========================================================================
``stick_slip_probability``     share with ``stick_time_fraction > 0`` (the bit below 10 % of the top speed)
``buckling_probability``       share with ``lowest_lateral_eigenvalue < 0`` (a buckled straight string)
``impact_probability``         share with ``impacts > 0`` (a node entered contact with the borehole wall)
``instability_probability``    share with ``growth_rate > 0`` (steady drilling linearly unstable; a draw
                               without steady drilling, growth rate NaN, counts as not unstable)
``torsional_``, ``axial_``     the same for the leading root of the torsional, resp. axial family
``instability_probability``    (``{family}_growth_rate > 0``): not hidden by a buckled string's lateral root
``coexistence_probability``    share with ``coexisting_cycles`` (:func:`~drillstring.stochastic.runs.
                               coexisting_cycles`): stick-slip although steady drilling is linearly stable
``bounce_probability``         share with ``bit_bounce_fraction > 0`` (the bit left the rock, zero force on
                               bit, some of the time after the transient)
``*_standard_error``           the binomial standard error ``sqrt(P̂(1 − P̂)/n)`` of each
``rate_of_penetration_q``      2.5, 50 and 97.5 % quantiles of the time-mean ROP [m/s] (dimension ``quantile``)
``stick_slip_index_q``         the same quantiles of the stick-slip index
``surface_torque_amplitude``   with a top drive: the mean over the point's realizations of their
``_mean``                      surface-torque amplitude (max − min)/2 after the transient [N m]
=============================  =========================================================================

**Closed form of the buckling probability** (what the tests check): with only ``sigma`` declared, a
realization is buckled when its weight-on-bit exceeds the critical one ``wob_cr`` of the case
(:func:`~drillstring.buckling.case_buckling_margin`), so ``P = P(wob + σZ > wob_cr) = Φ((wob − wob_cr)/σ)``
at each point, and ``n P̂`` is binomial ``(n, P)``. Not for a case with ``[well]``: its ``wob_cr``
(:func:`~drillstring.buckling.case_critical_weight_on_bit`) is sinusoidal buckling along the well path, while
the probability counts the reduced model's straight string (its lateral dynamics is not the curved hole's).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from functools import partial
from pathlib import Path
from typing import Any, Callable

import numpy as np
import xarray as xr

from drillstring.case import Case
from drillstring.dynamics.indicators import bit_area, has_top_drive
from drillstring.checks import integer
from drillstring.checks import seed as check_seed
from drillstring.stochastic.execution import Engine, StoreRun, TaskOutcome, run_locked
from drillstring.stochastic.locks import StudyLock
from drillstring.stochastic.operating_map import MAP_AXES, MAX_POINTS, MapSettings, check_map, map_attributes
from drillstring.stochastic.parameters import WEIGHT_ON_HOOK, ParameterError, with_parameters
from drillstring.stochastic.runs import (DERIVED_OUTPUTS, REALIZATION_OUTPUTS, RUN_OUTPUTS, STABILITY_OUTPUTS,
                                        TOP_DRIVE_OUTPUTS, coexisting_cycles, compile_kernels, run_outputs,
                                        stored_outputs, with_top_drive_outputs)
from drillstring.stochastic.random_matrices import ModelDispersion, model_generator, random_reduced_model
from drillstring.stochastic.store import DONE, FAILED, ArraySpec, TaskStore
from drillstring.stochastic.uncertainty import Uncertainty, input_attributes
from drillstring.stochastic.uncertainty_settings import (
    NO_UNCERTAINTY,
    UncertaintyFields,
    UncertaintySettings,
    accepts_uncertainty_fields,
)

__all__ = [
    "PROBABILITIES",
    "QUANTILES",
    "SAMPLE_OUTPUTS",
    "SampledMapSettings",
    "SampledMapStore",
    "point_uncertainty",
    "run_sampled_map",
    "sampled_map_dataset",
    "sampled_map_summary",
]

#: Outputs of every realization: name -> (unit, description).
SAMPLE_OUTPUTS = {**RUN_OUTPUTS, **STABILITY_OUTPUTS, **REALIZATION_OUTPUTS,
                  "realized_weight_on_bit": ("N", "weight on bit of the realization")}
#: Per-point probabilities: name -> (output, event, description).
PROBABILITIES: dict[str, tuple[str, Callable[[np.ndarray], np.ndarray], str]] = {
    "stick_slip_probability": ("stick_time_fraction", lambda v: v > 0.0,
                               "probability of stick-slip (bit below 10 % of the top speed)"),
    "buckling_probability": ("lowest_lateral_eigenvalue", lambda v: v < 0.0,
                             "probability of a buckled string (lowest lateral eigenvalue < 0)"),
    "impact_probability": ("impacts", lambda v: v > 0.0, "probability of wall impact"),
    "instability_probability": ("growth_rate", lambda v: v > 0.0,
                                "probability of unstable steady drilling (growth rate > 0)"),
    "torsional_instability_probability": ("torsional_growth_rate", lambda v: v > 0.0,
                                          "probability of a growing torsional root of steady drilling"),
    "axial_instability_probability": ("axial_growth_rate", lambda v: v > 0.0,
                                      "probability of a growing axial root of steady drilling"),
    "coexistence_probability": ("coexisting_cycles", lambda v: v > 0.0,
                                "probability of stick-slip although steady drilling is linearly stable "
                                "(torsion and axial): coexisting cycles"),
    "bounce_probability": ("bit_bounce_fraction", lambda v: v > 0.0,
                           "probability of bit bounce (the bit off the rock some of the time)"),
}
#: Quantile levels of the per-point distributions of the ROP and of the stick-slip index.
QUANTILES = (0.025, 0.5, 0.975)
#: Outputs whose quantiles are given per point: output -> name of the quantile variable.
QUANTILE_OUTPUTS = {"mean_rate_of_penetration": "rate_of_penetration_q", "stick_slip_index": "stick_slip_index_q"}
#: Parameters the grid sets, which cannot carry a declared law.
GRID_PARAMETERS = (*MAP_AXES.values(), WEIGHT_ON_HOOK)
#: Fewest realizations per point.
MIN_SAMPLES = 2
#: Largest accepted probability that a point's weight-on-bit draw falls outside (0, string weight) (as a
#: study's :data:`~drillstring.stochastic.montecarlo.OUT_OF_RANGE_PROBABILITY`).
OUT_OF_RANGE_PROBABILITY = 1e-3


@accepts_uncertainty_fields
@dataclass(frozen=True)
class SampledMapSettings(UncertaintyFields):
    """What defines a probabilistic map; a resumed map must have the same settings.

    Attributes:
        grid: the grid and run window (:class:`~drillstring.stochastic.operating_map.MapSettings`).
        samples: realizations per point (>= 2).
        seed: root seed of the realizations' random streams, in [0, 2**64 - 1].
        sigma: standard deviation [N] of the weight-on-hook, Normal around each point's hook load; None: the
            weight-on-hook is not random.
        uncertainty: the other random parameters' laws, their correlation (which may name ``weight_on_hook``,
            the law of ``sigma``) and the model dispersion ``(δ_M, δ_K, δ_D)`` of random reduced matrices
            (:class:`~drillstring.stochastic.uncertainty_settings.UncertaintySettings`; its fields are also
            accepted as keywords and read through); sample ``j`` draws the reduced matrices from
            ``model_generator(seed, j)`` at every point (as its parameters: common random numbers).
    """

    grid: MapSettings
    samples: int
    seed: int = 0
    sigma: float | None = None
    uncertainty: UncertaintySettings = NO_UNCERTAINTY

    def __post_init__(self) -> None:
        from drillstring.checks import real_number

        samples = integer("samples", self.samples, low=MIN_SAMPLES,
                          allowed=f"an integer >= {MIN_SAMPLES} (realizations per point)")
        total = samples * self.grid.points
        if total > MAX_POINTS:
            raise ValueError(f"samples = {samples}: {self.grid.points} points × {samples} realizations = {total} "
                             f"runs, above the limit of {MAX_POINTS} (fewer points or samples)")
        object.__setattr__(self, "samples", samples)
        object.__setattr__(self, "seed", check_seed(self.seed))
        if self.sigma is not None:
            object.__setattr__(self, "sigma", real_number("sigma", self.sigma, unit="N", low=0.0, low_open=True))
        self._check_uncertainty()
        grid_law = next((p for p in self.uncertainty.paths if p in GRID_PARAMETERS), None)
        if grid_law is not None:
            raise ValueError(f"{grid_law}: cannot carry a law on a map, whose grid sets it (give the weight-on-hook's "
                             "uncertainty as sigma, a Normal around each point's hook load)")
        if self.sigma is None and not self.uncertainty.laws:
            raise ValueError("no random parameter: give sigma (the weight-on-hook's standard deviation) or a law")

    @property
    def realizations(self) -> int:
        """Runs of the whole map: points × samples (row ``point × samples + sample``)."""
        return self.grid.points * self.samples


def point_case(case: Case, settings: SampledMapSettings, point: int) -> Case:
    """The case at grid point ``point`` (top speed major): its top speed and weight-on-bit set."""
    top_speed, weight_on_bit = settings.grid.point(point)
    return with_parameters(case, {MAP_AXES["top_speed"]: top_speed, MAP_AXES["weight_on_bit"]: weight_on_bit})


#: Built point laws, in this process.
_LAWS: dict[tuple, Uncertainty] = {}


def point_uncertainty(case: Case, settings: SampledMapSettings, point: int, *,
                      tolerance: float = 1.0) -> Uncertainty:
    """The declared uncertainty at grid point ``point``: the weight-on-hook Normal around the point's hook
    load of standard deviation ``sigma`` (first, when given), then ``laws`` (see the module docstring).
    ``tolerance``: the largest probability a law may put outside its parameter's range (1 accepts any;
    draws outside fail their realization)."""
    from drillstring.stochastic.montecarlo import weight_on_hook_normal
    from drillstring.stochastic.study_model import case_text

    key = (case_text(case), settings, point, tolerance)
    if key in _LAWS:
        return _LAWS[key]

    at_point = point_case(case, settings, point)
    first = dict([weight_on_hook_normal(at_point, settings.sigma)]) if settings.sigma is not None else None
    found = settings.uncertainty.law(at_point, first=first, tolerance=tolerance)
    if len(_LAWS) > 256:
        _LAWS.clear()
    _LAWS[key] = found
    return found


def check_sampled_map(case: Case, settings: SampledMapSettings) -> None:
    """Refuse (ValueError, one line) a map whose draws would often be impossible: a weight-on-bit of the grid
    at or above the string's weight (:func:`~drillstring.stochastic.operating_map.check_map`), a ``sigma`` that
    puts a weight-on-bit outside (0, string weight) with a probability above :data:`OUT_OF_RANGE_PROBABILITY`
    at some point (the message names that point and the largest accepted sigma there), and any law that does
    so for its parameter (checked at the first point: the other laws do not depend on the point); also unknown
    paths, bad laws and correlations."""
    from drillstring.stochastic.montecarlo import weight_on_bit_out_of_range_probability

    check_map(case, settings.grid)
    if settings.sigma is not None:
        for point in range(settings.grid.points):
            at_point = point_case(case, settings, point)
            p = weight_on_bit_out_of_range_probability(at_point, settings.sigma)
            if p > OUT_OF_RANGE_PROBABILITY:
                top_speed, wob = settings.grid.point(point)
                raise ValueError(
                    f"sigma = {settings.sigma:.6g} N: at the point {top_speed * 30 / math.pi:.4g} rpm, "
                    f"{wob / 1e3:.6g} kN the weight-on-bit falls outside (0, {case.weight / 1e3:.6g} kN) with probability {p:.3g}, above "
                    f"{OUT_OF_RANGE_PROBABILITY:g}: such realizations cannot run (a smaller sigma, or weights-on-bit "
                    "farther from 0 and from the string's weight)")
    try:
        point_uncertainty(case, settings, 0, tolerance=OUT_OF_RANGE_PROBABILITY)
    except ParameterError as error:
        raise ValueError(str(error)) from None
    if settings.model.active:
        from drillstring.dynamics.rom import case_reduced_model

        settings.model.check_model(case_reduced_model(point_case(case, settings, 0)))


# --- the store -----------------------------------------------------------------------------------


class SampledMapStore(TaskStore):
    """A probabilistic map's Zarr store: one row per realization (``point × samples + sample``, top speed
    major), each output of :data:`SAMPLE_OUTPUTS` and the drawn values."""

    kind = "probabilistic map"
    row_dim = "realization"
    noun = "realizations"
    differ = "case or settings differ: grid, samples, seed, sigma, laws, t_end, output_step, transient"

    def __init__(self, path: str | Path, case: Case, settings: SampledMapSettings,
                 critical_weight_on_bit: float) -> None:
        grid = settings.grid
        law = point_uncertainty(case, settings, 0)
        layout = {
            "top_speed": ArraySpec(("top_speed",), data=np.array(grid.top_speed), attributes={"units": "rad/s"}),
            "weight_on_bit": ArraySpec(("weight_on_bit",), data=np.array(grid.weight_on_bit),
                                       attributes={"units": "N"}),
            **{name: ArraySpec(("realization",), attributes={"units": unit, "long_name": text})
               for name, (unit, text) in with_top_drive_outputs(SAMPLE_OUTPUTS, has_top_drive(case)).items()},
            "input_values": ArraySpec(("realization", "parameter")),
        }
        sizes = {"realization": settings.realizations, "top_speed": grid.shape[0], "weight_on_bit": grid.shape[1],
                 "parameter": law.size}
        attrs = {"critical_weight_on_bit": float(critical_weight_on_bit), "bit_area": bit_area(case),
                 "weight": case.weight, **input_attributes(law)}
        super().__init__(path, case_toml=case.to_toml(), settings=settings.store_settings(), layout=layout, sizes=sizes,
                         attrs=attrs)


# --- running -------------------------------------------------------------------------------------


def run_realization(case: Case, settings: SampledMapSettings, index: int) -> TaskOutcome:
    """Draw, build and simulate realization ``index`` (``point × samples + sample``); never raises (a draw
    that gives no valid case fails with the cause, its drawn values kept)."""
    point, sample = divmod(index, settings.samples)
    grid = settings.grid
    values = None
    try:
        law = point_uncertainty(case, settings, point)
        values = law.draw(settings.seed, [sample])[0]
        realized = law.apply(point_case(case, settings, point), values)
    except (ValueError, ParameterError) as error:
        outcome = TaskOutcome(index, FAILED, str(error), {name: math.nan for name in SAMPLE_OUTPUTS})
        if values is not None:
            outcome.values["input_values"] = values
        return outcome
    realize = (partial(_random_model, settings.model, settings.seed, sample) if settings.model.active else None)
    outcome = run_outputs(realized, index, t_end=grid.t_end, output_step=grid.output_step,
                          t_transient=grid.transient, with_stability=True, with_realization=True,
                          with_top_drive=has_top_drive(case), realize_model=realize)
    outcome.values["realized_weight_on_bit"] = realized.operation.weight_on_bit
    outcome.values["input_values"] = values
    return outcome


def _random_model(dispersion: ModelDispersion, seed: int, sample: int, model):
    """Sample ``sample``'s random reduced matrices of ``model`` (:mod:`~drillstring.stochastic.random_matrices`)."""
    return random_reduced_model(model, dispersion, model_generator(seed, sample))


def run_sampled_map(case: Case, settings: SampledMapSettings, store_path: str | Path, engine: Engine = Engine(), *,
                    finish: Callable[[StoreRun], Any] | None = None) -> StoreRun:
    """Run (or resume) every pending realization of a probabilistic map into its Zarr store on ``engine``,
    then ``finish(run)`` under the store's lock (checked first: :func:`check_sampled_map`)."""
    from drillstring.buckling import case_critical_weight_on_bit

    check_sampled_map(case, settings)
    critical = case_critical_weight_on_bit(case)
    return run_locked(store_path, partial(SampledMapStore, Path(store_path), case, settings, critical),
                      lambda store: [(i, i) for i in store.pending()], partial(_task, case, settings), engine,
                      prepare=partial(compile_kernels, case), finish=finish, what="map", noun="realizations")


def _task(case: Case, settings: SampledMapSettings, index: int) -> TaskOutcome:
    return run_realization(case, settings, index)


# --- the result ----------------------------------------------------------------------------------


def binomial_standard_error(probability: np.ndarray, count: np.ndarray) -> np.ndarray:
    """``sqrt(P(1 − P)/n)`` (NaN where n = 0)."""
    count = np.asarray(count, dtype=float)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(count > 0, np.sqrt(probability * (1.0 - probability) / count), np.nan)


def sampled_map_dataset(store_path: str | Path) -> xr.Dataset:
    """The probabilistic map as a Dataset: every output of :data:`SAMPLE_OUTPUTS`, ``status``, ``wall_time``
    and ``input_values`` (dims ``top_speed`` [rad/s] × ``weight_on_bit`` [N] × ``sample`` [× ``parameter``]);
    per point ``samples_done``, each probability of :data:`PROBABILITIES` with its ``*_standard_error``, the
    quantiles of :data:`QUANTILE_OUTPUTS` (dim ``quantile``) and the nominal ``buckling_margin`` [N];
    attributes: the case, settings, laws, ``critical_weight_on_bit``, counts and failures. Refused while a
    map runs on the store (shared lock)."""
    with StudyLock(store_path, shared=True, what="map"):
        group = SampledMapStore.open_group(store_path, mode="r")
        attrs = dict(group.attrs)
        top = np.asarray(group["top_speed"][:], dtype=float)
        wob = np.asarray(group["weight_on_bit"][:], dtype=float)
        samples = int(dict(attrs["settings"])["samples"])
        shape = (top.size, wob.size, samples)
        outputs = with_top_drive_outputs(SAMPLE_OUTPUTS, any(name in attrs["layout"] for name in TOP_DRIVE_OUTPUTS))
        arrays = stored_outputs(group, attrs["layout"], (*outputs, "status", "wall_time"), shape)
        inputs = np.asarray(group["input_values"][:], dtype=float).reshape(*shape, -1)
    arrays["coexisting_cycles"] = coexisting_cycles(arrays)
    outputs = {**outputs, **DERIVED_OUTPUTS}
    dims = ("top_speed", "weight_on_bit", "sample")
    coords = {
        "top_speed": ("top_speed", top, {"units": "rad/s", "long_name": "top (rotary) speed"}),
        "weight_on_bit": ("weight_on_bit", wob, {"units": "N", "long_name": "nominal weight on bit of the point"}),
        "sample": ("sample", np.arange(samples)),
        "quantile": ("quantile", np.array(QUANTILES)),
        "parameter": ("parameter", [str(p) for p in attrs.get("parameters", [])]),
    }
    data: dict[str, Any] = {name: (dims, arrays[name], {"units": unit, "long_name": text})
                            for name, (unit, text) in outputs.items()}
    data["status"] = (dims, arrays["status"].astype("i1"), {"long_name": "0 pending, 1 done, 2 failed"})
    data["wall_time"] = (dims, arrays["wall_time"], {"units": "s"})
    data["input_values"] = ((*dims, "parameter"), inputs, {"long_name": "drawn values [SI]"})
    done = arrays["status"] == DONE
    count = done.sum(axis=2)
    data["samples_done"] = (dims[:2], count, {"long_name": "finished realizations of the point"})
    for name, (output, event, text) in PROBABILITIES.items():
        with np.errstate(invalid="ignore"):
            hits = (event(arrays[output]) & done).sum(axis=2)
        probability = np.where(count > 0, hits / np.maximum(count, 1), np.nan)
        data[name] = (dims[:2], probability, {"units": "1", "long_name": text})
        data[f"{name}_standard_error"] = (dims[:2], binomial_standard_error(probability, count),
                                          {"units": "1", "long_name": f"binomial standard error of the {text}"})
    for output, name in QUANTILE_OUTPUTS.items():
        values = np.where(done, arrays[output], np.nan)
        with warnings.catch_warnings():  # a point without finished realization: NaN quantiles
            warnings.simplefilter("ignore", RuntimeWarning)
            q = np.nanquantile(values, QUANTILES, axis=2)
        unit, text = SAMPLE_OUTPUTS[output]
        data[name] = ((*dims[:2], "quantile"), np.moveaxis(q, 0, -1),
                      {"units": unit, "long_name": f"quantiles of the {text} over the point's realizations"})
    for output in TOP_DRIVE_OUTPUTS:
        if output in arrays:
            values = np.where(done, arrays[output], np.nan)
            with warnings.catch_warnings():  # a point without finished realization: NaN
                warnings.simplefilter("ignore", RuntimeWarning)
                mean = np.nanmean(values, axis=2)
            unit, text = outputs[output]
            data[f"{output}_mean"] = (dims[:2], mean, {"units": unit,
                                                       "long_name": f"mean {text} over the point's realizations"})
    critical = float(attrs["critical_weight_on_bit"])
    data["buckling_margin"] = (dims[:2], np.broadcast_to(critical - wob, shape[:2]).copy(),
                               {"units": "N", "long_name": "critical weight on bit (lateral buckling) minus the "
                                                            "point's nominal weight on bit (< 0: buckled)"})
    settings = dict(attrs["settings"])
    ds = xr.Dataset(data, coords=coords)
    ds.attrs.update({
        **map_attributes(attrs, dict(settings["grid"])),
        "samples": samples,
        "seed": int(settings["seed"]),
        "sigma": math.nan if settings.get("sigma") is None else float(settings["sigma"]),
        "laws": [str(v) for v in attrs.get("laws", [])],
        "n_points": int(top.size * wob.size),
        "n_realizations": int(np.prod(shape)),
        "n_done": int(done.sum()),
        "n_failed": int(np.sum(arrays["status"] == FAILED)),
        "failures": "; ".join(f"realization {k}: {v}" for k, v in dict(attrs.get("failures", {})).items()),
    })
    return ds


def _grid_list(values: np.ndarray) -> list:
    """A 2-D array as nested lists (rows: top speeds), NaN as None (JSON)."""
    return [[None if not math.isfinite(float(v)) else float(v) for v in row] for row in np.asarray(values)]


def sampled_map_summary(ds: xr.Dataset) -> dict[str, Any]:
    """JSON-ready summary of a probabilistic map (SI): grid, samples, laws, counts; per point (lists by top
    speed, then weight-on-bit) each probability, its standard error and the quantiles; the largest of each
    probability and where; with a top drive, ``surface_torque_amplitude_mean`` per point [N m]."""
    summary: dict[str, Any] = {
        "top_speed": [float(v) for v in ds.top_speed.values],
        "weight_on_bit": [float(v) for v in ds.weight_on_bit.values],
        "points": int(ds.attrs["n_points"]),
        "samples": int(ds.attrs["samples"]),
        "seed": int(ds.attrs["seed"]),
        "sigma": None if math.isnan(ds.attrs["sigma"]) else float(ds.attrs["sigma"]),
        "laws": list(ds.attrs["laws"]),
        "parameters": [str(p) for p in ds.parameter.values],
        "realizations": int(ds.attrs["n_realizations"]),
        "done": int(ds.attrs["n_done"]),
        "failed": int(ds.attrs["n_failed"]),
        "t_end": float(ds.attrs["t_end"]),
        "t_transient": float(ds.attrs["t_transient"]),
        "critical_weight_on_bit": float(ds.attrs["critical_weight_on_bit"]),
        "samples_done": [[int(v) for v in row] for row in ds["samples_done"].values],
        "probabilities": {},
        "quantile_levels": list(QUANTILES),
        "quantiles": {},
    }
    for name in PROBABILITIES:
        values = ds[name].values
        entry: dict[str, Any] = {"values": _grid_list(values),
                                 "standard_error": _grid_list(ds[f"{name}_standard_error"].values)}
        if np.isfinite(values).any():
            i, j = np.unravel_index(int(np.nanargmax(values)), values.shape)
            entry["largest"] = {"probability": float(values[i, j]), "top_speed": float(ds.top_speed[i]),
                                "weight_on_bit": float(ds.weight_on_bit[j])}
        summary["probabilities"][name] = entry
    for name in QUANTILE_OUTPUTS.values():
        summary["quantiles"][name] = {f"{100 * q:g}": _grid_list(ds[name].values[..., k])
                                      for k, q in enumerate(QUANTILES)}
    for name in TOP_DRIVE_OUTPUTS:
        if f"{name}_mean" in ds:
            summary[f"{name}_mean"] = _grid_list(ds[f"{name}_mean"].values)
    return summary
