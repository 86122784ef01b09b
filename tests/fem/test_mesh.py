import numpy as np
import pytest

from drillstring.fem.mesh import build_mesh


def test_nodes_at_section_changes_and_points(drill_pipe, drill_collar):
    mesh = build_mesh([1400.0, 200.0], [drill_pipe, drill_collar], 30.0, [1400.0, 1560.0, 333.3])
    for x in (0.0, 333.3, 1400.0, 1560.0, 1600.0):
        assert mesh.nodes[mesh.node_index(x)] == pytest.approx(x, abs=1e-9)
    assert mesh.element_lengths.max() <= 30.0 + 1e-9
    assert np.all(mesh.element_lengths > 0)
    x_mid = 0.5 * (mesh.nodes[:-1] + mesh.nodes[1:])
    np.testing.assert_array_equal(mesh.element_section, (x_mid > 1400.0).astype(int))
    assert mesh.n_dofs == 6 * mesh.n_nodes


def test_missing_node_and_bad_input(drill_pipe):
    mesh = build_mesh([100.0], [drill_pipe], 10.0)
    with pytest.raises(ValueError, match="no node at x = 55"):
        mesh.node_index(55.0)
    with pytest.raises(ValueError, match="outside"):
        build_mesh([100.0], [drill_pipe], 10.0, [150.0])
    with pytest.raises(ValueError, match="max_element_length"):
        build_mesh([100.0], [drill_pipe], 0.0)
