"""Drilling-performance and vibration indicators of one run, after its start-up transient.

One definition for every consumer (the ``simulate`` summary, the per-realization records of a study,
operating maps):

- the **transient** lasts ``min(DEFAULT_TRANSIENT, t_end / 2)``: on the reference string the start-up
  (the string spinning from rest in torsion, no twist) settles onto the torsional limit cycle within
  10 s — the bit-speed extremes are then within 2 % of their final values (docs/verification.md);
- ``bit_speed_oscillation = (max − min) / (2 Ω)`` of the bit speed after the transient [-]: 0 in steady
  drilling, 1 when the bit speed swings between 0 and 2Ω (a full stick-slip cycle);
- ``stick_time_fraction``: the fraction of the time after the transient during which the bit turns
  slower than ``STICK_SPEED_RATIO`` Ω (the regularised bit–rock law has no exact stick, so "stuck" means
  nearly stopped); ``stick_slip`` is True when that fraction is positive;
- ``bit_bounce_fraction``: the fraction of that time during which the bit is off the rock (the force on bit
  is zero: every bit–rock law is a unilateral contact, :mod:`drillstring.forces.bit_rock`).

The **cycle metrics** of one run (:func:`cycle_metrics`, :data:`CYCLE_METRICS`) are what a drilling
engineer reads per well and per realization: the stick-slip index, the extremes and the period of the bit
speed, the time means of ROP, TOB and FOB and the mechanical specific energy, and the stick time fraction.
"""

from __future__ import annotations

import math

import numpy as np

#: Start of the steady regime for summaries [s] (or half the run when shorter).
DEFAULT_TRANSIENT = 10.0
#: The bit counts as stuck below this fraction of the top speed.
STICK_SPEED_RATIO = 0.1


def transient_end(t_end: float, transient: float = DEFAULT_TRANSIENT) -> float:
    """Start of the steady window [s] for a run of ``t_end`` [s]."""
    return min(transient, 0.5 * t_end)


def bit_area(case) -> float:
    """Area drilled by the bit [m²]: ``π D²/4`` with D the borehole diameter (the bit drills the hole; a case
    has no separate bit diameter)."""
    return math.pi * case.borehole.diameter**2 / 4.0


def has_top_drive(case) -> bool:
    """Whether ``case`` turns its string with a driving top boundary (``top_drive.controller`` other than
    ``"imposed_speed"``, or another ``top_drive.boundary``: :attr:`~drillstring.case.Case.top_driven`): its quill
    speed and surface torque then vary and are recorded in studies."""
    return case.top_driven


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


def steady_window(time, t_transient: float) -> np.ndarray:
    """Mask of the output times at or after ``t_transient`` [s] (to 1e-9 relative); the whole run when it
    ended before (a failed run: use what there is)."""
    time = np.asarray(time, dtype=float)
    steady = time >= t_transient - 1e-9 * max(1.0, abs(t_transient))
    return steady if steady.any() else np.ones_like(time, dtype=bool)


def _finite(values: np.ndarray) -> np.ndarray:
    values = np.asarray(values, dtype=float)
    return values[np.isfinite(values)]


def drilling_indicators(time, rate_of_penetration, bit_speed, top_speed: float, t_transient: float,
                        force_on_bit=None) -> dict:
    """Indicators of one run (SI) over ``time >= t_transient`` (the whole run if it ended before):
    ``mean_rate_of_penetration`` [m/s], ``bit_speed_min``, ``bit_speed_max`` [rad/s],
    ``bit_speed_oscillation`` [-], ``stick_time_fraction`` [-], ``stick_slip`` (bool) and, given the
    ``force_on_bit`` [N], ``bit_bounce_fraction`` [-] (:func:`bounce_fraction`); None where a failed run
    left no finite value."""
    steady = steady_window(time, t_transient)
    bounce = None if force_on_bit is None else bounce_fraction(np.asarray(force_on_bit)[steady])
    rop = _finite(np.asarray(rate_of_penetration)[steady])
    speed = _finite(np.asarray(bit_speed)[steady])
    if speed.size == 0:
        return {"mean_rate_of_penetration": float(rop.mean()) if rop.size else None, "bit_speed_min": None,
                "bit_speed_max": None, "bit_speed_oscillation": None, "stick_time_fraction": None,
                "stick_slip": None, "bit_bounce_fraction": bounce}
    fraction = float(np.mean(speed < STICK_SPEED_RATIO * top_speed))
    return {
        "mean_rate_of_penetration": float(rop.mean()) if rop.size else None,
        "bit_speed_min": float(speed.min()),
        "bit_speed_max": float(speed.max()),
        "bit_speed_oscillation": float((speed.max() - speed.min()) / (2.0 * top_speed)),
        "stick_time_fraction": fraction,
        "stick_slip": fraction > 0.0,
        "bit_bounce_fraction": bounce,
    }


