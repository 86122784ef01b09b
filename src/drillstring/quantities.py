"""One name, one unit and one description per output quantity, shared by every layer (results,
statistics, figures, reports). Units are SI; conversions for display happen in plots and tables."""

from drillstring.units import DisplayUnit, display_unit

UNITS = {
    "time": "s",
    "rate_of_penetration": "m/s",
    "bit_speed": "rad/s",
    "torque_on_bit": "N m",
    "force_on_bit": "N",
    "bit_depth": "m",
    "nodes_in_contact": "1",
    "contact_force": "N",
    "quill_speed": "rad/s",
    "surface_torque": "N m",
    "depth_of_cut": "m",
    "motor_speed": "rad/s",
    "motor_torque": "N m",
    "differential_pressure": "Pa",
    "hook_load": "N",
    "wear_flat_force": "N",
    "lateral_displacement": "m",
    "radial_displacement": "m",
    "x": "m",
    "weight_on_hook": "N",
    "weight_on_bit": "N",
}

LONG_NAMES = {
    "rate_of_penetration": "rate of penetration (bit axial velocity, down positive)",
    "bit_speed": "bit rotation speed",
    "torque_on_bit": "torque on bit (rock torque opposing the rotation)",
    "force_on_bit": "force on bit (rock reaction, upward positive)",
    "bit_depth": "bit advance from the static state",
    "nodes_in_contact": "number of nodes touching the borehole",
    "contact_force": "total normal force of the borehole wall on the string",
    "quill_speed": "rotation speed of the top (quill) of the string",
    "surface_torque": "torque the string takes from the quill (with a top drive: motor torque minus the quill's "
                      "inertial torque; with the speed imposed: elastic torque of the top element)",
    "depth_of_cut": "depth of cut per blade (Detournay law; 0 for the other laws)",
    "motor_speed": "downhole motor speed (its rotor relative to its stator: bit speed minus the string's above it)",
    "motor_torque": "downhole motor torque (its rotor's on the string below it)",
    "differential_pressure": "differential pressure across the downhole motor's power section",
    "hook_load": "hook load (the static one plus the weight not yet transferred to the bit during a ramp)",
    "wear_flat_force": "wear-flat part of the force on bit (Detournay law: force on bit minus the cutting force)",
    "lateral_displacement": "lateral displacement (v along y, w along z)",
    "radial_displacement": "radial (lateral) displacement",
    "weight_on_hook": "weight on hook",
    "weight_on_bit": "static weight on bit",
}

#: The kind of display unit of each observable (:func:`drillstring.units.display_unit`): tables, figures and
#: reports show it in the unit of this kind in the chosen unit system (si or field).
DISPLAY_KINDS = {
    "rate_of_penetration": "rate_of_penetration",
    "bit_speed": "angular_speed",
    "torque_on_bit": "torque",
    "quill_speed": "angular_speed",
    "surface_torque": "torque",
    "force_on_bit": "force",
    "depth_of_cut": "small_length",
    "motor_speed": "angular_speed",
    "motor_torque": "torque",
    "differential_pressure": "pressure",
    "hook_load": "force",
    "wear_flat_force": "force",
    "bit_depth": "length",
    "contact_force": "force",
    "lateral_displacement": "small_length",
    "radial_displacement": "small_length",
    "x": "length",
    "weight_on_hook": "force",
    "weight_on_bit": "force",
}

#: Observables kept for every realization (each (realization, time)); plus radial_displacement.
STUDY_OBSERVABLES = ("rate_of_penetration", "bit_speed", "torque_on_bit", "force_on_bit")
#: Observables kept too when the case has a top drive (:func:`~drillstring.dynamics.indicators.has_top_drive`);
#: with an imposed speed the quill turns at the set point and they are not stored.
TOP_DRIVE_OBSERVABLES = ("quill_speed", "surface_torque")


def stored_observables(data) -> tuple[str, ...]:
    """The study observables held by ``data`` (a study's raw Dataset, holding ``<v>``, or its statistics,
    holding ``<v>_mean``), in order: :data:`STUDY_OBSERVABLES` and those of :data:`TOP_DRIVE_OBSERVABLES` it
    has."""
    return STUDY_OBSERVABLES + tuple(name for name in TOP_DRIVE_OBSERVABLES
                                     if name in data or f"{name}_mean" in data)


#: The per-realization cycle metrics in tables and figures: name -> (unit, label). The unit is a kind of
#: :func:`drillstring.units.display_unit` (shown in the chosen unit system) or a fixed
#: :class:`~drillstring.units.DisplayUnit` (a plain number, a time, a percentage): :func:`metric_unit`.
METRIC_DISPLAY: dict[str, tuple[str | DisplayUnit, str]] = {
    "stick_slip_index": (DisplayUnit("-", 1.0), "stick-slip index"),
    "bit_speed_min": ("angular_speed", "bit speed min"),
    "bit_speed_max": ("angular_speed", "bit speed max"),
    "period": (DisplayUnit("s", 1.0), "period"),
    "mean_rate_of_penetration": ("rate_of_penetration", "ROP mean"),
    "mean_torque_on_bit": ("torque", "TOB mean"),
    "mean_force_on_bit": ("force", "FOB mean"),
    "mechanical_specific_energy": ("pressure", "MSE"),
    "stick_time_fraction": (DisplayUnit("%", 100.0), "stick time"),
    "bit_bounce_fraction": (DisplayUnit("%", 100.0), "bit bounce"),
    "bit_speed_oscillation": (DisplayUnit("-", 1.0), "oscillation/2Ω"),
    "surface_torque_amplitude": ("torque", "surface torque amplitude"),
    "quill_speed_min": ("angular_speed", "quill speed min"),
    "quill_speed_max": ("angular_speed", "quill speed max"),
}


def metric_unit(name: str, units: str | None = None) -> DisplayUnit:
    """The display unit of the cycle metric ``name`` (:data:`METRIC_DISPLAY`) in the unit system ``units``
    (``"si"``, ``"field"``; None: ``$DRILLSTRING_UNITS``, else si): ROP in m/h or ft/h, TOB in kN·m or
    kft·lbf, FOB in kN or klbf, MSE in MPa or psi, bit speeds in rpm in both."""
    unit = METRIC_DISPLAY[name][0]
    return unit if isinstance(unit, DisplayUnit) else display_unit(unit, units)
