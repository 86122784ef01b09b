"""Statics against the exact solution of the hanging two-section bar (SPEC §4, §10)."""

import numpy as np
import pytest

from drillstring.fem.mesh import build_mesh
from drillstring.statics import solve_statics

G = 9.81


@pytest.fixture
def reference_statics(drill_pipe, drill_collar):
    mesh = build_mesh([1400.0, 200.0], [drill_pipe, drill_collar], 10.0, [1560.0])
    loads = [s.mass_per_length * G for s in mesh.sections]
    return mesh, loads, solve_statics(mesh, loads, 100e3)


def test_reference_weights_and_neutral_point(reference_statics, drill_pipe, drill_collar):
    mesh, loads, st = reference_statics
    weight = G * (drill_pipe.mass_per_length * 1400 + drill_collar.mass_per_length * 200)
    assert st.weight == pytest.approx(weight, rel=1e-12)
    assert st.weight == pytest.approx(1.1634e6, rel=1e-4)  # SPEC §10
    assert st.weight_on_hook == pytest.approx(weight - 100e3, rel=1e-10)
    assert st.weight_on_hook == pytest.approx(1.0634e6, rel=1e-4)
    assert st.axial_force[-1] == pytest.approx(-100e3, rel=1e-9)
    assert st.axial_force[0] == pytest.approx(st.weight_on_hook, rel=1e-10)
    # Neutral point inside the collars: wob / (ρ g A_DC) above the bit (≈ 36 m, SPEC §10).
    assert st.neutral_point_height == pytest.approx(100e3 / loads[1], rel=1e-9)
    assert 35.0 < st.neutral_point_height < 37.0


def test_axial_force_and_displacement_are_exact_at_nodes(reference_statics):
    mesh, loads, st = reference_statics
    q = np.where(mesh.nodes <= 1400.0, loads[0], loads[1])
    # N(x) = woh − ∫₀ˣ q dx
    cumulative = np.where(mesh.nodes <= 1400.0, loads[0] * mesh.nodes,
                          loads[0] * 1400.0 + loads[1] * (mesh.nodes - 1400.0))
    np.testing.assert_allclose(st.axial_force, st.weight_on_hook - cumulative,
                               rtol=0, atol=1e-6 * st.weight)
    # u(L) = ∫ N / EA dx, N piecewise linear: exact by the trapezoid rule per section.
    ea = np.array([s.axial_stiffness for s in mesh.sections])
    u_bit = 0.0
    for i, (a, b) in enumerate([(0.0, 1400.0), (1400.0, 1600.0)]):
        na = st.weight_on_hook - (loads[0] * a if i == 0 else loads[0] * 1400.0)
        nb = na - loads[i] * (b - a)
        u_bit += 0.5 * (na + nb) * (b - a) / ea[i]
    assert st.displacement[6 * (mesh.n_nodes - 1)] == pytest.approx(u_bit, rel=1e-10)
    assert 0.1 < u_bit < 1.0  # about half a metre of stretch
    assert np.count_nonzero(q) == mesh.n_nodes


def test_negative_weight_on_bit_is_refused(reference_statics):
    mesh, loads, st = reference_statics
    for bad in (-1.0, float("nan"), float("inf")):
        with pytest.raises(ValueError, match="weight_on_bit"):
            solve_statics(mesh, loads, bad)


def test_the_hook_pushes_when_the_bit_carries_more_than_the_weight(reference_statics):
    """wob > weight (always so with gravity off): the hook reaction is negative and the top is in
    compression; N(x) = woh − ∫₀ˣ q dx still holds exactly."""
    mesh, loads, st = reference_statics
    heavy = solve_statics(mesh, loads, 2 * st.weight)
    assert heavy.weight_on_hook == pytest.approx(-st.weight, rel=1e-10)
    np.testing.assert_allclose(heavy.axial_force, st.axial_force - (2 * st.weight - 100e3),
                               rtol=0, atol=1e-6 * st.weight)
    weightless = solve_statics(mesh, [0.0, 0.0], 100e3)
    assert weightless.weight == 0.0
    assert weightless.weight_on_hook == pytest.approx(-100e3, rel=1e-12)
    np.testing.assert_allclose(weightless.axial_force, -100e3, rtol=1e-12)
    assert np.isnan(weightless.neutral_point)  # compression all along: no neutral point
