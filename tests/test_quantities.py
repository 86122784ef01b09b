import pytest

from drillstring.dynamics.rom import OBSERVABLES
from drillstring.quantities import LONG_NAMES, UNITS


def test_every_observable_has_one_unit_and_description():
    for name in OBSERVABLES + ("radial_displacement",):
        assert UNITS[name] and LONG_NAMES[name]
    assert UNITS["rate_of_penetration"] == "m/s" and UNITS["bit_speed"] == "rad/s"


def test_cycle_metric_units_in_both_systems():
    """Each cycle metric's display unit: SI m/h, kN·m, kN, MPa or field ft/h, kft·lbf, klbf, psi (the SI value
    over the defining factor); rpm, s, % and plain numbers the same in both."""
    import math

    from drillstring.quantities import METRIC_DISPLAY, metric_unit

    expected = {  # name -> (si label, si scale, field label, field scale)
        "mean_rate_of_penetration": ("m/h", 3600.0, "ft/h", 3600.0 / 0.3048),
        "mean_torque_on_bit": ("kN·m", 1e-3, "kft·lbf", 1.0 / 1355.8179483314004),
        "surface_torque_amplitude": ("kN·m", 1e-3, "kft·lbf", 1.0 / 1355.8179483314004),
        "mean_force_on_bit": ("kN", 1e-3, "klbf", 1.0 / 4448.2216152605),
        "mechanical_specific_energy": ("MPa", 1e-6, "psi", 1.0 / 6894.757293168361),
        "bit_speed_min": ("rpm", 30.0 / math.pi, "rpm", 30.0 / math.pi),
        "quill_speed_max": ("rpm", 30.0 / math.pi, "rpm", 30.0 / math.pi),
        "period": ("s", 1.0, "s", 1.0),
        "stick_time_fraction": ("%", 100.0, "%", 100.0),
        "stick_slip_index": ("-", 1.0, "-", 1.0),
    }
    for name, (si_label, si_scale, field_label, field_scale) in expected.items():
        si, field = metric_unit(name, "si"), metric_unit(name, "field")
        assert (si.label, field.label) == (si_label, field_label), name
        assert si.scale == pytest.approx(si_scale, rel=1e-12) and field.scale == pytest.approx(field_scale, rel=1e-12)
    assert set(expected) <= set(METRIC_DISPLAY)
