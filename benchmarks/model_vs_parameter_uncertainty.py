"""Study: nonparametric model uncertainty beside parameter uncertainty of comparable input dispersion.

Two Monte Carlo studies of the same coarse reference string (50 m elements; the basis below), same seed and
sample count, through the study engine (:func:`~drillstring.stochastic.montecarlo.run_study`):

* **model**: random reduced mass, stiffness and damping matrices (Soize's SE+ ensemble,
  :mod:`drillstring.stochastic.random_matrices`) of dispersions δ_M = δ_K = δ_D = δ;
* **parameters**: the parametric counterparts of the same three matrices, each with coefficient of
  variation δ (gamma laws, mean at the nominal value): the steel's density (mass), Young's modulus
  (stiffness) and the modal damping ratio (damping). A random scalar factor ``a`` of a matrix ``A`` gives
  ``‖aA − A‖_F / ‖A‖_F = |a − 1|``: its dispersion in Soize's normalisation is the factor's c.o.v.

A study must draw at least one case parameter: the model study draws the weight-on-hook with σ = 1 N
(1e-5 of the weight on bit), which moves nothing measurable. Prints, for each output over the steady window
(t ≥ t_end/2), the mean and standard deviation across realizations in each study and their ratio. Run:

    PYTHONPATH=src python benchmarks/model_vs_parameter_uncertainty.py [--samples 40] [--delta 0.1] [--t-end 20]
"""

from __future__ import annotations

import argparse
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np

from drillstring.case import load_case
from drillstring.stochastic.analysis import load_study
from drillstring.stochastic.execution import Engine
from drillstring.stochastic.montecarlo import StudySettings, check_study, run_study, weight_on_hook_normal


def coarse_reference(axial: int, torsional: int, lateral: int):
    case = load_case("reference")
    return case.model_copy(update={
        "mesh": case.mesh.model_copy(update={"max_element_length": 50.0}),
        "reduced_model": case.reduced_model.model_copy(update={
            "axial_modes": axial, "torsional_modes": torsional, "lateral_modes": lateral, "lateral_cutoff": 0.0}),
    })


def gamma(value: float, cov: float) -> str:
    return f"gamma mean={value!r} std={value * cov!r}"


def outputs(raw) -> dict[str, np.ndarray]:
    """Per-realization outputs over the steady window (finished realizations only)."""
    t = raw.time.values
    steady = t >= t[-1] / 2
    done = raw.status.values == 1
    bit_speed = raw.bit_speed.values[done][:, steady]
    return {
        "mean rate of penetration [m/h]": raw.rate_of_penetration.values[done][:, steady].mean(axis=1) * 3600,
        "mean bit speed [rpm]": bit_speed.mean(axis=1) * 30 / np.pi,
        "bit speed std [rpm]": bit_speed.std(axis=1) * 30 / np.pi,
        "mean torque on bit [kN m]": raw.torque_on_bit.values[done][:, steady].mean(axis=1) / 1e3,
        "max radial displacement [mm]": np.nanmax(raw.radial_displacement.values[done][:, steady], axis=(1, 2)) * 1e3,
    }


def run(case, settings, workers):
    folder = Path(tempfile.mkdtemp(prefix="model_uncertainty_"))
    try:
        check_study(case, settings)
        start = time.perf_counter()
        outcome = run_study(case, settings, folder / "study.zarr", Engine(workers=workers))
        wall = time.perf_counter() - start
        return outputs(load_study(folder / "study.zarr")), outcome, wall
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--samples", type=int, default=40)
    parser.add_argument("--delta", type=float, default=0.1)
    parser.add_argument("--t-end", type=float, default=20.0)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--workers", type=int, default=1)
    parser.add_argument("--modes", type=int, nargs=3, default=(4, 4, 4), metavar=("AXIAL", "TORSIONAL", "LATERAL"))
    args = parser.parse_args()
    case = coarse_reference(*args.modes)
    d = args.delta
    common = dict(samples=args.samples, seed=args.seed, t_end=args.t_end, output_step=0.01)
    steel = case.materials["steel"]
    studies = {
        "model": StudySettings(laws=(weight_on_hook_normal(case, 1.0),), model_dispersion=(d, d, d), **common),
        "parameters": StudySettings(laws=(
            ("materials.steel.density", gamma(steel.density, d)),
            ("materials.steel.young_modulus", gamma(steel.young_modulus, d)),
            ("damping.modal_damping_ratio", gamma(case.damping.modal_damping_ratio, d)),
        ), **common),
    }
    print(f"coarse reference (50 m elements; {args.modes[0]} axial, {args.modes[1]} torsional, {args.modes[2]} "
          f"lateral modes per plane), {args.samples} realizations of {args.t_end:g} s, δ = {d:g}")
    found = {}
    for name, settings in studies.items():
        values, outcome, wall = run(case, settings, args.workers)
        found[name] = values
        print(f"  {name:10s}: {outcome.completed} finished, {outcome.failed} failed, {wall:.1f} s")
    print("\n| output | model: mean | model: std (IQR) | parameters: mean | parameters: std (IQR) "
          "| ratio model/param: std (IQR) |")
    print("|---|---|---|---|---|---|")

    def iqr(x):
        q1, q3 = np.nanpercentile(x, [25, 75])
        return float(q3 - q1)

    for key in found["model"]:
        m, p = found["model"][key], found["parameters"][key]
        sm, sp = float(np.nanstd(m, ddof=1)), float(np.nanstd(p, ddof=1))
        im, ip = iqr(m), iqr(p)
        print(f"| {key} | {np.nanmean(m):.4g} | {sm:.3g} ({im:.3g}) | {np.nanmean(p):.4g} | {sp:.3g} ({ip:.3g}) | "
              f"{sm / sp if sp > 0 else float('inf'):.2f} ({im / ip if ip > 0 else float('inf'):.2f}) |")


if __name__ == "__main__":
    main()
