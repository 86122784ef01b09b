"""Basis convergence and cost of the truncation correction (issue 22, item 3).

    python benchmarks/basis_convergence.py [--modes 10 20 40 80] [--t-end 3] [--motor]

1. ``aarsnes2019``: the leading root of steady drilling with ``n`` axial + ``n`` torsional modes, plain
   (``reduced_model.truncation_correction = "none"``) and corrected (``"static"``: plus the residual-flexibility
   attachment modes at the bit), its energy shares, and the fastest root of the basis's cut-off (the roots
   living in the attachment modes). Up to 20 modes every root is found (:func:`stability`); above, the root
   nearest the 10-mode one by Newton's method on det Δ (the full root search grows like the cube of the basis).
2. Cost of the attachment modes for the explicit integrator (dopri5, rtol 1e-6): accepted and rejected steps
   and wall time of the same run with and without them, in the same process, for ``reference`` (Tucker–Wang law,
   imposed speed), ``stick_slip`` (a top drive:
   two torsional attachment modes, bit and top, and one axial) and ``aarsnes2019`` (the Detournay law).
3. ``motor`` (``--motor``): the leading root of steady drilling and the first axial root with ``n`` + ``n``
   modes, plain and corrected (the released torsion's attachment modes at the bit, the motor's torque pair and
   the top, :func:`drillstring.rotor.released_torsional_modes`); every root found (:func:`stability`).
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import math  # noqa: E402
import time  # noqa: E402


def _with(case, correction: str):
    return case.model_copy(update={"reduced_model": case.reduced_model.model_copy(
        update={"truncation_correction": correction})})


def convergence(modes: list[int]) -> None:
    from drillstring.case import load_case
    from drillstring.dynamics.delay_stability import _newton
    from drillstring.dynamics.rom import case_reduced_model
    from drillstring.dynamics.stability import delay_matrices, stability, steady_drilling

    base = load_case("aarsnes2019")
    print("aarsnes2019, leading root of steady drilling (growth rate [1/s], frequency [Hz], energy shares)")
    print("| basis | modes | leading root | axial/torsional share | fastest cut-off root | time |")
    print("|---|---|---|---|---|---|")
    for correction in ("none", "static"):
        case = _with(base, correction)
        start = None
        for n in modes:
            t = time.perf_counter()
            model = case_reduced_model(case, axial_modes=n, torsional_modes=n)
            if n <= 20 or start is None:
                found = stability(model)
                lead = found.leading
                start = lead.eigenvalue if start is None else start
                cut = [m for m in found.modes if m.beyond_basis]
                fastest = max(cut, key=lambda m: m.growth_rate) if cut else None
                text = (f"{lead.growth_rate:+.4f} at {lead.frequency:.3f}",
                        f"{lead.shares['axial']:.2f}/{lead.shares['torsional']:.2f}",
                        "-" if fastest is None else f"{fastest.growth_rate:+.3f} at {fastest.frequency:.1f}")
            else:
                steady = steady_drilling(model)
                a0, a1 = delay_matrices(model, steady)
                root = complex(_newton(a0, a1, steady.delay, [start])[0])
                text = (f"{root.real:+.4f} at {root.imag / (2 * math.pi):.3f} (Newton)", "", "")
            print(f"| {correction} | {n} + {n} | {text[0]} | {text[1]} | {text[2]} | {time.perf_counter() - t:.1f} s |",
                  flush=True)


def cost(t_end: float) -> None:
    from drillstring.case import load_case
    from drillstring.dynamics.rom import case_reduced_model
    from drillstring.dynamics.simulate import simulate_model

    print(f"\nexplicit integrator, {t_end:g} s of each case (dopri5, the case's tolerances)")
    print("| case | basis | basis size | highest ω/2π [Hz] | accepted | rejected | wall [s] |")
    print("|---|---|---|---|---|---|---|")
    warm = simulate_model(case_reduced_model(load_case("stick_slip")), t_end=0.05, output_step=0.01)  # compile
    del warm
    for name in ("reference", "stick_slip", "aarsnes2019"):
        base = load_case(name)
        for correction in ("none", "static"):
            case = _with(base, correction)
            model = case_reduced_model(case)
            s = case.simulation
            t = time.perf_counter()
            run = simulate_model(model, t_end=t_end, output_step=s.output_step, rtol=s.rtol, atol=s.atol,
                                 lateral_perturbation=case.initial.lateral_perturbation, seed=case.initial.seed)
            wall = time.perf_counter() - t
            stats = run.stats
            print(f"| {name} | {correction} | {model.size} | {model.angular_frequencies.max() / (2 * math.pi):.1f} | "
                  f"{stats.get('n_accepted', '?')} | {stats.get('n_rejected', '?')} | "
                  f"{wall:.2f} |", flush=True)


def motor_convergence(modes: list[int]) -> None:
    from drillstring.case import load_case
    from drillstring.dynamics.rom import case_reduced_model
    from drillstring.dynamics.stability import stability

    base = load_case("motor")
    print("\nmotor, steady drilling: leading root and first axial root (growth rate [1/s] at frequency [Hz])")
    print("| basis | modes | size | leading root | first axial root | fastest cut-off root | time |")
    print("|---|---|---|---|---|---|---|")
    for correction in ("none", "static"):
        case = _with(base, correction)
        for n in modes:
            t = time.perf_counter()
            model = case_reduced_model(case, axial_modes=n, torsional_modes=n)
            found = stability(model)
            lead = found.leading
            axial = min((m for m in found.modes if m.frequency > 0.1 and not m.beyond_basis
                         and m.shares["axial"] > 0.5), key=lambda m: m.frequency)
            cut = [m for m in found.modes if m.beyond_basis and m.frequency > 0]
            fastest = max(cut, key=lambda m: m.growth_rate) if cut else None
            print(f"| {correction} | {n} + {n} | {model.size} | {lead.growth_rate:+.5f} at {lead.frequency:.4f} "
                  f"({'torsional' if lead.shares['torsional'] > 0.5 else 'axial'}) | "
                  f"{axial.growth_rate:+.4f} at {axial.frequency:.4f} | "
                  f"{'-' if fastest is None else f'{fastest.growth_rate:+.2f} at {fastest.frequency:.1f}'} | "
                  f"{time.perf_counter() - t:.1f} s |", flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--modes", type=int, nargs="+", default=[10, 20, 40, 80])
    parser.add_argument("--t-end", type=float, default=3.0)
    parser.add_argument("--motor", action="store_true", help="the motor case's table only")
    args = parser.parse_args()
    if args.motor:
        motor_convergence(args.modes)
        return
    convergence(args.modes)
    cost(args.t_end)


if __name__ == "__main__":
    main()
