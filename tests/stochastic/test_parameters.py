"""Case parameter paths: reading, setting through the case's own validation, weight-on-hook, one-line errors."""

from __future__ import annotations

import math

import pytest

from drillstring.case import case_from_dict, load_case
from drillstring.stochastic.parameters import (
    WEIGHT_ON_HOOK,
    Bounds,
    ParameterError,
    case_parameter,
    numeric_parameter_paths,
    parameter_value,
    with_parameters,
)

RPM = 2.0 * math.pi / 60.0


@pytest.fixture(scope="module")
def case():
    return load_case("reference")


@pytest.mark.parametrize(
    ("path", "value", "unit", "bounds"),
    [
        # the field's own range, within its plausible range (PHYSICAL_BOUNDS) and, for the weight-on-bit,
        # below the string's weight: a law is checked against them before any realization (issue 26)
        ("operation.top_speed", 100 * RPM, "rad/s", ">= 0.001 and <= 1000"),
        ("operation.weight_on_bit", 1e5, "N", "> 0 and < 1.16343e+06"),
        ("fluid.inlet_velocity", 1.5, "m/s", ">= 0 and <= 1000"),
        ("bit_rock.a2", 5.672e-8, "m/(N*s)", ">= 1e-15 and <= 0.001"),
        ("sections[1].outer_diameter", 0.2286, "m", ">= 0.001 and <= 10"),
        ("damping.modal_damping_ratio", 0.3, "", ">= 0 and < 1"),
        ("materials.steel.young_modulus", 210e9, "Pa", ">= 1e+06 and <= 1e+13"),
        ('materials["steel"].density', 7850.0, "kg/m3", ">= 1 and <= 100000"),
        ("mesh.probes[0]", 1560.0, "m", "any number"),
        ("stabilizers[0].stiffness", 17.5e6, "N/m", "> 0 and <= 1e+15"),
    ],
)
def test_read_numeric_parameters(case, path, value, unit, bounds):
    p = case_parameter(case, path)
    assert p.value(case) == pytest.approx(value, rel=1e-15)
    assert parameter_value(case, path) == p.value(case)
    assert p.unit == unit
    assert p.bounds.describe() == bounds
    assert not p.integer and not p.derived


def test_canonical_path_and_integer_settings(case):
    assert case_parameter(case, ' materials["steel"].density ').path == "materials.steel.density"
    p = case_parameter(case, "reduced_model.lateral_modes")
    assert p.integer and p.value(case) == 20.0 and p.bounds == Bounds(0.0, math.inf, True, False)


def test_weight_on_hook_is_weight_minus_weight_on_bit(case):
    p = case_parameter(case, WEIGHT_ON_HOOK)
    assert p.derived and p.unit == "N"
    assert p.value(case) == pytest.approx(case.weight - case.operation.weight_on_bit, rel=1e-15)
    assert p.bounds.lower == 0.0 and p.bounds.upper == pytest.approx(case.weight)


def test_set_with_units_gives_a_new_validated_case(case):
    new = with_parameters(case, {"operation.top_speed": "120 rpm", "fluid.inlet_velocity": "90 m/min",
                                 "sections[1].outer_diameter": "8 in", "bit_rock.a2": 6e-8})
    assert new.operation.top_speed == pytest.approx(120 * RPM, rel=1e-15)
    assert new.fluid.inlet_velocity == pytest.approx(1.5, rel=1e-15)
    assert new.sections[1].outer_diameter == pytest.approx(8 * 0.0254, rel=1e-15)
    assert new.bit_rock.a2 == 6e-8
    assert case.operation.top_speed == pytest.approx(100 * RPM)  # the original is untouched
    # derived quantities follow: a thinner collar weighs less
    assert new.weight < case.weight


def test_setting_every_parameter_to_its_own_value_gives_an_equal_case(case):
    paths = numeric_parameter_paths(case)
    assert "operation.top_speed" in paths and WEIGHT_ON_HOOK in paths and "initial.seed" in paths
    assert "reduced_model.axial_modes" not in numeric_parameter_paths(case, integers=False)
    for path in paths:
        p = case_parameter(case, path)
        assert p.path == path
        if path == WEIGHT_ON_HOOK:
            new = with_parameters(case, {path: p.value(case)})
            assert new.operation.weight_on_bit == pytest.approx(case.operation.weight_on_bit, rel=1e-9)
        else:
            assert with_parameters(case, {path: p.value(case)}) == case, path


