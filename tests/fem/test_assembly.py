import numpy as np
import pytest

from drillstring.fem.assembly import (
    THETA_X, U, V, W, Stabilizer, assemble_matrix, dof, stabilizer_stiffness, structural_matrices,
)
from drillstring.fem.mesh import build_mesh


def test_assembly_of_uniform_bar_is_tridiagonal_with_summed_nodes(drill_pipe):
    mesh = build_mesh([30.0], [drill_pipe], 10.0)
    k, m = structural_matrices(mesh)
    kd = k.toarray()
    axial = kd[np.ix_(dof(np.arange(4), U), dof(np.arange(4), U))]
    ea_l = drill_pipe.axial_stiffness / 10.0
    expected = ea_l * np.array([[1, -1, 0, 0], [-1, 2, -1, 0], [0, -1, 2, -1], [0, 0, -1, 1]])
    np.testing.assert_allclose(axial, expected, rtol=1e-12)
    ones = np.zeros(mesh.n_dofs)
    ones[dof(np.arange(4), V)] = 1.0
    assert ones @ m @ ones == pytest.approx(drill_pipe.mass_per_length * 30.0, rel=1e-12)
    assert abs(k - k.T).max() < 1e-6


def test_stabilizer_springs_on_lateral_dofs(drill_pipe):
    mesh = build_mesh([30.0], [drill_pipe], 10.0)
    ks = stabilizer_stiffness(mesh, [Stabilizer(20.0, 5.0e6)]).toarray()
    node = mesh.node_index(20.0)
    assert ks[dof(node, V), dof(node, V)] == 5.0e6
    assert ks[dof(node, W), dof(node, W)] == 5.0e6
    assert ks[dof(node, THETA_X), dof(node, THETA_X)] == 0.0
    assert np.count_nonzero(ks) == 2


def test_generic_assembler_overlaps_shared_node():
    k = assemble_matrix(18, [np.ones((12, 12)), np.ones((12, 12))])
    assert k[6, 6] == 2.0 and k[0, 0] == 1.0 and k[17, 17] == 1.0 and k[0, 17] == 0.0
