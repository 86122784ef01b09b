"""Study: the robust operating point (``drillstring.optimize``) against a dense probabilistic map computed
independently, and how far model uncertainty moves it.

For a case, over top speed × weight-on-bit, with the weight-on-hook Normal around each point's hook load
(σ = 5 kN), ``--samples`` realizations per point of ``--t-end`` s (outputs after t_end/2):

1. ``optimize``: maximise the expected ROP subject to the chance constraints (``--constraint``), a surrogate
   search of ``--points`` design points, ``--batch`` of them chosen together after the initial design (their
   realizations in one pass of the workers); with ``--one-at-a-time`` the same search with batches of one
   point too, in the same run (the wall time a batch saves);
2. the same with random reduced matrices (δ_M = δ_K = δ_D = ``--delta``) on top of the parameter
   uncertainty: how far the answer moves;
3. with ``--map N``: a probabilistic map of N × N points over the same box, with the same seed, samples and
   laws (``run_sampled_map``: the engine of ``drillstring map --samples``, nothing shared with the search
   but the realizations' definition), and its best point: the largest mean ROP over the realizations among
   the points whose estimated probabilities meet the bounds.

Prints and writes ``--json`` (the recommended points, their estimates, the map's best point, run counts and
wall times; rewritten after each step); copies the figures next to it. ``--linear-too``: the first search
again with a linear prior mean of the probabilities' surrogates (``probability_mean="linear"``);
``--no-model``: without the search with model uncertainty. Run:

    PYTHONPATH=src python benchmarks/optimize_operating_point.py reference --map 9 --one-at-a-time \
        --json docs/studies/optimize_reference.json
    PYTHONPATH=src python benchmarks/optimize_operating_point.py stick_slip --json docs/studies/optimize_stick_slip.json \\
        --top-speed "60 rpm:180 rpm" --constraint stick_slip=0.1 --constraint buckling=0.05
"""

from __future__ import annotations

import argparse
import json
import math
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np

import drillstring
from drillstring.case import load_case
from drillstring.stochastic.optimize import DEFAULT_BATCH

RPM = math.pi / 30.0


def best_map_point(case, box, constraints, args, workdir: Path) -> dict:
    """The dense probabilistic map and its best feasible point (module docstring, 3)."""
    from drillstring.operating_point import parse_bounds
    from drillstring.stochastic.execution import Engine
    from drillstring.stochastic.operating_map import MapSettings
    from drillstring.stochastic.optimize import SAMPLE_OUTPUTS, event_function
    from drillstring.stochastic.probabilistic_map import SampledMapSettings, run_sampled_map, sampled_map_dataset
    from drillstring.stochastic.store import DONE

    (_, s0, s1), (_, w0, w1) = (parse_bounds(case, name, text) for name, text in box.items())
    grid = MapSettings(tuple(np.linspace(s0, s1, args.map)), tuple(np.linspace(w0, w1, args.map)),
                       t_end=args.t_end, output_step=0.01)
    settings = SampledMapSettings(grid, samples=args.samples, seed=args.seed, sigma=5e3)
    start = time.perf_counter()
    run = run_sampled_map(case, settings, workdir / "map.zarr", Engine(workers=args.workers))
    wall = time.perf_counter() - start
    ds = sampled_map_dataset(run.store.path)
    done = ds.status.values == DONE
    rop = np.where(done, ds.mean_rate_of_penetration.values, np.nan)
    mean_rop = np.nanmean(rop, axis=2)
    ok = np.ones(mean_rop.shape, dtype=bool)
    probabilities = {}
    outputs = {**SAMPLE_OUTPUTS, "surface_torque_amplitude": ("", "")}
    for event, bound in constraints.items():
        output, function = event_function(event, outputs)
        with np.errstate(invalid="ignore"):
            p = (function(ds[output].values) & done).sum(axis=2) / np.maximum(done.sum(axis=2), 1)
        probabilities[event] = p
        ok &= p <= bound
    if not ok.any():
        return {"feasible_points": 0, "runs": int(grid.points * args.samples), "wall_time": wall}
    i, j = np.unravel_index(int(np.nanargmax(np.where(ok, mean_rop, -np.inf))), mean_rop.shape)
    return {"grid": [args.map, args.map], "runs": int(grid.points * args.samples), "wall_time": wall,
            "feasible_points": int(ok.sum()), "top_speed_rpm": float(grid.top_speed[i] / RPM),
            "weight_on_bit_kN": float(grid.weight_on_bit[j] / 1e3), "expected_rop_m_h": float(mean_rop[i, j] * 3600),
            "probabilities": {e: float(p[i, j]) for e, p in probabilities.items()},
            "grid_step": {"top_speed_rpm": float((s1 - s0) / (args.map - 1) / RPM),
                          "weight_on_bit_kN": float((w1 - w0) / (args.map - 1) / 1e3)}}


