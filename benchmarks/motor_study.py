"""The downhole motor on the built-in ``motor`` case (issue 22, item 4): the numbers and figures of docs/model.md,
"Downhole motor". Run:

    .venv/bin/python benchmarks/motor_study.py [--part run,stability,map] [--out docs/studies]

- ``run``: the case as written (60 s, 60 rpm at the top, 500 gpm, 90 kN, its default basis) and the same string without the motor
  (its motor entry a plain section: the bit turns with the string) at the top speed that gives the motor case's
  steady bit speed, summarised after 20 s: the time the string just above the motor and the bit are stuck
  (below 0.1 rad/s), the bit's speed while the string above the motor is stuck; figure ``motor_stick_slip.png``.
- ``stability``: the leading torsional growth rate of steady drilling over top speed × weight-on-bit with and
  without the motor, and the boundary (the smallest weight-on-bit of torsional instability at each top speed).
- ``map``: flow rate × top speed, one 30 s run per point through the operating map's per-point function
  (:func:`drillstring.stochastic.runs.run_outputs`, the parameters ``motor.flow_rate`` and
  ``operation.top_speed`` set by :func:`~drillstring.stochastic.parameters.with_parameters`), with the steady
  motor speed and differential pressure; figure ``motor_map.png``, numbers ``motor_map.json``.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from drillstring.case import case_from_dict, load_case  # noqa: E402
from drillstring.dynamics.rom import case_reduced_model  # noqa: E402
from drillstring.dynamics.simulate import simulate_model  # noqa: E402
from drillstring.dynamics.stability import family_growth_rates, steady_drilling  # noqa: E402
from drillstring.stochastic.parameters import with_parameters  # noqa: E402
from drillstring.stochastic.runs import run_outputs, simulation_options  # noqa: E402

RPM = 30.0 / math.pi
GPM = 60.0 / 3.785411784e-3
STUCK = 0.1  # rad/s
TRANSIENT = 20.0  # s


def without_motor(case):
    """The case's string with its motor entry a plain section (no motor keys): the bit turns with the string."""
    data = case.model_dump(mode="python", exclude_none=True)
    data.pop("motor")
    return case_from_dict(data)


def _run(case, t_end):
    model = case_reduced_model(case)
    # DOPRI5, with which docs/studies/motor_study.json was made (the case now names "ark43"; one run of this
    # sensitive string is not reproduced by another method: docs/performance.md)
    return simulate_model(model, **{**simulation_options(case, t_end, case.simulation.output_step),
                                    "method": "dopri5"})


def part_run(out: Path) -> dict:
    case = load_case("motor")
    t_end = case.simulation.t_end
    steady = steady_drilling(case_reduced_model(case))
    found = {"steady": steady.to_dict()}
    runs = {"motor": case}
    plain = without_motor(case)
    runs["no_motor_same_bit_speed"] = with_parameters(plain, {"operation.top_speed": steady.bit_speed})
    runs["no_motor_same_top_speed"] = plain
    series = {}
    for name, c in runs.items():
        start = time.perf_counter()
        result = _run(c, t_end)
        wall = time.perf_counter() - start
        t, o = result.time, result.observables
        window = t >= TRANSIENT
        bit = o["bit_speed"][window]
        string = bit - o["motor_speed"][window]  # the string just above the motor (the stator)
        stuck = string < STUCK
        found[name] = {
            "top_speed_rpm": c.operation.top_speed * RPM, "wall_time_s": wall, "t_end": float(t[-1]),
            "string_at_motor_stuck_fraction": float(np.mean(stuck)),  # stopped or turning backwards
            "string_at_motor_backward_fraction": float(np.mean(string < -STUCK)),
            "bit_stuck_fraction": float(np.mean(bit < STUCK)),
            "bit_speed_rpm_min_mean_max": [float(bit.min() * RPM), float(bit.mean() * RPM), float(bit.max() * RPM)],
            "bit_speed_while_string_stuck_rpm_min_mean": ([float(bit[stuck].min() * RPM), float(bit[stuck].mean() * RPM)]
                                                          if stuck.any() else None),
            "string_at_motor_rpm_min_max": [float(string.min() * RPM), float(string.max() * RPM)],
            "mean_rate_of_penetration_m_per_h": float(np.mean(o["rate_of_penetration"][window]) * 3600),
            "motor_torque_kNm_min_max": [float(o["motor_torque"][window].min() / 1e3),
                                         float(o["motor_torque"][window].max() / 1e3)],
        }
        series[name] = (t, o)
        print(name, json.dumps(found[name]), flush=True)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t, o = series["motor"]
    keep = t >= t[-1] - 20.0
    fig, ax = plt.subplots(2, 1, figsize=(8, 5.5), sharex=True)
    ax[0].plot(t[keep], o["bit_speed"][keep] * RPM, label="bit", lw=1.0)
    ax[0].plot(t[keep], (o["bit_speed"] - o["motor_speed"])[keep] * RPM, label="string above the motor", lw=1.0)
    ax[0].plot(t[keep], o["quill_speed"][keep] * RPM, label="quill", lw=0.8)
    ax[0].set_ylabel("speed [rpm]")
    ax[0].legend(loc="upper right", fontsize=8)
    ax[0].set_title("motor case: 60 rpm at the top, 500 gpm, 90 kN on bit")
    ax[1].plot(t[keep], o["motor_torque"][keep] / 1e3, label="motor torque", lw=1.0)
    ax[1].plot(t[keep], o["torque_on_bit"][keep] / 1e3, label="torque on bit", lw=0.8)
    ax[1].set_ylabel("torque [kN·m]")
    ax[1].set_xlabel("time [s]")
    ax[1].legend(loc="upper right", fontsize=8)
    fig.tight_layout()
    fig.savefig(out / "motor_stick_slip.png", dpi=110)
    plt.close(fig)
    return found


