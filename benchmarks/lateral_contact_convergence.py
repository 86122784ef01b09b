"""Convergence of the lateral response with impacts: lateral modes and mesh, on the `contact` case.

The contact case whirls chaotically across its gap (the imbalance's force modulated by stick-slip), so
single histories do not converge: each setting runs several realizations of the seeded initial
perturbation (``initial.seed`` = 0, 1, ...) and compares statistics after the transient (t >= 10 s):

- impacts: contact zones that appeared (``SimulationResult.impacts``), per realization;
- RMS radial displacement at the probe (1560 m) [mm];
- mean contact force: the time average of the wall's total normal force [N] (its impulse per second);
- peak contact force: the largest total wall force at the output times [kN].

Part 1 sweeps the lateral modes per plane on the default 10 m mesh (58, 83 and 106 modes are the modes
below 1, 1.5 and 2 times the rotation frequency). Part 2 refines the mesh at the default basis (every mode
below 1.5x the rotation frequency), with the wall as a distributed stiffness (the model) and, for
comparison, with the same k_sh at every node whatever the element length (the earlier per-node law).
Prints Markdown tables (mean ± standard deviation over the realizations) and the CPU time per 30 s run.

    .venv/bin/python benchmarks/lateral_contact_convergence.py [--seeds 8] [--t-end 60] [--part modes|mesh|both]
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import dataclasses  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

from drillstring.case import load_case  # noqa: E402
from drillstring.dynamics.indicators import transient_end  # noqa: E402
from drillstring.dynamics.rom import case_reduced_model  # noqa: E402
from drillstring.dynamics.simulate import simulate_model  # noqa: E402
from drillstring.forces.contact import ContactStations  # noqa: E402


def per_node_wall(model):
    """The model with the earlier per-node wall: one station per node (its smallest gap), each with
    k_sh [N/m] whatever the element length (stations of tributary length 1 m)."""
    st = model.stations
    nodes = np.arange(model.static.mesh.n_nodes)
    gap = model.gap
    outer = np.array([st.outer_diameter[st.node == i][np.argmin(st.gap[st.node == i])] for i in nodes])
    return dataclasses.replace(model, stations=ContactStations(nodes.astype(np.int64), np.ones(len(nodes)),
                                                               gap, outer))


def statistics(case, seeds, t_end, **model_options):
    """Per realization: impacts, RMS r [mm], mean and peak contact force [N], CPU per 30 s [s]."""
    per_node = model_options.pop("per_node", False)
    rows = []
    for seed in range(seeds):
        model = case_reduced_model(case, **model_options)
        if per_node:
            model = per_node_wall(model)
        start = time.process_time()
        run = simulate_model(model, t_end=t_end, output_step=0.01, seed=seed, raise_on_failure=False)
        cpu = (time.process_time() - start) * 30.0 / t_end
        steady = run.time >= transient_end(t_end)
        r = run.radial_displacement[steady, 0]
        force = run.observables["contact_force"][steady]
        rows.append((run.impacts, 1e3 * np.sqrt(np.mean(r**2)), force.mean(), force.max(), cpu,
                     float(run.success)))
    return np.array(rows), model.family.count("lateral_y"), model.static.mesh.n_elements


def row(label, values, extra=""):
    mean, std = values.mean(axis=0), values.std(axis=0)
    failed = int(len(values) - values[:, 5].sum())
    return (f"| {label} |{extra} {mean[0]:.1f} ± {std[0]:.1f} | {mean[1]:.2f} ± {std[1]:.2f} | "
            f"{mean[2]:.0f} ± {std[2]:.0f} | {mean[3] / 1e3:.0f} ± {std[3] / 1e3:.0f} | {mean[4]:.2f} |"
            + (f" {failed} failed |" if failed else ""))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seeds", type=int, default=8)
    parser.add_argument("--t-end", type=float, default=60.0)
    parser.add_argument("--part", choices=("modes", "mesh", "both"), default="both")
    args = parser.parse_args()
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})  # one core
    case = load_case("contact")
    case_reduced_model(case)  # compile the kernels outside the timings
    header = ("impacts | RMS r at 1560 m [mm] | mean contact force [N] | peak contact force [kN] | "
              "CPU per 30 s [s] |")
    print(f"contact case, {args.seeds} realizations of {args.t_end:g} s each, statistics over "
          f"t >= {transient_end(args.t_end):g} s (mean ± std over the realizations)\n")
    if args.part in ("modes", "both"):
        print("| lateral modes per plane (cut-off) | " + header)
        print("|---" * 6 + "|")
        top = case.operation.top_speed
        for count in (20, 40, 58, 83, 106, 160, 240):
            values, lateral, _ = statistics(case, args.seeds, args.t_end, lateral_modes=count)
            model = case_reduced_model(case, lateral_modes=count)
            ratio = abs(model.angular_frequencies[model.family.index("lateral_y") + lateral - 1]) / top
            print(row(f"{lateral} ({ratio:.2f} Ω)", values), flush=True)
        print()
    if args.part in ("mesh", "both"):
        print("| max element [m] (elements, lateral modes) | wall | " + header)
        print("|---" * 7 + "|")
        for h in (20.0, 10.0, 5.0, 2.5):
            meshed = case.model_copy(update={"mesh": case.mesh.model_copy(update={"max_element_length": h})})
            for per_node in (False, True):
                values, lateral, elements = statistics(meshed, args.seeds, args.t_end, per_node=per_node)
                wall = " per node (k_sh at every node) |" if per_node else " distributed (the model) |"
                print(row(f"{h:g} ({elements}, {lateral})", values, wall), flush=True)


if __name__ == "__main__":
    main()
