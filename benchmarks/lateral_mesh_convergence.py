"""Mesh convergence of the reference case's first lateral frequencies (prestressed, with fluid).

Prints a Markdown table of the first 10 lateral frequencies [Hz] against the element count, and the
relative difference of each mesh to the finest. Run:

    .venv/bin/python benchmarks/lateral_mesh_convergence.py
"""

import numpy as np

from drillstring.case import load_case
from drillstring.fem.build import case_mesh
from drillstring.modal import case_linear_system, compute_modes
from drillstring.statics import case_static_state


def main() -> None:
    case = load_case("reference")
    rows = []
    for h in (80.0, 40.0, 20.0, 10.0, 5.0, 2.5):
        mesh = case_mesh(case, max_element_length=h)
        static = case_static_state(case, mesh=mesh)
        modes = compute_modes(case_linear_system(case, static), 1, 1, 10)
        rows.append((h, mesh.n_elements, modes.lateral.frequencies))
    finest = rows[-1][2]
    print("| max element [m] | elements | " + " | ".join(f"f{i + 1}" for i in range(10))
          + " | max rel. diff to finest |")
    print("|---" * 13 + "|")
    for h, n, f in rows:
        diff = np.max(np.abs(f / finest - 1))
        print(f"| {h:g} | {n} | " + " | ".join(f"{x:.5f}" for x in f) + f" | {diff:.1e} |")


if __name__ == "__main__":
    main()