def bounce_fraction(force_on_bit) -> float | None:
    """Fraction [-] of the samples of ``force_on_bit`` [N] (finite ones) at which the bit is off the rock:
    the force is not positive (the laws return exactly 0 then). None without a finite sample."""
    values = _finite(force_on_bit)
    return float(np.mean(values <= 0.0)) if values.size else None


#: Per-run cycle metrics (SI) after the transient: name -> (unit, description); :func:`cycle_metrics`. The one
#: table of the time means (``mean_rate_of_penetration``, ``mean_torque_on_bit``, ``mean_force_on_bit``) shared
#: by studies and maps (:data:`~drillstring.stochastic.runs.RUN_OUTPUTS` takes them from here); stores written
#: before this spelling (``rate_of_penetration_mean``, ...) are read through :data:`RENAMED_METRICS`.
CYCLE_METRICS: dict[str, tuple[str, str]] = {
    "stick_slip_index": ("1", "stick-slip index (max - min)/(2 mean) of the bit speed"),
    "bit_speed_min": ("rad/s", "smallest bit speed"),
    "bit_speed_max": ("rad/s", "largest bit speed"),
    "period": ("s", "period of the bit-speed oscillation (NaN when it does not oscillate)"),
    "mean_rate_of_penetration": ("m/s", "time-mean rate of penetration"),
    "mean_torque_on_bit": ("N m", "time-mean torque on bit"),
    "mean_force_on_bit": ("N", "time-mean force on bit"),
    "mechanical_specific_energy": ("Pa", "mechanical specific energy (Teale) from the time means"),
    "stick_time_fraction": ("1", "fraction of the time with the bit below 10 % of the top speed"),
    "bit_bounce_fraction": ("1", "fraction of the time with the bit off the rock (zero force on bit)"),
}
#: Earlier spellings of the time means (study stores written before the maps' and studies' names were made one):
#: old name -> name of :data:`CYCLE_METRICS`.
RENAMED_METRICS = {"rate_of_penetration_mean": "mean_rate_of_penetration", "torque_on_bit_mean": "mean_torque_on_bit",
                   "force_on_bit_mean": "mean_force_on_bit"}
#: Hysteresis of the period's level crossings, as a fraction of the bit-speed range (max - min).
PERIOD_HYSTERESIS = 0.25
#: Below this range (max - min) relative to the mean speed, the bit speed counts as constant: no period.
STEADY_RANGE = 1e-6


def oscillation_period(time, signal) -> float:
    """Mean period [s] of an oscillating record: the mean time between successive upward crossings of the
    mid-range level ``(max + min)/2``, each crossing located by linear interpolation between samples and
    counted only after the record fell below ``mid − PERIOD_HYSTERESIS·(max − min)`` since the last one
    (so that ripples near the level are not counted twice). Exact for a sampled sine up to the
    interpolation error; for a stick-slip cycle (long stick, short slip) it is the cycle time. NaN when
    fewer than two crossings are found or the record is constant (range below :data:`STEADY_RANGE` of its
    mean magnitude): steady drilling has no period."""
    t = np.asarray(time, dtype=float)
    x = np.asarray(signal, dtype=float)
    keep = np.isfinite(x) & np.isfinite(t)
    t, x = t[keep], x[keep]
    if x.size < 3:
        return math.nan
    high, low = float(x.max()), float(x.min())
    if high - low <= STEADY_RANGE * max(float(np.mean(np.abs(x))), np.finfo(float).tiny):
        return math.nan
    level = 0.5 * (high + low)
    rearm = level - PERIOD_HYSTERESIS * (high - low)
    crossings = []
    armed = False
    for k in range(1, x.size):
        if x[k - 1] <= rearm:
            armed = True
        if armed and x[k - 1] < level <= x[k]:
            crossings.append(t[k - 1] + (level - x[k - 1]) * (t[k] - t[k - 1]) / (x[k] - x[k - 1]))
            armed = False
    if len(crossings) < 2:
        return math.nan
    return float((crossings[-1] - crossings[0]) / (len(crossings) - 1))


