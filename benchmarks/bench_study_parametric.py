"""Benchmark: the reference Monte Carlo study (weight-on-hook Normal, σ = 5 kN) with each realization's model
rebuilt and each realization written to the store alone (the recipe before issue 35, "rebuild") and with the
models from the study's parametric model (dynamics/reduced/parametric.py) and the store's batched writes
("parametric"), in the same run.

Prints, per recipe: the stages of a realization measured in this process (draw, law.apply, model, random
matrices, growth rates, simulation, metrics; mean over ``--profile`` realizations, one BLAS thread as in the
workers), the wall time of the whole study on ``--workers`` local processes, the mean realization time the store
records, and the ratio; then the study's printed tables (the dispersion table and the per-realization metrics,
as ``drillstring study`` prints them) of both recipes compared line by line, and the largest difference of the
envelopes (mean, std, 95 % quantile envelope of every observable over time) relative to each observable's range.
With ``--sobol`` also the build (rebuilt, and from the design's parametric model, which covers the inlet velocity
and the top speed too) and solve cost of runs of the 3-parameter Sobol' study (benchmarks/bench_sensitivity.py).
Run:

    .venv/bin/python benchmarks/bench_study_parametric.py [--samples 500] [--workers 2] [--profile 10] [--repeat 1]
        [--sobol 4]
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

from _engine import cores, load_average, timed_in_folder  # before NumPy

import numpy as np  # noqa: E402

from drillstring.case import load_case  # noqa: E402
from drillstring.dynamics.rom import case_reduced_model  # noqa: E402
from drillstring.dynamics.simulate import simulate_model  # noqa: E402
from drillstring.dynamics.growth_rates import family_growth_rates  # noqa: E402
from drillstring.stochastic import DEFAULT_SEED  # noqa: E402
from drillstring.stochastic import montecarlo as mc  # noqa: E402
from drillstring.stochastic import study_model  # noqa: E402
from drillstring.stochastic.execution import Engine  # noqa: E402
from drillstring.stochastic.random_matrices import model_generator, random_reduced_model  # noqa: E402
from drillstring.stochastic.runs import (  # noqa: E402
    compile_kernels,
    metrics_transient,
    realization_metrics,
    simulation_options,
)

RECIPES = ("rebuild", "parametric")


#: The study store's flush interval of this tree (the new recipe's); main wrote each realization alone (0).
FLUSH_INTERVAL = mc.StudyStore.flush_interval


def recipe(name: str) -> None:
    """Select a recipe for this process and the workers it spawns: "rebuild" is main's (every model rebuilt,
    each realization written to the store alone), "parametric" this tree's."""
    if name == "rebuild":
        os.environ[study_model.REBUILD_VARIABLE] = "1"
        mc.StudyStore.flush_interval = 0.0
    else:
        os.environ.pop(study_model.REBUILD_VARIABLE, None)
        mc.StudyStore.flush_interval = FLUSH_INTERVAL


def stages(case, settings, count: int) -> dict[str, dict[str, float]]:
    """Mean seconds of each stage of a realization (the steps of montecarlo.run_realization) per recipe, over
    realizations 1..count, the recipes alternating realization by realization (the machine's load drifts);
    realization 0 first, untimed, so that the parametric model is built and the kernels loaded."""
    law = mc.study_uncertainty(case, settings)
    key = (case.to_toml(), settings)
    times: dict[str, dict[str, float]] = {name: {} for name in RECIPES}
    mc.run_realization(case, settings, 0)
    for i in range(1, count + 1):
        for name in RECIPES:
            recipe(name)
            spent = times[name]

            def tick(stage: str, start: float) -> float:
                now = time.perf_counter()
                spent[stage] = spent.get(stage, 0.0) + now - start
                return now

            t = time.perf_counter()
            values = mc.draw_inputs(case, settings, i)
            t = tick("draw", t)
            realized = law.apply(case, values)
            t = tick("law.apply", t)
            model = study_model.realization_model(case, key, law, realized)
            t = tick("model", t)
            model = random_reduced_model(model, settings.model, model_generator(settings.seed, i))
            t = tick("random_reduced_model", t)
            family_growth_rates(model)
            t = tick("family_growth_rates", t)
            result = simulate_model(model, **simulation_options(realized, settings.t_end, settings.output_step))
            t = tick("simulate_model", t)
            realization_metrics(result, realized, metrics_transient(settings))
            tick("metrics", t)
    return {name: {stage: value / count for stage, value in spent.items()} for name, spent in times.items()}


def study(case, settings, workers: int):
    """Run the study in a temporary folder: (wall time [s], the printed tables' text, the statistics, the mean
    realization time the store records [s])."""
    from rich.console import Console

    from drillstring.cli.study import _realizations_table, _study_table
    from drillstring.stochastic.analysis import load_study, study_statistics, study_summary

    def run(folder: Path):
        mc.run_study(case, settings, folder / "study.zarr", Engine(workers=workers))
        raw = load_study(folder / "study.zarr")
        stats = study_statistics(raw)
        summary = study_summary(stats)
        console = Console(record=True, width=160, file=open(os.devnull, "w"))
        console.print(_study_table(summary))
        console.print(_realizations_table(summary))
        return console.export_text(), stats, float(np.nanmean(raw["wall_time"].values))

    wall, (text, stats, realization) = timed_in_folder("bench_study_parametric_", run)
    return wall, text, stats, realization


