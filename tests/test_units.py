"""Tests for drillstring.units: every field unit against its defining factor, the dimension checks, the
output unit systems, and the reference case written entirely in field units."""

from __future__ import annotations

import copy
import math
import tomllib
from importlib import resources

import pytest

from drillstring import units
from drillstring.case import CaseError, case_from_dict, load_case
from drillstring.units import display_unit, to_si, unit_factor, unit_system

# Defining factors (NIST Special Publication 811, appendix B; the US gallon is 231 in³ exactly, the pound
# 0.45359237 kg exactly, standard gravity 9.80665 m/s² exactly).
FT = 0.3048  # m
IN = 0.0254  # m
LBF = 4.4482216152605  # N
KLBF = 4448.2216152605  # N
PPG = 119.826427  # kg/m³ (lb/gal)
GPM = 6.30901964e-5  # m³/s (gal/min)
PSI = 6894.757293168361  # Pa (lbf/in², from the exact pound-force and inch; NIST prints 6.894757E+03)
FT_LBF = 1.3558179483314004  # N·m
LB_PER_FT = 1.4881639435695537  # kg/m
LB_PER_FT3 = 16.01846337396014  # kg/m³
RPM = 2.0 * math.pi / 60.0  # rad/s
GALLON = 231.0 * IN**3  # m³, US gallon
PPG_EXACT = 0.45359237 / GALLON  # kg/m³, the pound per gallon from its definition (PPG rounds it to 9 digits)
FT_PER_H = FT / 3600.0  # m/s
DEG = math.pi / 180.0  # rad


@pytest.mark.parametrize(
    ("text", "dimension", "si", "rel"),
    [
        ("1 ft", units.LENGTH, FT, 1e-15),
        ("1 in", units.LENGTH, IN, 1e-15),
        ("1 lbf", units.FORCE, LBF, 1e-15),
        ("1 klbf", units.FORCE, KLBF, 1e-15),
        ("1 ppg", units.DENSITY, PPG, 1e-8),  # NIST gives 9 digits
        ("1 lb/ft3", units.DENSITY, LB_PER_FT3, 1e-15),
        ("1 gpm", units.VOLUME_FLOW, GPM, 1e-9),
        ("1 gal/min", units.VOLUME_FLOW, GPM, 1e-9),
        ("1 psi", units.PRESSURE, PSI, 1e-15),
        ("1 psi", units.PRESSURE, 6894.757293168, 1e-12),
        ("1 ft*lbf", units.TORQUE, FT_LBF, 1e-15),
        ("1 ft·lbf", units.TORQUE, FT_LBF, 1e-15),
        ("1 kft.lbf", units.TORQUE, 1e3 * FT_LBF, 1e-15),
        ("1 lb/ft", units.MASS_PER_LENGTH, LB_PER_FT, 1e-15),
        ("1 ft/h", units.VELOCITY, FT_PER_H, 1e-15),
        ("1 rpm", units.ANGULAR_SPEED, RPM, 1e-15),
        ("1 rev/min", units.ANGULAR_SPEED, RPM, 1e-15),
        ("1 Hz", units.ANGULAR_SPEED, 2.0 * math.pi, 1e-15),  # a frequency: revolutions per second
        ("1 deg", units.ANGLE, DEG, 1e-15),
        ("1 lbf/in", units.STIFFNESS, LBF / IN, 1e-15),
        ("1 ft/s2", units.ACCELERATION, FT, 1e-15),
    ],
)
def test_field_unit_equals_its_defining_factor(text, dimension, si, rel):
    assert to_si(text, dimension) == pytest.approx(si, rel=rel, abs=0)


@pytest.mark.parametrize(
    ("text", "dimension", "si"),
    [
        ("100 kN", units.FORCE, 1e5),
        ("17.5 MN/m", units.STIFFNESS, 17.5e6),
        ("7850 kg/m3", units.DENSITY, 7850.0),
        ("7850 kg/m^3", units.DENSITY, 7850.0),
        ("7.85 g/cm³", units.DENSITY, 7850.0),
        ("9.81 m/s2", units.ACCELERATION, 9.81),
        ("1475 N.m", units.TORQUE, 1475.0),
        ("1e8 N/m2", units.STIFFNESS_PER_LENGTH, 1e8),
        ("1e8 N/m", units.STIFFNESS_PER_LENGTH, 1e8),  # read per metre of string (the reference data)
        ("0.05 N*m*s/rad", units.ROTATIONAL_DAMPING, 0.05),
        ("5.672e-8 m/(N*s)", units.PENETRATION_PER_FORCE, 5.672e-8),
        ("0.1 mm", units.LENGTH, 1e-4),
        ("0.5 min", units.TIME, 30.0),
        ("2", units.LENGTH, 2.0),
        (3, units.FORCE, 3.0),
    ],
)
def test_si_and_plain_values(text, dimension, si):
    assert to_si(text, dimension) == pytest.approx(si, rel=1e-15)


