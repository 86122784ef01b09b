"""One case: a drilling run, its static state, modes, linear stability, Campbell diagram, and the comparison
of the two nonlinear models."""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING, Callable

import numpy as np

from drillstring.api.arguments import (
    as_case,
    case_window,
    check_callable,
    checked_tolerance,
    checked_weight_on_bit,
)
from drillstring.blas_threads import single_threaded_blas
from drillstring.case import Case

if TYPE_CHECKING:  # the simulating modules load with the functions that use them (light static, modes)
    import xarray as xr


@single_threaded_blas()
def simulate(
    case: Case | str | Path = "reference",
    *,
    t_end: float | None = None,
    output_step: float | None = None,
    rtol: float | None = None,
    atol: float | None = None,
    weight_on_bit: float | None = None,
    progress: Callable[[float], None] | None = None,
    raise_on_failure: bool = True,
) -> xr.Dataset:
    """Simulate one drilling run of ``case`` (docs/model.md §9) and return its observables as a Dataset.

    Arguments left as None take the case's ``[simulation]`` values; ``weight_on_bit`` [N] overrides
    the static weight-on-bit. A run that stops early raises :class:`~drillstring.dynamics.simulate.SimulationError` whose
    ``.dataset`` holds what was computed (or, with ``raise_on_failure=False``, that Dataset is
    returned with ``attrs["status"] == "failed"``).
    """
    from drillstring.dynamics.rom import case_reduced_model
    from drillstring.dynamics.simulate import SimulationError, simulate_model
    from drillstring.results import run_dataset

    case = as_case(case)
    s = case.simulation
    window = case_window(case, t_end, output_step)
    rtol, atol = checked_tolerance("rtol", rtol), checked_tolerance("atol", atol)
    if weight_on_bit is not None:
        weight_on_bit = checked_weight_on_bit(case, weight_on_bit)
    check_callable("progress", progress)
    model = case_reduced_model(case, weight_on_bit=weight_on_bit)
    extra = {
        "weight_on_hook": model.static.weight_on_hook,
        "weight_on_bit": model.static.weight_on_bit,
        "top_speed": case.operation.top_speed,
        "top_drive": case.top_drive.controller,
        "bit_rock_law": case.bit_rock.law,
        "modes": f"{case.reduced_model.axial_modes} axial + rigid, {case.reduced_model.torsional_modes} "
                 f"torsional{' + rigid' if model.top_drive.drives else ''}, "
                 f"{model.family.count('lateral_y')} lateral per plane",
        "elements": model.static.mesh.n_elements,
        "lateral_modes": int(model.family.count("lateral_y")),
    }
    kwargs = dict(
        t_end=window.t_end,
        output_step=window.output_step,
        rtol=s.rtol if rtol is None else rtol,
        atol=s.atol if atol is None else atol,
        method=s.method,
        max_steps=s.max_steps,
        min_step=s.min_step,
        lateral_perturbation=case.initial.lateral_perturbation,
        seed=case.initial.seed,
        progress=progress,
    )
    try:
        result = simulate_model(model, **kwargs)
    except SimulationError as error:
        dataset = _with_derived(run_dataset(error.result, case_toml=case.to_toml(), extra_attrs=extra), model)
        if raise_on_failure:
            error.dataset = dataset
            raise
        return dataset
    return _with_derived(run_dataset(result, case_toml=case.to_toml(), extra_attrs=extra), model)


