"""The README's first case (``my_case.toml``): what one realization of its study costs, and why.

    python benchmarks/first_case.py [--t-end 30] [--study]

The case is read from README.md itself (the TOML block saved as ``my_case.toml``), so the benchmark times
what a new user runs. One realization is what ``drillstring study my_case.toml`` computes per sample: the
reduced model built from the case (static state, modes, damping) and its run over ``t_end``. Each setting
below is timed in this process, kernels compiled (or loaded) beforehand so that no compilation is counted:

- ``dopri5`` — the default before ``simulation.method`` became ``"ark43"`` for new cases (the baseline);
- ``default`` — the case as loaded (``ark43``);
- ``dopri5, plain basis`` — ``truncation_correction = "none"``: without the attachment modes at the bit,
  to show that they (the bit's residual compliance under the bit–rock law) set DOPRI5's step;
- ``default, 20 lateral modes`` — ``lateral_cutoff = 0``: the per-step cost of the 163 lateral modes per
  plane below 1.5× the rotation frequency (the key that trades accuracy for time: fewer modes are right
  only while the string stays off the wall).

For each: the model's build time and the solve's time, both in CPU time of this process (one thread: on
a shared machine wall times vary with the load, CPU times much less; the solver's wall time is printed too),
accepted and rejected steps, right-hand sides and the time per right-hand side, the impacts, and the RMS
relative difference of the bit speed, ROP and torque on bit records from the baseline's (the baseline's own
error, at rtol/10, in the last line). ``--study`` also times the README's 20-sample study both ways
(``drillstring.api.monte_carlo_study``, local workers).
Ratios are against the baseline measured in the same run.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import re  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

README = Path(__file__).resolve().parents[1] / "README.md"
COMPARED = ("bit_speed", "rate_of_penetration", "torque_on_bit")


def readme_case_text() -> str:
    """The TOML of the README's first case: the fenced block after "Save this as `my_case.toml`"."""
    text = README.read_text(encoding="utf-8")
    found = re.search(r"Save this as `my_case\.toml`:\s*```toml\n(.*?)```", text, re.S)
    if found is None:
        raise SystemExit("README.md has no `my_case.toml` block")
    return found.group(1)


def _with(case, table: str, **values):
    return case.copy_with({table: getattr(case, table).copy_with(values)})


def realization(case) -> dict:
    """Build the reduced model of ``case`` and run it as a study realization does; times and counts."""
    from drillstring.dynamics.rom import case_reduced_model
    from drillstring.dynamics.simulate import simulate_model

    s = case.simulation
    start = time.process_time()
    model = case_reduced_model(case)
    build = time.process_time() - start
    start = time.process_time()
    result = simulate_model(model, t_end=s.t_end, output_step=s.output_step, rtol=s.rtol, atol=s.atol,
                            method=s.method, max_steps=s.max_steps, min_step=s.min_step,
                            lateral_perturbation=case.initial.lateral_perturbation, seed=case.initial.seed)
    solve = time.process_time() - start
    stats = result.stats
    return {"build": build, "solve": solve, "wall": stats["wall_time"], "steps": stats["n_accepted"],
            "rejected": stats["n_rejected"], "rhs": stats["n_rhs"], "impacts": result.impacts,
            "states": model.state_size, "lateral": model.family.count("lateral_y"),
            "records": {name: result.observables[name] for name in COMPARED}}


def rms_difference(records: dict, baseline: dict) -> float:
    """The largest over :data:`COMPARED` of the RMS difference relative to the baseline's RMS."""
    return max(float(np.sqrt(np.mean((records[n] - baseline[n]) ** 2)) / np.sqrt(np.mean(baseline[n] ** 2)))
               for n in COMPARED)


def prepare(cases) -> float:
    from drillstring.dynamics.compiled import prepare_kernels
    from drillstring.dynamics.rom import case_reduced_model

    start = time.perf_counter()
    model = case_reduced_model(_with(cases[0], "reduced_model", lateral_cutoff=0.0))
    for method in sorted({case.simulation.method for case in cases}):
        prepare_kernels(model, method)
    return time.perf_counter() - start


def study_time(path: Path, method: str | None, samples: int) -> float:
    from drillstring.api import monte_carlo_study
    from drillstring.case import load_case

    case = load_case(str(path))
    if method is not None:
        case = _with(case, "simulation", method=method)
    with tempfile.TemporaryDirectory() as folder:
        start = time.perf_counter()
        monte_carlo_study(case, samples=samples, out=Path(folder) / "study")
        return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--t-end", type=float, default=None, help="simulated time [s] (default: the case's)")
    parser.add_argument("--study", action="store_true", help="also time the README's 20-sample study")
    args = parser.parse_args()

    from drillstring.case import load_case

    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "my_case.toml"
        path.write_text(readme_case_text(), encoding="utf-8")
        case = load_case(str(path))
        if args.t_end is not None:
            case = _with(case, "simulation", t_end=args.t_end)
        settings = {
            "dopri5 (before)": _with(case, "simulation", method="dopri5"),
            "default (ark43)": case,
            "dopri5, plain basis": _with(_with(case, "simulation", method="dopri5"), "reduced_model",
                                         truncation_correction="none"),
            "default, 20 lateral modes": _with(case, "reduced_model", lateral_cutoff=0.0),
        }
        compile_time = prepare(list(settings.values()))
        print(f"README's first case, t_end = {case.simulation.t_end:g} s, rtol {case.simulation.rtol:g} "
              f"(kernels prepared in {compile_time:.1f} s, not counted); load average "
              f"{os.getloadavg()[0]:.1f}")
        print("| setting | states (lateral/plane) | build [s] | solve [s] (wall) | realization [s] | steps | "
              "rejected | RHS | us/RHS | impacts | records vs baseline | time ratio |")
        print("|---|---|---|---|---|---|---|---|---|---|---|---|")
        runs = {}
        for name, variant in settings.items():
            run = runs[name] = realization(variant)
            base = runs["dopri5 (before)"]
            total, base_total = run["build"] + run["solve"], base["build"] + base["solve"]
            print(f"| {name} | {run['states']} ({run['lateral']}) | {run['build']:.2f} | {run['solve']:.2f} "
                  f"({run['wall']:.2f}) | "
                  f"{total:.2f} | {run['steps']:,} | {run['rejected']} | {run['rhs']:,} | "
                  f"{1e6 * run['solve'] / run['rhs']:.1f} | {run['impacts']} | "
                  f"{rms_difference(run['records'], base['records']):.1e} | {base_total / total:.2f}x |",
                  flush=True)
        tight = realization(_with(settings["dopri5 (before)"], "simulation",
                                  rtol=case.simulation.rtol / 10))
        print(f"baseline's own error (dopri5 at rtol/10 against rtol): "
              f"{rms_difference(runs['dopri5 (before)']['records'], tight['records']):.1e}")
        if args.study:
            samples = 20
            before = study_time(path, "dopri5", samples)
            after = study_time(path, None, samples)
            print(f"study of {samples} samples (local workers): dopri5 {before:.1f} s, default {after:.1f} s: "
                  f"{before / after:.2f}x")


if __name__ == "__main__":
    main()