@pytest.mark.parametrize(
    ("text", "dimension", "fragments"),
    [
        ("3 kN", units.LENGTH, ["unit 'kN' is a force unit, not a length unit", "m, cm, mm, km, in, ft"]),
        ("10 ppg", units.PRESSURE, ["'ppg' is a density unit, not a pressure unit", "psi"]),
        ("600 gpm", units.VELOCITY, ["'gpm' is a volume flow unit, not a velocity unit"]),
        ("3 kg", units.LENGTH, ["'kg' is of dimension [mass], not a length unit"]),
        ("3 wombats", units.LENGTH, ["unknown unit 'wombats', not a length unit"]),
        ("0.05 N*m*s", units.ROTATIONAL_DAMPING, ["not a rotational damping coefficient unit", "N*m*s/rad"]),
        ("1 m/m", units.ANGLE, ["not a angle unit", "rad, deg"]),
        ("1 s", units.ANGULAR_SPEED, ["is a time unit, not a angular speed unit"]),
        ("0.3 rad", units.DIMENSIONLESS, ["a plain number without unit is expected"]),
        ("lots", units.FORCE, ['not a number or a "value unit" string']),
    ],
)
def test_inconsistent_unit_is_refused_in_one_line(text, dimension, fragments):
    with pytest.raises(ValueError) as info:
        to_si(text, dimension)
    message = str(info.value)
    assert "\n" not in message
    assert all(f in message for f in fragments), message


def test_unit_factor_is_the_si_value_of_one_unit():
    assert unit_factor("klbf", units.FORCE) == pytest.approx(KLBF, rel=1e-15)
    with pytest.raises(ValueError, match="force unit, not a length unit"):
        unit_factor("lbf", units.LENGTH)


# ---------------------------------------------------------------------------------------------- output units


def test_display_units_of_both_systems():
    force_si, force_field = display_unit("force", "si"), display_unit("force", "field")
    assert (force_si.label, force_field.label) == ("kN", "klbf")
    assert force_si(1e5) == pytest.approx(100.0, rel=1e-15)
    assert force_field(KLBF) == pytest.approx(1.0, rel=1e-15)
    assert display_unit("length", "field")(FT) == pytest.approx(1.0, rel=1e-15)
    assert display_unit("rate_of_penetration", "field")(FT_PER_H) == pytest.approx(1.0, rel=1e-15)
    assert display_unit("torque", "field").label == "kft·lbf"
    assert display_unit("torque", "field")(1e3 * FT_LBF) == pytest.approx(1.0, rel=1e-15)
    assert display_unit("density", "field")(PPG) == pytest.approx(1.0, rel=1e-8)
    assert display_unit("pressure", "field")(PSI) == pytest.approx(1.0, rel=1e-15)
    assert display_unit("diameter", "field")(IN) == pytest.approx(1.0, rel=1e-15)
    assert display_unit("angular_speed", "field")(RPM) == pytest.approx(1.0, rel=1e-15)


def test_unit_system_from_option_then_environment(monkeypatch):
    monkeypatch.delenv(units.UNITS_ENVIRONMENT, raising=False)
    assert unit_system() == "si"
    monkeypatch.setenv(units.UNITS_ENVIRONMENT, "field")
    assert unit_system() == "field"
    assert display_unit("force").label == "klbf"  # no system given: the user's setting
    assert unit_system("SI") == "si"  # the option wins
    monkeypatch.setenv(units.UNITS_ENVIRONMENT, "imperial")
    with pytest.raises(ValueError, match="DRILLSTRING_UNITS = 'imperial': must be one of si, field"):
        unit_system()
    with pytest.raises(ValueError, match="--units = 'metric'"):
        unit_system("metric")


# ---------------------------------------------------------------------------------------------- whole cases


def _reference_data() -> dict:
    text = resources.files("drillstring").joinpath("cases", "reference.toml").read_text(encoding="utf-8")
    return copy.deepcopy(tomllib.loads(text))


def _in_field_units(data: dict) -> dict:
    """The reference case with every dimensional value rewritten in oilfield units (from the SI values with
    the defining factors above), and the mud's inlet velocity given as a flow rate in gpm."""
    ft, inch = (lambda v: f"{v / FT!r} ft"), (lambda v: f"{v / IN!r} in")
    steel = data["materials"]["steel"]
    steel.update(young_modulus=f"{210e9 / PSI!r} psi", density=f"{7850.0 / LB_PER_FT3!r} lb/ft3")
    for section in data["sections"]:
        section.update(length=ft(to_si(section["length"], units.LENGTH)),
                       outer_diameter=inch(to_si(section["outer_diameter"], units.LENGTH)),
                       inner_diameter=inch(to_si(section["inner_diameter"], units.LENGTH)))
    data["borehole"]["diameter"] = inch(0.3)
    data["stabilizers"][0].update(position=ft(1400.0), stiffness=f"{17.5e6 / (LBF / IN)!r} lbf/in")
    bore = math.pi * 0.095**2 / 4.0
    data["fluid"].pop("inlet_velocity")
    data["fluid"].update(density=f"{1200.0 / PPG_EXACT!r} ppg", flow_rate=f"{1.5 * bore / GPM!r} gpm")
    data["bit_rock"].update(a1=f"{3.429e-3 / FT_PER_H!r} ft/h", a5=f"{1475.0 / FT_LBF!r} ft*lbf",
                            regularization=f"{2.0 / RPM!r} rpm")
    data["contact"].update(shock_stiffness=f"{1e8 / PSI!r} psi", speed_regularization=f"{0.1 / RPM!r} rpm")
    data["operation"].update(top_speed="100 rpm", weight_on_bit=f"{1e5 / KLBF!r} klbf")
    data["environment"]["gravity"] = f"{9.81 / FT!r} ft/s2"
    data["mesh"].update(max_element_length=ft(10.0), probes=[ft(1560.0)])
    data["initial"]["lateral_perturbation"] = inch(1e-4)
    data["bow"].update(amplitude="0 in", start="0 ft", end="0 ft", angle="0 deg")
    return data


