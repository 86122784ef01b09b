"""The implicit-explicit runs of two source trees set beside the integration error (issue 33: the IMEX stiff part
on the laws' compiled Jacobians instead of central differences of the compiled laws). The stiff part's matrix
moves by the differences' error (about 1e-10 relative), so the runs of ``ark43`` and ``ark32`` move; this tells
whether that move is below what the step-size controller's tolerance already makes of the run.

    python benchmarks/stiff_jacobian_equality.py save OUT.npz        # run with PYTHONPATH=<tree>/src
    python benchmarks/stiff_jacobian_equality.py compare BASE.npz NEW.npz

``save`` runs each case of :data:`RUNS` (a built-in case under an IMEX method, its own length and tolerances)
three times: at the case's ``rtol``/``atol``, at both divided by ``--tighten`` (10) and at ``rtol`` nudged by
:data:`NUDGE` (a change that means nothing), keeping the observables and the step counts. ``compare`` prints,
per run and observable, the largest difference relative to the largest value of NEW, of BASE at the tighter
tolerance (the size of the integration error) and of BASE nudged, each against BASE, the first output time at
which each passes 1e-9, 1e-6 and 1e-3, the mean and standard deviation over the run's second half, and the
step counts (accepted, rejected, right-hand sides).
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse

import numpy as np

#: (label, built-in case, method)
RUNS = (("aarsnes2019_ark43", "aarsnes2019", "ark43"), ("motor_ark43", "motor", "ark43"),
        ("aarsnes2019_ark32", "aarsnes2019", "ark32"), ("motor_ark32", "motor", "ark32"))
OBSERVABLES = ("rate_of_penetration", "bit_speed", "torque_on_bit", "force_on_bit", "bit_depth")
THRESHOLDS = (1e-9, 1e-6, 1e-3)
#: the relative change of rtol of the nudged run: a change of the run that means nothing
NUDGE = 1e-3


def save(path: str, tighten: float) -> None:
    from drillstring.case import load_case
    from drillstring.dynamics.rom import case_reduced_model
    from drillstring.dynamics.simulate import simulate_model

    out = {}
    for label, name, method in RUNS:
        case = load_case(name)
        s = case.simulation
        model = case_reduced_model(case)
        for tag, rtol, atol in (("", s.rtol, s.atol), ("tight/", s.rtol / tighten, s.atol / tighten),
                                ("nudged/", s.rtol * (1.0 + NUDGE), s.atol)):
            run = simulate_model(model, t_end=s.t_end, output_step=s.output_step, rtol=rtol, atol=atol, method=method,
                                 lateral_perturbation=case.initial.lateral_perturbation, seed=case.initial.seed)
            for key in OBSERVABLES:
                out[f"{tag}{label}/{key}"] = np.asarray(run.observables[key], dtype=float)
            out[f"{tag}{label}/time"] = np.asarray(run.time, dtype=float)
            out[f"{tag}{label}/counts"] = np.array([run.stats[k] for k in ("n_accepted", "n_rejected", "n_rhs")])
        print(label, "done", flush=True)
    np.savez(path, **out)


def _difference(a: np.ndarray, b: np.ndarray, time: np.ndarray) -> tuple[float, list]:
    scaled = np.abs(a - b) / np.abs(a).max()
    first = [f"{time[np.argmax(scaled > x)]:.2f}" if (scaled > x).any() else "-" for x in THRESHOLDS]
    return float(scaled.max()), first


def compare(base: str, new: str) -> None:
    x, y = np.load(base), np.load(new)
    print("largest |a - b| / max |a| per observable against BASE; 'from': the first output time [s] past "
          + ", ".join(f"{t:g}" for t in THRESHOLDS) + f"; 'tight': BASE at the tighter tolerance, 'nudged': BASE "
          f"at rtol x (1 + {NUDGE:g}); mean and standard deviation over the run's second half")
    others = (("new", y, ""), ("tight", x, "tight/"), ("nudged", x, "nudged/"))
    for label, _, _ in RUNS:
        time = x[f"{label}/time"]
        half = time >= 0.5 * time[-1]
        print(f"{label}: steps (accepted, rejected, RHS) base {x[f'{label}/counts'].tolist()}, "
              + ", ".join(f"{name} {data[f'{tag}{label}/counts'].tolist()}" for name, data, tag in others))
        for key in OBSERVABLES:
            a = x[f"{label}/{key}"]
            cells, stats = [], [f"base {a[half].mean():.5g} ± {a[half].std():.4g}"]
            for name, data, tag in others:
                b = data[f"{tag}{label}/{key}"]
                moved, moved_from = _difference(a, b, time)
                cells.append(f"{name} {moved:8.2g} from {'/'.join(moved_from):16s}")
                stats.append(f"{name} {b[half].mean():.5g} ± {b[half].std():.4g}")
            print(f"  {key:19s} " + " | ".join(cells))
            print(f"  {'':19s} " + ", ".join(stats))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser("save")
    p.add_argument("path")
    p.add_argument("--tighten", type=float, default=10.0)
    p = sub.add_parser("compare")
    p.add_argument("base")
    p.add_argument("new")
    args = parser.parse_args()
    if args.command == "save":
        save(args.path, args.tighten)
    else:
        compare(args.base, args.new)


if __name__ == "__main__":
    main()
