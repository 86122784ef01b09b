"""The downhole motor's law and keys (drillstring.forces.motor, case.MotorKeys): eq. (1)–(2) against numbers
worked by hand in oilfield units, the units, the refusals, the component protocol's pieces."""

import math
import tomllib
from importlib import resources

import numpy as np
import pytest

from drillstring.case import CaseError, case_from_dict, load_case
from drillstring.forces.motor import PositiveDisplacementMotor, case_motor, positive_displacement_kernel
from drillstring.forces.registry import MOTOR, MOTOR_CODE, MotorContext, motor, motors, pack

GALLON = 3.785411784e-3  # m³
PSI = 6894.757293168361  # Pa
FT_LBF = 1.3558179483314004  # N·m


def _motor_case_data():
    return tomllib.loads(resources.files("drillstring").joinpath("cases/motor.toml").read_text(encoding="utf-8"))


def test_the_builtin_motor_case_reads_its_motor_in_oilfield_units():
    m = case_motor(load_case("motor"))
    # 0.2 rev/gal at 500 gpm and 90 % volumetric efficiency: 0.9 * 500 * 0.2 = 90 rpm no-load
    assert m.no_load_speed == pytest.approx(90.0 * 2 * math.pi / 60, rel=1e-12)
    # stall torque eta_m V dp_s / 2 pi, V = 1/0.2 = 5 gal/rev, 1000 psi: 17.65 kN*m (13.0 kft*lbf)
    volume = 5.0 * GALLON
    assert m.stall_torque == pytest.approx(0.85 * volume * 1000 * PSI / (2 * math.pi), rel=1e-12)
    assert m.stall_torque / FT_LBF == pytest.approx(13.02e3, rel=1e-3)
    assert m.max_differential_pressure == pytest.approx(1000 * PSI, rel=1e-12)
    assert m.position == pytest.approx(2999.0)  # the bottom of the motor: the bit turns with the rotor
    assert m.flow_rate == pytest.approx(500 * GALLON / 60, rel=1e-12)  # the case's pumped flow by default


def test_the_law_is_the_line_from_no_load_speed_to_stall():
    m = PositiveDisplacementMotor(position=10.0, flow_rate=0.03, displacement=2e-3, stall_torque=8000.0,
                                  volumetric_efficiency=0.8, mechanical_efficiency=0.7)
    w0 = 0.8 * 0.03 / 2e-3
    assert m.no_load_speed == pytest.approx(w0)
    speeds = np.array([-3.0, 0.0, 0.25 * w0, w0, 1.5 * w0])
    torque = m.evaluate(speeds)
    np.testing.assert_allclose(torque, 8000.0 * (1 - speeds / w0), rtol=1e-14)
    assert torque[1] == 8000.0 and abs(torque[3]) < 1e-9  # stall, no load
    none = np.zeros(0)
    np.testing.assert_allclose([positive_displacement_kernel(m.kernel_array(), MotorContext(0.0, s), none, none)
                                for s in speeds], 8000.0 * (1 - speeds / w0), rtol=1e-14, atol=1e-9)
    assert m.evaluate(0.0).shape == () and m.evaluate([[0.0, w0]]).shape == (1, 2)
    np.testing.assert_allclose(m.speed_at(torque), speeds, atol=1e-12)
    # Jacobian against a central difference (the law is linear: exact)
    assert m.jacobian(1.0) == pytest.approx((m.evaluate(1.5) - m.evaluate(0.5)) / 1.0, rel=1e-12)
    # hydraulic power in, mechanical power out: T w = (w / w0) eta_v eta_m Q dp along the line (the slip that
    # slows the rotor below w0 is power lost on top of the efficiencies)
    for w in (0.1 * w0, 0.6 * w0):
        t = float(m.evaluate(w))
        q_dp = m.flow_rate * float(m.differential_pressure(t))
        assert t * w == pytest.approx((w / w0) * 0.8 * 0.7 * q_dp, rel=1e-12)


