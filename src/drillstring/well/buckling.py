"""Buckling of the string in inclined and curved holes: critical compressions along the string and where each
operation exceeds them (the lock-up depth when sliding, which runs the torque and drag with them:
:func:`drillstring.well.torque_drag.lockup_depth`).

The wall holds a compressed pipe in the hole with the lateral load per length ``n`` of the soft-string model
(:mod:`drillstring.well.torque_drag`, eq. (1)), which for a compression C = -F is

    n(C) = | -C kappa + w (z - (z.t) t) |.

The critical compressions are those of a pipe of bending stiffness EI in a hole of radial clearance r_c held
by that load:

    sinusoidal:   C_s^2 = 4 E I n(C_s) / r_c      (Dawson & Paslay 1984, SPE 11167),                 (1)
    helical:      C_h^2 = 8 E I n(C_h) / r_c      (Chen, Lin & Cheatham 1990, SPE 19176: 2 sqrt 2).     (2)

In a straight inclined hole n = w sin I and (1)-(2) are the classical ``C_s = 2 sqrt(E I w sin I / r_c)`` and
``C_h = 2 sqrt(2) sqrt(E I w sin I / r_c)``. In a curved hole the compression itself presses the pipe against
the outer wall of the bend, ``n = w sin I + C kappa`` in a build section, and (1) becomes the curved-hole
criterion of Wu & Juvkam-Wold (1995, J. Energy Resour. Technol. 117, 214-218; the same construction as
He & Kyllingstad 1995, SPE Drilling & Completion 10(1), 10-15):

    C_s = (2 E I kappa / r_c) [1 + sqrt(1 + r_c w sin I / (E I kappa^2))],

much larger than in a straight hole; in a drop section the bend lifts the pipe off the low side and the
critical load is smaller. (1)-(2) are solved at each node by bisection on the exact n(C) (vector geometry:
build, drop, turn alike). In a vertical hole n = 0 and both are 0: any compression buckles a long vertical
string (its length-dependent critical load is :mod:`drillstring.buckling`'s finite-element one).

**Margin along the path** (:func:`margin_along_path`; for a case's stiff string
:func:`drillstring.well.stiff_string.case_well_buckling_margin`, what ``drillstring static`` reports for
a case with ``[well]``): with the axial force N(s) of a static state (tension positive) and the critical compressions
C(s) of (1) or (2), the reserve ``C(s) + N(s)`` [N] is the compression the string still takes at s; the string
buckles where it is negative. A change of the weight on bit moves N by the same amount all along the string
when the axial force does not depend on the side forces (the frictionless soft string: dN/ds = -(w cos I +
q_f), the stiff string away from its bottom-hole assembly), and C(s) depends on the path only, so the
critical weight on bit is

    WOB_cr = WOB + min_s (C(s) + N(s)),                                                              (3)

reached first at the s of the minimum.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["WellBucklingMargin", "buckled_intervals", "critical_loads", "margin_along_path"]

#: Bisection steps of (1)-(2): the bracket shrinks 2^-80 times, below float precision.
_BISECTIONS = 80


def _node_geometry(string) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """a, b, c of n^2 = a F^2 + 2 b F + c at the nodes (from the element above; the top from element 0)."""
    a = np.concatenate([string.curvature_sq[:1, 0], string.curvature_sq[:, 1]])
    b = np.concatenate([string.coupling[:1, 0], string.coupling[:, 1]])
    c = np.concatenate([string.lateral_sq[:1, 0], string.lateral_sq[:, 1]])
    return a, b, c


def _node_values(per_element: np.ndarray) -> np.ndarray:
    return np.concatenate([per_element[:1], per_element])


def critical_loads(string) -> dict[str, np.ndarray]:
    """Sinusoidal and helical critical compressions [N] (> 0) at each node of ``string``, eqs. (1)-(2)."""
    a, b, c = _node_geometry(string)
    stiffness = _node_values(string.bending_stiffness)
    clearance = _node_values(string.clearance)
    out = {}
    for name, factor in (("sinusoidal", 4.0), ("helical", 8.0)):
        k = factor * stiffness / clearance
        # n(C) <= |kappa| C + sqrt(c): C^2 <= k (|kappa| C + sqrt(c)) bounds the root
        kappa = np.sqrt(a)
        high = k * kappa / 2.0 + np.sqrt((k * kappa / 2.0) ** 2 + k * np.sqrt(c)) + 1e-12
        low = np.zeros_like(high)
        for _ in range(_BISECTIONS):
            mid = 0.5 * (low + high)
            n = np.sqrt(np.maximum(a * mid * mid - 2.0 * b * mid + c, 0.0))
            above = mid * mid > k * n
            high = np.where(above, mid, high)
            low = np.where(above, low, mid)
        out[name] = 0.5 * (low + high)
    return out


def buckled_intervals(measured_depth, axial_force, critical) -> list[tuple[float, float]]:
    """Measured-depth intervals [m] where the compression -axial_force exceeds ``critical`` (node arrays),
    as (top, bottom) pairs of node depths."""
    md = np.asarray(measured_depth, float)
    over = -np.asarray(axial_force, float) > np.asarray(critical, float)
    intervals, start = [], None
    for i, flag in enumerate(over):
        if flag and start is None:
            start = i
        if not flag and start is not None:
            intervals.append((float(md[start]), float(md[i - 1])))
            start = None
    if start is not None:
        intervals.append((float(md[start]), float(md[-1])))
    return intervals


@dataclass(frozen=True)
class WellBucklingMargin:
    """Buckling of a static state along the well path, eqs. (1)-(3) (SI units).

    Attributes:
        critical_weight_on_bit: WOB_cr of sinusoidal buckling, eq. (3) [N].
        critical_measured_depth: where the reserve of (3) is smallest, i.e. where sinusoidal buckling starts [m].
        helical_weight_on_bit: WOB_cr of helical buckling [N]; helical_measured_depth: where [m].
        weight_on_bit: the state's weight on bit [N]; weight: the string's weight [N].
        sinusoidal_intervals, helical_intervals: measured-depth intervals [m] buckled at the state
            (:func:`buckled_intervals`).
    """

    critical_weight_on_bit: float
    critical_measured_depth: float
    helical_weight_on_bit: float
    helical_measured_depth: float
    weight_on_bit: float
    weight: float
    sinusoidal_intervals: list[tuple[float, float]]
    helical_intervals: list[tuple[float, float]]

    @property
    def buckled(self) -> bool:
        """True when the compression exceeds the sinusoidal critical load somewhere along the path."""
        return bool(self.sinusoidal_intervals)

    @property
    def margin(self) -> float:
        """WOB_cr − WOB [N]: extra weight on bit before sinusoidal buckling (negative: buckled)."""
        return self.critical_weight_on_bit - self.weight_on_bit


def margin_along_path(measured_depth, axial_force, critical: dict[str, np.ndarray], *, weight_on_bit: float,
                      weight: float) -> WellBucklingMargin:
    """The buckling margin, eq. (3), of the axial force ``axial_force`` [N] (tension positive) at the nodes
    ``measured_depth`` [m] against the critical compressions ``critical`` (:func:`critical_loads`, same
    nodes), at the state's ``weight_on_bit`` [N]; ``weight`` [N] the string's weight (carried along)."""
    md, force = np.asarray(measured_depth, float), np.asarray(axial_force, float)
    found = {}
    for name in ("sinusoidal", "helical"):
        reserve = np.asarray(critical[name], float) + force
        i = int(np.argmin(reserve))
        found[name] = (float(weight_on_bit + reserve[i]), float(md[i]))
    return WellBucklingMargin(*found["sinusoidal"], *found["helical"], float(weight_on_bit), float(weight),
                              buckled_intervals(md, force, critical["sinusoidal"]),
                              buckled_intervals(md, force, critical["helical"]))

