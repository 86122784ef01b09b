"""Benchmark: an operating map of the reference case, 17 × 13 points (221 runs of 20 s), on local
processes and on a local Dask cluster.

Prints the wall time of the map, points per second, the speed-up over the serial cost of the points
projected from a random sample of them run one after the other in this process (the baseline, measured in
the same run), and the sum of the points' own times over the wall time (the parallelism achieved). The
load average is printed too: the machine is shared. Goal: <= 3 min on the project's 2-core machine. Run:

    .venv/bin/python benchmarks/bench_map.py [--grid 17x13] [--t-end 20] [--dask] [--sample 8]
"""

from __future__ import annotations

import argparse
from pathlib import Path

from _engine import cores, load_average, local_dask_cluster, serial_cost, timed_in_folder  # before NumPy

from drillstring import api
from drillstring.case import load_case
from drillstring.stochastic.operating_map import _point_task


def timed_map(case, settings, keep: Path | None = None, **engine):
    return timed_in_folder(
        "bench_map_", lambda folder: api.operating_map(
            case, top_speed=settings.top_speed, weight_on_bit=settings.weight_on_bit, t_end=settings.t_end,
            out=folder, **engine),
        keep, ("map.nc", "map.json", "map.png", "report.html"))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--grid", default="17x13", help="top speeds x weights-on-bit (default 17x13)")
    parser.add_argument("--t-end", type=float, default=20.0)
    parser.add_argument("--sample", type=int, default=8, help="points run serially for the baseline")
    parser.add_argument("--dask", action="store_true", help="also time a local Dask cluster (2 workers)")
    parser.add_argument("--keep", type=Path, default=None, help="copy the local map's files to this folder")
    args = parser.parse_args()
    n_speed, n_wob = (int(v) for v in args.grid.lower().split("x"))
    case = load_case("reference")
    settings = api.map_settings(case, top_speed=f"40 rpm:200 rpm:{n_speed}", weight_on_bit=f"40 kN:160 kN:{n_wob}",
                                t_end=args.t_end)
    print(load_average("start"))

    # baseline: a sample of the points, one after the other in this process
    per_point, sampled = serial_cost(lambda i: _point_task(case, settings, (i, *settings.point(i))),
                                     settings.points, args.sample)
    serial = per_point * settings.points
    print(f"map {n_speed} x {n_wob} = {settings.points} points, runs of {args.t_end:g} s, {cores()} cores; "
          f"serial cost {per_point:.3f} s per point (sample of {sampled}) -> {serial:.1f} s projected serially")

    rows = []
    wall, outcome = timed_map(case, settings, args.keep)
    rows.append(("local processes (one per core)", wall, outcome))
    if args.dask:
        with local_dask_cluster() as address:
            wall, outcome = timed_map(case, settings, scheduler=address)
        rows.append(("local Dask cluster, 2 workers", wall, outcome))
    for label, wall, outcome in rows:
        s = outcome.summary
        busy = float(outcome.dataset.wall_time.sum())
        print(f"  {label:32s} {wall:7.1f} s  {settings.points / wall:6.2f} points/s  speed-up {serial / wall:4.2f}x"
              f" over the serial projection; sum of the points' own times {busy:.1f} s = {busy / wall:.2f} x the "
              f"wall time  (done {s['done']}, failed {s['failed']}; goal <= 180 s: {'met' if wall <= 180 else 'NOT met'})")
    s = rows[0][2].summary
    print(f"  linearly stable points {s['linearly_stable_points']}, stick-slip points {s['stick_slip_points']}, "
          f"critical WOB {s['critical_weight_on_bit'] / 1e3:.1f} kN")


if __name__ == "__main__":
    main()
    print(load_average("end"))