def _with_derived(dataset, model):
    """A run's Dataset with what its figure shows besides the observables: the ``hook_load`` [N] during a
    ramped start (:class:`~drillstring.forces.hook_load.HookLoadRamp`: the static hook load plus the weight
    not yet transferred) and, for a Detournay bit, the ``wear_flat_force`` [N] (the force on bit less the
    cutting force, :meth:`~drillstring.forces.detournay.DetournayParameters.cutting_force`); the
    ``depth_of_cut`` observable is dropped for the laws without one; with a downhole motor the
    ``differential_pressure`` [Pa] across it (:meth:`~drillstring.forces.motor.PositiveDisplacementMotor.
    differential_pressure`), without one its ``motor_speed`` and ``motor_torque`` observables are dropped."""
    from drillstring.quantities import LONG_NAMES, UNITS

    t = dataset["time"].values
    if model.hook_load.active:
        values = model.static.weight_on_hook - model.hook_load.force(t)
        dataset["hook_load"] = ("time", values, {"units": UNITS["hook_load"], "long_name": LONG_NAMES["hook_load"]})
    if model.bit_rock.delayed:
        cutting_force = getattr(model.bit_rock, "cutting_force", None)  # the law itself (component protocol)
        if cutting_force is not None:  # the Detournay law: the rest of the force on bit is the wear flats'
            force = dataset["force_on_bit"].values
            wear = np.where(force > 0.0, force - cutting_force(dataset["depth_of_cut"].values), 0.0)
            dataset["wear_flat_force"] = ("time", wear, {"units": UNITS["wear_flat_force"],
                                                         "long_name": LONG_NAMES["wear_flat_force"]})
    elif "depth_of_cut" in dataset:
        dataset = dataset.drop_vars("depth_of_cut")
    if model.motor is not None:  # a downhole motor: its differential pressure from its torque (its law, eq. (2))
        pressure = model.motor.differential_pressure(dataset["motor_torque"].values)
        dataset["differential_pressure"] = ("time", pressure, {"units": UNITS["differential_pressure"],
                                                               "long_name": LONG_NAMES["differential_pressure"]})
    else:
        dataset = dataset.drop_vars([name for name in ("motor_speed", "motor_torque") if name in dataset])
    return dataset


@single_threaded_blas()
def static(case: Case | str | Path = "reference"):
    """The prestressed static state of ``case`` and its buckling margin.

    Returns ``(state, margin)``: a :class:`~drillstring.statics.StaticState` (``weight``,
    ``weight_on_hook``, ``weight_on_bit`` [N], ``neutral_point_height`` [m], the mesh and the axial
    force ``axial_force`` [N] at its nodes, tension positive) and a :class:`~drillstring.buckling.
    BucklingMargin` (``critical_weight_on_bit`` [N], ``buckled``). For a case with ``[well]`` the stiff string
    along the well path instead (the state the dynamics is built on): a
    :class:`~drillstring.well.stiff_string.StiffStringState` (the same names, x the measured depth, the hook
    load as ``weight_on_hook``, and the wall's side forces) and a :class:`~drillstring.well.buckling.
    WellBucklingMargin` (sinusoidal and helical buckling along the path; the vertical string's lateral
    criterion does not apply in the deviated hole)."""
    case = as_case(case)
    if case.well is not None:
        from drillstring.well.stiff_string import (
            case_stiff_string,
            case_well_buckling_margin,
        )

        well_state = case_stiff_string(case)
        return well_state, case_well_buckling_margin(case, well_state)
    from drillstring.buckling import case_buckling_margin
    from drillstring.statics import case_static_state

    state = case_static_state(case)
    return state, case_buckling_margin(case, state)


#: Largest number of modes per family :func:`modes` computes.
MAX_MODES = 1000


