"""The deviated case's dynamics with along-string friction against the soft-string torque and drag (issue 34,
items 3-4; docs/stiff_string.md, "Dynamics in the well").

    PYTHONPATH=src python benchmarks/deviated_friction.py [--t-end 40] [--window 20]

Prints, for the ``deviated`` case (its [well], [string_friction]):

1. rotating off bottom: the time-mean surface torque over the last ``window`` seconds of a ``t_end`` run
   against the soft string's (``case_torque_drag``: rotating_off_bottom) and the stiff string's Σ μ N r, at
   three regularisation speeds and three torsional mode counts (the modal truncation of the twist);
2. drilling (the case's Tucker-Wang law at its weight on bit): time-mean surface torque, torque and force on
   bit, against the soft string's drilling torque (whose torque on bit is the case's ``well.torque_on_bit``)
   and its hook load; the hook load of the reduced model is the static state's (a constant hook force);
3. the torsional oscillation with and without friction: the bit speed's range and standard deviation over the
   window, off bottom and drilling, and the decay of the off-bottom start-up transient;
4. a static factor with a Stribeck decay (k_s = 1.5, v_S = 0.1 m/s) off bottom at 120, 60 and 30 rpm: the bit
   speed's range over the window against the kinetic friction's (a friction weakening with speed can drive the
   string's own stick-slip).
"""

from __future__ import annotations

import argparse
import dataclasses
import time

import numpy as np

from drillstring.case import load_case
from drillstring.dynamics.rom import case_reduced_model
from drillstring.dynamics.simulate import simulate_model
from drillstring.forces.string_friction import CoulombStringFriction
from drillstring.well.torque_drag import case_torque_drag


def _run(model, case, t_end):
    start = time.perf_counter()
    result = simulate_model(model, t_end=t_end, output_step=0.01, method=case.simulation.method,
                            rtol=case.simulation.rtol, atol=case.simulation.atol)
    return result, time.perf_counter() - start


def _window(result, name, window):
    keep = result.time >= result.time[-1] - window
    return np.asarray(result.observables[name])[keep]


