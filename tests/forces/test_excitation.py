"""Loads turning with the string: mass imbalance (nodal quadrature of ρA e θ̇²) and stress-free bow (K q_b)."""

import math

import numpy as np
import pytest
import scipy.sparse.linalg as spla

from drillstring.fem.assembly import structural_matrices
from drillstring.fem.dofs import THETA_Y, THETA_Z, V, W, dof
from drillstring.fem.mesh import build_mesh
from drillstring.forces.excitation import TurningLoads, bow_loads, bow_shape, imbalance_loads
from drillstring.modal import family_dofs


@pytest.fixture
def mesh(drill_pipe, drill_collar):
    # unequal elements: 30 m of pipe in 4 elements (7.5 m), 12 m of collar in 3 (4 m)
    return build_mesh([30.0, 12.0], [drill_pipe, drill_collar], 8.0)


def test_imbalance_force_is_the_centrifugal_force_of_each_section(mesh, drill_pipe, drill_collar):
    """Per section, the nodal forces add up to ρA e L exactly (per (rad/s)²), shared by nodal quadrature
    (h/2 per node of each element); a node at the section change carries one entry per section, each with
    its section's angle; the force points along (cos α, sin α), α = θx + φ, and scales with θ̇x²."""
    e = np.array([0.002, 0.005])
    phi = np.array([0.3, -1.0])
    loads = imbalance_loads(mesh, e, phi)
    assert loads.speed_squared.all()
    expected = [s.density * s.area * e_s * length for s, e_s, length in
                zip((drill_pipe, drill_collar), e, (30.0, 12.0))]
    for section, angle in enumerate(phi):
        columns = np.isclose(loads.phase, angle)
        assert loads.force_y[:, columns].sum() == pytest.approx(expected[section], rel=1e-12)
        assert loads.force_z[:, columns].sum() == pytest.approx(expected[section], rel=1e-12)
    change = mesh.node_index(30.0)
    assert np.count_nonzero(loads.node == change) == 2
    # interior pipe node: two half elements of 7.5 m
    pipe_node = mesh.node_index(15.0)
    column = np.nonzero(loads.node == pipe_node)[0][0]
    assert loads.force_y[dof(pipe_node, V), column] == pytest.approx(
        drill_pipe.density * drill_pipe.area * e[0] * 7.5, rel=1e-12)
    # direction and speed: node rotations θx and spins θ̇x
    rotation = np.linspace(0.0, 2.0, mesh.n_nodes)
    spin = np.linspace(9.0, 11.0, mesh.n_nodes)
    force = loads.forces(rotation, spin)
    unit = drill_pipe.density * drill_pipe.area * e[0] * 7.5
    alpha = rotation[pipe_node] + phi[0]
    assert force[dof(pipe_node, V)] == pytest.approx(unit * spin[pipe_node] ** 2 * math.cos(alpha), rel=1e-12)
    assert force[dof(pipe_node, W)] == pytest.approx(unit * spin[pipe_node] ** 2 * math.sin(alpha), rel=1e-12)
    assert len(imbalance_loads(mesh, [0.0, 0.0], [0.0, 0.0])) == 0


@pytest.mark.parametrize("angle", [0.0, 0.7])
def test_a_bowed_beam_at_rest_takes_its_stress_free_shape(drill_pipe, angle):
    """A pinned–pinned beam without other loads, loaded by its bow's K q_b, is in equilibrium exactly on
    the bowed shape: v = b cos φ, w = b sin φ, θz = b' cos φ, θy = −b' sin φ at every node (signs of both
    bending planes)."""
    mesh = build_mesh([60.0], [drill_pipe], 2.5)
    k, _ = structural_matrices(mesh)
    loads = bow_loads(mesh, k, 0.01, 12.0, 48.0, angle)
    assert not loads.speed_squared.any()
    force = loads.forces(np.zeros(mesh.n_nodes), np.zeros(mesh.n_nodes))
    nodes = np.arange(mesh.n_nodes)
    b, slope = bow_shape(mesh.nodes, 0.01, 12.0, 48.0)
    for family, (u, rot, sign, direction) in {"lateral_y": (V, THETA_Z, 1.0, math.cos(angle)),
                                              "lateral_z": (W, THETA_Y, -1.0, math.sin(angle))}.items():
        dofs = family_dofs(mesh, family)
        solution = np.zeros(mesh.n_dofs)
        solution[dofs] = spla.spsolve(k[dofs][:, dofs].tocsc(), force[dofs])
        np.testing.assert_allclose(solution[dof(nodes, u)], direction * b, atol=1e-12)
        np.testing.assert_allclose(solution[dof(nodes, rot)], sign * direction * slope, atol=1e-12)


def test_bow_shape_is_a_smooth_bump():
    x = np.linspace(0.0, 10.0, 1001)
    b, slope = bow_shape(x, 0.02, 2.0, 6.0)
    assert b.max() == pytest.approx(0.02) and x[np.argmax(b)] == pytest.approx(4.0)
    assert np.all(b[(x < 2.0) | (x > 6.0)] == 0.0) and np.all(slope[(x < 2.0) | (x > 6.0)] == 0.0)
    smooth = (np.abs(x - 2.0) > 0.02) & (np.abs(x - 6.0) > 0.02)  # b'' jumps at the ends
    np.testing.assert_allclose(np.gradient(b, x)[smooth], slope[smooth], atol=1e-6)  # b' is the derivative
    assert abs(slope[np.argmin(abs(x - 2.0))]) < 1e-12 and abs(slope[np.argmin(abs(x - 6.0))]) < 1e-12


def test_turning_loads_concatenate_and_refuse_bad_input(mesh):
    k, _ = structural_matrices(mesh)
    both = imbalance_loads(mesh, [0.001, 0.0], [0.0, 0.0]) + bow_loads(mesh, k, 0.005, 5.0, 25.0)
    assert len(both) == np.count_nonzero(both.speed_squared) + np.count_nonzero(~both.speed_squared)
    assert both.force_y.shape == (mesh.n_dofs, len(both))
    assert len(TurningLoads.empty(mesh.n_dofs)) == 0
    with pytest.raises(ValueError, match="per mesh section"):
        imbalance_loads(mesh, [0.001], [0.0])
    with pytest.raises(ValueError, match=">= 0"):
        imbalance_loads(mesh, [-0.001, 0.0], [0.0, 0.0])
    with pytest.raises(ValueError, match="start < end"):
        bow_loads(mesh, k, 0.005, 25.0, 5.0)