@single_threaded_blas()
def modes(case: Case | str | Path = "reference", *, count: int = 10):
    """The ``count`` lowest natural modes per family (axial with its rigid mode, torsional, lateral per plane)
    of the prestressed string of ``case`` with its drilling fluid, and its lateral buckling margin. With a
    downhole motor the torsional modes are those of the string released at its rotor
    (:func:`drillstring.rotor.released_modes`; the first, at 0 Hz, the string below turning relative to the
    string above).

    Returns ``(modes, margin)``: :class:`~drillstring.modal.Modes` (``.axial.frequencies`` [Hz], ...) and a
    :class:`~drillstring.buckling.BucklingMargin`. ``count``: an integer in [1, :data:`MAX_MODES`].

    A case with ``[well]``: the modes about the stiff string's static state along the well path, the families
    coupled, each mode named by its largest share of kinetic energy
    (:func:`~drillstring.well.well_modes.case_well_mode_families`): a
    :class:`~drillstring.well.well_modes.WellModes` (``.axial``, ``.torsional``, ``.lateral``: every lateral
    mode, the y/z pairs split; ``.shares``), and the :class:`~drillstring.well.buckling.WellBucklingMargin`
    along the path. A case with ``[well]`` and ``[motor]`` is refused (ValueError)."""
    from drillstring.buckling import buckling_margin
    from drillstring.checks import integer
    from drillstring.modal import case_linear_system, compute_modes
    from drillstring.rotor import released_modes
    from drillstring.statics import case_static_state

    count = integer("count", count, low=1, high=MAX_MODES)
    case = as_case(case)
    if case.well is not None:
        from drillstring.well.stiff_string import (
            case_stiff_string,
            case_well_buckling_margin,
        )
        from drillstring.well.well_modes import case_well_mode_families

        if case.motor is not None:
            raise ValueError("modes of a case with [well] and [motor] (the torsion released at the rotor along the "
                             "well path) are not supported yet: remove one of them")
        state = case_stiff_string(case)
        return case_well_mode_families(case, count, state), case_well_buckling_margin(case, state)
    system = case_linear_system(case, case_static_state(case))
    if case.motor is not None:  # the torsion released at the rotor: its first mode the string below turning
        return released_modes(system, case.motor.position, count, count, count)[0], buckling_margin(system)
    return compute_modes(system, axial=count, torsional=count, lateral=count), buckling_margin(system)


@single_threaded_blas()
def stability(case: Case | str | Path = "reference", *, weight_on_bit: float | None = None):
    """Steady drilling of ``case`` (closed form) and the eigenvalues of its reduced model linearised
    about it, bit–rock law included (:mod:`drillstring.dynamics.stability`).

    Returns a :class:`~drillstring.dynamics.stability.StabilityResult`: ``.stable``, ``.steady_state``
    (``rate_of_penetration`` [m/s], ``bit_speed`` [rad/s], ``torque_on_bit`` [N·m], ``force_on_bit``
    [N]), ``.modes`` sorted by frequency (``family``, ``frequency`` [Hz], ``damping_ratio``,
    ``growth_rate`` [1/s]), ``.leading`` and ``.to_dict()`` (JSON-ready). ``weight_on_bit`` [N]
    overrides the case's.
    """
    from drillstring.dynamics.stability import case_stability

    case = as_case(case)
    if weight_on_bit is not None:
        weight_on_bit = checked_weight_on_bit(case, weight_on_bit)
    return case_stability(case, weight_on_bit=weight_on_bit)


@single_threaded_blas()
def campbell(case: Case | str | Path = "reference", *, top_speed=None, blades: int | None = None,
             default_unit: str = "", progress: Callable[[int, int], None] | None = None):
    """The Campbell diagram of ``case`` (:mod:`drillstring.critical_speeds`): natural frequencies of the axial,
    torsional and lateral (forward and backward whirl) families against the rotary speed, prestressed at
    the case's weight-on-bit, with the drilling fluid and the gyroscopic terms; the excitation lines 1×
    and ``blades`` × (default :data:`~drillstring.critical_speeds.DEFAULT_BLADES`) and their critical speeds.

    ``top_speed``: the speeds, SI numbers [rad/s] or a grid string (``"5 rpm:300 rpm:60"``, bare numbers
    in ``default_unit`` or SI), default :data:`~drillstring.critical_speeds.DEFAULT_CAMPBELL_TOP_SPEED`. Returns a
    :class:`~drillstring.critical_speeds.CampbellDiagram` (``.to_dict()`` is JSON-ready). Raises ValueError (one
    line naming the argument) for a bad grid, more than :data:`~drillstring.critical_speeds.MAX_CAMPBELL_SPEEDS`
    speeds or a blade count outside [1, :data:`~drillstring.critical_speeds.MAX_BLADES`] (before any work),
    TypeError for a blade count that is not an integer. ``progress(done, total)`` is called after each exact
    solution of the lateral whirl (``total``: an upper bound; a diagram of 3,000 speeds needs about 20)."""
    from drillstring.case import DIMENSIONS
    from drillstring.checks import integer
    from drillstring.critical_speeds import (
        DEFAULT_BLADES,
        DEFAULT_CAMPBELL_TOP_SPEED,
        MAX_BLADES,
        case_campbell,
        check_speed_count,
    )
    from drillstring.stochastic.operating_map import parse_axis

    the_case = as_case(case)
    blades = integer("blades", DEFAULT_BLADES if blades is None else blades, low=1, high=MAX_BLADES)
    check_callable("progress", progress)
    dimension = {d.name: d for d in DIMENSIONS}["angular speed"]
    speeds = parse_axis(DEFAULT_CAMPBELL_TOP_SPEED if top_speed is None else top_speed, dimension,
                        name="top_speed", default_unit=default_unit)
    check_speed_count(len(speeds), name=f"top_speed = {top_speed!r}" if isinstance(top_speed, str) else "top_speed")
    return case_campbell(the_case, speeds, blades, progress=progress)


