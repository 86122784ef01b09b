"""Benchmark: one realization of the `contact` case (case 2 and case 1) on one core, against the
reference case's realization (case 2) measured in the same run.

The contact case whirls and hits the borehole: impacts make the step size collapse at each contact
and the lateral basis is the default cut-off's (every mode below 1.5x the rotation frequency: 83 per
plane). Goals (issue 10): <= 2 s for case 2 and <= 30 s for case 1, model build included. Run:

    .venv/bin/python benchmarks/bench_contact.py [--repeat 3] [--skip-full]
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import time  # noqa: E402

from drillstring.case import load_case  # noqa: E402
from drillstring.dynamics.compiled import prepare_kernels  # noqa: E402
from drillstring.dynamics.rom import case_reduced_model  # noqa: E402
from drillstring.dynamics.simulate import simulate_model  # noqa: E402


def one_run(case, nonlinear):
    """(build [s], integration [s], CPU of both [s], result) of one realization with the case's settings."""
    s = case.simulation
    wall, cpu = time.perf_counter(), time.process_time()
    model = case_reduced_model(case, nonlinear=nonlinear)
    build = time.perf_counter() - wall
    start = time.perf_counter()
    result = simulate_model(model, t_end=s.t_end, output_step=s.output_step, rtol=s.rtol, atol=s.atol,
                            lateral_perturbation=case.initial.lateral_perturbation, seed=case.initial.seed)
    return build, time.perf_counter() - start, time.process_time() - cpu, result, model


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--skip-full", action="store_true", help="case 2 only")
    args = parser.parse_args()
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})  # one core
    runs = [("reference", "bit_and_contact", "baseline: reference, case 2"),
            ("contact", "bit_and_contact", "contact, case 2 (bit-rock + contact)")]
    if not args.skip_full:
        runs.append(("contact", "full", "contact, case 1 (full nonlinear)"))
    for name, nonlinear, _ in runs:  # compile (or load) the kernels outside the timings
        prepare_kernels(case_reduced_model(load_case(name), nonlinear=nonlinear))
    best = {}
    for name, nonlinear, label in runs:
        case = load_case(name)
        timings = [one_run(case, nonlinear) for _ in range(args.repeat)]
        build, solve, cpu, result, model = min(timings, key=lambda t: t[0] + t[1])
        best[label] = build + solve
        lateral = model.family.count("lateral_y")
        print(f"{label}: {model.static.mesh.n_elements} elements, {model.size} modal coordinates "
              f"({lateral} lateral per plane), t_end = {case.simulation.t_end:g} s")
        print(f"    build {build:.3f} s + integration {solve:.3f} s = {build + solve:.3f} s (CPU {cpu:.3f} s); "
              f"{result.stats['n_accepted']} steps accepted, {result.stats['n_rejected']} rejected, "
              f"{result.stats['n_rhs']} RHS evaluations; {result.impacts} impacts")
    baseline = best[runs[0][2]]
    print(f"best of {args.repeat}, one core; relative to the baseline ({baseline:.3f} s):")
    for (_, nonlinear, label), goal in zip(runs[1:], (2.0, 30.0)):
        verdict = "meets" if best[label] <= goal else "MISSES"
        print(f"    {label}: {best[label]:.3f} s = {best[label] / baseline:.1f}x the baseline; "
              f"goal <= {goal:g} s: {verdict}")


if __name__ == "__main__":
    main()
