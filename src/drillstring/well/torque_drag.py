"""Soft-string torque and drag along a deviated well (Johancsik, Friesen & Dawson 1984, SPE 11380).

The string is a cable lying on the low (or high) side of the hole along the well path of
:mod:`drillstring.well.survey`: no bending stiffness, its axis that of the hole. With ``s`` the measured depth
(down), ``t`` the unit tangent, ``kappa = dt/ds`` the curvature vector, ``z`` the downward vertical and ``F``
the effective tension (positive in tension), the equilibrium of a length ds gives, along and across the axis,

    dF/ds = -(w cos I + q_f) - sigma mu n,        n = | F kappa + w (z - (z.t) t) |,                  (1)
    dM/ds = -mu r n   (string rotating),                                                            (2)

with ``n`` the side (normal) force per length against the wall, ``I`` the inclination, ``w`` the buoyed
weight per length, ``q_f`` the mud's axial skin friction when the case switches it on, ``mu`` the friction
factor of the interval (cased above ``well.casing_shoe``, open hole below), ``r`` the contact radius (the
tool joint's, else the pipe's) and ``M`` the torque. ``sigma`` is the direction of axial friction: +1 when the
string moves up (trip out: friction adds to the hook load), -1 when it moves down (trip in, sliding), 0 when it
rotates (the standard extension: the sliding velocity of a rotating string is almost all tangential, so
friction drags axially by nothing and resists the rotation by mu n r; Johancsik et al. 1984, Sheppard et al.
1987). The boundary conditions at the bit are ``F = -WOB`` and ``M = TOB`` when on bottom (drilling, sliding),
0 off bottom. The hook load is F at the surface, the surface torque M there. (1)-(2) are integrated from the
bit up by Heun's method on elements of at most ``max_step`` (each element lies on one arc of the path), exact
for straight sections and second order in the element length otherwise.

Buoyancy (Lubinski 1950; the effective-tension concept): with mud of density rho_i inside and rho_o outside,
``w = g (m + rho_i A_i - rho_o A_o)`` and (1) holds for the effective tension F; the true (steel) tension
is ``F - p_o A_o + p_i A_i`` with the hydrostatic pressures ``p = rho g TVD``. ``m`` is the mass per length,
tool joints smeared in (:mod:`drillstring.components`); their steel outside the pipe body's area is counted in
``A_o`` (it displaces annulus mud), so that with one mud, ``w = g (m - rho A_s)``: the steel's weight less the
mud its volume ``A_s = m / rho_s`` displaces (Archimedes), as in the statics. With ``model.buoyancy`` off the
mud is ignored (w = rho_s A g, as the statics does), so that a vertical well reproduces
:func:`drillstring.statics.solve_statics` exactly.

Helically buckled sections (compression above the helical critical load of :mod:`drillstring.well.buckling`)
press on the wall with the extra ``r_c F^2/(4 E I)`` per length (Mitchell 1986, SPE 15470; r_c the radial
clearance), which is what locks a string up when sliding.

Lock-up when sliding: the string slides down only while the surface still holds it, hook load > 0; the
lock-up depth is the shallowest bit depth at which the sliding hook load, with the helical wall force of
Mitchell (1986) included, reaches 0 at the case's weight on bit (:func:`lockup_depth`).

Units: SI throughout (m, N, N*m, rad). This module reads a :class:`~drillstring.case.Case`, never plotting or
the command line.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from drillstring.derived import axial_load_per_length
from drillstring.fem.sections import hollow_circle
from drillstring.well.buckling import critical_loads
from drillstring.well.survey import Trajectory, trajectory

__all__ = ["LOCKED", "OPERATIONS", "StringInWell", "TorqueDragResult", "case_trajectory", "string_in_well",
           "torque_drag", "case_torque_drag", "lockup_depth"]

#: Operations: (axial friction direction sigma, rotating, on bottom).
OPERATIONS: dict[str, tuple[int, bool, bool]] = {
    "trip_out": (1, False, False),
    "trip_in": (-1, False, False),
    "rotating_off_bottom": (0, True, False),
    "sliding": (-1, False, True),
    "drilling": (0, True, True),
}
#: A compression [N] taken as infinite: the string is locked up (helical buckling, eq. (1) diverges).
LOCKED = 1e15
#: Largest element of the soft-string integration [m].
MAX_STEP = 1.0


@dataclass(frozen=True)
class StringInWell:
    """The string discretised along the well (SI units). Elements e join nodes e (top) and e + 1.

    Attributes:
        measured_depth: node depths [m], 0 (surface) to the bit.
        inclination_cos: cos I at the top and bottom of each element, shape (m, 2).
        curvature_sq, coupling, lateral_sq: per element end, the coefficients of
            n(F)^2 = a F^2 + 2 b F + c, i.e. a = |kappa|^2, b = w kappa.(z - (z.t)t), c = w^2 sin^2 I; (m, 2).
        weight: buoyed weight per length w of each element [N/m]; skin_friction q_f [N/m].
        contact_radius: torque arm r [m]; cased: element in the casing; bending_stiffness EI [N m^2];
        clearance: radial clearance r_c to the hole or casing wall [m].
        pressure_area: A_o rho_o g and A_i rho_i g of each element, to convert to true tension [N/m].
        true_vertical_depth: node TVD [m].
        section: section index of each element.
    """

    measured_depth: np.ndarray
    inclination_cos: np.ndarray
    curvature_sq: np.ndarray
    coupling: np.ndarray
    lateral_sq: np.ndarray
    weight: np.ndarray
    skin_friction: np.ndarray
    contact_radius: np.ndarray
    cased: np.ndarray
    bending_stiffness: np.ndarray
    clearance: np.ndarray
    pressure_area: np.ndarray
    true_vertical_depth: np.ndarray
    section: np.ndarray

    @property
    def bit_depth(self) -> float:
        return float(self.measured_depth[-1])

    def side_force(self, force: np.ndarray, end: int) -> np.ndarray:
        """n of eq. (1) at element ends ``end`` (0 top, 1 bottom) for tensions ``force`` (m,) [N/m]."""
        a, b, c = self.curvature_sq[:, end], self.coupling[:, end], self.lateral_sq[:, end]
        return np.sqrt(np.maximum(a * force**2 + 2.0 * b * force + c, 0.0))


def case_trajectory(case) -> Trajectory:
    """The minimum-curvature path of ``case.well``; a vertical well as deep as the string without one."""
    well = case.well
    if well is None:
        return trajectory([0.0, case.length], [0.0, 0.0], [0.0, 0.0])
    return trajectory(well.measured_depth, well.inclination, well.azimuth)


def _section_table(case):
    """Per section: top, bottom [m], buoyed weight, skin friction [N/m], EI, contact radius, outer diameter, and
    the pressure areas rho_o g A_o', rho_i g A_i [N/m] (A_o' the outer area plus the smeared tool joints' steel
    outside the body, which displaces annulus mud)."""
    g = case.environment.gravity if case.model.gravity else 0.0
    well = case.well
    rho_o = case.fluid.density if case.model.buoyancy else 0.0
    rho_i = rho_o if well is None or well.inner_fluid_density is None or not case.model.buoyancy \
        else well.inner_fluid_density
    joints = {} if well is None else well.tool_joints
    rows, top = [], 0.0
    for s, q in zip(case.sections, case.axial_load_per_length):
        material = case.material_of(s)
        beam = hollow_circle(s.outer_diameter, s.inner_diameter, material.young_modulus, material.density,
                             material.poisson_ratio)
        # q = (m - rho_o A_s) g + skin (drillstring.derived.axial_load_per_length): the skin friction is the rest
        skin = q - axial_load_per_length(steel_density=material.density, area=s.area, gravity=g,
                                         buoyancy_density=rho_o, skin_friction=0.0,
                                         solid_area=material.solid_fraction * s.area)
        outer_area = s.outer_area + (material.solid_fraction - 1.0) * s.area
        weight = g * (material.density * s.area + rho_i * s.inner_area - rho_o * outer_area)
        radius = joints.get(s.name, s.outer_diameter) / 2.0
        rows.append((top, top + s.length, weight, skin, beam.bending_stiffness, radius, s.outer_diameter,
                     rho_o * g * outer_area, rho_i * g * s.inner_area))
        top += s.length
    return rows


def string_in_well(case, path: Trajectory | None = None, *, bit_depth: float | None = None,
                   max_step: float = MAX_STEP) -> StringInWell:
    """The string of ``case`` with its bit at ``bit_depth`` (default: the string's length; a shorter depth
    keeps the bottom ``bit_depth`` metres of the string, as when tripping) along ``path`` (default
    :func:`case_trajectory`), in elements of at most ``max_step`` [m]."""
    path = case_trajectory(case) if path is None else path
    length = case.length
    bit = length if bit_depth is None else float(bit_depth)
    if not (math.isfinite(bit) and 0.0 < bit <= length):
        raise ValueError(f"bit_depth = {bit_depth!r} m: must be in (0, {length:g}] (the string's length)")
    if bit > path.depth * (1.0 + 1e-12):
        raise ValueError(f"bit_depth = {bit:g} m: deeper than the well ({path.depth:g} m)")
    if not (math.isfinite(max_step) and max_step > 0.0):
        raise ValueError(f"max_step = {max_step!r} m: must be > 0")
    offset = length - bit
    table = _section_table(case)
    well = case.well
    shoe = 0.0 if well is None else well.casing_shoe
    breaks = {0.0, bit, *(min(max(b - offset, 0.0), bit) for row in table for b in row[:2])}
    breaks |= {float(s) for s in path.measured_depth if 0.0 < s < bit}
    if 0.0 < shoe < bit:
        breaks.add(shoe)
    breaks_sorted = np.array(sorted(breaks))
    nodes = [breaks_sorted[:1]]
    for a, b in zip(breaks_sorted[:-1], breaks_sorted[1:]):
        count = max(1, math.ceil((b - a) / max_step - 1e-9))
        nodes.append(a + (b - a) * np.arange(1, count + 1) / count)
    md = np.concatenate(nodes)
    md[-1] = bit
    middle = 0.5 * (md[:-1] + md[1:])
    tops = np.array([row[0] - offset for row in table])
    section = np.clip(np.searchsorted(tops, middle, side="right") - 1, 0, len(table) - 1)
    # Geometry at both ends of each element, on the element's own arc.
    course = np.clip(np.searchsorted(path.measured_depth, middle, side="right") - 1, 0, len(path.measured_depth) - 2)
    ends = np.stack([md[:-1], md[1:]], axis=1)
    weight = np.array([table[i][2] for i in section])
    cos_i = np.empty_like(ends)
    a = np.empty_like(ends)
    b = np.empty_like(ends)
    c = np.empty_like(ends)
    for j in range(2):
        _, t, kappa, _ = path.locate(ends[:, j])
        # the element's arc may differ from the one locate picked at a station: recompute on `course`
        at_station = _on_other_course(path, ends[:, j], course)
        if np.any(at_station):
            t[at_station], kappa[at_station] = _arc_values(path, ends[at_station, j], course[at_station])
        cos_i[:, j] = t[:, 2]
        lateral = np.stack([-t[:, 2] * t[:, 0], -t[:, 2] * t[:, 1], 1.0 - t[:, 2] ** 2], axis=1)  # z - (z.t)t
        a[:, j] = np.einsum("ij,ij->i", kappa, kappa)
        b[:, j] = weight * np.einsum("ij,ij->i", kappa, lateral)
        c[:, j] = (weight**2) * np.maximum(1.0 - t[:, 2] ** 2, 0.0)
    tvd = path.locate(md)[0][:, 2]
    cased = middle < shoe
    hole = case.borehole.diameter
    casing = hole if well is None or well.casing_inner_diameter is None else well.casing_inner_diameter
    outer = np.array([table[i][6] for i in section])
    clearance = (np.where(cased, casing, hole) - outer) / 2.0
    return StringInWell(
        measured_depth=md, inclination_cos=cos_i, curvature_sq=a, coupling=b, lateral_sq=c, weight=weight,
        skin_friction=np.array([table[i][3] for i in section]),
        contact_radius=np.array([table[i][5] for i in section]), cased=cased,
        bending_stiffness=np.array([table[i][4] for i in section]), clearance=np.maximum(clearance, 1e-6),
        pressure_area=np.array([[table[i][7], table[i][8]] for i in section]), true_vertical_depth=tvd,
        section=section)


def _on_other_course(path: Trajectory, depth: np.ndarray, course: np.ndarray) -> np.ndarray:
    k = np.clip(np.searchsorted(path.measured_depth, depth, side="right") - 1, 0, len(path.measured_depth) - 2)
    return k != course


def _arc_values(path: Trajectory, depth: np.ndarray, course: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Tangent and curvature at the end of ``course`` (a station seen from the arc above it)."""
    t = path.tangent[course + 1]
    length = np.diff(path.measured_depth)[course]
    bend = path.dogleg[course]
    t1 = path.tangent[course]
    e = t - np.cos(bend)[:, None] * t1
    with np.errstate(divide="ignore", invalid="ignore"):
        b_over_sin = np.where(bend > 0.0, bend / np.where(bend > 0.0, np.sin(bend), 1.0), 1.0)
    kappa = (-(bend * np.sin(bend))[:, None] * t1 + (np.cos(bend) * b_over_sin)[:, None] * e) / length[:, None]
    return t, kappa


