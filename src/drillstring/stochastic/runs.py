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
``bit_speed_min``, ``_max``    rad/s   extremes of the bit speed after the transient
``mean_torque_on_bit``         N m     time mean of the TOB; ``std_torque_on_bit`` its std in time
``mean_force_on_bit``          N       time mean of the FOB; ``std_force_on_bit`` its std in time
``mechanical_specific_energy`` Pa      Teale's MSE from the time means, :func:`mechanical_specific_energy`
``max_radial_displacement``    m       largest radial displacement at the probes after the transient
``impacts``                    1       impacts on the borehole wall over the whole run (contact zones that appear)
=============================  ======  ========================================================================

(the first five from :func:`~drillstring.dynamics.indicators.drilling_indicators`). With ``stability``,
the linear stability of steady drilling (:func:`~drillstring.dynamics.stability.stability`, on the same
reduced model) adds ``growth_rate`` [1/s] (the leading eigenvalue's real part; > 0: steady drilling is
unstable), ``leading_frequency`` [Hz], ``leading_family`` (0 axial, 1 torsional, 2 lateral) and the
closed-form steady state ``steady_rate_of_penetration`` [m/s], ``steady_torque_on_bit`` [N m],
``steady_force_on_bit`` [N] (NaN where the bit–rock law gives no penetration).
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np

from drillstring.case import Case
from drillstring.dynamics.indicators import drilling_indicators, transient_end
from drillstring.dynamics.rom import case_reduced_model
from drillstring.dynamics.simulate import SimulationError, simulate_model
from drillstring.dynamics.stability import STABILITY_FAMILIES, stability
from drillstring.stochastic.execution import TaskOutcome
from drillstring.stochastic.store import DONE, FAILED

#: Scalar outputs of every run: name -> (unit, description).
RUN_OUTPUTS: dict[str, tuple[str, str]] = {
    "mean_rate_of_penetration": ("m/s", "time-mean rate of penetration"),
    "std_rate_of_penetration": ("m/s", "standard deviation in time of the rate of penetration"),
    "bit_speed_oscillation": ("1", "bit-speed oscillation (max - min)/(2 top speed)"),
    "stick_time_fraction": ("1", "fraction of the time with the bit below 10 % of the top speed"),
    "bit_speed_min": ("rad/s", "smallest bit speed"),
    "bit_speed_max": ("rad/s", "largest bit speed"),
    "mean_torque_on_bit": ("N m", "time-mean torque on bit"),
    "std_torque_on_bit": ("N m", "standard deviation in time of the torque on bit"),
    "mean_force_on_bit": ("N", "time-mean force on bit"),
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
    "steady_rate_of_penetration": ("m/s", "rate of penetration of steady drilling (closed form)"),
    "steady_torque_on_bit": ("N m", "torque on bit of steady drilling (closed form)"),
    "steady_force_on_bit": ("N", "force on bit of steady drilling (closed form)"),
}


def simulation_options(case: Case, t_end: float, output_step: float) -> dict[str, Any]:
    """Keyword arguments of :func:`~drillstring.dynamics.simulate.simulate_model` for ``case``: its
    ``[simulation]`` tolerances and limits and its initial lateral perturbation, with ``t_end`` and
    ``output_step`` [s]."""
    s = case.simulation
    return dict(t_end=t_end, output_step=output_step, rtol=s.rtol, atol=s.atol, method=s.method,
                max_steps=s.max_steps, min_step=s.min_step,
                lateral_perturbation=case.initial.lateral_perturbation, seed=case.initial.seed)


def compile_kernels(case: Case) -> None:
    """Compile the simulation kernels once, in the driver, before local worker processes start (announced
    on stderr the first time), so that the workers only load them from Numba's cache and no run's time
    includes compiling."""
    from drillstring.dynamics.compiled import prepare_kernels

    try:
        model = case_reduced_model(case)
    except Exception:  # the runs record why; the kernels then compile in the first of them
        return
    prepare_kernels(model, case.simulation.method)


def bit_area(case: Case) -> float:
    """Area drilled by the bit [m²]: ``π D²/4`` with D the borehole diameter (the bit drills the hole)."""
    return math.pi * case.borehole.diameter**2 / 4.0


