"""What each top-drive controller does on the built-in ``stick_slip`` and ``reference`` cases: closed-loop
stability of steady drilling (leading eigenvalue) and one simulation with the case's settings, summarised after
the start-up (stick time fraction, bit-speed range, mean ROP, surface-torque amplitude). The numbers of
docs/model.md, "Top drive". Run:

    .venv/bin/python benchmarks/top_drive_controllers.py [--cases stick_slip,reference]

On ``reference`` the ``pi`` controller has the stick_slip case's stiff gains (k_p = 3e4 N·m·s/rad,
k_i = 3e5 N·m/rad); ``soft_torque`` and ``z_torque`` tune theirs.
"""

from __future__ import annotations

import argparse
import math


from drillstring.case import load_case
from drillstring.dynamics.indicators import drilling_indicators
from drillstring.dynamics.rom import case_reduced_model
from drillstring.dynamics.simulate import simulate_model
from drillstring.dynamics.stability import stability

RPM = 30.0 / math.pi
CONTROLLERS = {
    "imposed_speed": {"controller": "imposed_speed"},
    "pi": {"controller": "pi", "proportional_gain": 3e4, "integral_gain": 3e5},
    "soft_torque": {"controller": "soft_torque", "proportional_gain": None, "integral_gain": None},
    "z_torque": {"controller": "z_torque", "proportional_gain": None, "integral_gain": None},
}
TRANSIENT = {"stick_slip": 30.0, "reference": 10.0}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--cases", default="stick_slip,reference")
    args = parser.parse_args()
    print("| case | controller | leading growth rate [1/s] at [Hz] | stick time | bit speed [rpm] | mean ROP [m/h] "
          "| surface torque amplitude [kN·m] | quill speed [rpm] |")
    print("|---|---|---|---|---|---|---|---|")
    for name in args.cases.split(","):
        base = load_case(name)
        s = base.simulation
        for controller, fields in CONTROLLERS.items():
            case = base.model_copy(update={"top_drive": base.top_drive.model_copy(update=fields)})
            model = case_reduced_model(case)
            lead = stability(model).leading
            run = simulate_model(model, t_end=s.t_end, output_step=s.output_step, rtol=s.rtol, atol=s.atol,
                                 lateral_perturbation=case.initial.lateral_perturbation, seed=case.initial.seed)
            o = run.observables
            ind = drilling_indicators(run.time, o["rate_of_penetration"], o["bit_speed"], case.operation.top_speed,
                                      TRANSIENT[name])
            steady = run.time >= TRANSIENT[name]
            torque = o["surface_torque"][steady]
            quill = o["quill_speed"][steady]
            print(f"| {name} | {controller} | {lead.growth_rate:+.4f} at {lead.frequency:.3f} "
                  f"| {ind['stick_time_fraction']:.0%} | {ind['bit_speed_min'] * RPM:.1f} – {ind['bit_speed_max'] * RPM:.1f} "
                  f"| {ind['mean_rate_of_penetration'] * 3600:.2f} | {(torque.max() - torque.min()) / 2e3:.2f} "
                  f"| {quill.min() * RPM:.1f} – {quill.max() * RPM:.1f} |", flush=True)
            if controller != "imposed_speed":
                d = model.top_drive
                print(f"<!-- {name} {controller}: k_p = {d.proportional_gain:.4g}, k_i = {d.integral_gain:.4g}, "
                      f"omega_f = {d.filter_frequency:.4g}, tuned {list(d.tuned)} -->", flush=True)


if __name__ == "__main__":
    main()