def test_keys_in_any_unit_give_the_same_motor():
    data = _motor_case_data()
    entry = data["components"][3]
    base = case_motor(case_from_dict(data))
    entry.pop("speed_per_flow"), entry.pop("max_differential_pressure")
    entry["displacement"] = f"{5.0 * GALLON * 1e3} L/rev"
    entry["stall_torque"] = f"{base.stall_torque / FT_LBF} ft*lbf"
    entry["flow_rate"] = f"{500 * GALLON * 1e3} L/min"
    other = case_motor(case_from_dict(data))
    for field in ("flow_rate", "displacement", "stall_torque", "no_load_speed", "position"):
        assert getattr(other, field) == pytest.approx(getattr(base, field), rel=1e-12), field


@pytest.mark.parametrize("change, fragment", [
    ({"speed_per_flow": None}, "components[3].displacement = (missing): give displacement or speed_per_flow"),
    ({"stall_torque": "5000 ft*lbf"}, "components[3].max_differential_pressure = "),
    ({"volumetric_efficiency": 1.2}, "components[3].volumetric_efficiency = 1.2: must be <= 1"),
    ({"speed_per_flow": "600 psi"}, "unit 'psi' is a pressure unit, not a motor speed per flow"),
    ({"flow_rate": "-5 gpm"}, "components[3].flow_rate = '-5 gpm': must be > 0"),
])
def test_bad_motor_keys_are_refused_naming_the_field(change, fragment):
    data = _motor_case_data()
    entry = data["components"][3]
    for key, value in change.items():
        if value is None:
            entry.pop(key)
        else:
            entry[key] = value
    with pytest.raises(CaseError) as info:
        case_from_dict(data)
    assert fragment in str(info.value), str(info.value)


def test_motor_keys_on_another_component_and_a_motor_at_the_bit_are_refused():
    data = _motor_case_data()
    data["components"][2]["flow_rate"] = "500 gpm"
    with pytest.raises(CaseError, match=r"components\[2\]\.flow_rate = .*only for a motor, not a collar"):
        case_from_dict(data)
    data = _motor_case_data()
    data["components"].pop()  # the motor is now the last component
    with pytest.raises(CaseError, match="a motor must have a component below it"):
        case_from_dict(data)


def test_a_motor_entry_without_motor_keys_is_a_plain_section():
    data = _motor_case_data()
    entry = data["components"][3]
    for key in ("speed_per_flow", "max_differential_pressure", "volumetric_efficiency", "mechanical_efficiency"):
        entry.pop(key)
    case = case_from_dict(data)
    assert case.motor is None and case_motor(case) is None
    assert [s.name for s in case.sections][-2:] == ["motor", "bit"]


def test_the_motor_case_round_trips_through_toml(tmp_path):
    case = load_case("motor")
    path = tmp_path / "case.toml"
    path.write_text(case.to_toml(), encoding="utf-8")
    assert load_case(path) == case


def test_the_motor_is_a_registered_component_packed_by_the_registry():
    assert "positive_displacement" in motors() and motor("positive_displacement") is PositiveDisplacementMotor
    m = case_motor(load_case("motor"))
    from drillstring.forces.bit_rock import case_bit_rock
    from drillstring.forces.hook_load import OnBottomStart
    from drillstring.forces.top_drive import TopDriveParameters

    laws, layout = pack(case_bit_rock(load_case("motor")), TopDriveParameters("imposed_speed", 1.0), OnBottomStart(),
                        np.zeros(4), 10, motor=m)
    assert laws[MOTOR_CODE] == PositiveDisplacementMotor.component_code > 0
    start = int(laws[MOTOR])
    assert start == layout.numbers["motor"]
    np.testing.assert_array_equal(laws[start:start + 2], m.kernel_array())
    without, _ = pack(case_bit_rock(load_case("motor")), TopDriveParameters("imposed_speed", 1.0), OnBottomStart(),
                      np.zeros(4), 10)
    assert without[MOTOR_CODE] == 0.0
