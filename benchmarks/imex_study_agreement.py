"""Do the IMEX pairs change a study's statistics? Paired realizations of a case with a random weight-on-bit
(Normal, 5 % dispersion, seeded), each run with compiled DOPRI5 and with the IMEX methods; per cycle metric
(:func:`drillstring.dynamics.indicators.cycle_metrics`) the DOPRI5 mean, its Monte Carlo standard error
(σ/√N), each method's mean and the mean paired difference with its standard error, also relative to the
DOPRI5 mean with the bound |mean| + 2 SE (about 95 %); and the total solving times. Every run uses the method
given here, whatever the case file's ``simulation.method``. Run:

    PYTHONPATH=src python benchmarks/imex_study_agreement.py aarsnes2019 --samples 16 [--methods ark43]
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import math  # noqa: E402

import numpy as np  # noqa: E402

from drillstring.case import load_case  # noqa: E402
from drillstring.dynamics.indicators import CYCLE_METRICS, bit_area, cycle_metrics, transient_end  # noqa: E402
from drillstring.dynamics.rom import case_reduced_model  # noqa: E402
from drillstring.dynamics.simulate import simulate_model  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("case")
    parser.add_argument("--samples", type=int, default=16)
    parser.add_argument("--methods", default="ark43")
    parser.add_argument("--dispersion", type=float, default=0.05)
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()
    base = load_case(args.case)
    s = base.simulation
    methods = ["dopri5", *args.methods.split(",")]
    rng = np.random.default_rng(args.seed)
    values = {m: {k: [] for k in CYCLE_METRICS} for m in methods}
    seconds = {m: 0.0 for m in methods}
    for i in range(args.samples):
        wob = base.operation.weight_on_bit * (1.0 + args.dispersion * rng.standard_normal())
        case = base.model_copy(update={"operation": base.operation.model_copy(update={"weight_on_bit": wob})})
        model = case_reduced_model(case)
        for m in methods:
            r = simulate_model(model, t_end=s.t_end, output_step=s.output_step, rtol=s.rtol, atol=s.atol, method=m,
                               lateral_perturbation=case.initial.lateral_perturbation, seed=case.initial.seed,
                               raise_on_failure=False)
            seconds[m] += r.stats["wall_time"]
            metrics = cycle_metrics(r.time, r.observables, case.operation.top_speed, bit_area(case),
                                    transient_end(s.t_end))
            for k in CYCLE_METRICS:
                values[m][k].append(metrics[k])
        print(f"realization {i + 1}/{args.samples}: weight on bit {wob:.0f} N", flush=True)
    n = args.samples
    print(f"case {args.case}: {n} paired realizations, weight on bit ±{args.dispersion:.0%}, case rtol {s.rtol:g}")
    print("solving time: " + ", ".join(f"{m} {seconds[m]:.1f} s" for m in methods)
          + "; " + ", ".join(f"speed-up vs dopri5: {seconds['dopri5'] / seconds[m]:.1f}x ({m})" for m in methods[1:]))
    for k in CYCLE_METRICS:
        ref = np.array(values["dopri5"][k])
        if not np.all(np.isfinite(ref)):
            continue
        error = ref.std(ddof=1) / math.sqrt(n)
        line = f"  {k}: dopri5 {ref.mean():.5g} ± {error:.2g} (MC standard error)"
        for m in methods[1:]:
            x = np.array(values[m][k])
            diff = x - ref
            spread = diff.std(ddof=1) / math.sqrt(n)
            scale = abs(ref.mean())
            relative = (f", {100 * diff.mean() / scale:+.2f} % ± {100 * spread / scale:.2f} %"
                        f" (|mean| + 2 SE: {100 * (abs(diff.mean()) + 2 * spread) / scale:.2f} %)"
                        if scale > 0 else "")
            line += (f"; {m} {x.mean():.5g}, paired difference {diff.mean():+.2g} ± {spread:.2g}{relative}"
                     f" ({abs(diff.mean()) / error if error > 0 else 0.0:.2f} MC errors)")
        print(line)


if __name__ == "__main__":
    main()
