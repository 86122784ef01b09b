"""The reduced model's frame (docs/model.md §8): the compiled functions that map the modal state to a
station's motion, one per quantity: its spin (:func:`station_spin`, from the frame's own rotation
:func:`frame_speed`), the bit's axial motion (:func:`bit_axial_motion`), the lateral displacements
(:func:`lateral_displacements`) and velocities (:func:`station_lateral_velocity`), so that every law reads a
station's motion from the same place. A curved string
changes this mapping (the rotation about each station's local tangent), not the laws that read it: the bit law
(:class:`~drillstring.forces.registry.BitContext`), the top boundary
(:class:`~drillstring.forces.registry.TopContext`), the contact (:class:`~drillstring.forces.registry.
ContactContext`) and the turning loads.
"""

from __future__ import annotations

from numba import njit

from drillstring.dynamics.kernel_data import AXIAL_ROW

_AXIAL_BIT = AXIAL_ROW["bit"]


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


@njit(cache=True, no_cpython_wrapper=True)
def bit_axial_motion(d, y):
    """The bit's axial position u [m] (from the static state, down) and velocity u̇ [m/s] for the state ``y`` =
    [η, η̇] of the case-2 data ``d`` (its axial row ``bit``). Compiled code only."""
    n = d.omega2.shape[0]
    a0, a1 = d.ranges.axial_start, d.ranges.axial_end
    position = 0.0
    velocity = 0.0
    for j in range(a0, a1):
        position += d.axial_rows[_AXIAL_BIT, j - a0] * y[j]
        velocity += d.axial_rows[_AXIAL_BIT, j - a0] * y[n + j]
    return position, velocity


@njit(cache=True, no_cpython_wrapper=True)
def friction_station_axial_velocity(d, y, station):
    """The axial velocity u̇ [m/s] along the string (down positive) of the along-string friction's station
    ``station`` (:class:`~drillstring.dynamics.kernel_data.StringFrictionData`) for the state ``y`` = [η, η̇].
    Compiled code only."""
    n = d.omega2.shape[0]
    a0, a1 = d.ranges.axial_start, d.ranges.axial_end
    velocity = 0.0
    for j in range(a0, a1):
        velocity += d.friction.axial_t[j - a0, station] * y[n + j]
    return velocity


@njit(cache=True, no_cpython_wrapper=True)
def _columns_matvec(matrix_t, vector, offset, out, sign):
    """out (+)= sign · matrix @ vector[offset:] given ``matrix_t`` = matrixᵀ (C order): column by
    column, so the inner loop is contiguous and vectorises without reassociating sums."""
    for j in range(matrix_t.shape[0]):
        x = sign * vector[offset + j]
        if x != 0.0:
            for i in range(matrix_t.shape[1]):
                out[i] += matrix_t[j, i] * x


@njit(cache=True, no_cpython_wrapper=True)
def lateral_displacements(d, y, v, w):
    """The lateral displacements v and w [m] of every node from the hole's axis for the state ``y``, written into
    ``v`` and ``w`` (n_nodes,): the node's static offset (``d.contact.rest``: zeros for the
    straight string, the stiff string's rest in a well basis) plus the modal motion. Compiled code only."""
    rest = d.contact.rest
    for i in range(v.shape[0]):  # a loop: the slice copy v[:] = rest[0] cost +12 % cold compile, this +3 %
        v[i] = rest[0, i]
        w[i] = rest[1, i]
    _columns_matvec(d.phi_v_t, y, d.ranges.lateral_y_start, v, 1.0)
    _columns_matvec(d.phi_w_t, y, d.ranges.lateral_z_start, w, 1.0)


@njit(cache=True, no_cpython_wrapper=True)
def station_lateral_velocity(d, y, node):
    """The lateral velocities v̇ and ẇ [m/s] of the mesh node ``node`` for the state ``y`` = [η, η̇].
    Compiled code only."""
    n = d.omega2.shape[0]
    ranges = d.ranges
    vd = 0.0
    wd = 0.0
    for j in range(ranges.lateral_y_start, ranges.lateral_y_end):
        vd += d.phi_v_t[j - ranges.lateral_y_start, node] * y[n + j]
    for j in range(ranges.lateral_z_start, ranges.lateral_z_end):
        wd += d.phi_w_t[j - ranges.lateral_z_start, node] * y[n + j]
    return vd, wd
