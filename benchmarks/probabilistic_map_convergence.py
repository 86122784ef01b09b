"""Convergence in N of the probabilities of a probabilistic operating map of the reference case.

Runs ``--samples`` realizations per point (weight-on-hook Normal around each point's hook load, σ =
``--sigma``) at the points ``--top-speed`` × ``--weight-on-bit``, then, since realization s of a map seeded
``seed`` depends only on (seed, s), reads the maps of N = 16, 64, ... realizations as the first N of them
(exactly what ``drillstring map --samples N`` with the same seed computes). Prints, per point and N, the
estimate P̂ of each probability, and for the buckling probability its closed form
P = Φ((wob − wob_cr)/σ), |P̂ − P| and the binomial standard error sqrt(P(1 − P)/N). Run:

    .venv/bin/python benchmarks/probabilistic_map_convergence.py [--samples 256] [--keep DIR]
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

import numpy as np
from scipy import stats

from drillstring import api
from drillstring.stochastic.probabilistic_map import PROBABILITIES
from drillstring.stochastic.store import DONE


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--top-speed", default="100 rpm")
    parser.add_argument("--weight-on-bit", default="104 kN,114 kN,124 kN")
    parser.add_argument("--samples", type=int, default=256)
    parser.add_argument("--sigma", type=float, default=5000.0)
    parser.add_argument("--t-end", type=float, default=10.0)
    parser.add_argument("--workers", type=int, default=None)
    parser.add_argument("--out", type=Path, required=True, help="the map's folder (resumable)")
    parser.add_argument("--json", type=Path, default=None, help="write the table as JSON here")
    args = parser.parse_args()
    outcome = api.operating_map("reference", top_speed=args.top_speed, weight_on_bit=args.weight_on_bit,
                                t_end=args.t_end, samples=args.samples, sigma=args.sigma, out=args.out,
                                workers=args.workers)
    ds = outcome.dataset
    critical = float(ds.attrs["critical_weight_on_bit"])
    counts = [n for n in (16, 64, 256, 1024, 4096) if n <= args.samples]
    rows = []
    print(f"critical weight-on-bit {critical / 1e3:.2f} kN, sigma {args.sigma / 1e3:g} kN, "
          f"wall time {outcome.summary['wall_time']:.0f} s")
    print(f"{'rpm':>5} {'WOB kN':>7} {'N':>5} {'P':>7} {'P^':>7} {'|P^-P|':>7} {'se(P)':>7} "
          + " ".join(f"{name.split('_probability')[0][:11]:>11}" for name in PROBABILITIES))
    for i, speed in enumerate(ds.top_speed.values):
        for j, wob in enumerate(ds.weight_on_bit.values):
            exact = float(stats.norm.cdf((wob - critical) / args.sigma))
            for n in counts:
                done = ds.status.values[i, j, :n] == DONE
                estimates = {}
                for name, (output, event, _) in PROBABILITIES.items():
                    with np.errstate(invalid="ignore"):
                        estimates[name] = float((event(ds[output].values[i, j, :n]) & done).sum() / done.sum())
                error = abs(estimates["buckling_probability"] - exact)
                se = math.sqrt(exact * (1 - exact) / n)
                rows.append({"top_speed": float(speed), "weight_on_bit": float(wob), "n": n, "exact": exact,
                             "abs_error": error, "standard_error": se, **estimates})
                print(f"{speed * 30 / math.pi:5.0f} {wob / 1e3:7.1f} {n:5d} {exact:7.4f} "
                      f"{estimates['buckling_probability']:7.4f} {error:7.4f} {se:7.4f} "
                      + " ".join(f"{estimates[name]:11.4f}" for name in PROBABILITIES))
    if args.json:
        args.json.write_text(json.dumps({"critical_weight_on_bit": critical, "sigma": args.sigma,
                                         "t_end": args.t_end, "wall_time": outcome.summary["wall_time"],
                                         "rows": rows}, indent=2) + "\n")


if __name__ == "__main__":
    main()
