import math

import pytest

from drillstring.fem.sections import BeamSection, hollow_circle


def test_hollow_circle_properties(drill_pipe):
    d, di = 0.127, 0.095
    assert drill_pipe.area == pytest.approx(math.pi / 4 * (d**2 - di**2), rel=1e-14)
    assert drill_pipe.second_moment == pytest.approx(math.pi / 64 * (d**4 - di**4), rel=1e-14)
    assert drill_pipe.polar_moment == pytest.approx(math.pi / 32 * (d**4 - di**4), rel=1e-14)
    assert drill_pipe.shear_modulus == pytest.approx(210e9 / 2.58, rel=1e-14)
    assert drill_pipe.shear_stiffness == pytest.approx(6 / 7 * 210e9 / 2.58 * drill_pipe.area)
    assert drill_pipe.inner_area + drill_pipe.area == pytest.approx(drill_pipe.outer_area)


@pytest.mark.parametrize(
    "kwargs, field",
    [
        (dict(outer_diameter=0.0, inner_diameter=0.0), "outer_diameter"),
        (dict(outer_diameter=0.1, inner_diameter=0.1), "inner_diameter"),
        (dict(outer_diameter=0.1, inner_diameter=-0.01), "inner_diameter"),
    ],
)
def test_bad_geometry_is_refused(kwargs, field):
    with pytest.raises(ValueError, match=field):
        BeamSection(young_modulus=1.0, shear_modulus=1.0, density=1.0, shear_factor=1.0, **kwargs)


def test_bad_poisson_ratio():
    with pytest.raises(ValueError, match="poisson_ratio"):
        hollow_circle(0.1, 0.05, 210e9, 7850, 0.5)