def store_write_cost(case, settings, batch: int) -> tuple[float, float]:
    """Seconds per realization of the study store's write (in the driver process): one realization per write,
    and ``batch`` per write (what the store's ``flush_interval`` gathers)."""
    import pickle
    import tempfile

    outcomes = [mc.run_realization(case, settings, i) for i in range(2)]
    rows = []
    for i in range(2 * batch):
        copy = pickle.loads(pickle.dumps(outcomes[i % 2]))
        copy.index = i
        rows.append(copy)
    with tempfile.TemporaryDirectory() as folder:
        store = mc.StudyStore(Path(folder) / "s.zarr", case, settings)
        start = time.perf_counter()
        for row in rows[:batch]:
            store.write_many([row])
        single = (time.perf_counter() - start) / batch
        start = time.perf_counter()
        store.write_many(rows[batch:])
        grouped = (time.perf_counter() - start) / batch
    return single, grouped


def _empty_realization(case, settings, index: int):
    """A task that computes nothing and returns an outcome of a reference realization's size (30 s at 0.01 s:
    4 observables and one probe): what the process pool moves per realization."""
    from drillstring.stochastic.store import DONE

    n = len(settings.time)
    outcome = mc.RealizationOutcome(index, 0.0, 0.0, DONE, "")
    outcome.observables = {name: np.full(n, float(index)) for name in mc.study_observables(case)}
    outcome.radial_displacement = np.zeros((n, len(case.mesh.probes)))
    return outcome


def task_overhead(case, settings, workers: int) -> float:
    """Seconds of wall time per task that the process pool adds (sending the case and settings, returning the
    outcome): empty tasks, 400 against 40, so that the pool's start-up cancels (issue 35 item 3: batching
    realizations per worker call can save at most this)."""
    from functools import partial

    from drillstring.stochastic.execution import execute

    walls = []
    for n in (40, 400):
        start = time.perf_counter()
        execute(partial(_empty_realization, case, settings), [(i, i) for i in range(n)], lambda outcome: None,
                workers=workers)
        walls.append(time.perf_counter() - start)
    return (walls[1] - walls[0]) / 360


def documented_table(path: Path) -> list[str] | None:
    """The dispersion table that ``drillstring study`` printed for the documented study ``path`` (its
    summary.json), rendered as the benchmark renders its own; None when the file is not there."""
    import json

    from rich.console import Console

    from drillstring.cli.study import _realizations_table, _study_table

    if not path.exists():
        return None
    payload = json.loads(path.read_text())
    console = Console(record=True, width=160, file=open(os.devnull, "w"))
    console.print(_study_table(payload))
    if payload.get("realizations"):
        console.print(_realizations_table(payload))
    return console.export_text().splitlines()


def envelope_difference(a, b) -> tuple[float, str]:
    """Largest difference of the statistics' time series between two studies, relative to the range of the
    variable, and the variable where it is."""
    worst, where = 0.0, ""
    for name in a.data_vars:
        if not name.endswith(("_mean", "_std", "_lower", "_upper")):
            continue
        x, y = np.asarray(a[name].values, dtype=float), np.asarray(b[name].values, dtype=float)
        scale = np.nanmax(np.abs(y)) if np.isfinite(y).any() else 0.0
        if scale == 0.0:
            continue
        diff = float(np.nanmax(np.abs(x - y)) / scale)
        if diff > worst:
            worst, where = diff, name
    return worst, where