def cycle_metrics(time, observables, top_speed: float, area: float, t_transient: float) -> dict[str, float]:
    """The :data:`CYCLE_METRICS` of one run (SI) over ``time >= t_transient`` (the whole run if it ended
    before), from its ``observables`` (``rate_of_penetration``, ``bit_speed``, ``torque_on_bit``,
    ``force_on_bit`` on the output times), the top speed Ω [rad/s] and the bit area A [m²] of the case the
    run was made of (for a realization: its realized case):

    - ``stick_slip_index = (max − min)/(2·mean)`` of the bit speed (the field's definition, divided by the
      time-mean bit speed, not by Ω; NaN when the mean is not positive); ``bit_speed_min``, ``_max``;
    - ``period``: :func:`oscillation_period` of the bit speed;
    - time means of ROP, TOB and FOB (``mean_*``), and :func:`mechanical_specific_energy` from them with Ω;
    - ``stick_time_fraction``: fraction of the samples with the bit below ``STICK_SPEED_RATIO·Ω``;
    - ``bit_bounce_fraction``: fraction of the samples with the bit off the rock (:func:`bounce_fraction`).

    NaN where a failed run left no finite value."""
    t = np.asarray(time, dtype=float)
    steady = steady_window(t, t_transient)
    out = {name: math.nan for name in CYCLE_METRICS}
    for name in ("rate_of_penetration", "torque_on_bit", "force_on_bit"):
        values = _finite(np.asarray(observables[name])[steady])
        if values.size:
            out[f"mean_{name}"] = float(values.mean())
    speed_all = np.asarray(observables["bit_speed"], dtype=float)[steady]
    speed = _finite(speed_all)
    if speed.size:
        high, low, mean = float(speed.max()), float(speed.min()), float(speed.mean())
        out.update({
            "bit_speed_min": low,
            "bit_speed_max": high,
            "stick_slip_index": (high - low) / (2.0 * mean) if mean > 0.0 else math.nan,
            "period": oscillation_period(t[steady], speed_all),
            "stick_time_fraction": float(np.mean(speed < STICK_SPEED_RATIO * top_speed)),
        })
    bounce = bounce_fraction(np.asarray(observables["force_on_bit"], dtype=float)[steady])
    out["bit_bounce_fraction"] = math.nan if bounce is None else bounce
    out["mechanical_specific_energy"] = mechanical_specific_energy(
        out["mean_force_on_bit"], out["mean_torque_on_bit"], top_speed, out["mean_rate_of_penetration"], area)
    return out


#: Per-run top-drive metrics (SI) after the transient, for a case with a top drive (:func:`has_top_drive`):
#: name -> (unit, description); :func:`top_drive_metrics`.
TOP_DRIVE_METRICS: dict[str, tuple[str, str]] = {
    "surface_torque_amplitude": ("N m", "surface-torque amplitude (max - min)/2"),
    "quill_speed_min": ("rad/s", "smallest quill speed"),
    "quill_speed_max": ("rad/s", "largest quill speed"),
}


def top_drive_metrics(time, observables, t_transient: float) -> dict[str, float]:
    """The :data:`TOP_DRIVE_METRICS` of one run (SI) over ``time >= t_transient`` (the whole run if it ended
    before), from its ``observables`` ``quill_speed`` [rad/s] and ``surface_torque`` [N m] on the output
    times: the surface-torque amplitude ``(max − min)/2`` (the swing of the motor's load that a driller reads
    on the torque gauge; 0 in steady drilling) and the extremes of the quill speed. NaN where a failed run
    left no finite value."""
    steady = steady_window(np.asarray(time, dtype=float), t_transient)
    out = {name: math.nan for name in TOP_DRIVE_METRICS}
    torque = _finite(np.asarray(observables["surface_torque"], dtype=float)[steady])
    if torque.size:
        out["surface_torque_amplitude"] = 0.5 * float(torque.max() - torque.min())
    speed = _finite(np.asarray(observables["quill_speed"], dtype=float)[steady])
    if speed.size:
        out["quill_speed_min"], out["quill_speed_max"] = float(speed.min()), float(speed.max())
    return out
