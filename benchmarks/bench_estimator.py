"""Benchmark: the ensemble estimator (drillstring.estimation.ensemble) on a twin experiment of the stick-slip case.

A truth from another model than the estimator's (tests/estimation/twin.py: the case's full basis with lateral
modes and contact, random reduced matrices of dispersion 0.05, a5 1.3 times the case's, the hook-load sensor
reading 15 kN high), its surface channels sampled at 1 Hz with noise. For each ensemble size: the real-time factor
(record seconds per wall second, pinned to one core, model build and compilation excluded), the 90 % bands'
coverage of the truth's bit speed and torque on bit after a spin-up, the bit-speed RMSE against the surface-only
guess (bit speed = top speed), the stick-slip index's coverage, and the parameters recovered at the end. Run:

    .venv/bin/python benchmarks/bench_estimator.py [--t-end 300] [--sizes 16 32 64] [--spin-up 10]
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))
sys.path.insert(0, str(ROOT / "tests" / "estimation"))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--t-end", type=float, default=300.0, help="record length [s]")
    parser.add_argument("--sizes", type=int, nargs="+", default=[16, 32, 64], help="ensemble sizes")
    parser.add_argument("--spin-up", type=float, default=10.0, help="start left out of the scores [s]")
    parser.add_argument("--seed", type=int, default=0, help="the estimator's seed")
    args = parser.parse_args()
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})
    from twin import twin

    from drillstring.case import load_case
    from drillstring.estimation.ensemble import (
        EstimatorSettings,
        estimate,
        estimator_model,
    )

    case = load_case("stick_slip")
    begin = time.perf_counter()
    truth = twin(case, args.t_end)
    print(f"truth: {args.t_end:g} s of stick_slip in {time.perf_counter() - begin:.1f} s (1 Hz record, 4 channels)")
    model = estimator_model(case, EstimatorSettings())
    estimate(case, truth.record.__class__.from_arrays(truth.time[:3], top_speed=truth.record.channels["top_speed"][:3]),
             EstimatorSettings(ensemble_size=4, spin_up=0.0), model=model)  # compile / load the kernels
    naive = None
    print(f"{'members':>8} {'wall [s]':>9} {'real-time x':>12} {'cov bit speed':>14} {'cov TOB':>8} "
          f"{'cov SSI':>8} {'RMSE ratio':>11} {'a5 [N m] 5/50/95 %':>26} {'bias [kN] 5/50/95 %':>22} {'replaced':>9}")
    for size in args.sizes:
        settings = EstimatorSettings(ensemble_size=size, seed=args.seed, spin_up=0.0)  # the twin starts at t = 0
        begin = time.perf_counter()
        result = estimate(case, truth.record, settings, model=model)
        wall = time.perf_counter() - begin
        keep = result.time >= args.spin_up
        error = np.sqrt(np.mean((result.mean["bit_speed"] - truth.truth["bit_speed"])[keep] ** 2))
        naive = np.sqrt(np.mean((truth.record.channels["top_speed"] - truth.truth["bit_speed"])[keep] ** 2))
        index = truth.stick_slip_index(settings.stick_slip_window)
        a5 = result.quantiles["a5"][-1]
        bias = result.quantiles["weight_on_bit_bias"][-1] / 1e3
        print(f"{size:>8} {wall:>9.1f} {args.t_end / wall:>12.2f} "
              f"{result.coverage('bit_speed', truth.truth['bit_speed'], args.spin_up):>14.3f} "
              f"{result.coverage('torque_on_bit', truth.truth['torque_on_bit'], args.spin_up):>8.3f} "
              f"{result.coverage('stick_slip_index', index, settings.stick_slip_window):>8.3f} "
              f"{naive / error:>11.1f} {'/'.join(f'{v:.0f}' for v in a5):>26} "
              f"{'/'.join(f'{v:.1f}' for v in bias):>22} {result.replaced_members:>9}", flush=True)
    print(f"truth: a5 = {truth.coefficient:.0f} N m (prior centred on {case.bit_rock.a5:.0f}), weight-on-bit bias "
          f"{truth.bias / 1e3:.1f} kN (prior 0); surface-only bit-speed RMSE {naive:.2f} rad/s")


if __name__ == "__main__":
    main()