def mechanical_specific_energy(force_on_bit: float, torque_on_bit: float, top_speed: float,
                               rate_of_penetration: float, area: float) -> float:
    """Mechanical specific energy [Pa = J/m³] (Teale 1965): the work spent per volume of rock drilled,

        MSE = WOB/A + Ω·TOB/(A·ROP)      (= WOB/A + 2π N·TOB/(A·ROP) with N in rev/s),

    with the force on bit WOB [N], torque on bit TOB [N m], rotary speed Ω [rad/s] (the top speed, as
    measured at the surface), rate of penetration ROP [m/s] and bit area A [m²]. NaN when ROP <= 0.
    R. Teale, "The concept of specific energy in rock drilling", Int. J. Rock Mech. Min. Sci. 2, 57-73
    (1965)."""
    values = (force_on_bit, torque_on_bit, top_speed, rate_of_penetration, area)
    if not all(math.isfinite(v) for v in values) or rate_of_penetration <= 0.0 or area <= 0.0:
        return math.nan
    return force_on_bit / area + top_speed * torque_on_bit / (area * rate_of_penetration)


def _steady(values: np.ndarray, steady: np.ndarray) -> np.ndarray:
    values = np.asarray(values, dtype=float)[steady]
    return values[np.isfinite(values)]


def result_outputs(result, case: Case, t_transient: float) -> dict[str, float]:
    """The scalar outputs of :data:`RUN_OUTPUTS` of one run (a :class:`~drillstring.dynamics.simulate.
    SimulationResult`, possibly partial) of ``case`` after ``t_transient`` [s]; NaN where undefined."""
    t = np.asarray(result.time, dtype=float)
    top_speed = case.operation.top_speed
    obs = result.observables
    row = drilling_indicators(t, obs["rate_of_penetration"], obs["bit_speed"], top_speed, t_transient)
    steady = t >= t_transient - 1e-9 * max(1.0, abs(t_transient))
    if not steady.any():
        steady = np.ones_like(t, dtype=bool)
    out = {name: math.nan for name in RUN_OUTPUTS}
    for name in ("mean_rate_of_penetration", "bit_speed_oscillation", "stick_time_fraction", "bit_speed_min",
                 "bit_speed_max"):
        out[name] = math.nan if row[name] is None else float(row[name])
    for name in ("rate_of_penetration", "torque_on_bit", "force_on_bit"):
        values = _steady(obs[name], steady)
        if values.size:
            out[f"std_{name}"] = float(values.std())
            if name != "rate_of_penetration":
                out[f"mean_{name}"] = float(values.mean())
    radial = np.asarray(result.radial_displacement, dtype=float)
    if radial.size:
        values = _steady(radial, steady)
        out["max_radial_displacement"] = float(values.max()) if values.size else math.nan
    out["impacts"] = float(result.impacts)
    out["mechanical_specific_energy"] = mechanical_specific_energy(
        out["mean_force_on_bit"], out["mean_torque_on_bit"], top_speed, out["mean_rate_of_penetration"],
        bit_area(case))
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
    out.update({
        "growth_rate": leading.growth_rate,
        "leading_frequency": leading.frequency,
        "leading_family": float(STABILITY_FAMILIES.index(leading.family)),
        "steady_rate_of_penetration": steady.rate_of_penetration,
        "steady_torque_on_bit": steady.torque_on_bit,
        "steady_force_on_bit": steady.force_on_bit,
    })
    return out, ""


def run_outputs(case: Case, index: int, *, t_end: float, output_step: float, t_transient: float | None = None,
                with_stability: bool = False) -> TaskOutcome:
    """Simulate ``case`` for ``t_end`` [s] and return its scalar outputs as the outcome of task ``index``
    (``values``: :data:`RUN_OUTPUTS`, plus :data:`STABILITY_OUTPUTS` when ``with_stability``). Never
    raises: a run that stops early is FAILED with its cause and the outputs of what it computed; a case
    that cannot be built is FAILED with NaN outputs."""
    start = time.perf_counter()
    t_transient = transient_end(t_end) if t_transient is None else t_transient
    names = list(RUN_OUTPUTS) + (list(STABILITY_OUTPUTS) if with_stability else [])
    outcome = TaskOutcome(index, FAILED, "", {name: math.nan for name in names})
    try:
        model = case_reduced_model(case)
        if with_stability:
            values, _ = stability_outputs(model)
            outcome.values.update(values)
        try:
            result = simulate_model(model, **simulation_options(case, t_end, output_step))
            outcome.status = DONE
        except SimulationError as error:
            result = error.result
            outcome.message = str(error)
        outcome.values.update(result_outputs(result, case, t_transient))
    except Exception as error:  # any failure is recorded with its cause, never dropped
        outcome.status = FAILED
        outcome.message = f"{type(error).__name__}: {error}"
    outcome.wall_time = time.perf_counter() - start
    return outcome
