"""The reduced model of the ``deviated`` case against a full finite-element time integration on the case's own mesh:
the modal truncation's error as modes are added, and the full integration's cost (issue 34, "Must show";
docs/stiff_string.md, "Against a full finite-element integration").

    PYTHONPATH=src python benchmarks/full_fe_convergence.py [--t-end 1.0] [--modes 5,10,20,40,80,160]
                                                            [--element 10]

The case as written (10 m elements, 303 nodes) started on bottom (``initial.start = "on_bottom"``: the bit–rock
law switched on at t = 0 with the string turning at 120 rpm and twisted by the wall's friction). The full
integration (tests/dynamics/full_fe_reference.py: every axial and torsional DOF, Radau IIA at rtol 1e-8, no lateral
DOF) is the reference; the reduced model keeps ``n`` axial and ``n`` torsional modes (no lateral one), with and
without the static truncation correction (``reduced_model.truncation_correction = "static"``: attachment modes at
the bit and for the along-string friction's two load patterns), and every mode of the mesh last. Printed for each: the largest difference of the surface torque, the bit
speed and the force on bit over the record, relative to the full integration's largest value, and the run's wall
time, the errors from 0.5 s on and the surface torque's error at t = 0 (the steady twist under the friction,
truncated); then the full integration's cost per simulated second; then the lateral check: the reduced model with the
case's lateral modes (20 per plane, the case's 0.1 mm perturbation) touches the wall at no node during the record,
and its axial and torsional outputs are those of the model without lateral modes to the integration's tolerance.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "dynamics"))

from full_fe_reference import full_fe_model, integrate

from drillstring.case import load_case
from drillstring.dynamics.rom import case_reduced_model
from drillstring.dynamics.simulate import simulate_model

COMPARED = ("surface_torque", "bit_speed", "force_on_bit")
OUTPUT_STEP = 0.01
RTOL = 1e-7  # the reduced model's (implicit-explicit steps, ark43)
LATER = 0.5  # [s]: the errors are also shown from then on (the second half of a 1 s record)


def _case(element: float, correction: str = "none"):
    case = load_case("deviated")
    return case.model_copy(update={
        "mesh": case.mesh.model_copy(update={"max_element_length": element}),
        "initial": case.initial.model_copy(update={"start": "on_bottom"}),
        "reduced_model": case.reduced_model.model_copy(update={"truncation_correction": correction})})


def _run(model, t_end: float, **options):
    start = time.perf_counter()
    run = simulate_model(model, t_end=t_end, output_step=OUTPUT_STEP, rtol=RTOL, atol=1e-12, method="ark43",
                         **options)
    return run, time.perf_counter() - start


def _errors(run, reference, after: float = 0.0) -> dict[str, float]:
    """The largest difference of each compared signal at the output times ``t >= after`` [s], relative to the
    full integration's largest value over the record."""
    times = reference.times if hasattr(reference, "times") else reference.time
    kept = times >= after - 1e-12
    return {name: float(np.max(np.abs(run.observables[name] - reference.observables[name])[kept])
                        / np.max(np.abs(reference.observables[name]))) for name in COMPARED}


def _start_error(run, reference) -> float:
    """The surface torque at t = 0 (the steady twist under the friction) relative to the full integration's."""
    exact = reference.observables["surface_torque"][0]
    return float(abs(run.observables["surface_torque"][0] - exact) / abs(exact))


