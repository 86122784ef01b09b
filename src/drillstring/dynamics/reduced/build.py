"""The reduced model's build (docs/model.md §5): the prestressed system projected on its modes, the structural and
fluid damping reduced on the basis (:func:`reduced_model`), from a case (:func:`case_reduced_model`), with the
case's start (:func:`case_hook_load`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from drillstring.damping import reduced_structural_damping
from drillstring.fem.dofs import THETA_X, U, dof
from drillstring.fem.geometry import direction_cosines
from drillstring.dynamics.reduced.model import ReducedOrderModel
from drillstring.forces.bit_rock import case_bit_rock
from drillstring.forces.contact import ContactStations, case_contact, mesh_contact_stations
from drillstring.forces.excitation import TurningLoads
from drillstring.forces.motor import case_motor
from drillstring.forces.protocol import StringFrictionContext
from drillstring.forces.registry import BitLaw, ContactLaw, HookLoad, Motor, StringFriction, TopBoundary
from drillstring.forces.registry import hook_load as registered_hook_load
from drillstring.forces.registry import string_friction as registered_string_friction
from drillstring.forces.string_friction import FrictionStations
from drillstring.forces.top_drive import TopDriveParameters, case_top_drive
from drillstring.forces.turning_loads import case_turning_loads
from drillstring.modal import (
    LinearSystem,
    ModeFamily,
    Modes,
    case_linear_system,
    check_truncation_correction,
    compute_modes,
    coupled_modes,
    family_coupling,
    family_modes,
)
from drillstring.rotor import first_torsional_frequency, released_modes
from drillstring.statics import StaticState, case_static_state
from drillstring.well.stiff_string import StiffStringState, case_hole_diameters, case_stiff_string
from drillstring.well.well_modes import KINDS, case_path_curvature, case_well_system, path_slide, quota_modes


def reduced_model(
    static: StaticState,
    system: LinearSystem,
    *,
    axial_modes: int,
    torsional_modes: int,
    lateral_modes: int,
    modal_damping_ratio: float,
    rigid_axial_damping: float,
    top_speed: float,
    bit_rock: BitLaw,
    contact: ContactLaw,
    borehole_diameter: float,
    rigid_rotation_damping: float = 0.0,
    damping_basis: str = "free_free",
    probe_positions=(),
    nonlinear: str = "bit_and_contact",
    turning_loads: TurningLoads | None = None,
    lateral_cutoff: float = 0.0,
    top_drive: TopDriveParameters | None = None,
    hook_load: HookLoad | None = None,
    rayleigh: tuple[float, float] = (0.0, 0.0),
    truncation_correction: str = "none",
    motor: Motor | None = None,
    string_friction: StringFriction | None = None,
    friction_stations: FrictionStations | None = None,
    well_basis: WellBasis | None = None,
) -> ReducedOrderModel:
    """Project the prestressed system on its modes (``axial_modes`` elastic + the rigid one;
    ``lateral_modes`` per plane at least, plus every lateral mode below ``lateral_cutoff`` [rad/s];
    ``torsional_modes`` elastic, plus the rigid rotation with a top drive).

    Args:
        modal_damping_ratio: ξ [-]; rigid_axial_damping: c1 [N·s/m], viscous resistance to the
            rigid axial motion; rigid_rotation_damping: c2 [N·m·s/rad], to the rigid rotation.
        damping_basis: "free_free" (ξ, c1, c2 on the free–free modes) or "constrained" (ξ on every
            basis mode); see :mod:`drillstring.damping`.
        top_speed: Ω [rad/s].
        contact: the contact law, ``shock_stiffness`` read as k'_sh [N/m per m of string].
        borehole_diameter: D_ch [m]; the contact stations follow from it and the mesh
            (:func:`~drillstring.forces.contact.mesh_contact_stations`).
        turning_loads: mass imbalance and bow (:mod:`drillstring.forces.excitation`), or None.
        top_drive: the top boundary; None: the top speed imposed.
        hook_load: the start (a :class:`~drillstring.forces.registry.HookLoad`); None: the reference start.
        rayleigh: (α [1/s], β [s]) of the Rayleigh damping ``α M + β K`` added to the above.
        truncation_correction: "none" (the modes alone) or "static" (each of the axial and torsional families
            followed by its residual-flexibility attachment modes at the bit, and at the top with a top drive:
            :func:`drillstring.modal.compute_modes`; with along-string friction, one more for each of its
            load patterns, :func:`friction_load_patterns`; not in a motor's released torsional family).
        motor: a downhole motor (:mod:`drillstring.forces.motor`), None without: the torsional family is then that
            of the string released at the motor's rotor station (:func:`drillstring.rotor.released_modes`;
            ``torsional_modes`` elastic modes plus its rigid motions).
        string_friction, friction_stations: the along-string friction law and where it acts
            (:mod:`drillstring.forces.string_friction`); None: none.
        well_basis: the modes along the well path (:class:`WellBasis`, ``system`` then in the nodes' frames,
            :func:`drillstring.well.well_modes.well_linear_system`), chosen by kind; None: the straight string's.
    """
    drive = top_drive is not None and top_drive.drives
    coupled = well_basis is not None or family_coupling(system) > 0.0
    release, damped = None, system
    patterns = None
    if truncation_correction == "static" and string_friction is not None and friction_stations is not None:
        patterns = friction_load_patterns(string_friction, friction_stations, top_speed, system.mesh.n_dofs)
    if well_basis is not None:
        _check_well_basis(top_drive, motor, damping_basis, rayleigh, top_speed, hook_load)
        found, kinds = quota_modes(system, well_basis.slide, axial_modes, torsional_modes, 2 * lateral_modes,
                                   lateral_cutoff, well_basis.loads(truncation_correction), patterns)
        # the slide first (the rigid axial motion), each other column labelled by its kind
        modes, basis, omega, family, residual = _as_coupled(found, ["rigid_axial"] + [KINDS[k] for k in kinds[1:]],
                                                            system.mesh)
        released = basis
    elif coupled:
        if motor is not None:
            raise ValueError("a downhole motor on a coupled basis (a string out of the straight axis) is not "
                             "supported yet: its rotor is released in the torsional family of a straight string")
        modes, basis, omega, family, residual = _coupled_basis(
            system, axial_modes + 1 + torsional_modes + 2 * lateral_modes, lateral_cutoff, truncation_correction,
            damping_basis, patterns)
        released = basis
    else:
        if drive:
            torsional_modes += 1
        top_inertia = top_drive.top_inertia if drive else None
        if motor is None:
            modes = compute_modes(system, axial_modes + 1, torsional_modes, lateral_modes, lateral_cutoff,
                                  top_inertia=top_inertia, truncation_correction=truncation_correction,
                                  load_patterns=patterns)
        else:
            modes, release, damped = released_modes(system, motor.position, axial_modes + 1, torsional_modes + 1,
                                                    lateral_modes, lateral_cutoff, top_inertia, truncation_correction)
        families = [modes.axial, modes.torsional, modes.lateral_y, modes.lateral_z]
        basis = np.hstack([f.shapes for f in families])
        omega = np.concatenate([f.angular_frequencies for f in families])
        # the family's size, its attachment modes (truncation_correction = "static") included
        family = ["rigid_axial"] + ["axial"] * (len(modes.axial.angular_frequencies) - 1)
        for f in families[1:]:
            family += [f.name] * len(f.angular_frequencies)
        residual = np.concatenate([np.arange(len(f.angular_frequencies)) >= len(f.angular_frequencies)
                                   - f.attachments for f in families])
        released = basis if release is None else np.vstack([basis, np.concatenate(  # the rotor side's row after
            [np.zeros(f.shapes.shape[1]) if f is not modes.torsional else release.rotor for f in families])])
    structural = reduced_structural_damping(
        damped.mass, damped.stiffness, released, family, omega, damping_ratio=modal_damping_ratio,
        rigid_axial=rigid_axial_damping, rigid_rotation=rigid_rotation_damping,
        top_speed=0.0 if drive else top_speed, definition=damping_basis, rayleigh=rayleigh,
    )
    damping = basis.T @ (system.fluid_damping @ basis) + structural.matrix
    stations = mesh_contact_stations(static.mesh, borehole_diameter)
    if well_basis is not None:  # the wall under a resting node is in the basis (its linearised springs)
        stations = well_basis.stations(stations)
    return ReducedOrderModel(
        static=static, system=system, modes=modes, basis=basis, family=tuple(family),
        angular_frequencies=omega, damping=damping, top_speed=top_speed,
        weight_on_bit=static.weight_on_bit, bit_rock=bit_rock, contact=contact,
        stations=stations,
        probe_positions=np.asarray(probe_positions, dtype=float),
        nonlinear=nonlinear, generalized_force=structural.generalized_force, turning_loads=turning_loads,
        top_drive=top_drive, hook_load=hook_load, residual_columns=residual, coupled=coupled, motor=motor,
        rotor=release, string_friction=string_friction, friction_stations=friction_stations,
        rest_offsets=None if well_basis is None else well_basis.rest_offsets,
        centreline_spin=well_basis is not None,
    )


@dataclass(frozen=True)
class WellBasis:
    """What the well basis adds to a reduced model's build (``reduced_model.lateral_basis = "well"``,
    docs/stiff_string.md): the string's slide along the path in the nodes' frames
    (:func:`~drillstring.well.well_modes.path_slide`), each node's static lateral offset from the hole's axis
    in its frame (n_nodes, 2) [m] (v, w: where the wall's gap is measured from), the nodes resting on the
    wall (n_nodes,) bool (their wall is the basis's linearised springs, not a contact station) and the hole's
    diameter at each node (n_nodes,) [m] (the casing's bore above the casing shoe, as the statics)."""

    slide: np.ndarray
    rest_offsets: np.ndarray
    resting: np.ndarray
    hole_diameter: np.ndarray

    @classmethod
    def of(cls, state: StiffStringState, curvature: np.ndarray, hole_diameter: np.ndarray) -> WellBasis:
        """From the stiff string's static ``state``, the path's curvature vectors at its nodes (n, 3) [1/m] and the
        hole's diameter there (n,) [m]."""
        frames = direction_cosines(np.asarray(state.tangent, dtype=float))  # rows: tangent, then across it
        offsets = np.einsum("nij,nj->ni", frames[:, 1:, :], state.translation)
        return cls(path_slide(state, curvature), offsets, np.asarray(state.in_contact, dtype=bool),
                   np.asarray(hole_diameter, dtype=float))

    def loads(self, truncation_correction: str) -> list[int]:
        """The global DOFs (nodes' frames) whose unit loads get the static correction
        (``reduced_model.truncation_correction``): none for "none"; for "static" the bit's u (along its tangent)
        and θx (about it), the top's u and θx (the held ones add nothing). The nodes resting on the wall get
        none: across the path at each of them (45 of 55 nodes in ``deviated`` on a 60 m mesh) that is 90 more
        columns on 330 free DOFs, ω̃ up to 1640 rad/s."""
        check_truncation_correction(truncation_correction)
        if truncation_correction == "none":
            return []
        bit = len(self.resting) - 1
        return [int(dof(bit, U)), int(dof(bit, THETA_X)), int(dof(0, U)), int(dof(0, THETA_X))]

    def stations(self, stations: ContactStations) -> ContactStations:
        """``stations`` less those on a resting node, each gap that of the hole at its node (the casing's above
        the shoe: the statics' gap, so that a node at rest is inside it)."""
        kept = stations.subset(~self.resting[stations.node])
        gap = 0.5 * (self.hole_diameter[kept.node] - kept.outer_diameter)
        return ContactStations(kept.node, kept.length, gap, kept.outer_diameter)


def friction_load_patterns(law: StringFriction, stations: FrictionStations, top_speed: float,
                           n_dofs: int) -> np.ndarray | None:
    """The along-string friction's two load patterns (n_dofs, 2), global DOFs (or the nodes' frames: u along the
    string, θx about it), for the static correction (``truncation_correction = "static"``,
    :func:`drillstring.modal.attachment_loads`): the axial one ``μ_i N_i`` at each station's u (the drag's
    distribution) and the torsional one at each station's θx: the law's torques τ_i(Ω) with the stations turning
    at ``top_speed`` Ω [rad/s] and no axial motion (eq. (2) of :mod:`drillstring.forces.string_friction`, ``≈ −μ_i
    N_i r_i``: the load of the string's steady twist, :meth:`ReducedOrderModel.friction_twist`), ``μ_i N_i r_i``
    when Ω = 0. One column per pattern, not one per station: the truncated basis then carries the static
    response to these distributions exactly, not to any other. None without a station."""
    if len(stations) == 0:
        return None
    node = np.asarray(stations.node, dtype=np.int64)
    drag = stations.friction * stations.normal_force
    _, torque = law.evaluate_at(StringFrictionContext(np.zeros(len(node)), np.full(len(node), float(top_speed)),
                                                      stations.normal_force, stations.radius, stations.friction))
    torque = np.asarray(torque, dtype=float)
    if not np.any(torque):
        torque = drag * stations.radius
    patterns = np.zeros((n_dofs, 2))
    np.add.at(patterns[:, 0], dof(node, U), drag)
    np.add.at(patterns[:, 1], dof(node, THETA_X), torque)
    return patterns


def _check_well_basis(top_drive, motor, damping_basis: str, rayleigh, top_speed: float, hook_load) -> None:
    """ValueError, one line naming it, for what the well basis does not support yet."""
    problems = []
    if top_drive is not None and top_drive.drives:
        problems.append(f"a top boundary with states ({top_drive.name!r}: the rigid rotation of the curved string "
                        "is not in the basis; use an imposed top speed)")
    if motor is not None:
        problems.append("a downhole motor (its rotor is released in a straight string's torsional family)")
    if damping_basis != "constrained":
        problems.append(f"damping.basis = {damping_basis!r} (the free-free damping is defined family by family; "
                        "use 'constrained')")
    if rayleigh[0] and top_speed:
        problems.append("damping.mass_proportional > 0 with a spinning string (it would damp the spin itself)")
    if hook_load is not None and hook_load.active:
        problems.append("initial.start = 'ramp' (the weight moved to the hook in the linear basis swings the string "
                        "round the wall at t = 0, pressing spans into it: use 'on_bottom')")
    if problems:
        raise ValueError("reduced_model.lateral_basis = 'well' does not support yet: " + "; ".join(problems))


def _as_coupled(found: ModeFamily, family: list[str], mesh):
    """``(modes, basis, ω, labels, residual)`` of one coupled family ``found`` whose columns are labelled
    ``family`` (what the stability analysis reports a root's family by), its attachment modes last."""
    empty = {name: ModeFamily(name, np.zeros(0), np.zeros((mesh.n_dofs, 0)))
             for name in ("axial", "torsional", "lateral_y", "lateral_z")}
    n = len(found.angular_frequencies)
    residual = np.arange(n) >= n - found.attachments
    return Modes(**empty, coupled=found), found.shapes, found.angular_frequencies, family, residual


def _coupled_basis(system: LinearSystem, count: int, cutoff: float, truncation_correction: str,
                   damping_basis: str, patterns: np.ndarray | None = None):
    """The one basis of a system whose families couple (:func:`~drillstring.modal.coupled_modes`: the ``count``
    lowest modes of the whole string and every one below ``cutoff`` [rad/s], then its attachment modes):
    ``(modes, basis, ω, labels, residual)``, labels "rigid_axial" for the rigid translation and "coupled" for
    the others."""
    if damping_basis != "constrained":
        raise ValueError(f"damping.basis = {damping_basis!r} with coupled families (a string out of its straight "
                         "axis): the free-free damping is defined family by family; use 'constrained' (and "
                         "Rayleigh damping)")
    found = coupled_modes(system, count, cutoff, truncation_correction, patterns)
    family = ["coupled"] * len(found.angular_frequencies)
    if family and found.angular_frequencies[0] == 0.0:  # coupled_modes put the rigid axial translation first
        family[0] = "rigid_axial"
    return _as_coupled(found, family, system.mesh)


def _lateral_cutoff(case_value: float, lateral_modes: int | None, lateral_cutoff: float | None) -> float:
    if lateral_cutoff is not None:
        return lateral_cutoff
    return 0.0 if lateral_modes is not None else case_value


def case_reduced_model(
    case,
    *,
    weight_on_bit: float | None = None,
    axial_modes: int | None = None,
    torsional_modes: int | None = None,
    lateral_modes: int | None = None,
    static: StaticState | None = None,
    nonlinear: str | None = None,
    lateral_cutoff: float | None = None,
    bit_rock: BitLaw | None = None,
    top_drive: TopBoundary | None = None,
    motor: Motor | None = None,
) -> ReducedOrderModel:
    """The ROM of a :class:`~drillstring.case.Case`; keyword arguments override the case's values
    (``bit_rock``, ``top_drive``, ``motor``: a bit–rock law, a top boundary or a downhole motor instance, e.g.
    one registered outside the package, instead of the case's; the case's motor is its ``[motor]``)
    (``nonlinear``: "bit_and_contact" = case 2, "full" = case 1, default the case's ``model.nonlinear``;
    ``lateral_cutoff``: ratio to the rotation speed, as ``reduced_model.lateral_cutoff``). A
    ``lateral_modes`` given without ``lateral_cutoff`` asks for exactly that many lateral modes (no
    cut-off).

    A case with ``[well]`` (a deviated well) is built on the well's static state: the stiff string's axial
    force along measured depth as the prestress (:func:`~drillstring.well.stiff_string.case_stiff_string`),
    unless ``static`` is given; with a friction law (``[string_friction] law``) the wall's friction acts at the
    nodes resting on the wall there, with their static normal forces (:func:`case_friction_stations`). The
    lateral dynamics stays that of a straight string (docs/stiff_string.md)."""
    well_state = None
    well_basis = case.reduced_model.lateral_basis == "well"
    if static is None and (case.well is not None or well_basis):
        well_state = case_stiff_string(case, weight_on_bit=weight_on_bit)
        static = well_state.static_state()
    static = case_static_state(case, weight_on_bit) if static is None else static
    friction = case_string_friction(case)
    stations = None
    if friction is not None and case.well is not None:
        if well_state is None:
            well_state = case_stiff_string(case, weight_on_bit=static.weight_on_bit)
        stations = case_friction_stations(case, well_state)
    system = case_linear_system(case, static)
    basis = None
    if well_basis:
        if well_state is None:
            raise ValueError("reduced_model.lateral_basis = 'well' with a given static state: the well basis is "
                             "built on the stiff string's (leave static out)")
        system, basis = case_well_basis(case, well_state)
    motor = case_motor(case) if motor is None else motor
    if top_drive is None:
        top_drive = case_top_drive(case, lambda: (
            float(family_modes(system, "torsional", 1).angular_frequencies[0]) if motor is None
            else first_torsional_frequency(system, motor.position)))
    r = case.reduced_model
    return reduced_model(
        static,
        system,
        axial_modes=r.axial_modes if axial_modes is None else axial_modes,
        torsional_modes=r.torsional_modes if torsional_modes is None else torsional_modes,
        lateral_modes=r.lateral_modes if lateral_modes is None else lateral_modes,
        modal_damping_ratio=case.damping.modal_damping_ratio,
        rigid_axial_damping=case.damping.rigid_axial,
        rigid_rotation_damping=case.damping.rigid_rotation,
        rayleigh=(case.damping.mass_proportional, case.damping.stiffness_proportional),
        damping_basis=case.damping.basis,
        top_speed=case.operation.top_speed,
        bit_rock=case_bit_rock(case) if bit_rock is None else bit_rock,
        contact=case_contact(case),
        borehole_diameter=case.borehole.diameter,
        probe_positions=case.mesh.probes,
        nonlinear=case.model.nonlinear if nonlinear is None else nonlinear,
        turning_loads=case_turning_loads(case, static.mesh),
        lateral_cutoff=_lateral_cutoff(r.lateral_cutoff, lateral_modes, lateral_cutoff) * case.operation.top_speed,
        top_drive=top_drive,
        hook_load=case_hook_load(case, static.weight_on_bit),
        truncation_correction=r.truncation_correction,
        motor=motor,
        string_friction=friction,
        friction_stations=stations,
        well_basis=basis,
    )


def case_well_basis(case, state: StiffStringState) -> tuple[LinearSystem, WellBasis]:
    """The linear system of a case about its stiff-string ``state`` in the nodes' frames, for the dynamics
    (:func:`~drillstring.well.well_modes.case_well_system`: the path's curvature and the centreline spin), and
    its :class:`WellBasis`."""
    curvature = case_path_curvature(case, state)
    hole = case_hole_diameters(case, state.mesh.nodes)  # the casing's bore above its shoe, as the statics'
    return case_well_system(case, state, curvature), WellBasis.of(state, curvature, hole)


def case_string_friction(case) -> StringFriction | None:
    """The case's along-string friction law (``[string_friction] law``; None for ``"none"``)."""
    name = case.string_friction.law
    if name == "none":
        return None
    return registered_string_friction(name, "string_friction.law").from_case(case)


def case_friction_stations(case, state: StiffStringState) -> FrictionStations:
    """The along-string friction's stations of a case in its well: the nodes of the stiff string ``state`` that
    the wall (or a stabilizer) pushes, with that force's magnitude as their normal force N_i [N], the contact
    radius of the section below the node (the bit's node: above; the tool joint's where ``well.tool_joints``
    gives one, as the soft string's torque arm, :func:`drillstring.well.torque_drag._section_table`) and the
    well's friction factor there (``cased_hole_friction`` above the casing shoe, ``open_hole_friction`` at and
    below it, as :func:`drillstring.well.torque_drag._friction`)."""
    from drillstring.well.torque_drag import _section_table

    well = case.well
    if well is None:
        return FrictionStations.empty()
    mesh = state.mesh
    table = _section_table(case)
    if len(table) != len(mesh.sections):
        raise ValueError(f"the mesh has {len(mesh.sections)} sections, the case {len(table)}")
    node = np.nonzero(state.in_contact)[0].astype(np.int64)
    element = np.minimum(node, mesh.n_elements - 1)
    radius = np.array([row[5] for row in table])[mesh.element_section[element]]
    friction = np.where(in_casing(case, mesh, node), well.cased_hole_friction, well.open_hole_friction)
    return FrictionStations(node, state.side_force[node], radius, friction)


def in_casing(case, mesh, node) -> np.ndarray:
    """True for each mesh node of ``node`` above the casing shoe of the case's well (``well.casing_shoe`` [m] of
    measured depth: the cased hole's friction factor acts there, the open hole's at and below it)."""
    return np.asarray(mesh.nodes[np.asarray(node, dtype=np.int64)] < case.well.casing_shoe)


def case_hook_load(case, weight_on_bit: float) -> HookLoad:
    """The start of a :class:`~drillstring.case.Case` (``[initial]``): the registered hook load that
    ``initial.start`` names (:func:`~drillstring.forces.registry.hook_load`), built from the case and the static
    ``weight_on_bit`` [N]: the ramp of it over ``weight_ramp_time`` with the bit ``clearance`` off bottom for
    ``start = "ramp"`` (:class:`~drillstring.forces.hook_load.HookLoadRamp`); the reference start for
    ``"on_bottom"``."""
    return registered_hook_load(case.initial.start).from_case(case, weight_on_bit)