@single_threaded_blas()
def stability_boundary(case: Case | str | Path = "reference") -> dict:
    """The stability boundary of steady drilling along the weight-on-bit at the case's top speed (SI):
    ``weight_on_bit`` [N] where the leading growth rate crosses 0 nearest the case's weight-on-bit (None
    when it does not between 0 and the string's weight), ``top_speed`` [rad/s], ``nominal_weight_on_bit``
    [N] and ``nominal_growth_rate`` [1/s] (:func:`~drillstring.dynamics.stability.weight_on_bit_boundary`).
    ValueError when the case itself has no steady drilling."""
    from drillstring.dynamics.stability import weight_on_bit_boundary

    return weight_on_bit_boundary(as_case(case))


#: The two nonlinear models compared by :func:`compare`, in the order returned: case 1, case 2.
COMPARED_MODELS = ("full", "bit_and_contact")
#: Scalar observables compared by :func:`compare` (the radial displacement is added per probe).
COMPARED_OBSERVABLES = ("rate_of_penetration", "bit_speed", "torque_on_bit", "force_on_bit")


def _ratio(numerator: float, denominator: float) -> float | None:
    """``numerator / denominator`` as a JSON-ready float, None when undefined (0/0, x/0, NaN)."""
    if not (math.isfinite(numerator) and math.isfinite(denominator)) or denominator == 0.0:
        return None
    return float(numerator / denominator)


def _finite_or_none(value: float) -> float | None:
    return float(value) if math.isfinite(value) else None


def _difference_numbers(full, reduced, steady) -> dict[str, float | None]:
    """Differences of one observable, case 1 (``full``) minus case 2 (``reduced``), SI units: the largest
    absolute difference over time, the RMS difference relative to the RMS of case 2, and the difference of
    the means over the ``steady`` samples (t after the transient), absolute and relative to case 2's."""
    full = np.asarray(full, dtype=float)
    reduced = np.asarray(reduced, dtype=float)
    delta = full - reduced
    mean_full = float(np.mean(full[steady]))
    mean_reduced = float(np.mean(reduced[steady]))
    return {
        "max_abs_difference": _finite_or_none(float(np.max(np.abs(delta)))),
        "rms_relative_difference": _ratio(float(np.sqrt(np.mean(delta**2))),
                                          float(np.sqrt(np.mean(reduced**2)))),
        "mean_full": _finite_or_none(mean_full),
        "mean_bit_and_contact": _finite_or_none(mean_reduced),
        "mean_difference": _finite_or_none(mean_full - mean_reduced),
        "mean_relative_difference": _ratio(mean_full - mean_reduced, abs(mean_reduced)),
    }