@dataclass(frozen=True)
class TorqueDragResult:
    """One operation's loads along the string (SI units; node arrays from the surface to the bit).

    ``axial_force`` is the effective tension (tension > 0) [N], ``true_axial_force`` the steel's [N],
    ``torque`` [N*m], ``side_force`` the wall's normal force per length [N/m] (at each node, from the element
    above it); ``hook_load`` = axial_force at the surface, ``surface_torque`` = torque there. ``friction`` is
    the friction factors used, one value or one per draw (then every array has a trailing axis of draws).
    ``extras["locked_up"]``: the compression diverged (helical lock-up): the hook load is then -LOCKED."""

    operation: str
    measured_depth: np.ndarray
    axial_force: np.ndarray
    true_axial_force: np.ndarray
    torque: np.ndarray
    side_force: np.ndarray
    weight_on_bit: float
    torque_on_bit: float
    extras: dict = field(default_factory=dict)

    @property
    def hook_load(self):
        return self.axial_force[0]

    @property
    def surface_torque(self):
        return self.torque[0]

    def profile(self) -> dict[str, list[float]]:
        """JSON-ready profile: measured_depth, axial_force, torque, side_force (SI)."""
        return {"measured_depth": self.measured_depth.tolist(), "axial_force": self.axial_force.tolist(),
                "torque": self.torque.tolist(), "side_force": self.side_force.tolist()}


