"""Quantities shared by the case validation and the model (drillstring.derived), each against the model
code that builds on it or against a closed form."""

import math

import numpy as np
import pytest

from drillstring.derived import (
    axial_load_per_length,
    element_counts,
    flow_velocities,
    fluid_skin_friction,
    mesh_breaks,
    mode_family_sizes,
    string_axial_load,
)
from drillstring.fem.mesh import build_mesh
from drillstring.modal import family_dofs


@pytest.mark.parametrize("lengths, points, h", [
    ([1400.0, 200.0], [1400.0, 1560.0], 10.0),
    ([60.0, 20.0], [60.0, 70.0], 7.0),
    ([1.0], [0.5, 0.5 + 1e-12, 1.0], 0.3),
    ([5.0, 5.0], [], 100.0),
])
def test_mesh_layout_is_the_one_the_mesh_uses(drill_pipe, drill_collar, lengths, points, h):
    sections = [drill_pipe, drill_collar][: len(lengths)]
    mesh = build_mesh(lengths, sections, h, points)
    breaks = mesh_breaks(lengths, points)
    counts = element_counts(breaks, h)
    assert mesh.n_elements == sum(counts)
    assert all(np.any(np.abs(mesh.nodes - x) < 1e-12) for x in breaks)  # every break is a node
    assert np.max(mesh.element_lengths) <= h * (1 + 1e-12)
    assert breaks[0] == 0.0 and breaks[-1] == sum(lengths)


@pytest.mark.parametrize("top_free", [False, True])
@pytest.mark.parametrize("n_elements", [1, 2, 7, 40])
def test_mode_family_sizes_are_the_modal_dofs(drill_pipe, n_elements, top_free):
    mesh = build_mesh([100.0], [drill_pipe], 100.0 / n_elements)
    sizes = mode_family_sizes(mesh.n_nodes, top_free)
    assert sizes["axial"] == len(family_dofs(mesh, "axial", top_free))
    assert sizes["torsional"] == len(family_dofs(mesh, "torsional", top_free))
    assert sizes["lateral"] == len(family_dofs(mesh, "lateral_y")) == len(family_dofs(mesh, "lateral_z"))


@pytest.mark.parametrize("top_free", [False, True])
def test_family_dofs_are_the_boundary_conditions_written_out(drill_pipe, top_free):
    """Nodes 0..3 (6 DOFs each: u v w θx θy θz): the family DOFs numbered by hand."""
    mesh = build_mesh([100.0], [drill_pipe], 100.0 / 3)
    assert mesh.n_nodes == 4
    assert family_dofs(mesh, "axial", top_free).tolist() == [0, 6, 12, 18]
    assert family_dofs(mesh, "torsional", top_free).tolist() == ([3] if top_free else []) + [9, 15, 21]
    assert family_dofs(mesh, "lateral_y", top_free).tolist() == [5, 7, 11, 13, 17, 23]  # θz everywhere, v inside
    assert family_dofs(mesh, "lateral_z", top_free).tolist() == [4, 8, 10, 14, 16, 22]  # θy everywhere, w inside
    assert family_dofs(mesh, "axial").dtype == np.int64
    with pytest.raises(ValueError, match="family = 'bending'"):
        family_dofs(mesh, "bending")


def test_fluid_loads_by_continuity_and_skin_friction():
    d_o, d_i, d_ch, rho, q, c_f = 0.127, 0.095, 0.3, 1200.0, 0.01, 0.0125
    u_i, u_o = flow_velocities(d_o, d_i, d_ch, q)
    assert u_i * math.pi * d_i**2 / 4 == pytest.approx(q, rel=1e-14)
    assert u_o * math.pi * (d_ch**2 - d_o**2) / 4 == pytest.approx(q, rel=1e-14)
    assert flow_velocities(d_o, 0.0, d_ch, q)[0] == 0.0  # solid section: no bore flow
    f = fluid_skin_friction(d_o, d_i, d_ch, rho, q, c_f)
    assert f == pytest.approx(0.5 * c_f * rho * math.pi * (d_i * u_i**2 - d_o * u_o**2), rel=1e-14)
    assert f > 0  # the fast bore flow of this pipe drags it down more than the annulus drags it up
    assert fluid_skin_friction(d_o, d_i, d_ch, rho, 0.0, c_f) == 0.0


def test_axial_load_and_its_total():
    q = axial_load_per_length(steel_density=7850.0, area=0.01, gravity=9.81, buoyancy_density=1200.0,
                              skin_friction=-3.0)
    assert q == pytest.approx((7850.0 - 1200.0) * 0.01 * 9.81 - 3.0, rel=1e-15)
    assert axial_load_per_length(steel_density=7850.0, area=0.01, gravity=0.0, buoyancy_density=0.0,
                                 skin_friction=0.0) == 0.0
    assert string_axial_load([2.0, 3.0], [10.0, 100.0]) == 320.0