def _assert_same_numbers(a, b, path="case"):
    if isinstance(a, dict):
        assert a.keys() == b.keys(), path
        for key in a:
            _assert_same_numbers(a[key], b[key], f"{path}.{key}")
    elif isinstance(a, (list, tuple)):
        assert len(a) == len(b), path
        for i, (x, y) in enumerate(zip(a, b)):
            _assert_same_numbers(x, y, f"{path}[{i}]")
    elif isinstance(a, float) and not isinstance(a, bool):
        assert b == pytest.approx(a, rel=1e-12, abs=0), path
    else:
        assert a == b, path


def test_reference_case_in_field_units_equals_the_si_case():
    field = case_from_dict(_in_field_units(_reference_data()))
    reference = load_case("reference")
    _assert_same_numbers(reference.model_dump(), field.model_dump())
    assert field.fluid.inlet_velocity == pytest.approx(1.5, rel=1e-12)
    assert field.weight == pytest.approx(reference.weight, rel=1e-12)


def test_flow_rate_is_the_inlet_velocity_through_the_top_bore():
    data = _reference_data()
    data["fluid"].pop("inlet_velocity")
    data["fluid"]["flow_rate"] = "600 gpm"
    case = case_from_dict(data)
    assert case.fluid.inlet_velocity == pytest.approx(600 * GPM / (math.pi * 0.095**2 / 4.0), rel=1e-9)
    assert case.flow_rate == pytest.approx(600 * GPM, rel=1e-9)


@pytest.mark.parametrize(
    ("fluid", "fragments"),
    [
        ({"flow_rate": "600 gpm"}, ["fluid.flow_rate = '600 gpm'", "not both"]),  # inlet_velocity kept
        ({"flow_rate": "600 psi"}, ["fluid.flow_rate = '600 psi'", "pressure unit, not a volume flow unit"]),
        ({"flow_rate": -1.0, "inlet_velocity": None}, ["fluid.flow_rate = -1.0", "must be >= 0"]),
    ],
)
def test_flow_rate_refusals(fluid, fragments):
    data = _reference_data()
    data["fluid"].update(fluid)
    if data["fluid"].get("inlet_velocity", 0) is None:
        data["fluid"].pop("inlet_velocity")
    with pytest.raises(CaseError) as info:
        case_from_dict(data)
    assert all(f in str(info.value) for f in fragments), str(info.value)


def test_api_refuses_a_bad_unit_system_before_running(monkeypatch, tmp_path):
    from drillstring import api

    with pytest.raises(ValueError, match="units = 'metric': must be one of si, field"):
        api.operating_map("reference", top_speed="100 rpm", weight_on_bit="100 kN", t_end=1.0, units="metric",
                          out=tmp_path / "map")
    monkeypatch.setenv(units.UNITS_ENVIRONMENT, "cubits")
    with pytest.raises(ValueError, match="DRILLSTRING_UNITS = 'cubits'"):
        api.monte_carlo_study("reference", samples=2, t_end=1.0, out=tmp_path / "study")
    assert not (tmp_path / "map").exists() and not (tmp_path / "study").exists()


def test_uncertainty_laws_accept_field_units():
    """A study's law written in field units is the law of the SI values (the parameter's dimension)."""
    from drillstring.stochastic.uncertainty import parse_law

    law = parse_law("normal 10 0.25 ppg", units.DENSITY)
    assert law.density.mean() == pytest.approx(10 * PPG_EXACT, rel=1e-12)
    assert law.density.std() == pytest.approx(0.25 * PPG_EXACT, rel=1e-12)
    law = parse_law("uniform 20 30 klbf", units.FORCE)
    assert law.support == pytest.approx((20 * KLBF, 30 * KLBF), rel=1e-15)


def test_one_gravity_the_cases_and_the_pound_force():
    """The case default g is standard gravity, the same g that defines the pound-force and the kilogram-force:
    a string of w lb/ft weighs w lbf per foot in air."""
    from drillstring.case import Environment
    from drillstring.constants import STANDARD_GRAVITY

    assert Environment().gravity == STANDARD_GRAVITY == 9.80665
    assert units.to_si("1 lbf", units.FORCE) == pytest.approx(0.45359237 * STANDARD_GRAVITY, rel=1e-15)
    assert units.to_si("1 kgf", units.FORCE) == pytest.approx(STANDARD_GRAVITY, rel=1e-15)
