import math

import numpy as np
import pytest

from drillstring.fem import element as el
from drillstring.fem.fluid import fluid_coefficients, fluid_planar_matrices

D_CH = 0.3


def test_coefficients_follow_continuity_and_confinement(drill_pipe, drill_collar):
    q = 1.5 * drill_pipe.inner_area
    top = fluid_coefficients(drill_pipe, D_CH, 1200.0, q, 0.0125, 0.0)
    bottom = fluid_coefficients(drill_collar, D_CH, 1200.0, q, 0.0125, 0.0)
    assert top.inner_velocity == pytest.approx(1.5)
    for c, s in ((top, drill_pipe), (bottom, drill_collar)):
        annulus = math.pi / 4 * (D_CH**2 - s.outer_diameter**2)
        assert c.inner_velocity * s.inner_area == pytest.approx(q)
        assert c.annular_velocity * annulus == pytest.approx(q)
        chi = (D_CH**2 + s.outer_diameter**2) / (D_CH**2 - s.outer_diameter**2)
        assert c.confinement == pytest.approx(chi)
        assert c.added_mass == pytest.approx(1200 * (s.inner_area + chi * s.outer_area))
        assert c.coriolis == pytest.approx(
            2 * 1200 * (s.inner_area * c.inner_velocity - chi * s.outer_area * c.annular_velocity)
        )
        assert c.viscous == pytest.approx(0.5 * 0.0125 * 1200 * s.outer_diameter * c.annular_velocity)
        assert c.centrifugal == pytest.approx(
            1200 * (s.inner_area * c.inner_velocity**2 + chi * s.outer_area * c.annular_velocity**2)
        )
    assert top.axial_load == 0.0


def test_switches_zero_their_terms(drill_pipe):
    c = fluid_coefficients(drill_pipe, D_CH, 1200.0, 0.01, 0.0125, 2.0, added_mass=False,
                           coriolis=False, viscous_damping=False, centrifugal=False)
    assert (c.added_mass, c.coriolis, c.viscous, c.centrifugal) == (0.0, 0.0, 0.0, 0.0)
    on = fluid_coefficients(drill_pipe, D_CH, 1200.0, 0.01, 0.0125, 2.0, axial_loads=True)
    expected = 0.5 * 0.0125 * 1200 * math.pi * (
        drill_pipe.inner_diameter * on.inner_velocity**2
        - drill_pipe.outer_diameter * on.annular_velocity**2
    )
    assert on.axial_load == pytest.approx(expected)


def test_string_touching_borehole_is_refused(drill_collar):
    with pytest.raises(ValueError, match="borehole"):
        fluid_coefficients(drill_collar, 0.2, 1200.0, 0.01, 0.0, 0.0)


def test_planar_matrices(drill_collar):
    L = 4.0
    c = fluid_coefficients(drill_collar, D_CH, 1200.0, 0.01, 0.0125, 3.0)
    m_f, c_f, k_f = fluid_planar_matrices(drill_collar, L, c)
    translation = np.array([1.0, 0.0, 1.0, 0.0])
    assert translation @ m_f @ translation == pytest.approx(c.added_mass * L, rel=1e-12)
    np.testing.assert_allclose(m_f, m_f.T, atol=1e-12)
    # ∫NᵀN' + ∫N'ᵀN = [NᵀN] at the ends: the Coriolis part is skew up to end terms.
    coriolis = c_f - c.viscous / c.added_mass * m_f
    ends = np.diag([-1.0, 0.0, 1.0, 0.0]) * c.coriolis
    np.testing.assert_allclose(coriolis + coriolis.T, ends, atol=1e-9 * abs(c.coriolis))
    # Centrifugal stiffness is a compressive geometric stiffness of magnitude p.
    kg = el.bending_geometric_stiffness(drill_collar, L, -c.centrifugal, -c.centrifugal)
    np.testing.assert_allclose(k_f, kg, rtol=1e-12, atol=1e-12)
