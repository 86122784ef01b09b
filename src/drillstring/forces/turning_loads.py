"""Loads turning with the string — mass imbalance and bow — as a component of the reduced model (docs/extending.md).

The physical loads (:class:`~drillstring.forces.excitation.TurningLoads`) come from the registered sources of the
component protocol (:class:`~drillstring.forces.registry.TurningLoadSource`: :class:`MassImbalance`, keys
:class:`~drillstring.case.ImbalanceKeys` on each section, and :class:`StressFreeBow`, keys
:class:`~drillstring.case.Bow`), built from the case in one place by :func:`case_turning_loads`, and are
projected once on the lateral modes (:func:`turning_load_data`). Entry ``k``
sits on node ``i_k`` and, at the node's angle ``α_k = θx(i_k) + φ_k`` [rad] and spin speed ``θ̇_k = θ̇x(i_k)``
[rad/s], adds to the modal accelerations::

    f_y = s_k cos α_k · load_y[k]        f_z = s_k sin α_k · load_z[k]        s_k = θ̇_k² (imbalance) or 1 (bow)

(Vandiver, Nicholson & Shyu 1990 for the imbalance; the bow's elastic load of a stress-free bent string turns
the same way, :mod:`drillstring.forces.excitation`). Its pieces: :class:`TurningLoadData` (the kernel's data,
with the NumPy reference :meth:`TurningLoadData.evaluate` and its Jacobian :meth:`TurningLoadData.jacobian`
over the entries' angles and speeds), and the compiled kernel :func:`turning_load`, called by the reduced
model once per entry with the angle and speed it reads from the modal state.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar, NamedTuple

import numpy as np
from numba import njit

from drillstring.case import Bow, ImbalanceKeys
from drillstring.forces.excitation import TurningLoads, bow_loads, imbalance_loads
from drillstring.forces.registry import TurningLoadSource, register, turning_load_source, turning_load_sources

__all__ = ["MassImbalance", "StressFreeBow", "TurningLoadData", "case_turning_loads", "turning_load",
           "turning_load_data"]


@register
@dataclass(frozen=True)
class MassImbalance(TurningLoadSource):
    """The sections' mass imbalance (:func:`~drillstring.forces.excitation.imbalance_loads`): ``eccentricity``
    e [m] and ``eccentricity_angle`` φ [rad] per section (:class:`~drillstring.case.ImbalanceKeys`)."""

    name: ClassVar[str] = "imbalance"
    keys: ClassVar = ImbalanceKeys
    order: ClassVar[int] = 0

    eccentricity: tuple = ()
    eccentricity_angle: tuple = ()

    @classmethod
    def from_case(cls, case) -> "MassImbalance":
        return cls(tuple(s.eccentricity for s in case.sections), tuple(s.eccentricity_angle for s in case.sections))

    def loads(self, mesh) -> TurningLoads:
        return imbalance_loads(mesh, list(self.eccentricity), list(self.eccentricity_angle))


@register
@dataclass(frozen=True)
class StressFreeBow(TurningLoadSource):
    """A stress-free bow (:func:`~drillstring.forces.excitation.bow_loads`, on the beams' elastic stiffness):
    ``amplitude`` [m] between ``start`` and ``end`` [m] from the top, at ``angle`` [rad]
    (:class:`~drillstring.case.Bow`); none when the amplitude is 0."""

    name: ClassVar[str] = "bow"
    keys: ClassVar = Bow
    order: ClassVar[int] = 1

    amplitude: float = 0.0
    start: float = 0.0
    end: float = 0.0
    angle: float = 0.0

    @classmethod
    def from_case(cls, case) -> "StressFreeBow":
        b = case.bow
        return cls(b.amplitude, b.start, b.end, b.angle)

    def loads(self, mesh) -> TurningLoads:
        from drillstring.fem.assembly import structural_matrices

        if not self.amplitude > 0.0:
            return TurningLoads.empty(mesh.n_dofs)
        stiffness, _ = structural_matrices(mesh)
        return bow_loads(mesh, stiffness, self.amplitude, self.start, self.end, self.angle)


class TurningLoadData(NamedTuple):
    """Loads turning with the string (:class:`~drillstring.forces.excitation.TurningLoads`) projected on
    the lateral modes: entry ``k`` adds ``s_k cos α_k load_y[k]`` to the y family and ``s_k sin α_k
    load_z[k]`` to the z family, ``α_k = Ω t + (Φ η)_θx(node_k) + phase_k``, ``s_k`` the local spin
    speed squared (imbalance) or 1 (bow)."""

    node: np.ndarray  # (m,) int64
    phase: np.ndarray  # (m,) [rad]
    speed_squared: np.ndarray  # (m,) bool
    load_y: np.ndarray  # (m, n_y) generalized forces on the lateral-y modes
    load_z: np.ndarray  # (m, n_z)

    def evaluate(self, angle, spin_speed):
        """NumPy reference: the generalized forces ``(f_y (n_y,), f_z (n_z,))`` of every entry at its angle
        ``α_k`` [rad] (phase included) and spin speed ``θ̇_k`` [rad/s] (arrays of length m)."""
        angle = np.asarray(angle, dtype=float)
        scale = np.where(self.speed_squared, np.asarray(spin_speed, dtype=float) ** 2, 1.0)
        return self.load_y.T @ (scale * np.cos(angle)), self.load_z.T @ (scale * np.sin(angle))

    def jacobian(self, angle, spin_speed) -> np.ndarray:
        """Jacobian of :meth:`evaluate`, shape ``(n_y + n_z, 2 m)``: rows the y then the z generalized
        forces, columns ``∂/∂α_k`` [per rad] then ``∂/∂θ̇_k`` [per rad/s] (zero for a bow's entry)::

            ∂f_y/∂α_k = −s_k sin α_k load_y[k]     ∂f_y/∂θ̇_k = 2 θ̇_k cos α_k load_y[k]  (imbalance)
            ∂f_z/∂α_k =  s_k cos α_k load_z[k]     ∂f_z/∂θ̇_k = 2 θ̇_k sin α_k load_z[k]  (imbalance)
        """
        angle = np.asarray(angle, dtype=float)
        speed = np.asarray(spin_speed, dtype=float)
        scale = np.where(self.speed_squared, speed**2, 1.0)
        slope = np.where(self.speed_squared, 2.0 * speed, 0.0)
        cos, sin = np.cos(angle), np.sin(angle)
        top = np.hstack([self.load_y.T * (-scale * sin), self.load_y.T * (slope * cos)])
        bottom = np.hstack([self.load_z.T * (scale * cos), self.load_z.T * (slope * sin)])
        return np.vstack([top, bottom])


def turning_load_data(loads: TurningLoads, lateral_y_shapes: np.ndarray, lateral_z_shapes: np.ndarray
                      ) -> TurningLoadData:
    """Project ``loads`` on the lateral modes: ``lateral_y_shapes`` (n_dofs, n_y) and ``lateral_z_shapes``
    (n_dofs, n_z) are the lateral-y and lateral-z mode shapes in global DOFs."""
    transposed = np.ascontiguousarray
    load_y = transposed((loads.force_y.T @ lateral_y_shapes), dtype=float)
    load_z = transposed((loads.force_z.T @ lateral_z_shapes), dtype=float)
    return TurningLoadData(
        node=transposed(loads.node, dtype=np.int64), phase=transposed(loads.phase, dtype=float),
        speed_squared=transposed(loads.speed_squared, dtype=np.bool_),
        load_y=load_y.reshape(len(loads), lateral_y_shapes.shape[1]),
        load_z=load_z.reshape(len(loads), lateral_z_shapes.shape[1]),
    )


@njit(cache=True, no_cpython_wrapper=True, inline="always")
def turning_load(r, k, angle, speed, acc, y0, y1, z0, z1):
    """Add entry ``k`` of :class:`TurningLoadData` ``r`` at angle ``α_k`` [rad] and spin speed ``θ̇_k``
    [rad/s] to the modal accelerations ``acc`` (lateral-y columns ``[y0, y1)``, lateral-z ``[z0, z1)``).
    Inlined into the caller by Numba: as a separate call the reference realization was 18 % slower
    (0.22 s against 0.185 s of CPU time), although the reference case has no turning load."""
    scale = speed * speed if r.speed_squared[k] else 1.0
    cy = scale * math.cos(angle)
    cz = scale * math.sin(angle)
    for j in range(y0, y1):
        acc[j] += cy * r.load_y[k, j - y0]
    for j in range(z0, z1):
        acc[j] += cz * r.load_z[k, j - z0]


def case_turning_loads(case, mesh, sources=None) -> TurningLoads:
    """The turning loads of a :class:`~drillstring.forces.registry.TurningLoadSource` each, as
    :class:`~drillstring.forces.excitation.TurningLoads` on ``mesh``, their entries concatenated in the sources'
    order: by default the package's registered sources built from the case (the sections' mass imbalance,
    ``sections[i].eccentricity``, ``eccentricity_angle``, then the stress-free bow, ``[bow]``); ``sources``:
    instances instead (e.g. one registered outside the package). Empty when none has any."""
    if sources is None:
        sources = [turning_load_source(name).from_case(case) for name in turning_load_sources(package_only=True)]
    loads = None
    for source in sources:
        entries = source.loads(mesh)
        if loads is None:
            loads = entries
        elif len(entries):
            loads = loads + entries
    return loads if loads is not None else TurningLoads.empty(mesh.n_dofs)