@single_threaded_blas()
def compare(
    case: Case | str | Path = "reference",
    *,
    t_end: float | None = None,
    output_step: float | None = None,
    progress: Callable[[str, float], None] | None = None,
) -> tuple[xr.Dataset, xr.Dataset, dict]:
    """Run ``case`` with the full nonlinear model (case 1: kinetic- and strain-energy forces added) and with
    the bit–rock and contact forces only (case 2), everything else equal (docs/model.md §5), and compare them.

    Returns ``(full, bit_and_contact, differences)``: the two run Datasets and a JSON-ready dict (SI
    units) with, under ``observables``, for the rate of penetration, bit speed, torque- and force-on-bit
    and the radial displacement at each probe (``radial_displacement_<j>``, with its ``probe_x``):
    ``max_abs_difference`` over time, ``rms_relative_difference`` (RMS of the difference / RMS of case 2),
    the means after the transient (t >= min(10 s, t_end/2)) of each case, their ``mean_difference`` and
    ``mean_relative_difference`` (relative to |mean of case 2|; None when that mean is 0). Differences are
    case 1 minus case 2. ``wall_time`` holds the wall time [s] of each ``simulate`` call (model build and
    integration, measured around the call), ``ratio`` = full / bit_and_contact; ``solver_wall_time`` and
    ``n_rhs`` the integrator's own numbers. ``progress(model, t)`` is called with the model name
    ("full" or "bit_and_contact") and the simulated time [s]. A run that stops early raises
    :class:`~drillstring.dynamics.simulate.SimulationError` (``.dataset`` the partial run, ``.nonlinear`` which model failed).
    """
    import time

    from drillstring.dynamics.indicators import transient_end
    from drillstring.dynamics.simulate import SimulationError

    case = as_case(case)
    runs: dict[str, xr.Dataset] = {}
    wall: dict[str, float] = {}
    for nonlinear in COMPARED_MODELS:
        variant = case.model_copy(update={"model": case.model.model_copy(update={"nonlinear": nonlinear})})
        report = None if progress is None else (lambda t, _m=nonlinear: progress(_m, t))
        start = time.perf_counter()
        try:
            runs[nonlinear] = simulate(variant, t_end=t_end, output_step=output_step, progress=report)
        except SimulationError as error:
            error.nonlinear = nonlinear
            raise
        wall[nonlinear] = time.perf_counter() - start
    full, reduced = runs["full"], runs["bit_and_contact"]

    t = np.asarray(full["time"].values, dtype=float)
    t_reduced = np.asarray(reduced["time"].values, dtype=float)

    def on_grid(values) -> np.ndarray:
        values = np.asarray(values, dtype=float)
        if t_reduced.shape == t.shape and np.allclose(t_reduced, t, rtol=0.0, atol=1e-12):
            return values
        return np.interp(t, t_reduced, values)

    t_final = float(t[-1])
    t_transient = transient_end(t_final)
    steady = t >= t_transient - 1e-9 * max(1.0, t_final)
    if not steady.any():
        steady = np.ones_like(t, dtype=bool)

    observables: dict[str, dict] = {}
    for name in COMPARED_OBSERVABLES:
        observables[name] = _difference_numbers(full[name].values, on_grid(reduced[name].values), steady)
    x = np.atleast_1d(np.asarray(full["x"].values, dtype=float))
    radial_full = np.asarray(full["radial_displacement"].values, dtype=float)
    radial_reduced = np.asarray(reduced["radial_displacement"].values, dtype=float)
    for j, position in enumerate(x):
        entry = {"probe_x": float(position)}
        entry.update(_difference_numbers(radial_full[:, j], on_grid(radial_reduced[:, j]), steady))
        observables[f"radial_displacement_{j}"] = entry

    def pair(key: str, cast=float) -> dict:
        return {m: cast(runs[m].attrs.get(key, float("nan"))) for m in COMPARED_MODELS}

    differences = {
        "case": case.name,
        "t_end": t_final,
        "t_transient": float(t_transient),
        "difference": "case 1 (full) minus case 2 (bit_and_contact)",
        "observables": observables,
        "wall_time": {**{m: float(wall[m]) for m in COMPARED_MODELS},
                      "ratio": _ratio(wall["full"], wall["bit_and_contact"])},
        "solver_wall_time": pair("solver_wall_time"),
        "n_rhs": pair("solver_n_rhs", int),
        "impacts": pair("impacts", int),
    }
    return full, reduced, differences


# --- operating maps and global sensitivity -------------------------------------------------------
