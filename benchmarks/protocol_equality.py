"""Equality of a source tree with another (issue 22, the component protocol): every output array of one run
and every eigenvalue of the stability analysis of the built-in cases, saved by each tree and compared.

    python benchmarks/protocol_equality.py save OUT.npz          # run with PYTHONPATH=<tree>/src
    python benchmarks/protocol_equality.py compare A.npz B.npz    # the largest relative difference

``save --gravity 9.81`` sets ``environment.gravity`` [m/s^2] of every case (standard gravity is the default of
a case without it since issue 37; ``reference`` and ``contact`` write 9.81): a tree saved so against one from
before that change tells whether g is the whole difference. ``save --cases a,b`` runs those of the cases below
(the stick-slip variants always).

The cases: ``reference``, ``stick_slip``, ``contact``, ``aarsnes2019`` and ``motor`` as written (their bases of
today, their own run length), and, for the top boundaries, the stick-slip case under each controller
(``pi``, ``soft_torque``, ``z_torque``, 3 s), and off bottom.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402

import numpy as np  # noqa: E402

CASES = ("reference", "stick_slip", "contact", "aarsnes2019", "motor")
CONTROLLERS = {"pi": {"controller": "pi", "proportional_gain": 2000.0, "integral_gain": 4000.0},
               "soft_torque": {"controller": "soft_torque"}, "z_torque": {"controller": "z_torque"}}


def _variants(cases=CASES, gravity: float | None = None):
    from drillstring.case import load_case as load_written

    def load_case(name):
        case = load_written(name)
        if gravity is None:
            return case
        return case.model_copy(update={"environment": case.environment.model_copy(update={"gravity": gravity})})

    for name in cases:
        yield name, load_case(name), None
    base = load_case("stick_slip")
    for name, fields in CONTROLLERS.items():
        case = base.model_copy(update={"top_drive": base.top_drive.model_copy(update=fields)})
        yield f"stick_slip_{name}", case, 3.0
    case = base.model_copy(update={"bit_rock": base.bit_rock.model_copy(update={"law": "off_bottom"})})
    yield "stick_slip_off_bottom", case, 2.0


def save(path: str, cases=CASES, gravity: float | None = None) -> None:
    from drillstring.api import simulate, stability

    out = {}
    for name, case, t_end in _variants(cases, gravity):
        data = simulate(case, t_end=t_end)
        for var in data.data_vars:
            out[f"{name}/{var}"] = np.asarray(data[var].values, dtype=float)
        out[f"{name}/time"] = np.asarray(data["time"].values, dtype=float)
        try:
            result = stability(case)
        except ValueError as error:
            print(name, "stability:", error, flush=True)
            continue
        modes = sorted(result.modes, key=lambda m: (m.frequency, m.growth_rate))
        out[f"{name}/eigenvalues"] = np.array([[m.growth_rate, m.frequency, m.damping_ratio] for m in modes])
        out[f"{name}/steady"] = np.array(list(result.steady_state.to_dict().values()), dtype=float)
        print(name, "done", flush=True)
    np.savez(path, **out)


def compare(a: str, b: str) -> None:
    x, y = np.load(a), np.load(b)
    keys = sorted(set(x.files) | set(y.files))
    worst = 0.0
    for key in keys:
        if key not in x.files or key not in y.files:
            print(f"{key}: only in {'the first' if key in x.files else 'the second'}")
            worst = np.inf
            continue
        u, v = x[key], y[key]
        if u.shape != v.shape:
            print(f"{key}: shapes {u.shape} and {v.shape}")
            worst = np.inf
            continue
        scale = np.max(np.abs(u)) if u.size else 0.0
        diff = float(np.max(np.abs(u - v)) / scale) if scale > 0 else float(np.max(np.abs(u - v), initial=0.0))
        worst = max(worst, diff)
        if diff > 1e-12:
            print(f"{key}: {diff:.3g}")
    print(f"largest relative difference (max |a - b| / max |a| per array): {worst:.3g} over {len(keys)} arrays")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    commands = parser.add_subparsers(dest="command", required=True)
    saving = commands.add_parser("save", help="run the cases and save every array to OUT.npz")
    saving.add_argument("out")
    saving.add_argument("--gravity", type=float, default=None, help="environment.gravity of every case [m/s^2]")
    saving.add_argument("--cases", default=",".join(CASES), help="the built-in cases run as written (the stick-slip variants always run)")
    comparing = commands.add_parser("compare", help="the largest relative difference of each array")
    comparing.add_argument("first")
    comparing.add_argument("second")
    args = parser.parse_args()
    if args.command == "save":
        save(args.out, tuple(name for name in args.cases.split(",") if name), args.gravity)
    else:
        compare(args.first, args.second)


if __name__ == "__main__":
    main()