def search(case, box, constraints, args, workdir: Path, model=None, batch=None, probability_mean="constant") -> dict:
    batch = args.batch if batch is None else batch
    start = time.perf_counter()
    outcome = drillstring.optimize(case, variables=box, constraints=constraints, samples=args.samples,
                                   points=args.points, initial=args.initial, batch=batch, seed=args.seed,
                                   t_end=args.t_end, probability_mean=probability_mean,
                                   sigma=5e3, model=model, out=workdir, workers=args.workers)
    wall = time.perf_counter() - start
    best = outcome.summary["recommended"]
    steps = 1 + math.ceil((args.points - args.initial) / batch)
    return {"feasible": outcome.feasible, "runs": outcome.summary["realizations"], "batch": batch,
            "probability_mean": probability_mean,
            "engine_passes": steps, "wall_time": wall,
            "top_speed_rpm": best["values"][0] / RPM, "weight_on_bit_kN": best["values"][1] / 1e3,
            "expected_rop_m_h": best["objective"] * 3600,
            "expected_rop_standard_error_m_h": best["objective_standard_error"] * 3600,
            "surrogate_rop_m_h": best["surrogate_objective"] * 3600,
            "constraints": best["constraints"], "figure": outcome.files["figure"],
            "design_points": outcome.summary["design"]}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("case")
    parser.add_argument("--top-speed", default="60 rpm:140 rpm")
    parser.add_argument("--weight-on-bit", default="80 kN:120 kN")
    parser.add_argument("--constraint", action="append", default=None, metavar="EVENT=BOUND")
    parser.add_argument("--samples", type=int, default=16)
    parser.add_argument("--points", type=int, default=16)
    parser.add_argument("--initial", type=int, default=8)
    parser.add_argument("--batch", type=int, default=DEFAULT_BATCH)
    parser.add_argument("--one-at-a-time", action="store_true")
    parser.add_argument("--linear-too", action="store_true")
    parser.add_argument("--no-model", action="store_true")
    parser.add_argument("--t-end", type=float, default=10.0)
    parser.add_argument("--delta", type=float, default=0.1)
    parser.add_argument("--map", type=int, default=0)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--json", type=Path, default=None)
    args = parser.parse_args()
    case = load_case(args.case)
    box = {"top_speed": args.top_speed, "weight_on_bit": args.weight_on_bit}
    constraints = dict((e, float(b)) for e, b in (c.split("=") for c in (args.constraint or
                                                                          ["buckling=0.05", "torsional_instability=0.1"])))
    workdir = Path(tempfile.mkdtemp(prefix="optimize-bench-"))
    result = {"case": args.case, "box": box, "constraints": constraints, "samples": args.samples,
              "points": args.points, "initial": args.initial, "batch": args.batch, "t_end": args.t_end, "sigma": 5e3,
              "delta": args.delta, "workers": args.workers}

    def save(key: str | None = None) -> None:
        if args.json:
            args.json.parent.mkdir(parents=True, exist_ok=True)
            if key is not None:  # the search's figure, next to the JSON file
                target = args.json.with_name(f"{args.json.stem}_{key}.png")
                shutil.copyfile(Path(result[key]["figure"]), target)
                result[key]["figure"] = target.name
            args.json.write_text(json.dumps(result, indent=1, default=str) + "\n")

    try:
        result["parameter_uncertainty"] = search(case, box, constraints, args, workdir / "parameters")
        print(json.dumps(result["parameter_uncertainty"], indent=1, default=str), flush=True)
        save("parameter_uncertainty")
        if args.one_at_a_time:
            result["one_at_a_time"] = search(case, box, constraints, args, workdir / "single", batch=1)
            result["one_at_a_time"].pop("figure")
            print(json.dumps(result["one_at_a_time"], indent=1, default=str), flush=True)
            save()
        if args.map:
            result["dense_map"] = best_map_point(case, box, constraints, args, workdir / "map")
            print(json.dumps(result["dense_map"], indent=1), flush=True)
            save()
        if args.linear_too:
            result["linear_probability_mean"] = search(case, box, constraints, args, workdir / "linear",
                                                       probability_mean="linear")
            print(json.dumps(result["linear_probability_mean"], indent=1, default=str), flush=True)
            save("linear_probability_mean")
        if args.no_model:
            return
        model = {k: args.delta for k in ("mass_dispersion", "stiffness_dispersion", "damping_dispersion")}
        result["with_model_uncertainty"] = search(case, box, constraints, args, workdir / "model", model)
        print(json.dumps(result["with_model_uncertainty"], indent=1, default=str), flush=True)
        save("with_model_uncertainty")
        a, b = result["parameter_uncertainty"], result["with_model_uncertainty"]
        result["moved"] = {"top_speed_rpm": b["top_speed_rpm"] - a["top_speed_rpm"],
                           "weight_on_bit_kN": b["weight_on_bit_kN"] - a["weight_on_bit_kN"],
                           "expected_rop_m_h": b["expected_rop_m_h"] - a["expected_rop_m_h"]}
        if "buckling" in constraints:
            from drillstring.buckling import case_buckling_margin
            from scipy.special import ndtri

            critical = case_buckling_margin(case).critical_weight_on_bit
            result["closed_form_buckling_limit_kN"] = (critical - 5e3 * float(ndtri(1 - constraints["buckling"]))) / 1e3
            result["critical_weight_on_bit_kN"] = critical / 1e3
        print(json.dumps(result["moved"], indent=1))
        save()
    finally:
        shutil.rmtree(workdir, ignore_errors=True)


if __name__ == "__main__":
    main()
