"""Benchmark: the Campbell diagram at interactive speed (issue 26).

The lateral whirl of the reference string is a symmetric eigenproblem of 2 × 320 roots per speed (0.02 s
each): solved at every speed, 3,000 speeds took about 60 s. :func:`drillstring.critical_speeds.lateral_whirl`
solves it exactly at a few speeds and interpolates between them (cubic Hermite on the roots and their
Hellmann–Feynman slopes, every interval checked at its middle against an exact solution). Measured here,
in one process and the same run, one BLAS thread:

- ``exact at every speed``: the baseline, each speed solved (the former algorithm), on ``--baseline-speeds``
  speeds (default 300), its time per speed extrapolated to the others;
- ``checked interpolation``: the diagram's lateral whirl over 300, 3,000 and 10,000 speeds (5-300 rpm),
  with the number of exact solutions it needed and its largest difference from the baseline's exact roots
  (at the baseline's speeds);
- ``api.campbell``: the whole diagram (all families, excitation lines, critical speeds) over 3,000 speeds.

Run from the repository root:

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_campbell.py [--case reference]
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np
import scipy.linalg as sla

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--case", default="reference")
    parser.add_argument("--baseline-speeds", type=int, default=300)
    args = parser.parse_args()

    from drillstring import api
    from drillstring import critical_speeds as cs
    from drillstring.case import load_case
    from drillstring.fem.assembly import gyroscopic_matrix
    from drillstring.modal import case_linear_system, family_modes, family_modes_below
    from drillstring.statics import case_static_state

    case = load_case(args.case)
    system = case_linear_system(case, case_static_state(case))
    rpm = 2.0 * math.pi / 60.0
    cutoff = 2.0 * math.pi * cs.DEFAULT_BLADES * 300.0 * rpm / (2.0 * math.pi)
    basis = max(20, len(family_modes_below(system, "lateral_y", 1, 2.0 * cutoff).frequencies))
    phi = family_modes(system, "lateral_y", basis).shapes
    lam = family_modes(system, "lateral_y", basis).eigenvalues
    h = phi.T @ (gyroscopic_matrix(system.mesh) @ cs.turned_plane(system.mesh, phi))
    h = 0.5 * (h + h.T)
    print(f"case {case.name!r}: {basis} lateral modes per plane in the basis (eigenproblem of {2 * basis})")

    base_speeds = np.linspace(5.0, 300.0, args.baseline_speeds) * rpm
    root = np.diag(np.sqrt(lam))
    start = time.perf_counter()
    exact = []
    for spin in base_speeds:  # the former algorithm: the roots alone (no eigenvectors), at every speed
        theta = sla.eigh(np.block([[np.zeros((basis, basis)), root], [root, spin * h]]), eigvals_only=True)
        exact.append((theta[basis:], -theta[:basis][::-1]))
    per_speed = (time.perf_counter() - start) / len(base_speeds)
    exact_f = np.array([e[0] for e in exact])
    exact_b = np.array([e[1] for e in exact])
    print(f"exact at every speed: {per_speed * 1e3:.1f} ms per speed")

    print(f"{'speeds':>7s} {'exact [s]':>10s} {'interpolated [s]':>17s} {'solutions':>10s} {'speed-up':>9s} "
          f"{'max error [Hz]':>15s}")
    for count in (args.baseline_speeds, 3000, 10000):
        speeds = np.linspace(5.0, 300.0, count) * rpm
        solves = []
        start = time.perf_counter()
        forward, backward, _, _ = cs.lateral_whirl(system, speeds, basis, progress=lambda d, t: solves.append(d))
        took = time.perf_counter() - start
        error = ""
        if count == args.baseline_speeds:
            worst = max(np.abs(forward - exact_f).max(), np.abs(backward - exact_b).max())
            error = f"{worst / (2.0 * math.pi):.2e}"
        baseline = per_speed * count
        print(f"{count:7d} {baseline:10.2f} {took:17.2f} {solves[-1]:10d} {baseline / took:8.1f}x {error:>15s}")

    start = time.perf_counter()
    diagram = api.campbell(case, top_speed="5 rpm:300 rpm:3000")
    took = time.perf_counter() - start
    print(f"api.campbell, 3,000 speeds: {took:.2f} s ({len(diagram.curves)} curves, "
          f"{len(diagram.critical_speeds)} critical speeds)")


if __name__ == "__main__":
    main()