def _torsional_growth(case) -> float:
    try:
        return family_growth_rates(case_reduced_model(case))["torsional_growth_rate"]
    except ValueError:  # no steady drilling (the motor stalls)
        return math.nan


def part_stability() -> dict:
    case = load_case("motor")
    plain = without_motor(case)
    speeds = [20.0, 40.0, 60.0, 80.0, 100.0, 120.0]  # rpm
    weights = [40.0, 60.0, 80.0, 100.0, 120.0, 140.0, 160.0]  # kN
    found = {"top_speed_rpm": speeds, "weight_on_bit_kN": weights}
    for name, base in (("motor", case), ("no_motor", plain)):
        grid = np.array([[_torsional_growth(with_parameters(base, {"operation.top_speed": f"{w} rpm",
                                                                   "operation.weight_on_bit": f"{f} kN"}))
                          for f in weights] for w in speeds])
        boundary = []
        for row in grid:  # the smallest weight-on-bit with a torsional growth rate > 0, linearly interpolated
            edge = None
            for j in range(1, len(weights)):
                if row[j - 1] <= 0.0 < row[j]:
                    edge = weights[j - 1] + (weights[j] - weights[j - 1]) * (-row[j - 1]) / (row[j] - row[j - 1])
                    break
            if edge is None and len(row) and row[0] > 0.0:
                edge = f"<= {weights[0]}"
            boundary.append(edge)
        found[name] = {"torsional_growth_rate": grid.tolist(), "boundary_weight_on_bit_kN": boundary}
        print(name, json.dumps(found[name]), flush=True)
    return found


def part_map(out: Path) -> dict:
    case = load_case("motor")
    flows = [300.0, 400.0, 500.0, 600.0, 700.0]  # gpm
    speeds = [20.0, 40.0, 60.0, 80.0, 100.0]  # rpm
    names = ("growth_rate", "torsional_growth_rate", "stick_time_fraction", "mean_rate_of_penetration",
             "bit_speed_min", "bit_speed_max")
    arrays = {name: np.full((len(flows), len(speeds)), np.nan) for name in names + ("motor_speed",
                                                                                   "differential_pressure")}
    start = time.perf_counter()
    for i, flow in enumerate(flows):
        for j, speed in enumerate(speeds):
            point = with_parameters(case, {"motor.flow_rate": f"{flow} gpm", "operation.top_speed": f"{speed} rpm"})
            outcome = run_outputs(point, i * len(speeds) + j, t_end=30.0, output_step=0.01, t_transient=10.0,
                                  with_stability=True, with_top_drive=True)
            for name in names:
                arrays[name][i, j] = outcome.values.get(name, math.nan)
            try:
                steady = steady_drilling(case_reduced_model(point)).motor
                arrays["motor_speed"][i, j] = steady["motor_speed"]
                arrays["differential_pressure"][i, j] = steady["differential_pressure"]
            except ValueError:
                pass
            print(f"{flow:.0f} gpm {speed:.0f} rpm: {outcome.status} growth {arrays['growth_rate'][i, j]:+.4f} "
                  f"torsional {arrays['torsional_growth_rate'][i, j]:+.4f} stick {arrays['stick_time_fraction'][i, j]:.2f}"
                  f" ROP {arrays['mean_rate_of_penetration'][i, j] * 3600:.2f} m/h", flush=True)
    found = {"flow_rate_gpm": flows, "top_speed_rpm": speeds, "wall_time_s": time.perf_counter() - start,
             **{name: values.tolist() for name, values in arrays.items()}}
    (out / "motor_map.json").write_text(json.dumps(found, indent=1), encoding="utf-8")
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(1, 3, figsize=(12, 3.8))
    for a, (name, scale, label) in zip(ax, (("torsional_growth_rate", 1.0, "torsional growth rate [1/s]"),
                                            ("stick_time_fraction", 1.0, "bit stick time fraction"),
                                            ("mean_rate_of_penetration", 3600.0, "mean ROP [m/h]"))):
        image = a.pcolormesh(speeds, flows, arrays[name] * scale, shading="nearest")
        fig.colorbar(image, ax=a)
        a.set_title(label, fontsize=9)
        a.set_xlabel("top speed [rpm]")
    ax[0].set_ylabel("motor flow rate [gpm]")
    fig.tight_layout()
    fig.savefig(out / "motor_map.png", dpi=110)
    plt.close(fig)
    return found


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--part", default="run,stability,map")
    parser.add_argument("--out", default="docs/studies")
    args = parser.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    found = {}
    parts = args.part.split(",")
    if "run" in parts:
        found["run"] = part_run(out)
    if "stability" in parts:
        found["stability"] = part_stability()
    if "map" in parts:
        found["map"] = part_map(out)
    path = out / "motor_study.json"
    previous = json.loads(path.read_text(encoding="utf-8")) if path.exists() else {}
    path.write_text(json.dumps({**previous, **{k: v for k, v in found.items() if k != "map"}}, indent=1),
                    encoding="utf-8")


if __name__ == "__main__":
    main()
