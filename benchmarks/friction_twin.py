"""The estimator's friction factor on the deviated case (docs/estimation.md, "The friction factor"): the twin of
tests/estimation/test_friction_estimation.py over seeds (off bottom: μ of the open hole alone, truth 0.25 on a
5 m mesh, the prior centred on the case's 0.30), with and without the parameters' relaxation; then drilling
(the case's Tucker–Wang law on bottom), a5 and μ estimated together, the correlation of their posteriors.

    python benchmarks/friction_twin.py [--seeds 1,2,3,4,5] [--seconds 30] [--members 16]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from drillstring.case import load_case
from drillstring.estimation.ensemble import EstimatorSettings, estimate, estimator_model

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "estimation"))
from test_friction_estimation import TWIN_SETTINGS
from twin import TRUE_FRICTION, friction_twin, off_bottom


def _line(label: str, result, name: str = "open_hole_friction") -> str:
    mean = result.mean[name][-1]
    low, high = result.band(name)
    inside = low[-1] <= TRUE_FRICTION <= high[-1]
    return (f"{label:40s} mu {mean:.4f} error {100 * (mean / TRUE_FRICTION - 1):+5.1f} % band {low[-1]:.4f}.."
            f"{high[-1]:.4f} ({100 * (high[-1] - low[-1]) / 2 / mean:.1f} %) inside {inside}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", default="1,2,3,4,5")
    parser.add_argument("--seconds", type=float, default=30.0)
    parser.add_argument("--members", type=int, default=16)
    parser.add_argument("--drilling-only", action="store_true")
    options = parser.parse_args()
    case = load_case("deviated")
    lifted = off_bottom(case)
    seeds = [int(s) for s in options.seeds.split(",")]
    if not options.drilling_only:
        for seed in seeds:
            record = friction_twin(lifted, seed, options.seconds)
            for relaxation in (0.0, TWIN_SETTINGS["parameter_relaxation"]):
                settings = EstimatorSettings(seed=seed, **{**TWIN_SETTINGS, "ensemble_size": options.members,
                                                           "parameter_relaxation": relaxation})
                result = estimate(lifted, record, settings, model=estimator_model(lifted, settings))
                print(_line(f"off bottom seed {seed} relaxation {relaxation}", result), flush=True)
    for seed in seeds[:2]:
        record = friction_twin(case, seed, options.seconds, drilling=True)
        settings = EstimatorSettings(seed=seed, **{**TWIN_SETTINGS, "ensemble_size": options.members,
                                                   "bit_rock_coefficient": "a5"})
        result = estimate(case, record, settings, model=estimator_model(case, settings))
        correlation = result.parameter_correlation[("a5", "open_hole_friction")]
        a5 = result.mean["a5"][-1] / case.bit_rock.a5
        print(_line(f"drilling seed {seed}", result) + f" a5/case {a5:.3f} corr(log a5, log mu) {correlation:+.2f}",
              flush=True)


if __name__ == "__main__":
    np.set_printoptions(precision=4)
    main()