def sobol_cost(count: int) -> None:
    """Build and solve cost of ``count`` runs of the Sobol' benchmark's design (the reference case, 20 s)."""
    from bench_sensitivity import LAWS

    from drillstring.stochastic.parameters import with_parameters
    from drillstring.stochastic.sensitivity_study import SensitivitySettings, sensitivity_design

    case = load_case("reference")
    settings = SensitivitySettings(1024, tuple(LAWS.items()), t_end=20.0)
    design = sensitivity_design(case, settings)
    law = design.uncertainty
    t = time.perf_counter()
    parametric = study_model.parametric_model(case, ("sobol", case.to_toml(), settings.laws), law)
    made = time.perf_counter() - t
    rng = np.random.default_rng(0)
    build = quick = solve = 0.0
    rows = rng.choice(design.runs, count, replace=False)
    for i in rows:
        run_case = with_parameters(case, dict(zip(law.paths, design.values[i])))
        t = time.perf_counter()
        model = case_reduced_model(run_case)
        t1 = time.perf_counter()
        parametric.model(run_case)
        t2 = time.perf_counter()
        simulate_model(model, **simulation_options(run_case, 20.0, run_case.simulation.output_step))
        build, quick, solve = build + t1 - t, quick + t2 - t1, solve + time.perf_counter() - t2
    n = len(rows)
    print(f"Sobol' study (3 parameters, {design.runs} runs of 20 s), sample of {n}: per run solve "
          f"{1e3 * solve / n:.1f} ms; build rebuilt {1e3 * build / n:.1f} ms ({100 * build / (build + solve):.1f} % of a run), from the "
          f"design's parametric model {1e3 * quick / n:.1f} ms ({100 * quick / (quick + solve):.1f} %; the model "
          f"built once in {made:.2f} s); {design.runs} runs = {design.runs * (build + solve) / n / 60:.1f} min "
          f"serial rebuilt, {design.runs * (quick + solve) / n / 60:.1f} min from the parametric model")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--samples", type=int, default=500)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--profile", type=int, default=10, help="realizations timed stage by stage per recipe")
    parser.add_argument("--repeat", type=int, default=1, help="studies per recipe, alternating (fastest kept)")
    parser.add_argument("--sobol", type=int, default=0, help="also time this many Sobol' runs (build vs solve)")
    args = parser.parse_args()
    case = load_case("reference")
    settings = mc.StudySettings(samples=args.samples, seed=DEFAULT_SEED, laws=(mc.weight_on_hook_normal(case, 5000.0),),
                                t_end=case.simulation.t_end, output_step=case.simulation.output_step)
    compile_kernels(case)
    print(load_average("start"))
    print(f"reference study: {args.samples} realizations + the nominal run, weight-on-hook Normal σ = 5 kN, "
          f"t_end {settings.t_end:g} s, {args.workers} worker(s), {cores()} cores")

    profiles = stages(case, settings, args.profile)
    print(f"stages of one realization [ms], mean of {args.profile} in this process:")
    print(f"  {'stage':22s}" + "".join(f"{name:>12s}" for name in RECIPES))
    for stage in profiles["rebuild"]:
        print(f"  {stage:22s}" + "".join(f"{1e3 * profiles[name][stage]:12.2f}" for name in RECIPES))
    for name in RECIPES:
        p = profiles[name]
        print(f"  {name}: model build {1e3 * p['model']:.2f} ms = {100 * p['model'] / p['simulate_model']:.1f} % of the "
              f"solve ({1e3 * p['simulate_model']:.1f} ms); whole realization {1e3 * sum(p.values()):.1f} ms")
    print(f"  build speed-up {profiles['rebuild']['model'] / profiles['parametric']['model']:.1f}x; realization "
          f"speed-up {sum(profiles['rebuild'].values()) / sum(profiles['parametric'].values()):.2f}x")

    recipe("parametric")
    batch = min(8, args.samples // 2)
    single, grouped = store_write_cost(case, settings, batch)
    print(f"store write in the driver: {1e3 * single:.1f} ms per realization written alone, {1e3 * grouped:.1f} ms "
          f"in a batch of {batch} (the study store's flush_interval = {mc.StudyStore.flush_interval:g} s gathers them)")

    overhead = task_overhead(case, settings, args.workers)
    print(f"process pool: {1e3 * overhead:.2f} ms of wall time per task (empty tasks returning a realization's "
          f"outcome, {args.workers} workers): batching realizations per worker call could save at most that")

    results = {}
    for repeat in range(args.repeat):  # the recipes alternate: the machine's load drifts
        for name in RECIPES:
            recipe(name)
            found = study(case, settings, args.workers)
            wall, _, _, realization = found
            print(f"study, {name:10s}: wall {wall:7.1f} s ({(args.samples + 1) / wall:5.2f} realizations/s); mean "
                  f"realization time in the store {1e3 * realization:.1f} ms")
            if name not in results or wall < results[name][0]:
                results[name] = found
    recipe("parametric")
    ratio = results["rebuild"][0] / results["parametric"][0]
    print(f"study wall-time ratio rebuild/parametric (fastest of {args.repeat} each): {ratio:.2f}x (issue 35 asks >= 10x and <= 20 s: "
          f"{'met' if ratio >= 10 and results['parametric'][0] <= 20 else 'NOT met'})")

    old, new = (results[name][1].splitlines() for name in RECIPES)
    differing = [(a, b) for a, b in zip(old, new) if a != b]
    print(f"printed tables: {len(old)} lines, {len(differing)} differ" + (":" if differing else " (identical)"))
    for a, b in differing:
        print(f"  rebuild:    {a}\n  parametric: {b}")
    worst, where = envelope_difference(results["parametric"][2], results["rebuild"][2])
    print(f"envelopes (mean, std, 95 % band of every observable): largest difference {worst:.2e} of the range ({where})")
    print(results["parametric"][1])
    documented = documented_table(Path(__file__).resolve().parents[1] / "docs" / "studies" / "summary_sigma5000.json")
    if documented is not None and args.samples == 500:
        for name in RECIPES:
            lines = set(results[name][1].splitlines())
            missing = [line for line in documented if line not in lines]
            print(f"against docs/studies/summary_sigma5000.json (the documented 500-realization study), {name}: "
                  f"{len(documented) - len(missing)} of its {len(documented)} printed lines found identical")
            for line in missing:
                print(f"  documented, not printed by {name}: {line}")
    if args.sobol:
        sobol_cost(args.sobol)
    print(load_average("end"))


if __name__ == "__main__":
    main()
