"""One torque-and-drag analysis of a case: every operation, buckling, lock-up and (given measured hook loads)
the friction calibration, gathered for the command line, reports and JSON (SI units throughout)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from drillstring.well.buckling import buckled_intervals, critical_loads
from drillstring.well.calibration import FrictionPosterior, HookLoadMeasurements, calibrate
from drillstring.well.survey import Trajectory
from drillstring.well.torque_drag import (MAX_STEP, TorqueDragResult, case_torque_drag, case_trajectory, lockup_depth,
                                          string_in_well)

__all__ = ["TorqueDragAnalysis", "analyse"]

#: Bit-depth step of the lock-up search [m].
LOCKUP_STEP = 100.0


@dataclass(frozen=True)
class TorqueDragAnalysis:
    """Results of :func:`analyse`: the path, each operation's loads, critical loads, the calibration."""

    trajectory: Trajectory
    results: dict[str, TorqueDragResult]
    critical: dict[str, np.ndarray]
    lockup_depth: float | None
    posterior: FrictionPosterior | None
    payload: dict[str, Any]


def _finite(x: float) -> float | None:
    return float(x) if math.isfinite(x) and abs(x) < 1e14 else None


def analyse(case, *, measurements: HookLoadMeasurements | None = None, sigma: float | None = None,
            max_step: float = MAX_STEP, progress=None) -> TorqueDragAnalysis:
    """Torque and drag of every operation of ``case``, buckled intervals, lock-up depth when sliding
    (bit depths every :data:`LOCKUP_STEP`), and the friction posterior when ``measurements`` are given
    (``sigma`` [N] the noise, None: estimated; ``progress(done, total)`` after each of their bit depths)."""
    path = case_trajectory(case)
    string = string_in_well(case, path, max_step=max_step)
    critical = critical_loads(string)
    results = case_torque_drag(case, string=string)
    depths = np.arange(LOCKUP_STEP, case.length, LOCKUP_STEP).tolist() + [case.length]
    lockup = lockup_depth(case, depths)
    posterior = None if measurements is None else calibrate(case, measurements, sigma=sigma, progress=progress)
    well = case.well
    operations = {}
    for op, r in results.items():
        operations[op] = {
            "hook_load": _finite(r.hook_load), "surface_torque": _finite(r.surface_torque),
            "weight_on_bit": r.weight_on_bit, "torque_on_bit": r.torque_on_bit,
            "locked_up": bool(r.extras["locked_up"]),
            "sinusoidal_buckling": buckled_intervals(r.measured_depth, r.axial_force, critical["sinusoidal"]),
            "helical_buckling": buckled_intervals(r.measured_depth, r.axial_force, critical["helical"]),
            "profile": {k: [_finite(v) for v in values] for k, values in r.profile().items()},
        }
    payload: dict[str, Any] = {
        "case": case.name,
        "weight": float(case.weight),
        "well": {
            "depth": path.depth, "true_vertical_depth": float(path.true_vertical_depth[-1]),
            "north": float(path.position[-1, 0]), "east": float(path.position[-1, 1]),
            "stations": len(path.measured_depth),
            "max_dogleg_severity": float(np.max(path.dogleg_severity)) if len(path.dogleg) else 0.0,
            "casing_shoe": 0.0 if well is None else well.casing_shoe,
            "cased_hole_friction": 0.0 if well is None else well.cased_hole_friction,
            "open_hole_friction": 0.0 if well is None else well.open_hole_friction,
        },
        "operations": operations,
        "critical_compression": {"measured_depth": string.measured_depth.tolist(),
                                 "sinusoidal": critical["sinusoidal"].tolist(),
                                 "helical": critical["helical"].tolist()},
        "lockup_depth": lockup,
    }
    if posterior is not None:
        mean, std = posterior.mean(), posterior.std()
        payload["calibration"] = {
            "measurements": int(posterior.n),
            "noise": "Gaussian, sigma given" if sigma is not None else "Gaussian, sigma unknown (Jeffreys prior)",
            "sigma": sigma, "residual_sigma": posterior.residual_sigma,
            "cased_hole_friction": {"mean": mean[0], "std": std[0], "interval_90": posterior.interval("cased")},
            "open_hole_friction": {"mean": mean[1], "std": std[1], "interval_90": posterior.interval("open_hole")},
            "mode": posterior.mode(),
        }
    return TorqueDragAnalysis(path, results, critical, lockup, posterior, payload)