def _worst_time(run, reference, name: str) -> float:
    """The output time [s] of the largest difference of ``name``."""
    return float(reference.times[np.argmax(np.abs(run.observables[name] - reference.observables[name]))])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--t-end", type=float, default=1.0, help="the record [s]")
    parser.add_argument("--modes", default="5,10,20,40,80,160", help="axial and torsional modes kept, each")
    parser.add_argument("--element", type=float, default=10.0, help="mesh.max_element_length [m] (the case's: 10)")
    args = parser.parse_args()
    t_end = args.t_end

    case = _case(args.element)
    full = full_fe_model(case)
    n_nodes = full.bit_axial + 1
    print(f"deviated, {args.element:g} m elements: {n_nodes} nodes, {full.size} axial and torsional DOFs, "
          f"{len(full.stations)} friction stations; record {t_end:g} s, started on bottom")
    reference = integrate(full, t_end, OUTPUT_STEP, rtol=1e-8)
    per_second = reference.seconds / t_end
    print(f"full finite-element integration (Radau, rtol 1e-8): {reference.seconds:.1f} s wall, "
          f"{reference.evaluations} right-hand sides, {reference.jacobians} Jacobians")
    o = reference.observables
    print(f"  over the record: bit speed {o['bit_speed'].min():.3f} to {o['bit_speed'].max():.3f} rad/s, surface "
          f"torque {o['surface_torque'].min():.0f} to {o['surface_torque'].max():.0f} N*m, force on bit "
          f"{o['force_on_bit'].min():.0f} to {o['force_on_bit'].max():.0f} N")

    counts = [int(m) for m in args.modes.split(",") if int(m) < n_nodes - 1] + [n_nodes - 1]
    print("\nrelative error (largest difference over the record / largest value of the full integration)")
    print(f"(then from {LATER:g} s on, after the switch-on's transient, and the time of the bit speed's largest "
          "difference)")
    print("(and the surface torque at t = 0 relative to the full integration's there: the steady twist under the "
          "friction, before any dynamics)")
    print(f"{'modes':>6} {'correction':>10} {'columns':>7} {'surface torque':>15} {'bit speed':>10} "
          f"{'force on bit':>12} {'wall [s]':>8} {'torque, later':>13} {'speed, later':>12} {'at [s]':>6} "
          f"{'torque, t=0':>11}")
    plain = None
    for n in counts:
        for correction in ("none", "static"):
            if n == n_nodes - 1 and correction == "static":
                continue  # every mode: nothing left to correct
            model = case_reduced_model(_case(args.element, correction), axial_modes=n, torsional_modes=n,
                                       lateral_modes=0)
            run, wall = _run(model, t_end, lateral_perturbation=0.0)
            errors = _errors(run, reference)
            later = _errors(run, reference, min(LATER, 0.5 * t_end))
            print(f"{n:>6} {correction:>10} {model.size:>7} {errors['surface_torque']:>15.2e} "
                  f"{errors['bit_speed']:>10.2e} {errors['force_on_bit']:>12.2e} {wall:>8.1f} "
                  f"{later['surface_torque']:>13.2e} {later['bit_speed']:>12.2e} "
                  f"{_worst_time(run, reference, 'bit_speed'):>6.2f} {_start_error(run, reference):>11.2e}")
            if n == n_nodes - 1:
                plain = (model, run, wall)
    model, run, wall = plain
    print(f"\nfull finite-element integration: {per_second:.1f} s of wall time per simulated second; the reduced "
          f"model with every mode ({model.size} columns) {wall / t_end:.1f} s ({per_second / (wall / t_end):.1f}x "
          "less)")

    lateral = case_reduced_model(case, axial_modes=n_nodes - 1, torsional_modes=n_nodes - 1)
    with_lateral, _ = _run(lateral, t_end, lateral_perturbation=case.initial.lateral_perturbation)
    columns = int(lateral.lateral_columns.sum())
    gap = float(np.min(lateral.stations.gap))
    reach = float(np.max(with_lateral.radial_displacement)) if with_lateral.radial_displacement.size else 0.0
    print(f"\nlateral check: the same model with {columns} lateral modes and the case's "
          f"{1e3 * case.initial.lateral_perturbation:g} mm perturbation: nodes in contact at most "
          f"{int(np.max(with_lateral.observables['nodes_in_contact']))}, impacts {with_lateral.impacts}, the "
          f"probe's radial displacement at most {1e3 * reach:.3f} mm (smallest gap {1e3 * gap:.1f} mm); its "
          "outputs against the model without lateral modes: "
          + ", ".join(f"{name} {value:.1e}" for name, value in _errors(with_lateral, run).items()))


if __name__ == "__main__":
    main()
