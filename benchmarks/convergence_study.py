"""Convergence study of one reference run: mode counts, mesh and integration tolerance.

For each setting it prints steady-state drilling numbers (after the transient) and the RMS difference
of the bit-speed and ROP histories against the finest setting of the same sweep. Used to choose the
default mode counts, mesh and tolerances (see docs/verification.md). Run:

    .venv/bin/python benchmarks/convergence_study.py [--t-end 20]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from drillstring.case import load_case
from drillstring.dynamics.rom import case_reduced_model
from drillstring.dynamics.simulate import simulate_model

T_TRANSIENT = 10.0


def run(case, *, rtol=None, atol=None, t_end=20.0, **modes):
    start = time.perf_counter()
    model = case_reduced_model(case, **modes)
    s = case.simulation
    result = simulate_model(model, t_end=t_end, output_step=s.output_step,
                            rtol=rtol or s.rtol, atol=atol or s.atol,
                            lateral_perturbation=case.initial.lateral_perturbation,
                            seed=case.initial.seed)
    return result, time.perf_counter() - start


def rms(a, b):
    return float(np.sqrt(np.mean((a - b) ** 2)) / np.sqrt(np.mean(b**2)))


def summarize(label, result, finest, wall):
    o, late = result.observables, result.time >= T_TRANSIENT
    f = finest.observables
    print(f"{label:>24} | {o['rate_of_penetration'][late].mean() * 3600:9.5f} m/h"
          f" | {o['torque_on_bit'][late].mean() / 1e3:8.5f} kN m"
          f" | {o['bit_speed'][late].min() * 30 / np.pi:7.3f}-{o['bit_speed'][late].max() * 30 / np.pi:7.3f} rpm"
          f" | r_max {result.radial_displacement.max() * 1e3:7.4f} mm"
          f" | rms dROP {rms(o['rate_of_penetration'], f['rate_of_penetration']):.1e}"
          f" dspeed {rms(o['bit_speed'], f['bit_speed']):.1e}"
          f" dr {rms(result.radial_displacement, finest.radial_displacement):.1e}"
          f" | {wall:5.2f} s")


def sweep(title, case, settings, t_end):
    print(f"\n{title}")
    results = [(label, *run(case, t_end=t_end, **kw)) for label, kw in settings]
    finest = results[-1][1]
    for label, result, wall in results:
        summarize(label, result, finest, wall)


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--t-end", type=float, default=20.0)
    args = parser.parse_args()
    case = load_case("reference")
    r = case.reduced_model
    print(f"defaults: {r.axial_modes} axial + rigid, {r.torsional_modes} torsional, {r.lateral_modes}"
          f" lateral per plane, mesh {case.mesh.max_element_length} m, rtol {case.simulation.rtol}")
    sweep("axial modes (torsional, lateral at defaults)", case,
          [(f"axial {n}", {"axial_modes": n}) for n in (1, 2, 4, 6, 10, 16)], args.t_end)
    sweep("torsional modes", case,
          [(f"torsional {n}", {"torsional_modes": n}) for n in (1, 2, 4, 6, 10, 16)], args.t_end)
    sweep("lateral modes per plane", case,
          [(f"lateral {n}", {"lateral_modes": n}) for n in (5, 10, 20, 40, 80)], args.t_end)
    sweep("integration tolerance (atol = rtol/1000)", case,
          [(f"rtol {t:.0e}", {"rtol": t, "atol": t * 1e-3}) for t in (1e-4, 1e-5, 1e-6, 1e-7, 1e-9)],
          args.t_end)
    print("\nmesh (max element length)")
    results = []
    for h in (40.0, 20.0, 10.0, 5.0):
        c = case.model_copy(update={"mesh": case.mesh.model_copy(update={"max_element_length": h})})
        results.append((f"mesh {h:g} m", *run(c, t_end=args.t_end)))
    for label, result, wall in results:
        summarize(label, result, results[-1][1], wall)


if __name__ == "__main__":
    main()
