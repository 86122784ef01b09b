from drillstring.dynamics.rom import OBSERVABLES
from drillstring.quantities import LONG_NAMES, UNITS


def test_every_observable_has_one_unit_and_description():
    for name in OBSERVABLES + ("radial_displacement",):
        assert UNITS[name] and LONG_NAMES[name]
    assert UNITS["rate_of_penetration"] == "m/s" and UNITS["bit_speed"] == "rad/s"
