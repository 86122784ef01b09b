"""Benchmark: one reference drilling run (case 2) on one core, against SciPy's solve_ivp(RK45), and the
implicit–explicit methods (``--imex``, default ark43 and ark32: docs/model.md §9) against compiled DOPRI5
at the case's tolerances: ``speed-up vs dopri5: N.Nx`` per method with its right-hand-side and Jacobian
counts and its largest relative deviation from the DOPRI5 records (``benchmarks/imex_accuracy.py`` compares
at several tolerances, with the cycle metrics).

Both integrate the same reduced-order model (same right-hand side, same rtol/atol, same output grid)
in the same process, so the ratio is meaningful on a noisy machine. Run:

    .venv/bin/python benchmarks/bench_simulate.py [--repeat 3] [--case reference] [--nonlinear full]
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402
from scipy.integrate import solve_ivp  # noqa: E402

from drillstring.case import load_case  # noqa: E402
from drillstring.dynamics import compiled  # noqa: E402
from drillstring.dynamics.rom import case_reduced_model  # noqa: E402
from drillstring.dynamics.simulate import simulate_model  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--case", default="reference")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--nonlinear", choices=("bit_and_contact", "full"), default=None,
                        help="case 2 (default of the case) or case 1 (full nonlinear model)")
    parser.add_argument("--imex", default="ark43,ark32", help="IMEX methods to time against DOPRI5 ('' for none)")
    parser.add_argument("--imex-only", action="store_true", help="skip the reference path and solve_ivp")
    args = parser.parse_args()
    imex = [m for m in args.imex.split(",") if m]
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})  # one core
    case = load_case(args.case)
    s = case.simulation
    t0 = time.perf_counter()
    model = case_reduced_model(case, nonlinear=args.nonlinear)
    build = time.perf_counter() - t0
    y0 = model.initial_state(case.initial.lateral_perturbation, case.initial.seed)
    model.rhs(0.0, y0)  # compile / load the kernels outside the timings
    for method in ("dopri5", *imex):
        compiled.prepare_kernels(model, method)
    kwargs = dict(t_end=s.t_end, output_step=s.output_step, rtol=s.rtol, atol=s.atol,
                  lateral_perturbation=case.initial.lateral_perturbation, seed=case.initial.seed)

    timings: dict[str, list[float]] = {k: [] for k in ("compiled", "unpaused", "reference", "ivp_numpy",
                                                       "ivp_compiled", *imex)}
    imex_results = {}
    for _ in range(args.repeat):
        start = time.perf_counter()
        result = simulate_model(model, engine="compiled", **kwargs)
        timings["compiled"].append(time.perf_counter() - start)
        # the compiled loop without its pauses (one call per chunk of the output grid, as before issue 19)
        pauses = compiled.FIRST_CALL_ATTEMPTS, compiled.CALL_SECONDS
        compiled.FIRST_CALL_ATTEMPTS, compiled.CALL_SECONDS = 10**12, 1e12
        start = time.perf_counter()
        simulate_model(model, engine="compiled", **kwargs)
        timings["unpaused"].append(time.perf_counter() - start)
        compiled.FIRST_CALL_ATTEMPTS, compiled.CALL_SECONDS = pauses
        for method in imex:
            start = time.perf_counter()
            imex_results[method] = simulate_model(model, engine="compiled", method=method, **kwargs)
            timings[method].append(time.perf_counter() - start)
        if args.imex_only:
            continue
        start = time.perf_counter()
        reference = simulate_model(model, engine="reference", **kwargs)
        timings["reference"].append(time.perf_counter() - start)
        grid = result.time
        start = time.perf_counter()
        baseline = solve_ivp(model.rhs_reference, (0.0, s.t_end), y0, method="RK45", t_eval=grid,
                             rtol=s.rtol, atol=s.atol)
        timings["ivp_numpy"].append(time.perf_counter() - start)
        start = time.perf_counter()
        compiled_rhs = solve_ivp(model.rhs, (0.0, s.t_end), y0, method="RK45", t_eval=grid,
                                 rtol=s.rtol, atol=s.atol)
        timings["ivp_compiled"].append(time.perf_counter() - start)
    best = {k: min(v) for k, v in timings.items() if v}
    for method in imex:
        st = imex_results[method].stats
        deviation = max(np.max(np.abs(imex_results[method].observables[k] - result.observables[k]))
                        / np.max(np.abs(result.observables[k])) for k in ("rate_of_penetration", "bit_speed",
                                                                          "torque_on_bit", "force_on_bit"))
        print(f"{method} (compiled, case rtol): {best[method]:.3f} s; RHS evaluations {st['n_rhs']}, Jacobians "
              f"{st['n_jacobians']}, accepted {st['n_accepted']}, rejected {st['n_rejected']}; records within "
              f"{deviation:.1e} of DOPRI5's; speed-up vs dopri5: {best['compiled'] / best[method]:.1f}x")
    if args.imex_only:
        print(f"dopri5 (compiled): {best['compiled']:.3f} s; RHS evaluations {result.stats['n_rhs']}, "
              f"accepted {result.stats['n_accepted']}, rejected {result.stats['n_rejected']}")
        return
    rop = result.observables["rate_of_penetration"]
    ref_rop = np.array([model.observe(t, y)[0] for t, y in zip(baseline.t, baseline.y.T)])
    agreement = np.max(np.abs(rop - ref_rop)) / np.max(np.abs(ref_rop))
    print(f"case {args.case} ({model.nonlinear}): {model.static.mesh.n_elements} elements, {model.size} modal coordinates,"
          f" t_end = {s.t_end} s, rtol = {s.rtol}, atol = {s.atol}, one core, best of {args.repeat}")
    print(f"model build (mesh, statics, modes, projection): {build:.3f} s")
    print(f"fast path (compiled DOPRI5 + compiled RHS):   {best['compiled']:.3f} s;"
          f" RHS evaluations {result.stats['n_rhs']}, accepted {result.stats['n_accepted']},"
          f" rejected {result.stats['n_rejected']}")
    print(f"fast path without pauses (Ctrl-C checks):     {best['unpaused']:.3f} s; with them "
          f"{best['compiled'] / best['unpaused']:.3f}x")
    print(f"reference path (Python DOPRI5 + NumPy RHS):   {best['reference']:.3f} s;"
          f" RHS evaluations {reference.stats['n_rhs']}")
    print(f"baseline solve_ivp RK45 + NumPy RHS:           {best['ivp_numpy']:.3f} s;"
          f" RHS evaluations {baseline.nfev}")
    print(f"solve_ivp RK45 + our compiled RHS:             {best['ivp_compiled']:.3f} s;"
          f" RHS evaluations {compiled_rhs.nfev}")
    print(f"speed-up of the fast path: {best['ivp_numpy'] / best['compiled']:.1f}x vs the baseline,"
          f" {best['ivp_compiled'] / best['compiled']:.1f}x vs solve_ivp with the compiled RHS,"
          f" {best['reference'] / best['compiled']:.1f}x vs the reference path")
    print(f"max ROP difference fast path vs baseline: {agreement:.2e} (relative)")
    goal = "120 s (case 1)" if model.nonlinear == "full" else "0.3 s (case 2, with the torsional limit cycle)"
    print(f"one full run incl. model build: {build + best['compiled']:.3f} s (goal <= {goal})")


if __name__ == "__main__":
    main()
