"""Modes about the stiff string's static state in the well (drillstring.well.well_modes)."""

import math

import numpy as np
import scipy.linalg as sla

from drillstring.fem.mesh import build_mesh
from drillstring.fem.sections import hollow_circle
from drillstring.modal import case_linear_system, coupled_modes, family_coupling
from drillstring.statics import case_static_state
from drillstring.well.stiff_string import (
    case_stiff_string,
    solve_stiff_string,
    wall_stations,
)
from drillstring.well.survey import trajectory
from drillstring.well.well_modes import case_well_modes, well_linear_system, well_modes

PIPE = hollow_circle(0.127, 0.1086, 207e9, 7850.0, 0.3)
HOLE = 0.2159


def test_vertical_hole_gives_the_vertical_modes(coarse_case):
    """No [well] (the reference string on a 40 m mesh): every frame is the identity, no wall contact: the
    modes of today's linear system."""
    state = case_stiff_string(coarse_case)
    assert state.wall_stiffness.nnz == 0
    found = case_well_modes(coarse_case, 12, state)
    expected = coupled_modes(case_linear_system(coarse_case, case_static_state(coarse_case)), 12)
    assert np.allclose(found.angular_frequencies, expected.angular_frequencies, rtol=1e-9, atol=1e-9)


def test_string_lying_on_the_wall_rolls_like_a_beam_on_a_foundation():
    """A horizontal string (no axial force) lying on the wall: rolling round the hole, each station in
    contact is a spring F/r across the radius (its wall force over its distance from the axis). The lowest
    flexural modes against an independent finite-difference beam on that foundation, pinned at both ends:
    EI y'''' + k(x) y = ω² ρA y."""
    length, step, weight = 100.0, 1.0, 250.0
    mesh = build_mesh([length], [PIPE], step)
    path = trajectory([0.0, length], [math.pi / 2, math.pi / 2], [0.0, 0.0])
    state = solve_stiff_string(mesh, path, [weight], wall_stations(mesh, [0.127], HOLE, 1e8))
    system = well_linear_system(state)
    assert family_coupling(system) > 0.0
    modes = well_modes(system, 8)
    # independent: per node the rolling spring F_i / r_i, pinned-pinned FD beam (ghost nodes y_-1 = -y_1)
    spring = state.side_force / np.where(state.in_contact, state.lateral_offset, 1.0)
    n = mesh.n_nodes - 2
    d4 = np.zeros((n, n))
    for i in range(n):
        for j, c in zip(range(i - 2, i + 3), (1.0, -4.0, 6.0, -4.0, 1.0)):
            if 0 <= j < n:
                d4[i, j] += c
            elif j in (-2, n + 1):  # ghost beyond a pinned end (j = -1, n: y = 0): y = -y(mirror)
                d4[i, 0 if j == -2 else n - 1] -= c
    k = PIPE.bending_stiffness * d4 / step**4 + np.diag(spring[1:-1] / step)
    omega2 = sla.eigh(k, PIPE.mass_per_length * np.eye(n), eigvals_only=True)[:3]
    # the FE's lowest modes past the rigid slide along the axis: the rolling ones (torsion is above 7 Hz)
    fe = modes.angular_frequencies[modes.angular_frequencies > 1e-3][:3]
    assert np.allclose(fe, np.sqrt(omega2), rtol=5e-4)  # measured 1e-6, 3e-5, 1.5e-4
    assert fe[0] < 0.5 * 2 * math.pi * 3200 / (4 * length)


def test_curved_string_on_the_wall_is_stable_and_stiffened_by_it():
    """A 40 deg build over 600 m, pulled at the bit and hanging its weight: every mode about the static
    state is stable (ω² > 0), the families couple, and the wall's springs raise the lowest frequencies."""
    length = 600.0
    mesh = build_mesh([length], [PIPE], 10.0)
    path = trajectory([0.0, length], [0.0, 40 * math.pi / 180], [0.5, 0.5])
    state = solve_stiff_string(mesh, path, [300.0], wall_stations(mesh, [0.127], HOLE, 1e8), bit_force=1e5)
    assert state.in_contact.sum() > mesh.n_nodes // 2
    with_wall = well_linear_system(state)
    assert family_coupling(with_wall) > 0.0
    found = well_modes(with_wall, 6).angular_frequencies
    bare = well_modes(well_linear_system(state, wall=False), 6).angular_frequencies
    assert np.all(found > 0.0) and np.all(bare > 0.0)
    assert np.all(found > bare)
