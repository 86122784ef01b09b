"""What sets the step count of a realization, and the solve's floor: one realization of a case (default
``reference``, its own run length) solved with DOPRI5 at a sweep of relative tolerances (the absolute tolerance
scaled with it), one core; per tolerance the accepted and rejected steps, the right-hand sides, the CPU time of
the solve and its cost per right-hand side, and the records' largest difference from the tightest run (ROP, bit
speed, TOB, FOB; relative to each record's largest magnitude). Then, at a state of the case's limit cycle
(``--at`` seconds), the components of DOPRI5's weighted error estimate at the case's mean step: which modes
carry it (the modal coordinate of each of the largest terms, its family and frequency). Run:

    .venv/bin/python benchmarks/step_floor.py [--case reference] [--rtols 1e-7,1e-6,1e-5,1e-4,1e-3,1e-2]
        [--at 3.0] [--repeat 3]
"""

from __future__ import annotations

import argparse
import os
import time

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

RECORDS = ("rate_of_penetration", "bit_speed", "torque_on_bit", "force_on_bit")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--case", default="reference")
    parser.add_argument("--rtols", default="1e-7,1e-6,1e-5,1e-4,1e-3,1e-2")
    parser.add_argument("--at", type=float, default=3.0, help="time of the state whose error estimate is split [s]")
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {max(os.sched_getaffinity(0))})
    import numpy as np

    from drillstring.case import load_case
    from drillstring.dynamics.compiled import RunState, SolverSettings, advance
    from drillstring.dynamics.rom import OBSERVABLE_COLUMN, case_reduced_model
    from drillstring.dynamics.runge_kutta import DORMAND_PRINCE_54
    from drillstring.dynamics.steps.explicit_rk import ReferenceStep

    case = load_case(args.case)
    s = case.simulation
    model = case_reduced_model(case)
    y0 = model.initial_state(case.initial.lateral_perturbation, case.initial.seed)
    grid = np.arange(0.0, s.t_end + 0.5 * s.output_step, s.output_step)
    rtols = sorted(float(r) for r in args.rtols.split(","))
    runs = {}
    for rtol in rtols:
        solver = SolverSettings(method="dopri5", rtol=rtol, atol=s.atol * rtol / s.rtol)
        advance(model, solver, RunState.start(model, y0), s.t_end, output_times=grid)
        cpu = []
        for _ in range(args.repeat):
            start = time.process_time()
            result = advance(model, solver, RunState.start(model, y0), s.t_end, output_times=grid)
            cpu.append(time.process_time() - start)
        runs[rtol] = (result, min(cpu))
    tight = runs[rtols[0]][0].outputs
    print(f"case {args.case}: {model.state_size} states, t_end {s.t_end} s, DOPRI5, atol = {s.atol:g} x rtol / "
          f"{s.rtol:g}, one core, best CPU of {args.repeat}")
    print("rtol      accepted  rejected  RHS      CPU [s]  us/RHS  steps vs case rtol  records vs tightest")
    base = runs.get(s.rtol, runs[rtols[0]])[0].stats["n_accepted"]
    for rtol in rtols:
        result, cpu = runs[rtol]
        st = result.stats
        worst = 0.0
        for name in RECORDS:
            col = OBSERVABLE_COLUMN[name]
            scale = np.max(np.abs(tight[:, col])) or 1.0
            worst = max(worst, float(np.max(np.abs(result.outputs[:, col] - tight[:, col])) / scale))
        print(f"{rtol:<9.0e} {st['n_accepted']:<9d} {st['n_rejected']:<9d} {st['n_rhs']:<8d} {cpu:<8.4f} "
              f"{cpu / st['n_rhs'] * 1e6:<7.2f} {base / st['n_accepted']:<19.2f} {worst:.1e}")
    # the error estimate's components at a state of the limit cycle, at the case's mean step
    solver = SolverSettings(method="dopri5", rtol=s.rtol, atol=s.atol)
    at = advance(model, solver, RunState.start(model, y0), args.at)
    mean_step = args.at / max(at.stats["n_accepted"], 1)
    step = ReferenceStep(DORMAND_PRINCE_54, at.state.y)
    y_new, err, _, _ = step.attempt(model.rhs, at.state.t, mean_step, at.state.y, model.rhs(at.state.t, at.state.y))
    scale = s.atol + s.rtol * np.maximum(np.abs(at.state.y), np.abs(y_new))
    weighted = (err / scale) ** 2
    norm = np.sqrt(weighted.mean())
    n = model.size
    print(f"at t = {at.state.t:.3f} s, h = {mean_step * 1e3:.3f} ms (the mean step so far): error norm {norm:.3f}; "
          "largest shares of its square:")
    for i in np.argsort(weighted)[::-1][:8]:
        column = i % n if i < 2 * n else None
        what = "velocity" if n <= i < 2 * n else ("displacement" if i < n else "controller state")
        family = model.family[column] if column is not None else "-"
        omega = model.angular_frequencies[column] if column is not None else float("nan")
        print(f"  state {i:4d}: {what} of mode {column} ({family}, omega = {omega:.1f} rad/s): "
              f"{weighted[i] / weighted.sum():.3f}")


if __name__ == "__main__":
    main()
