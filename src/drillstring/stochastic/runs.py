"""One drilling run of a case, summarised by scalar outputs: the unit of work of operating maps and
sensitivity designs (a Monte Carlo study keeps the whole time histories instead).

Outputs (SI; "after the transient" means ``t >= t_transient``, :func:`~drillstring.dynamics.indicators.
transient_end` by default), one definition for every consumer:

=============================  ======  ========================================================================
name                           unit    definition
=============================  ======  ========================================================================
``mean_rate_of_penetration``   m/s     time mean of the ROP after the transient
``std_rate_of_penetration``    m/s     its standard deviation in time (0 in steady drilling)
``bit_speed_oscillation``      1       ``(max − min)/(2Ω)`` of the bit speed after the transient
``stick_time_fraction``        1       fraction of that time with the bit below 10 % of the top speed
``bit_bounce_fraction``        1       fraction of that time with the bit off the rock (zero force on bit)
``bit_speed_min``, ``_max``    rad/s   extremes of the bit speed after the transient
``mean_torque_on_bit``         N m     time mean of the TOB; ``std_torque_on_bit`` its std in time
``mean_force_on_bit``          N       time mean of the FOB; ``std_force_on_bit`` its std in time
``mechanical_specific_energy`` Pa      Teale's MSE from the time means, :func:`mechanical_specific_energy`
``max_radial_displacement``    m       largest radial displacement at the probes after the transient
``impacts``                    1       impacts on the borehole wall over the whole run (contact zones that appear)
=============================  ======  ========================================================================

(the bit-speed, ROP, TOB, FOB and MSE outputs from :func:`~drillstring.dynamics.indicators.cycle_metrics`).
With ``stability``, the linear stability of steady drilling (:func:`~drillstring.dynamics.stability.stability`, on
the same reduced model) adds ``growth_rate`` [1/s] (the leading eigenvalue's real part; > 0: steady drilling is
unstable), ``leading_frequency`` [Hz], ``leading_family`` (0 axial, 1 torsional, 2 lateral), per family
(:data:`~drillstring.dynamics.stability.STABILITY_FAMILIES`) the leading root's ``{family}_growth_rate`` [1/s]
and ``{family}_frequency`` [Hz] (a root belongs to the family holding most of its modal energy: above the
buckling load the lateral divergence leads, and the torsional and axial growth rates stay visible),
``leading_share`` (the leading root's share of energy in its family), ``mixed_roots`` (how many roots no
family dominates) and the closed-form steady state ``steady_bit_speed`` [rad/s], ``steady_rate_of_penetration``
[m/s], ``steady_torque_on_bit`` [N m], ``steady_force_on_bit`` [N] (NaN where the bit–rock law gives no
penetration).
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np

from drillstring.case import Case
from drillstring.dynamics.indicators import (
    CYCLE_METRICS,
    TOP_DRIVE_METRICS,
    bit_area,
    cycle_metrics,
    has_top_drive,
    steady_window,
    top_drive_metrics,
    transient_end,
)
from drillstring.dynamics.rom import case_reduced_model
from drillstring.dynamics.simulate import SimulationError, simulate_model
from drillstring.dynamics.stability import STABILITY_FAMILIES, stability
from drillstring.stochastic.execution import TaskOutcome
from drillstring.stochastic.store import DONE, FAILED

#: Scalar outputs of every run: name -> (unit, description).
RUN_OUTPUTS: dict[str, tuple[str, str]] = {
    "mean_rate_of_penetration": CYCLE_METRICS["mean_rate_of_penetration"],
    "std_rate_of_penetration": ("m/s", "standard deviation in time of the rate of penetration"),
    "bit_speed_oscillation": ("1", "bit-speed oscillation (max - min)/(2 top speed)"),
    "stick_time_fraction": ("1", "fraction of the time with the bit below 10 % of the top speed"),
    "bit_bounce_fraction": ("1", "fraction of the time with the bit off the rock (zero force on bit)"),
    "bit_speed_min": ("rad/s", "smallest bit speed"),
    "bit_speed_max": ("rad/s", "largest bit speed"),
    "mean_torque_on_bit": CYCLE_METRICS["mean_torque_on_bit"],
    "std_torque_on_bit": ("N m", "standard deviation in time of the torque on bit"),
    "mean_force_on_bit": CYCLE_METRICS["mean_force_on_bit"],
    "std_force_on_bit": ("N", "standard deviation in time of the force on bit"),
    "mechanical_specific_energy": ("Pa", "mechanical specific energy (Teale) from the time means"),
    "max_radial_displacement": ("m", "largest radial displacement at the probes"),
    "impacts": ("1", "impacts on the borehole wall: contact zones that appear (whole run)"),
}
#: Outputs added by the linear stability of steady drilling.
STABILITY_OUTPUTS: dict[str, tuple[str, str]] = {
    "growth_rate": ("1/s", "leading growth rate of the linearised model about steady drilling (> 0: unstable)"),
    "leading_frequency": ("Hz", "frequency of the leading eigenvalue"),
    "leading_family": ("1", "family of the leading eigenvalue: 0 axial, 1 torsional, 2 lateral"),
    **{f"{family}_growth_rate": ("1/s", f"leading growth rate of the {family} roots (NaN: the model has none)")
       for family in STABILITY_FAMILIES},
    **{f"{family}_frequency": ("Hz", f"frequency of the leading {family} root") for family in STABILITY_FAMILIES},
    "leading_share": ("1", "share of the leading root's modal energy in its family (< 0.8: a mixed root)"),
    "mixed_roots": ("1", "roots whose energy no family holds 80 % of"),
    "steady_bit_speed": ("rad/s", "bit speed of steady drilling (the set point unless integral_gain = 0)"),
    "steady_rate_of_penetration": ("m/s", "rate of penetration of steady drilling (closed form)"),
    "steady_torque_on_bit": ("N m", "torque on bit of steady drilling (closed form)"),
    "steady_force_on_bit": ("N", "force on bit of steady drilling (closed form)"),
}
#: Outputs added for a realization of random inputs (the probabilistic operating map).
REALIZATION_OUTPUTS: dict[str, tuple[str, str]] = {
    "lowest_lateral_eigenvalue": ("rad^2/s^2",
                                  "lowest lateral eigenvalue ω² of the prestressed string (< 0: buckled)"),
    "stick_slip_index": CYCLE_METRICS["stick_slip_index"],
}
#: Outputs added for a case with a top drive (:func:`~drillstring.dynamics.indicators.has_top_drive`) in the
#: operating maps: the surface-torque amplitude (max − min)/2 after the transient.
TOP_DRIVE_OUTPUTS: dict[str, tuple[str, str]] = {
    "surface_torque_amplitude": TOP_DRIVE_METRICS["surface_torque_amplitude"],
}


#: Per-point outputs derived from the stored ones (maps and probabilistic maps): name -> (unit, description).
DERIVED_OUTPUTS: dict[str, tuple[str, str]] = {
    "coexisting_cycles": ("1", "1 where steady drilling is linearly stable (torsion and axial) but the run ends in "
                               "stick-slip (the bit stuck part of the time): a stick-slip cycle coexists with "
                               "stable steady drilling"),
}


def coexisting_cycles(values) -> np.ndarray:
    """:data:`DERIVED_OUTPUTS` ``coexisting_cycles`` from a run's outputs (a mapping of arrays of one shape:
    ``torsional_growth_rate``, ``axial_growth_rate``, ``stick_time_fraction``): 1.0 where the torsional and
    axial roots of steady drilling all decay (its linearisation says steady drilling is stable; a family the
    model lacks, NaN growth rate, counts as stable; the lateral roots are left out: a buckled string's lateral
    divergence is static and is not what stick-slip comes from) and yet the bit sticks and slips after the
    transient (``0 < stick_time_fraction < 1``; stuck all the time is a stalled bit, not a cycle — e.g. a
    controller whose integral action builds the motor torque slower than the run lasts): the run landed on a
    stick-slip limit cycle that
    coexists with stable steady drilling (a subcritical Hopf bifurcation; which one the string takes
    depends on the start). 0.0 where not; NaN where a growth rate of both families or the stick time is NaN
    (no steady drilling, or a run that left no value)."""
    torsion = np.asarray(values["torsional_growth_rate"], dtype=float)
    axial = np.asarray(values["axial_growth_rate"], dtype=float)
    stick = np.asarray(values["stick_time_fraction"], dtype=float)
    with np.errstate(invalid="ignore"):
        stable = (np.isnan(torsion) | (torsion < 0.0)) & (np.isnan(axial) | (axial < 0.0))
        out = (stable & (stick > 0.0) & (stick < 1.0)).astype(float)
    out[(np.isnan(torsion) & np.isnan(axial)) | np.isnan(stick)] = math.nan
    return out


def stored_outputs(group, layout, names, shape) -> dict[str, np.ndarray]:
    """The arrays ``names`` of a task store's Zarr ``group``, each reshaped to ``shape``; a name its
    ``layout`` (the store's recorded layout) lacks — an output added after the store was written — reads as
    NaN, so that older stores stay readable."""
    return {name: (np.asarray(group[name][:]).reshape(shape) if name in layout else np.full(shape, math.nan))
            for name in names}


def with_top_drive_outputs(outputs: dict[str, tuple[str, str]], top_drive: bool) -> dict[str, tuple[str, str]]:
    """``outputs`` (name -> (unit, description)) followed by :data:`TOP_DRIVE_OUTPUTS` when ``top_drive``
    (the case has a top drive, or the store holds its outputs)."""
    return {**outputs, **(TOP_DRIVE_OUTPUTS if top_drive else {})}


#: Scalar results of each realization of a Monte Carlo study, computed in the worker from its realized
#: case (:func:`realization_metrics`; the growth rate from :func:`stability_outputs`): name -> (unit,
#: description). ``top_speed`` and ``bit_area`` are the realized case's, kept so that the cycle metrics can be
#: recomputed for another transient. A case with a top drive adds the :data:`~drillstring.dynamics.indicators.
#: TOP_DRIVE_METRICS`.
REALIZATION_METRICS: dict[str, tuple[str, str]] = {
    **CYCLE_METRICS,
    "top_speed": ("rad/s", "top speed of the realized case"),
    "bit_area": ("m^2", "bit area of the realized case (borehole cross-section)"),
    "growth_rate": ("1/s", "leading growth rate of steady drilling at the realization's inputs (> 0: unstable)"),
}


#: Per-family growth rates of each realization of a Monte Carlo study (:func:`~drillstring.dynamics.stability.
#: family_growth_rates`): stored by studies written since they exist, read when a store holds them.
FAMILY_GROWTH_METRICS: dict[str, tuple[str, str]] = {
    f"{family}_growth_rate": ("1/s", f"leading growth rate of the {family} roots of steady drilling (NaN: none)")
    for family in STABILITY_FAMILIES
}


def metrics_transient(settings) -> float:
    """Start [s] of the window of the cycle metrics a study's workers store: ``transient_end(t_end)``."""
    return transient_end(settings.t_end)


def realization_metrics(result, case: Case, t_transient: float) -> dict[str, float]:
    """The :data:`~drillstring.dynamics.indicators.CYCLE_METRICS` of one run (a :class:`~drillstring.
    dynamics.simulate.SimulationResult`, possibly partial) of ``case`` after ``t_transient`` [s], with the
    case's ``top_speed`` [rad/s] and ``bit_area`` [m²] that they use; with a top drive (:func:`~drillstring.
    dynamics.indicators.has_top_drive`) also the :data:`~drillstring.dynamics.indicators.TOP_DRIVE_METRICS`."""
    top_speed, area = float(case.operation.top_speed), bit_area(case)
    extra = top_drive_metrics(result.time, result.observables, t_transient) if has_top_drive(case) else {}
    return {**cycle_metrics(result.time, result.observables, top_speed, area, t_transient),
            "top_speed": top_speed, "bit_area": area, **extra}


def simulation_options(case: Case, t_end: float, output_step: float) -> dict[str, Any]:
    """Keyword arguments of :func:`~drillstring.dynamics.simulate.simulate_model` for ``case``: its
    ``[simulation]`` tolerances and limits and its initial lateral perturbation, with ``t_end`` and
    ``output_step`` [s]."""
    s = case.simulation
    return dict(t_end=t_end, output_step=output_step, rtol=s.rtol, atol=s.atol, method=s.method,
                max_steps=s.max_steps, min_step=s.min_step,
                lateral_perturbation=case.initial.lateral_perturbation, seed=case.initial.seed)


def compile_kernels(case: Case, note=None) -> None:
    """Compile the simulation kernels once, in the driver, before local worker processes start (announced
    on stderr the first time), so that the workers only load them from Numba's cache and no run's time
    includes compiling. ``note(text)``, when given, is told what makes each run of ``case`` costly
    (:func:`cost_notes`) before the runs start."""
    from drillstring.dynamics.compiled import prepare_kernels

    try:
        model = case_reduced_model(case)
    except Exception:  # the runs record why; the kernels then compile in the first of them
        return
    if note is not None:
        for text in cost_notes(case, model.family.count("lateral_y")):
            note(text)
    prepare_kernels(model, case.simulation.method)


def cost_notes(case: Case, lateral_per_plane: int) -> list[str]:
    """What makes each run of ``case`` costly, and the keys that trade accuracy for time (docs/performance.md,
    "The README's first case"): a lateral basis that the cut-off made larger than ``lateral_modes`` (the time
    per step grows with it), and an explicit method on the basis with attachment modes (their fast motion
    sets the step)."""
    r = case.reduced_model
    notes = []
    if lateral_per_plane > r.lateral_modes:
        notes.append(f"each run keeps {lateral_per_plane} lateral modes per plane (every one below "
                     f"{r.lateral_cutoff:g}× the rotation frequency: reduced_model.lateral_cutoff), not "
                     f"{r.lateral_modes} (lateral_modes); the time per step grows with them: lateral_cutoff = 0 "
                     "is faster, and right while the string stays off the wall (docs/performance.md)")
    if case.simulation.method in ("dopri5", "bs32") and r.truncation_correction == "static":
        notes.append(f"with the attachment modes of truncation_correction = \"static\" the explicit method "
                     f"{case.simulation.method!r} takes steps as short as their fast motion (4.3× the steps on "
                     "the README's first case); simulation.method = \"ark43\" is not limited by it "
                     "(docs/model.md §9)")
    return notes


def _steady(values: np.ndarray, steady: np.ndarray) -> np.ndarray:
    values = np.asarray(values, dtype=float)[steady]
    return values[np.isfinite(values)]


def result_outputs(result, case: Case, t_transient: float, *, cycle: tuple[str, ...] = ()) -> dict[str, float]:
    """The scalar outputs of :data:`RUN_OUTPUTS` of one run (a :class:`~drillstring.dynamics.simulate.
    SimulationResult`, possibly partial) of ``case`` after ``t_transient`` [s], and the ``cycle`` metrics named
    (:data:`~drillstring.dynamics.indicators.CYCLE_METRICS`); NaN where undefined."""
    t = np.asarray(result.time, dtype=float)
    top_speed = case.operation.top_speed
    obs = result.observables
    metrics = cycle_metrics(t, obs, top_speed, bit_area(case), t_transient)
    steady = steady_window(t, t_transient)
    out = {name: math.nan for name in RUN_OUTPUTS} | {name: metrics[name] for name in cycle}
    for name in ("stick_time_fraction", "bit_bounce_fraction", "bit_speed_min", "bit_speed_max",
                 "mechanical_specific_energy"):
        out[name] = metrics[name]
    out["bit_speed_oscillation"] = (metrics["bit_speed_max"] - metrics["bit_speed_min"]) / (2.0 * top_speed)
    for name in ("rate_of_penetration", "torque_on_bit", "force_on_bit"):
        out[f"mean_{name}"] = metrics[f"mean_{name}"]
        values = _steady(obs[name], steady)
        if values.size:
            out[f"std_{name}"] = float(values.std())
    radial = np.asarray(result.radial_displacement, dtype=float)
    if radial.size:
        values = _steady(radial, steady)
        out["max_radial_displacement"] = float(values.max()) if values.size else math.nan
    out["impacts"] = float(result.impacts)
    return out


def stability_outputs(model) -> tuple[dict[str, float], str]:
    """The outputs of :data:`STABILITY_OUTPUTS` of a reduced model, and a note ('' or why they are NaN)."""
    out = {name: math.nan for name in STABILITY_OUTPUTS}
    try:
        found = stability(model)
    except ValueError as error:  # no steady drilling: the bit-rock law gives no penetration
        return out, str(error)
    leading = found.leading
    steady = found.steady_state
    for family, root in found.leading_by_family.items():
        if root is not None:
            out[f"{family}_growth_rate"] = root.growth_rate
            out[f"{family}_frequency"] = root.frequency
    out.update({
        "growth_rate": leading.growth_rate,
        "leading_frequency": leading.frequency,
        "leading_family": float(STABILITY_FAMILIES.index(leading.family)),
        "leading_share": max(leading.shares.values()) if leading.shares else math.nan,
        "mixed_roots": float(len(found.mixed_roots)),
        "steady_bit_speed": steady.bit_speed,
        "steady_rate_of_penetration": steady.rate_of_penetration,
        "steady_torque_on_bit": steady.torque_on_bit,
        "steady_force_on_bit": steady.force_on_bit,
    })
    return out, steady.note


def run_outputs(case: Case, index: int, *, t_end: float, output_step: float, t_transient: float | None = None,
                with_stability: bool = False, with_realization: bool = False,
                with_top_drive: bool = False, realize_model=None, build_model=None) -> TaskOutcome:
    """Simulate ``case`` for ``t_end`` [s] and return its scalar outputs as the outcome of task ``index``
    (``values``: :data:`RUN_OUTPUTS`, plus :data:`STABILITY_OUTPUTS` when ``with_stability`` and
    :data:`REALIZATION_OUTPUTS` when ``with_realization`` and :data:`TOP_DRIVE_OUTPUTS` when
    ``with_top_drive``: the case has a top drive); ``build_model(case)``, when given, builds the case's reduced
    model instead of :func:`case_reduced_model` (a study's parametric model); ``realize_model(model)``, when
    given, returns the reduced model to run instead of the case's (random reduced matrices). Never
    raises: a run that stops early is FAILED with its cause and the outputs of what it computed; a case
    that cannot be built is FAILED with NaN outputs."""
    start = time.perf_counter()
    t_transient = transient_end(t_end) if t_transient is None else t_transient
    names = (list(RUN_OUTPUTS) + (list(STABILITY_OUTPUTS) if with_stability else [])
             + (list(REALIZATION_OUTPUTS) if with_realization else [])
             + (list(TOP_DRIVE_OUTPUTS) if with_top_drive else []))
    outcome = TaskOutcome(index, FAILED, "", {name: math.nan for name in names})
    try:
        model = case_reduced_model(case) if build_model is None else build_model(case)
        if realize_model is not None:
            model = realize_model(model)
        if with_stability:
            values, _ = stability_outputs(model)
            outcome.values.update(values)
        if with_realization:
            outcome.values["lowest_lateral_eigenvalue"] = float(model.lowest_lateral_eigenvalue)
        try:
            result = simulate_model(model, **simulation_options(case, t_end, output_step))
            outcome.status = DONE
        except SimulationError as error:
            result = error.result
            outcome.message = str(error)
        outcome.values.update(result_outputs(result, case, t_transient,
                                             cycle=("stick_slip_index",) if with_realization else ()))
        if with_top_drive:
            metrics = top_drive_metrics(result.time, result.observables, t_transient)
            outcome.values.update({name: metrics[name] for name in TOP_DRIVE_OUTPUTS})
    except Exception as error:  # any failure is recorded with its cause, never dropped
        outcome.status = FAILED
        outcome.message = f"{type(error).__name__}: {error}"
    outcome.wall_time = time.perf_counter() - start
    return outcome