def _friction(string: StringInWell, cased_friction, open_friction) -> np.ndarray:
    """mu per element, shape (m, G) for G draws of the two factors."""
    mu_c = np.atleast_1d(np.asarray(cased_friction, dtype=float))
    mu_o = np.atleast_1d(np.asarray(open_friction, dtype=float))
    return np.where(string.cased[:, None], mu_c[None, :], mu_o[None, :])


def torque_drag(string: StringInWell, operation: str, *, cased_friction, open_hole_friction,
                weight_on_bit: float = 0.0, torque_on_bit: float = 0.0, helical=None,
                bit_force: float | None = None) -> TorqueDragResult:
    """Loads of ``operation`` (a key of :data:`OPERATIONS`) by eqs. (1)-(2). ``cased_friction`` and
    ``open_hole_friction`` may be arrays of G draws (broadcast together): every result then has a trailing
    axis of G. ``weight_on_bit`` [N] and ``torque_on_bit`` [N*m] act only on bottom (sliding: no TOB reaches
    the string, a motor turns the bit). ``bit_force`` [N, tension > 0] replaces -WOB as the effective axial
    force at the bit (an overpull on a stuck bit; the closed-form checks). ``helical``: the helical critical
    compression per node [N]
    (:func:`drillstring.well.buckling.critical_loads`); beyond it the wall force gains r_c F^2/(4 E I)."""
    if operation not in OPERATIONS:
        raise ValueError(f"operation = {operation!r}: must be one of {', '.join(OPERATIONS)}")
    for name, value in (("weight_on_bit", weight_on_bit), ("torque_on_bit", torque_on_bit)):
        if not (math.isfinite(value) and value >= 0.0):
            raise ValueError(f"{name} = {value!r}: must be a finite number >= 0")
    sigma, rotating, on_bottom = OPERATIONS[operation]
    mu_c, mu_o = np.broadcast_arrays(np.atleast_1d(np.asarray(cased_friction, float)),
                                     np.atleast_1d(np.asarray(open_hole_friction, float)))
    if np.any(~np.isfinite(mu_c)) or np.any(mu_c < 0) or np.any(~np.isfinite(mu_o)) or np.any(mu_o < 0):
        raise ValueError("friction factors must be finite numbers >= 0")
    mu = _friction(string, mu_c, mu_o)
    wob = weight_on_bit if on_bottom else 0.0
    tob = torque_on_bit if (on_bottom and rotating) else 0.0
    md = string.measured_depth
    m, g = len(md) - 1, mu.shape[1]
    force = np.zeros((m + 1, g))
    torque = np.zeros((m + 1, g))
    side = np.zeros((m + 1, g))
    force[m] = -wob if bit_force is None else float(bit_force)
    torque[m] = tob
    h = np.diff(md)
    axial = string.weight[:, None] * string.inclination_cos + string.skin_friction[:, None]  # (m, 2)
    a, b, c = string.curvature_sq, string.coupling, string.lateral_sq
    extra = None
    if helical is not None:
        extra = (string.clearance / (4.0 * string.bending_stiffness), np.asarray(helical, float))
    drag = sigma * mu
    twist = (mu * string.contact_radius[:, None]) if rotating else np.zeros_like(mu)
    sqrt, maximum = np.sqrt, np.maximum

    def wall(e: int, end: int, f: np.ndarray) -> np.ndarray:
        n = sqrt(maximum(a[e, end] * f * f + 2.0 * b[e, end] * f + c[e, end], 0.0))
        if extra is not None:
            critical = extra[1][e + end]
            n = n + np.where(-f > critical, extra[0][e] * f * f, 0.0)
        return n

    f_bottom = force[m]
    for e in range(m - 1, -1, -1):
        n_bottom = wall(e, 1, f_bottom)
        slope_bottom = -axial[e, 1] - drag[e] * n_bottom
        guess = f_bottom - h[e] * slope_bottom
        n_top = wall(e, 0, guess)
        f_top = f_bottom - 0.5 * h[e] * (slope_bottom - axial[e, 0] - drag[e] * n_top)
        f_top = maximum(f_top, -LOCKED)  # helical lock-up: compression diverging (Mitchell's F^2 wall force)
        n_top = wall(e, 0, f_top)
        torque[e] = torque[e + 1] + 0.5 * h[e] * twist[e] * (n_bottom + n_top)
        side[e + 1] = n_bottom
        force[e] = f_top
        f_bottom = f_top
    side[0] = n_top if m else 0.0
    # true (steel) tension: F - p_o A_o + p_i A_i, p = rho g TVD
    element = np.minimum(np.arange(m + 1), m - 1)
    tvd = string.true_vertical_depth
    true = force - ((string.pressure_area[element, 0] - string.pressure_area[element, 1]) * tvd)[:, None]
    squeeze = (lambda x: x[:, 0]) if g == 1 and np.ndim(cased_friction) == 0 and np.ndim(open_hole_friction) == 0 \
        else (lambda x: x)
    return TorqueDragResult(operation, md, squeeze(force), squeeze(true), squeeze(torque), squeeze(side),
                            float(wob), float(tob), {"locked_up": squeeze(np.any(force <= -LOCKED, axis=0)[None, :])})


