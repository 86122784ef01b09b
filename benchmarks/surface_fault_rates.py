"""The surface-record fault tests' false-positive rates and the smallest spike they find
(drillstring.estimation.faults; docs/estimation.md, "Faults").

    python benchmarks/surface_fault_rates.py [--draws 20]

False positives: samples flagged in white Gaussian noise (100,000 samples a draw, logged at 0.1 σ) and in the
shipped synthetic record's true surface channels plus noise at its levels (801 samples a draw), by Hampel's
filter at 4, 5 and 6 robust σ (6 is the one used), by the test against the local trend at 6, 7 and 8 noise σ
(8 is the one used) and by the frozen test. Detection: the fraction of single-sample spikes of k noise σ found
at random samples of the stick-slip series, per channel, by the two spike tests together (as flag_faults runs
them).
"""

from __future__ import annotations

import argparse
from importlib import resources

import numpy as np

from drillstring.estimation.faults import frozen, spikes, trend_spikes
from drillstring.estimation.synthetic import NOISE, read_truth


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--draws", type=int, default=20)
    args = parser.parse_args()
    truth = read_truth(resources.files("drillstring").joinpath("cases", "stick_slip_surface_truth.csv"))[1]
    rng = np.random.default_rng(0)
    print("false positives (samples flagged / samples tested)")
    for test, thresholds in ((spikes, (4.0, 5.0, 6.0)), (trend_spikes, (6.0, 7.0, 8.0))):
        for threshold in thresholds:
            gauss = stick = 0
            n_gauss = n_stick = 0
            for _ in range(args.draws):
                x = np.round(rng.standard_normal(100_000), 1)
                gauss += int(test(x, threshold=threshold).sum())
                n_gauss += len(x)
                for name, sigma in NOISE.items():
                    y = truth[name] + sigma * rng.standard_normal(len(truth["time"]))
                    stick += int(test(y, threshold=threshold).sum())
                    n_stick += len(y)
            print(f"  {test.__name__} {threshold:g} sigma: white noise {gauss}/{n_gauss}, stick-slip record "
                  f"{stick}/{n_stick}")
    frozen_white = sum(int(frozen(np.round(rng.standard_normal(100_000), 1))[0].sum()) for _ in range(args.draws))
    frozen_stick = sum(int(frozen(np.round(truth[name] + sigma * rng.standard_normal(len(truth["time"])), 6))[0].sum())
                       for _ in range(args.draws) for name, sigma in NOISE.items())
    print(f"  frozen: white noise {frozen_white}/{args.draws * 100_000}, stick-slip record "
          f"{frozen_stick}/{args.draws * len(NOISE) * len(truth['time'])}")
    print("single spikes of k noise sigma found (fraction of 200 random samples), both spike tests")
    for name, sigma in NOISE.items():
        found = []
        for k in (6, 8, 10, 15, 20):
            hits = 0
            for i in rng.choice(np.arange(20, len(truth["time"]) - 20), 200):
                y = truth[name] + sigma * rng.standard_normal(len(truth["time"]))
                y[i] += k * sigma * rng.choice([-1, 1])
                hits += bool(spikes(y)[i] or trend_spikes(y)[i])
            found.append(f"{k}: {hits / 200:.2f}")
        print(f"  {name} (sigma {sigma:.3g} SI): " + ", ".join(found))


if __name__ == "__main__":
    main()
