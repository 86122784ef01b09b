"""The reduced model's frame (docs/model.md §8): the one compiled function that maps the modal state to a
station's spin (:func:`station_spin`, from the frame's own rotation :func:`frame_speed`), so that every law
reads a station's angle and spin speed from the same place. A curved string
changes this mapping (the rotation about each station's local tangent), not the laws that read it: the bit law
(:class:`~drillstring.forces.registry.BitContext`), the top boundary
(:class:`~drillstring.forces.registry.TopContext`), the contact (:class:`~drillstring.forces.registry.
ContactContext`) and the turning loads.
"""

from __future__ import annotations

from numba import njit


@njit(cache=True, no_cpython_wrapper=True)
def station_spin(d, t, y, node, phase):
    """The angle θ [rad] and spin speed θ̇ [rad/s] of the mesh node ``node`` about its local tangent at time
    ``t`` [s] for the state ``y`` = [η, η̇] of the case-2 data ``d``
    (:class:`~drillstring.dynamics.kernel_data.RhsData`): the frame's rotation ``Ω t + phase`` (``phase`` [rad]
    a station's angle at t = 0) plus the torsional mode shapes' ``φ_θx η``, and ``Ω + φ_θx η̇`` (docs/model.md
    §8). For today's straight string the tangent is the global x axis at every node. Compiled code only."""
    n = d.omega2.shape[0]
    t0, t1 = d.ranges.torsion_start, d.ranges.torsion_end
    angle = d.top_speed * t + phase
    speed = d.top_speed
    for j in range(t0, t1):
        angle += d.phi_tx_t[j - t0, node] * y[j]
        speed += d.phi_tx_t[j - t0, node] * y[n + j]
    return angle, speed


@njit(cache=True, no_cpython_wrapper=True)
def frame_speed(d):
    """The frame's own spin speed Ω [rad/s] of the case-2 data ``d``: an imposed top speed, 0 with a top drive;
    what a state of zero η̇ spins at, at every node (the full model's ``q̇ = Φη̇ + Ω`` at the θx DOFs, the bit's
    angle over a step). Compiled code only."""
    return d.top_speed