def case_torque_drag(case, operations=tuple(OPERATIONS), *, string: StringInWell | None = None,
                     cased_friction=None, open_hole_friction=None, with_buckling: bool = True
                     ) -> dict[str, TorqueDragResult]:
    """Every operation of ``case`` at its weight-on-bit (``operation.weight_on_bit``) and torque on bit
    (``well.torque_on_bit``), with the case's friction factors unless given; helical lock-up forces when
    ``with_buckling``. A case without ``[well]`` is a vertical well (friction factors then 0 unless given)."""
    string = string_in_well(case) if string is None else string
    well = case.well
    mu_c = (0.0 if well is None else well.cased_hole_friction) if cased_friction is None else cased_friction
    mu_o = (0.0 if well is None else well.open_hole_friction) if open_hole_friction is None else open_hole_friction
    tob = 0.0 if well is None else well.torque_on_bit
    helical = critical_loads(string)["helical"] if with_buckling else None
    return {op: torque_drag(string, op, cased_friction=mu_c, open_hole_friction=mu_o,
                            weight_on_bit=case.operation.weight_on_bit, torque_on_bit=tob, helical=helical)
            for op in operations}


def lockup_depth(case, bit_depths, *, max_step: float = 10.0) -> float | None:
    """Shallowest of ``bit_depths`` [m] at which sliding at the case's weight on bit locks up (hook load
    <= 0 with the helical wall force); None if none does."""
    path = case_trajectory(case)
    well = case.well
    mu_c = 0.0 if well is None else well.cased_hole_friction
    mu_o = 0.0 if well is None else well.open_hole_friction
    for depth in sorted(bit_depths):
        string = string_in_well(case, path, bit_depth=depth, max_step=max_step)
        result = torque_drag(string, "sliding", cased_friction=mu_c, open_hole_friction=mu_o,
                             weight_on_bit=case.operation.weight_on_bit,
                             helical=critical_loads(string)["helical"])
        if result.hook_load <= 0.0:
            return float(depth)
    return None
