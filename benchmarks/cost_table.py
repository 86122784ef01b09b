"""Cost model of one realization: where the time goes, and how it grows with elements, modes and
t_end. Prints Markdown tables (used in docs/performance.md). One core. Run:

    .venv/bin/python benchmarks/cost_table.py
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import time  # noqa: E402

import numpy as np  # noqa: E402

from drillstring.case import load_case  # noqa: E402
from drillstring.dynamics.rom import case_reduced_model  # noqa: E402
from drillstring.dynamics.simulate import simulate_model  # noqa: E402
from drillstring.fem.build import case_mesh  # noqa: E402
from drillstring.modal import case_linear_system, compute_modes  # noqa: E402
from drillstring.statics import case_static_state  # noqa: E402


def best(function, repeat=3):
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        value = function()
        times.append(time.perf_counter() - start)
    return min(times), value


def realization(case, t_end=20.0, **modes):
    build, model = best(lambda: case_reduced_model(case, weight_on_bit=100e3 + 1.0, **modes))
    simulate_model(model, t_end=0.1, output_step=0.01)  # warm
    run, result = best(lambda: simulate_model(model, t_end=t_end, output_step=0.01))
    return build, run, result.stats["n_rhs"], model


def breakdown(case):
    print("\n## Where the time of one reference realization goes (case 2, defaults)\n")
    mesh_t, mesh = best(lambda: case_mesh(case))
    static_t, static = best(lambda: case_static_state(case, mesh=mesh))
    system_t, system = best(lambda: case_linear_system(case, static))
    r = case.reduced_model
    modes_t, _ = best(lambda: compute_modes(system, r.axial_modes + 1, r.torsional_modes, r.lateral_modes))
    build, run, n_rhs, model = realization(case)
    y = model.initial_state(1e-4, 0)
    rhs_t, _ = best(lambda: [model.rhs(0.0, y) for _ in range(2000)])
    rhs_t /= 2000
    print("| step | time [ms] |\n|---|---|")
    for label, value in (("mesh", mesh_t), ("statics", static_t), ("assembly of M, K, K_g, fluid", system_t),
                         ("eigenproblems (4 families)", modes_t),
                         ("whole model build (incl. projection)", build),
                         (f"integration, {n_rhs} RHS evaluations", run),
                         ("  of which RHS (Python-called kernel x count, upper bound)", rhs_t * n_rhs)):
        print(f"| {label} | {value * 1e3:.1f} |")


def main() -> None:
    case = load_case("reference")
    breakdown(case)
    print("\n## Time per realization vs number of elements (case 2, default modes, t_end 20 s)\n")
    print("| max element length [m] | elements | build [s] | integration [s] | RHS evaluations |")
    print("|---|---|---|---|---|")
    for h in (40.0, 20.0, 10.0, 5.0):
        c = case.model_copy(update={"mesh": case.mesh.model_copy(update={"max_element_length": h})})
        build, run, n_rhs, model = realization(c)
        print(f"| {h:g} | {model.static.mesh.n_elements} | {build:.3f} | {run:.3f} | {n_rhs} |")
    print("\n## Time per realization vs modes (10 m mesh, t_end 20 s)\n")
    print("| axial + torsional | lateral per plane | build [s] | integration [s] | RHS evaluations |")
    print("|---|---|---|---|---|")
    for n_at, n_l in ((6, 20), (10, 10), (10, 20), (10, 40), (16, 20)):
        build, run, n_rhs, _ = realization(case, axial_modes=n_at, torsional_modes=n_at,
                                           lateral_modes=n_l)
        print(f"| {n_at} + {n_at} | {n_l} | {build:.3f} | {run:.3f} | {n_rhs} |")
    print("\n## Time per realization vs simulated time (defaults)\n")
    print("| t_end [s] | integration [s] | RHS evaluations |\n|---|---|---|")
    for t_end in (5.0, 10.0, 20.0, 40.0):
        _, run, n_rhs, _ = realization(case, t_end=t_end)
        print(f"| {t_end:g} | {run:.3f} | {n_rhs} |")
    full = case.model_copy(update={"model": case.model.model_copy(update={"nonlinear": "full"})})
    build, run, n_rhs, _ = realization(full)
    print(f"\ncase 1 (full nonlinear), defaults: build {build:.3f} s, integration {run:.3f} s, "
          f"{n_rhs} RHS evaluations")


if __name__ == "__main__":
    main()
