"""Cost of the convergence check of the roots of steady drilling (issue 37, item 2).

    python benchmarks/bench_root_convergence.py [--cases aarsnes2019 aarsnes2019_paper reference] [--repeats 3]

For each case, in the same process: the reduced model and :func:`~drillstring.dynamics.stability.stability`
without the check (the baseline), and the larger basis (:func:`~drillstring.dynamics.stability.larger_basis`,
twice the modes of every family) with the check (:func:`~drillstring.dynamics.stability.check_convergence`).
CPU seconds, best of ``--repeats``, and the ratio of the whole with the check to the baseline; the roots checked
and how many did not converge. One BLAS thread.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import time  # noqa: E402

from drillstring.case import load_case  # noqa: E402
from drillstring.dynamics.rom import case_reduced_model  # noqa: E402
from drillstring.dynamics.stability import check_convergence, larger_basis, stability  # noqa: E402


def _best(function, repeats: int):
    best, value = float("inf"), None
    for _ in range(repeats):
        start = time.process_time()
        value = function()
        best = min(best, time.process_time() - start)
    return best, value


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", nargs="+", default=["aarsnes2019", "aarsnes2019_paper", "reference"])
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    print(f"{'case':20s} {'model [s]':>10s} {'stability [s]':>14s} {'larger [s]':>11s} {'check [s]':>10s} "
          f"{'ratio':>6s} {'checked':>8s} {'unconv.':>8s}")
    for name in args.cases:
        case = load_case(name)
        build, model = _best(lambda: case_reduced_model(case), args.repeats)
        plain, result = _best(lambda: stability(model), args.repeats)
        grow, larger = _best(lambda: larger_basis(case, model), args.repeats)
        check, (_, facts) = _best(lambda: check_convergence(result.modes, larger), args.repeats)
        ratio = (build + plain + grow + check) / (build + plain)
        print(f"{name:20s} {build:10.3f} {plain:14.3f} {grow:11.3f} {check:10.3f} {ratio:6.2f} "
              f"{facts['checked']:8d} {facts['unconverged']:8d}", flush=True)


if __name__ == "__main__":
    main()
