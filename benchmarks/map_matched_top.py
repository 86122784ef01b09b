"""The operating map of the reference string under a matched top (issue 25): a PI top drive with
k_p = Z_p = 443.4 N*m*s/rad (the drill pipe's torsional impedance: a torsional wave arriving at the top is
absorbed, not reflected), k_i = 1 N*m/rad (≈ 0: just enough integral action to hold the set point) and a light
top drive (J_td = 10 kg*m2), over 20–160 rpm × 100–200 kN. Above the buckling load (114 kN) the lateral
divergence of the straight string leads the overall growth rate, so the torsional stability windows show
only on the per-family figure (stability.png). Prints the per-family counts and writes the map's files to
--out (default docs/studies/map_reference_matched_top_files). Run:

    .venv/bin/python benchmarks/map_matched_top.py [--grid 15x6] [--t-end 20] [--out DIR]
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

from drillstring import api
from drillstring.case import load_case

#: The matched top drive.
MATCHED_TOP = {"controller": "pi", "inertia": 10.0, "proportional_gain": 443.4, "integral_gain": 1.0}


def matched_top_case():
    case = load_case("reference")
    return case.model_copy(update={"name": "reference_matched_top",
                                   "top_drive": case.top_drive.model_copy(update=MATCHED_TOP)})


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--grid", default="15x6", help="top speeds x weights-on-bit (default 15x6)")
    parser.add_argument("--t-end", type=float, default=20.0)
    parser.add_argument("--workers", type=int, default=None)
    parser.add_argument("--out", type=Path, default=Path("map_reference_matched_top"))
    args = parser.parse_args()
    n_speed, n_wob = (int(v) for v in args.grid.lower().split("x"))
    start = time.perf_counter()
    outcome = api.operating_map(matched_top_case(), top_speed=f"20 rpm:160 rpm:{n_speed}",
                                weight_on_bit=f"100 kN:200 kN:{n_wob}", t_end=args.t_end, out=args.out,
                                workers=args.workers)
    summary = outcome.summary
    print(f"{summary['points']} points in {time.perf_counter() - start:.1f} s; linearly stable (every root): "
          f"{summary['linearly_stable_points']}; per family: "
          f"{json.dumps(summary['linearly_stable_points_by_family'])}; coexisting cycles: "
          f"{summary['coexisting_cycle_points']}; critical weight-on-bit {summary['critical_weight_on_bit']:.0f} N")
    ds = outcome.dataset
    for name in ("growth_rate", "torsional_growth_rate", "axial_growth_rate", "lateral_growth_rate"):
        print(name)
        print(ds[name].to_pandas().round(4).to_string())


if __name__ == "__main__":
    main()