def _bit_speed_line(label, result, window):
    w = _window(result, "bit_speed", window)
    return (f"  {label:<34s} bit speed mean {w.mean():7.3f} rad/s, range [{w.min():7.3f}, {w.max():7.3f}], "
            f"std {w.std():.4f}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--t-end", type=float, default=40.0)
    parser.add_argument("--window", type=float, default=20.0)
    args = parser.parse_args()
    case = load_case("deviated")
    off = case.model_copy(update={"bit_rock": case.bit_rock.model_copy(update={"law": "off_bottom"})})
    soft = case_torque_drag(case)
    soft_off = soft["rotating_off_bottom"]
    soft_drill = soft["drilling"]
    print(f"soft string: rotating off bottom {soft_off.torque[0]:.1f} N*m, hook {soft_off.axial_force[0]:.0f} N; "
          f"drilling {soft_drill.torque[0]:.1f} N*m (TOB {soft_drill.torque_on_bit:.0f}), hook "
          f"{soft_drill.axial_force[0]:.0f} N")

    print("\n1. rotating off bottom: time-mean surface torque [N*m] over the window")
    for modes in (10, 20, 40):
        model = case_reduced_model(off, torsional_modes=modes)
        fs = model.friction_stations
        if modes == 10:
            print(f"  stiff string: {len(fs)} nodes on the wall, sum N {fs.normal_force.sum():.0f} N, "
                  f"sum mu N r {fs.rotating_torque():.1f} N*m, hook {model.static.weight_on_hook:.0f} N")
        for v_reg in ((0.1, 0.01, 0.001) if modes == 10 else (0.01,)):
            friction = dataclasses.replace(model, string_friction=CoulombStringFriction(v_reg))
            result, wall = _run(friction, off, args.t_end)
            torque = _window(result, "surface_torque", args.window)
            slide = fs.radius * off.operation.top_speed
            expected = float(np.sum(fs.friction * fs.normal_force * fs.radius * slide / np.hypot(slide, v_reg)))
            print(f"  torsional modes {modes:3d}, v_reg {v_reg:6.3f} m/s: mean {torque.mean():9.1f} (range "
                  f"{torque.min():8.1f}..{torque.max():8.1f}); /sum(mu N r) {torque.mean() / fs.rotating_torque():.4f}"
                  f", /regularised sum {torque.mean() / expected:.4f}, /soft {torque.mean() / soft_off.torque[0]:.4f}"
                  f"; {result.stats['n_steps']} steps, {wall:.2f} s")
            if modes == 10 and v_reg == 0.01:
                off_friction = result
    plain = dataclasses.replace(case_reduced_model(off), string_friction=None)
    off_plain, _ = _run(plain, off, args.t_end)

    print("\n2. drilling (the case's bit law at its weight on bit)")
    model = case_reduced_model(case)
    drilling, wall = _run(model, case, args.t_end)
    torque = _window(drilling, "surface_torque", args.window)
    tob = _window(drilling, "torque_on_bit", args.window)
    fob = _window(drilling, "force_on_bit", args.window)
    rop = _window(drilling, "rate_of_penetration", args.window)
    print(f"  surface torque mean {torque.mean():.1f} N*m (soft string {soft_drill.torque[0]:.1f}); torque on bit "
          f"mean {tob.mean():.1f} (soft string's {soft_drill.torque_on_bit:.0f}); surface - TOB {torque.mean() - tob.mean():.1f}"
          f" (soft string {soft_drill.torque[0] - soft_drill.torque_on_bit:.1f}, stiff sum mu N r "
          f"{model.friction_stations.rotating_torque():.1f})")
    print(f"  force on bit mean {fob.mean():.0f} N (static WOB {model.weight_on_bit:.0f}); ROP mean {rop.mean() * 3600:.2f} m/h;"
          f" hook load (constant, the static state's) {model.static.weight_on_hook:.0f} N (soft string "
          f"{soft_drill.axial_force[0]:.0f}); {drilling.stats['n_steps']} steps, {wall:.2f} s")
    drilling_plain, _ = _run(dataclasses.replace(model, string_friction=None), case, args.t_end)

    print("\n3. torsional oscillation over the window, with and without friction")
    print(_bit_speed_line("off bottom, friction (v_reg 0.01)", off_friction, args.window))
    print(_bit_speed_line("off bottom, no friction", off_plain, args.window))
    print(_bit_speed_line("drilling, friction", drilling, args.window))
    print(_bit_speed_line("drilling, no friction", drilling_plain, args.window))
    for label, result in (("off bottom, friction", off_friction), ("off bottom, no friction", off_plain)):
        speed = np.asarray(result.observables["bit_speed"]) - off.operation.top_speed
        t = result.time
        early = np.abs(speed[(t > 2.0) & (t <= 12.0)]).max()
        late = np.abs(speed[t > t[-1] - 10.0]).max()
        print(f"  {label:<34s} |bit speed - top speed| max over 2-12 s {early:.3f}, over the last 10 s {late:.3f} rad/s")

    print("\n4. static factor 1.5, Stribeck speed 0.1 m/s, off bottom (window as above)")
    for rpm in (120.0, 60.0, 30.0):
        at = off.model_copy(update={"operation": off.operation.model_copy(update={"top_speed": rpm * np.pi / 30.0})})
        model = case_reduced_model(at)
        for label, law in (("kinetic", CoulombStringFriction(0.01)),
                           ("k_s 1.5, v_S 0.1", CoulombStringFriction(0.01, 1.5, 0.1))):
            result, _ = _run(dataclasses.replace(model, string_friction=law), at, args.t_end)
            torque = _window(result, "surface_torque", args.window)
            print(_bit_speed_line(f"{rpm:g} rpm, {label}", result, args.window)
                  + f"; surface torque mean {torque.mean():.0f}, range {torque.min():.0f}..{torque.max():.0f} N*m")


if __name__ == "__main__":
    main()
