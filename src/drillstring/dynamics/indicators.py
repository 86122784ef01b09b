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
  nearly stopped); ``stick_slip`` is True when that fraction is positive.
"""

from __future__ import annotations

import numpy as np

#: Start of the steady regime for summaries [s] (or half the run when shorter).
DEFAULT_TRANSIENT = 10.0
#: The bit counts as stuck below this fraction of the top speed.
STICK_SPEED_RATIO = 0.1


def transient_end(t_end: float, transient: float = DEFAULT_TRANSIENT) -> float:
    """Start of the steady window [s] for a run of ``t_end`` [s]."""
    return min(transient, 0.5 * t_end)


def _finite(values: np.ndarray) -> np.ndarray:
    values = np.asarray(values, dtype=float)
    return values[np.isfinite(values)]


def drilling_indicators(time, rate_of_penetration, bit_speed, top_speed: float, t_transient: float) -> dict:
    """Indicators of one run (SI) over ``time >= t_transient`` (the whole run if it ended before):
    ``mean_rate_of_penetration`` [m/s], ``bit_speed_min``, ``bit_speed_max`` [rad/s],
    ``bit_speed_oscillation`` [-], ``stick_time_fraction`` [-], ``stick_slip`` (bool); None where a
    failed run left no finite value."""
    time = np.asarray(time, dtype=float)
    steady = time >= t_transient - 1e-9 * max(1.0, abs(t_transient))
    if not steady.any():
        steady = np.ones_like(time, dtype=bool)
    rop = _finite(np.asarray(rate_of_penetration)[steady])
    speed = _finite(np.asarray(bit_speed)[steady])
    if speed.size == 0:
        return {"mean_rate_of_penetration": float(rop.mean()) if rop.size else None, "bit_speed_min": None,
                "bit_speed_max": None, "bit_speed_oscillation": None, "stick_time_fraction": None,
                "stick_slip": None}
    fraction = float(np.mean(speed < STICK_SPEED_RATIO * top_speed))
    return {
        "mean_rate_of_penetration": float(rop.mean()) if rop.size else None,
        "bit_speed_min": float(speed.min()),
        "bit_speed_max": float(speed.max()),
        "bit_speed_oscillation": float((speed.max() - speed.min()) / (2.0 * top_speed)),
        "stick_time_fraction": fraction,
        "stick_slip": fraction > 0.0,
    }
