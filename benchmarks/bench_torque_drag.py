"""Speed of soft-string torque and drag: the built-in case `deviated` and a 10 km well surveyed every metre.

Prints, for each well: survey stations, string nodes (elements of at most 1 m), the time to build the string
along the path, the time of the five operations, and the time of one operation for 100 friction-factor draws
at once against 100 single runs (the vectorised pass the calibration and the bands use), measured in the same
run. Best of 3 repeats.

    PYTHONPATH=src python benchmarks/bench_torque_drag.py
"""

from __future__ import annotations

import time
import tomllib
from importlib import resources

import numpy as np

from drillstring.case import case_from_dict, load_case
from drillstring.well.torque_drag import OPERATIONS, case_torque_drag, string_in_well, torque_drag


def _best(function, repeats: int = 3) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        function()
        times.append(time.perf_counter() - start)
    return min(times)


def long_well():
    """`deviated`'s string lengthened to 10 km of drill pipe-led string in a 10 km well: vertical to 500 m,
    3 deg/30 m to 80 deg, then a tangent with a slow turn and a small steering wiggle, a station every metre."""
    data = tomllib.loads(resources.files("drillstring").joinpath("cases", "deviated.toml").read_text())
    data["components"][0]["length"] = "9610 m"
    data["mesh"]["max_element_length"] = "10 m"
    data["mesh"]["probes"] = []
    md = np.arange(0.0, 10001.0)
    inc = np.clip((md - 500.0) / 30.0 * 3.0, 0.0, 80.0) + np.where(md > 1300, 0.3 * np.sin(md / 97.0), 0.0)
    azi = 60.0 + np.where(md > 1300, (md - 1300) / 8700 * 20.0, 0.0)
    data["well"].pop("survey_file")
    data["well"].update(measured_depth=md.tolist(), inclination=np.radians(inc).tolist(),
                        azimuth=np.radians(azi).tolist())
    return case_from_dict(data)


def report(name: str, case) -> None:
    build = _best(lambda: string_in_well(case))
    string = string_in_well(case)
    every = _best(lambda: case_torque_drag(case, string=string))
    mu = np.linspace(0.1, 0.5, 100)
    vector = _best(lambda: torque_drag(string, "trip_out", cased_friction=mu, open_hole_friction=mu))
    single = _best(lambda: [torque_drag(string, "trip_out", cased_friction=m, open_hole_friction=m) for m in mu], 1)
    nodes = len(string.measured_depth)
    print(f"{name}: {len(case.well.measured_depth):,} stations, {nodes:,} nodes; string along the path "
          f"{build * 1e3:.0f} ms; {len(OPERATIONS)} operations (with buckling) {every * 1e3:.0f} ms "
          f"({every / len(OPERATIONS) / nodes * 1e6:.2f} us per node and operation); 100 friction draws: "
          f"{vector * 1e3:.0f} ms at once vs {single * 1e3:.0f} ms one by one ({single / vector:.0f}x)")


def main() -> None:
    report("deviated (3 km)", load_case("deviated"))
    report("10 km well, 1 m stations", long_well())


if __name__ == "__main__":
    main()
