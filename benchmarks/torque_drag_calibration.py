"""Synthetic "measured" hook loads of the built-in case `deviated` and their calibration (docs/torque_drag.md).

Hook loads tripping out and in at bit depths every 150 m from 600 m to 3000 m are computed with friction
factors 0.22 (cased) and 0.33 (open hole), different from the case's 0.20 and 0.30, plus Gaussian noise of
standard deviation 15 kN (seed 2026): docs/torque_drag/measured_hook_loads.csv (in field units, as a rig would
record them). The friction factors are then recovered with sigma known and with sigma estimated, and the
coverage of the 90 % region is measured over repeated noise draws.

    PYTHONPATH=src python benchmarks/torque_drag_calibration.py
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from drillstring.case import load_case
from drillstring.well.calibration import (
    HookLoadMeasurements,
    calibrate,
    posterior_from_predictions,
    predicted_hook_loads,
)

TRUE = (0.22, 0.33)
SIGMA = 15e3  # N
OUT = Path(__file__).resolve().parents[1] / "docs" / "torque_drag" / "measured_hook_loads.csv"
KLBF = 4448.2216152605  # N
FT = 0.3048  # m


def main() -> None:
    case = load_case("deviated")
    depths = np.repeat(np.arange(600.0, 3001.0, 150.0), 2)
    ops = ("trip_out", "trip_in") * (len(depths) // 2)
    plan = HookLoadMeasurements(depths, ops, np.zeros(len(depths)))
    exact = predicted_hook_loads(case, plan, *TRUE)[:, 0]
    rng = np.random.default_rng(2026)
    measured = exact + SIGMA * rng.standard_normal(len(exact))
    lines = ["# Synthetic hook loads of the built-in case `deviated` (benchmarks/torque_drag_calibration.py):",
             f"# friction factors {TRUE[0]} cased, {TRUE[1]} open hole, Gaussian noise sigma = {SIGMA / 1e3:g} kN.",
             "bit_depth [ft],operation,hook_load [klbf]"]
    lines += [f"{d / FT:.1f},{op},{h / KLBF:.2f}" for d, op, h in zip(depths, ops, measured)]
    OUT.write_text("\n".join(lines) + "\n", encoding="utf-8")
    data = HookLoadMeasurements(depths, ops, measured)
    for sigma in (SIGMA, None):
        start = time.perf_counter()
        posterior = calibrate(case, data, sigma=sigma)
        elapsed = time.perf_counter() - start
        mean, std = posterior.mean(), posterior.std()
        print(f"sigma {'known' if sigma else 'estimated'}: cased {mean[0]:.3f} ± {std[0]:.3f} "
              f"{posterior.interval('cased')}, open {mean[1]:.3f} ± {std[1]:.3f} {posterior.interval('open_hole')}, "
              f"residual {posterior.residual_sigma / 1e3:.1f} kN, grid 61x61 in {elapsed:.1f} s")
    # coverage of the 90 % highest-posterior-density region over repeated noise draws (truth on the grid)
    grid = np.linspace(0.0, 0.6, 61)
    mu_c, mu_o = np.meshgrid(grid, grid, indexing="ij")
    predictions = predicted_hook_loads(case, plan, mu_c.ravel(), mu_o.ravel())
    i, j = 22, 33
    truth = predictions[:, i * 61 + j]
    for level in (0.5, 0.9, 0.95):
        hits = sum(posterior_from_predictions(predictions, truth + SIGMA * rng.standard_normal(len(truth)), grid,
                                              grid, SIGMA).in_region(i, j, level) for _ in range(1000))
        print(f"coverage of the {level:.0%} region over 1000 draws: {hits / 1000:.3f}")


if __name__ == "__main__":
    main()