def test_weight_on_hook_uses_the_weight_after_the_other_parameters(case):
    new = with_parameters(case, {WEIGHT_ON_HOOK: "1000 kN", "materials.steel.density": 8000.0})
    assert new.materials["steel"].density == 8000.0
    assert new.weight == pytest.approx(case.weight * 8000.0 / 7850.0, rel=1e-12)
    assert new.weight_on_hook == pytest.approx(1e6, rel=1e-12)
    assert new.operation.weight_on_bit == pytest.approx(new.weight - 1e6, rel=1e-12)


def _error(case, values) -> str:
    with pytest.raises(ParameterError) as info:
        with_parameters(case, values)
    message = str(info.value)
    assert "\n" not in message
    return message


@pytest.mark.parametrize(
    ("values", "fragments"),
    [
        ({"operation.top_speed": "-5 rpm"}, ["operation.top_speed = '-5 rpm'", "must be > 0"]),
        ({"operation.top_speed": "5 kN"}, ["operation.top_speed = '5 kN'", "force unit", "rpm"]),
        ({"damping.modal_damping_ratio": 1.2}, ["damping.modal_damping_ratio = 1.2", "must be < 1"]),
        ({"sections[1].outer_diameter": "0.35 m"}, ["sections[1].outer_diameter", "borehole diameter (0.3 m)"]),
        ({"operation.weight_on_bit": "2000 kN"}, ["operation.weight_on_bit", "must be less than the string's weight"]),
        ({WEIGHT_ON_HOOK: "2000 kN"}, ["weight_on_hook = '2000 kN'", "must be in (0, 1.16343e+06) N"]),
        ({WEIGHT_ON_HOOK: -5.0}, ["weight_on_hook = -5.0", "must be in (0,"]),
        ({WEIGHT_ON_HOOK: 1e6, "operation.weight_on_bit": 1e5}, ["cannot both be set"]),
        ({"reduced_model.lateral_modes": 2.5}, ["reduced_model.lateral_modes = 2.5", "integer"]),
        ({"operation.top_speed": True}, ["operation.top_speed = True", "must be a number"]),
        ({"materials.steel.density": 7e3, 'materials["steel"].density': 8e3}, ["materials.steel.density is given twice"]),
        ({"operation.top_sped": 10.0}, ["unknown case parameter 'operation.top_sped'", "did you mean 'top_speed'",
                                        "top_speed, weight_on_bit"]),
        ({"fluid.coriolis": 1.0}, ["fluid.coriolis is not a numeric parameter (a true/false switch)"]),
        ({"model.nonlinear": 1.0}, ["model.nonlinear is not a numeric parameter", "'full'"]),
        ({"sections[2].length": 1.0}, ["sections has 2 items, index 2 is not in [0, 1]"]),
        ({"sections.length": 1.0}, ["sections is a list; give an index"]),
        ({"operation": 1.0}, ["operation is not a numeric parameter (a table)"]),
        ({"materials.iron.density": 1.0}, ["materials has no entry 'iron'", "entries there: steel"]),
        ({"operation.top_speed.x": 1.0}, ["operation.top_speed is a number"]),
        ({"a..b": 1.0}, ["parameter path 'a..b' is not of the form"]),
    ],
)
def test_bad_paths_and_values_give_one_clear_line(case, values, fragments):
    message = _error(case, values)
    for fragment in fragments:
        assert fragment in message, message


def test_gravity_off_weight_on_hook_pushes(case):
    data = case.model_dump(mode="python")
    data["model"]["gravity"] = False
    weightless = case_from_dict(data)
    p = case_parameter(weightless, WEIGHT_ON_HOOK)
    assert p.bounds.upper == 0.0
    new = with_parameters(weightless, {WEIGHT_ON_HOOK: "-80 kN"})
    assert new.operation.weight_on_bit == pytest.approx(8e4)
    assert "gravity is off" in _error(weightless, {WEIGHT_ON_HOOK: "80 kN"})


def test_the_uncertainty_table_is_not_a_parameter():
    import tomllib

    from drillstring.case import case_from_dict, load_case
    from drillstring.stochastic.parameters import case_parameter, numeric_parameter_paths, ParameterError

    case = load_case("reference")
    data = tomllib.loads(case.to_toml())
    data["uncertainty"] = {"parameters": {"weight_on_hook": "normal 1063 5 kN", "operation.top_speed": "normal 100 5 rpm"},
                           "correlation": {"parameters": ["weight_on_hook", "operation.top_speed"],
                                           "matrix": [[1.0, 0.3], [0.3, 1.0]]}}
    with_table = case_from_dict(data)
    assert case_from_dict(tomllib.loads(with_table.to_toml())) == with_table  # round trip
    assert numeric_parameter_paths(with_table) == numeric_parameter_paths(case)
    with pytest.raises(ParameterError, match="not a numeric parameter .the \\[uncertainty\\] table"):
        case_parameter(with_table, "uncertainty.correlation.matrix[0][1]")
