"""Tests for drillstring.case: the reference case, units, TOML round trip and every refusal rule."""

from __future__ import annotations

import copy
import math
import pickle
import tomllib
from importlib import resources
from pathlib import Path

import pytest

from drillstring.case import (
    Case,
    CaseError,
    Fluid,
    Material,
    Section,
    Simulation,
    builtin_cases,
    case_from_dict,
    load_case,
)

RPM = 2.0 * math.pi / 60.0


@pytest.fixture(scope="module")
def reference() -> Case:
    return load_case("reference")


@pytest.fixture()
def data() -> dict:
    """The reference case as a raw TOML dict, fresh for each test to mutate."""
    text = resources.files("drillstring").joinpath("cases", "reference.toml").read_text(encoding="utf-8")
    return copy.deepcopy(tomllib.loads(text))


def refused(data: dict) -> CaseError:
    with pytest.raises(CaseError) as info:
        case_from_dict(data)
    return info.value


def assert_problem(err: CaseError, path: str, value: str, *fragments: str) -> None:
    """Some line of the message starts with ``path = value`` and contains every fragment.

    (A value given with a unit is followed by its SI value: ``length = '-3 ft' (= -0.9144 SI): ...``.)
    """
    head = f"{path} = {value}"
    lines = [p for p in err.problems if p.startswith(head + ":") or p.startswith(head + " (= ")]
    assert lines, f"no problem line starting with {head!r} in:\n{err}"
    assert all(f in lines[0] for f in fragments), lines[0]
    assert head in str(err)


# ---------------------------------------------------------------------------------------------- reference


def test_builtin_cases_lists_reference():
    assert "reference" in builtin_cases()


def test_reference_loads(reference):
    c = reference
    assert c.name == "reference"
    assert [s.name for s in c.sections] == ["drill pipe", "drill collar"]
    dp, dc = c.sections
    assert (dp.length, dp.outer_diameter, dp.inner_diameter) == (1400.0, 0.127, 0.095)
    assert (dc.length, dc.outer_diameter, dc.inner_diameter) == (200.0, 0.2286, 0.0762)
    assert dp.shear_factor == pytest.approx(6 / 7)
    assert c.borehole.diameter == 0.3
    assert len(c.stabilizers) == 1
    assert c.stabilizers[0].position == 1400.0
    assert c.stabilizers[0].stiffness == 17.5e6
    steel = c.material_of(dp)
    assert (steel.young_modulus, steel.density, steel.poisson_ratio) == (210e9, 7850.0, 0.29)
    assert steel.shear_modulus == pytest.approx(210e9 / 2.58)
    assert c.material_of(1) is steel
    assert c.fluid.density == 1200.0 and c.fluid.inlet_velocity == 1.5
    assert c.fluid.friction_coefficient == 0.0125 and c.fluid.viscous_coefficient == 0.0
    assert c.damping.modal_damping_ratio == 0.3
    assert c.damping.rigid_axial == 0.05 and c.damping.rigid_rotation == 0.05
    assert c.contact.shock_stiffness == 1e8 and c.contact.friction_coefficient == 0.0005
    assert c.operation.top_speed == pytest.approx(100 * RPM)
    assert c.operation.weight_on_bit == 1e5
    assert c.environment.gravity == 9.81
    br = c.bit_rock
    coefficients = (br.a1, br.a2, br.a3, br.a4, br.a5, br.regularization)
    assert coefficients == (3.429e-3, 5.672e-8, 1.374e-4, 9.537e6, 1.475e3, 2.0)
    assert c.mesh.probes == [1560.0]
    assert c.initial.lateral_perturbation == pytest.approx(1e-4)


def test_reference_geometry_and_weight(reference):
    c = reference
    assert c.length == 1600.0
    assert c.section_boundaries == (1400.0, 1600.0)
    dp = c.sections[0]
    assert dp.inner_area == pytest.approx(math.pi * 0.095**2 / 4)
    assert dp.outer_area == pytest.approx(math.pi * 0.127**2 / 4)
    assert dp.area == pytest.approx(dp.outer_area - dp.inner_area)
    assert c.weight == pytest.approx(1.1634e6, rel=1e-4)
    assert c.weight_on_hook == pytest.approx(1.0634e6, rel=1e-4)
    assert c.weight - c.weight_on_hook == pytest.approx(1e5)


def test_weight_switches(reference):
    buoyant = reference.model_copy(update={"model": reference.model.model_copy(update={"buoyancy": True})})
    expected = sum((7850.0 - 1200.0) * 9.81 * s.area * s.length for s in reference.sections)
    assert buoyant.weight == pytest.approx(expected)
    weightless = reference.model_copy(update={"model": reference.model.model_copy(update={"gravity": False})})
    assert weightless.weight == 0.0


def test_reference_tables_equal_defaults(reference):
    """Every optional table in reference.toml is written with its default values (the file documents them),
    except the lateral cut-off, which the reference case switches off (its string never reaches the wall),
    the start, which the reference study makes on bottom (new cases ramp the weight on bit up), and the truncation
    correction, which the reference study leaves out (its paper's plain modal basis; new cases take "static"),
    and gravity, the paper's 9.81 m/s^2 (new cases take standard gravity, the g of the pound-force), and the
    method, which the reference study keeps DOPRI5 (new cases take "ark43": the attachment modes of their basis
    would set DOPRI5's step, benchmarks/first_case.py)."""
    from drillstring.constants import STANDARD_GRAVITY

    minimal = Case(name="m", sections=reference.sections, borehole=reference.borehole)
    for table in ("materials", "fluid", "bit_rock", "contact", "operation", "damping", "model",
                  "mesh"):  # fmt: skip
        assert getattr(minimal, table) == getattr(reference, table), table
    assert minimal.simulation.method == "ark43"
    assert minimal.simulation.model_copy(update={"method": "dopri5"}) == reference.simulation
    assert minimal.initial.model_copy(update={"start": "on_bottom"}) == reference.initial
    assert minimal.initial.start == "ramp"
    assert minimal.reduced_model.model_copy(
        update={"lateral_cutoff": 0.0, "truncation_correction": "none"}) == reference.reduced_model
    assert minimal.reduced_model.lateral_cutoff == 1.5
    assert minimal.reduced_model.truncation_correction == "static"
    assert (minimal.environment.gravity, reference.environment.gravity) == (STANDARD_GRAVITY, 9.81)


def test_models_are_frozen(reference):
    with pytest.raises(Exception):
        reference.name = "other"  # type: ignore[misc]
    with pytest.raises(Exception):
        reference.fluid.density = 1.0  # type: ignore[misc]


# -------------------------------------------------------------------------------------------------- units


@pytest.mark.parametrize(
    ("text", "si"),
    [("100 rpm", 100 * RPM), ("1 Hz", 2 * math.pi), ("3 rad/s", 3.0), ("60 rev/min", 2 * math.pi), (5.0, 5.0)],
)
def test_angular_speed_units(data, text, si):
    data["operation"]["top_speed"] = text
    assert case_from_dict(data).operation.top_speed == pytest.approx(si)


@pytest.mark.parametrize(("text", "si"), [("100 kN", 1e5), ("0.1 MN", 1e5), ("2e4 N", 2e4), (50000, 5e4)])
def test_force_units(data, text, si):
    data["operation"]["weight_on_bit"] = text
    assert case_from_dict(data).operation.weight_on_bit == pytest.approx(si)


@pytest.mark.parametrize(
    ("text", "si"), [("8.5 in", 8.5 * 0.0254), ("5 in", 0.127), ("127 mm", 0.127), ("12.7 cm", 0.127)]
)
def test_length_units(data, text, si):
    data["sections"][0]["outer_diameter"] = text
    assert case_from_dict(data).sections[0].outer_diameter == pytest.approx(si)


def test_other_units(data):
    data["sections"][0]["length"] = "1.4 km"
    data["stabilizers"][0]["position"] = "4593.175853018373 ft"
    data["stabilizers"][0]["stiffness"] = "17500 kN/m"
    data["materials"]["steel"]["young_modulus"] = "210000 MPa"
    data["materials"]["steel"]["density"] = "7.85 g/cm3"
    data["fluid"]["inlet_velocity"] = "5400 m/h"
    data["simulation"]["t_end"] = "0.5 min"
    data["simulation"]["output_step"] = "10 ms"
    data["bit_rock"]["a5"] = "1.475 kN*m"
    data["environment"]["gravity"] = "9.81 m/s^2"
    c = case_from_dict(data)
    assert c.sections[0].length == pytest.approx(1400.0)
    assert c.stabilizers[0].position == pytest.approx(1400.0)
    assert c.stabilizers[0].stiffness == pytest.approx(17.5e6)
    assert c.materials["steel"].young_modulus == pytest.approx(210e9)
    assert c.materials["steel"].density == pytest.approx(7850.0)
    assert c.fluid.inlet_velocity == pytest.approx(1.5)
    assert (c.simulation.t_end, c.simulation.output_step) == pytest.approx((30.0, 0.01))
    assert c.bit_rock.a5 == pytest.approx(1475.0)
    assert c.environment.gravity == pytest.approx(9.81)


# ------------------------------------------------------------------------------------------- round trip


def test_to_toml_round_trip(reference, tmp_path):
    text = reference.to_toml()
    tomllib.loads(text)  # valid TOML
    path = tmp_path / "copy.toml"
    path.write_text(text, encoding="utf-8")
    again = load_case(path)
    assert again == reference
    assert load_case(str(path)) == reference
    assert again.to_toml() == text


def test_round_trip_of_a_modified_case(data, tmp_path):
    data["operation"]["top_speed"] = "77 rpm"
    data["materials"]["alloy"] = {"young_modulus": "70 GPa", "density": 2700, "poisson_ratio": 0.33}
    data["sections"][0]["material"] = "alloy"
    data["model"]["buoyancy"] = True
    data["simulation"]["method"] = "bs32"
    case = case_from_dict(data)
    (tmp_path / "m.toml").write_text(case.to_toml(), encoding="utf-8")
    assert load_case(tmp_path / "m.toml") == case


def test_case_error_is_value_error_and_picklable(data):
    data["sections"][0]["length"] = -1
    err = refused(data)
    assert isinstance(err, ValueError)
    again = pickle.loads(pickle.dumps(err))
    assert str(again) == str(err)


# ----------------------------------------------------------------------------------------------- refusals


@pytest.mark.parametrize("bad", [0, -5.0, "0 m", "-3 ft"])
def test_refuses_non_positive_length(data, bad):
    data["sections"][0]["length"] = bad
    err = refused(data)
    assert_problem(err, "sections[0].length", repr(bad), "must be > 0")


def test_refuses_negative_inner_diameter(data):
    data["sections"][1]["inner_diameter"] = "-1 in"
    assert_problem(refused(data), "sections[1].inner_diameter", "'-1 in'", "must be >= 0")


@pytest.mark.parametrize("bad", [0, -0.1])
def test_refuses_non_positive_outer_diameter(data, bad):
    data["sections"][0]["outer_diameter"] = bad
    assert_problem(refused(data), "sections[0].outer_diameter", repr(bad), "must be > 0")


def test_refuses_zero_borehole_diameter(data):
    data["borehole"]["diameter"] = 0
    assert_problem(refused(data), "borehole.diameter", "0", "must be > 0")


@pytest.mark.parametrize("inner", ["0.127 m", "0.2 m"])
def test_refuses_inner_not_less_than_outer(data, inner):
    data["sections"][0]["inner_diameter"] = inner
    err = refused(data)
    assert_problem(err, "sections[0].inner_diameter", repr(float(inner.split()[0])), "outer_diameter", "0.127")


@pytest.mark.parametrize("outer", ["0.3 m", "12 in"])
def test_refuses_outer_not_less_than_borehole(data, outer):
    data["sections"][1]["outer_diameter"] = outer
    data["sections"][1]["inner_diameter"] = "0.1 m"
    err = refused(data)
    si = {"0.3 m": "0.3", "12 in": "0.3048"}[outer]
    assert_problem(err, "sections[1].outer_diameter", si, "borehole", "0.3 m")


@pytest.mark.parametrize(("position", "shown"), [("1700 m", "1700.0"), (0, "0.0"), (-10, "-10.0")])
def test_refuses_stabilizer_outside_string(data, position, shown):
    data["stabilizers"][0]["position"] = position
    assert_problem(refused(data), "stabilizers[0].position", shown, "within the string", "1600 m")


def test_refuses_probe_outside_string(data):
    data["mesh"]["probes"] = ["10 m", "1601 m"]
    assert_problem(refused(data), "mesh.probes[1]", "1601.0", "within the string", "1600 m")


def test_probe_at_the_ends_is_allowed(data):
    data["mesh"]["probes"] = [0, 1600]
    assert case_from_dict(data).mesh.probes == [0.0, 1600.0]


@pytest.mark.parametrize("wob", ["1163.5 kN", "2 MN"])
def test_refuses_weight_on_bit_not_less_than_weight(data, wob):
    data["operation"]["weight_on_bit"] = wob
    err = refused(data)
    shown = repr(float(wob.split()[0]) * {"kN": 1e3, "MN": 1e6}[wob.split()[1]])
    assert_problem(err, "operation.weight_on_bit", shown, "weight", "kN", "1163.43 kN")


def test_refuses_lateral_perturbation_not_less_than_gap(data):
    data["initial"]["lateral_perturbation"] = "4 cm"
    assert_problem(refused(data), "initial.lateral_perturbation", "0.04", "radial gap", "0.0357", "drill collar")


def test_refuses_output_step_longer_than_run(data):
    data["simulation"]["output_step"] = 40
    assert_problem(refused(data), "simulation.output_step", "40.0", "t_end")


def test_refuses_unknown_top_level_key(data):
    data["colour"] = "red"
    assert_problem(refused(data), "colour", "'red'", "unknown key", "sections", "borehole")


def test_refuses_unknown_nested_key(data):
    data["fluid"]["colour"] = "red"
    data["sections"][1]["thickness"] = 3
    err = refused(data)
    assert_problem(err, "fluid.colour", "'red'", "unknown key", "inlet_velocity")
    assert_problem(err, "sections[1].thickness", "3", "unknown key", "outer_diameter")


def test_refuses_unknown_table(data):
    data["bit"] = {"a1": 1}
    assert_problem(refused(data), "bit", "{'a1': 1}", "unknown key", "bit_rock")


def test_refuses_wrong_dimension_unit(data):
    data["sections"][0]["length"] = "1400 kg"
    data["operation"]["top_speed"] = "100 kN"
    err = refused(data)
    assert_problem(err, "sections[0].length", "'1400 kg'", "'kg'", "not a length unit", "m, cm, mm, km, in, ft")
    assert_problem(err, "operation.top_speed", "'100 kN'", "'kN' is a force unit", "rpm")


def test_refuses_unknown_unit(data):
    data["borehole"]["diameter"] = "3 wombats"
    assert_problem(refused(data), "borehole.diameter", "'3 wombats'", "unknown unit 'wombats'", "in, ft")


def test_refuses_unit_on_dimensionless(data):
    data["materials"]["steel"]["poisson_ratio"] = "0.29 m"
    assert_problem(refused(data), "materials.steel.poisson_ratio", "'0.29 m'", "plain number")


@pytest.mark.parametrize("bad", ["fast", "nan", True, [1]])
def test_refuses_non_numbers(data, bad):
    data["fluid"]["inlet_velocity"] = bad
    assert_problem(refused(data), "fluid.inlet_velocity", repr(bad))


def test_refuses_unknown_material(data):
    data["sections"][1]["material"] = "titanium"
    assert_problem(refused(data), "sections[1].material", "'titanium'", "unknown material", "steel")


def test_refuses_missing_required_and_empty_sections(data):
    del data["borehole"]
    data["sections"] = []
    err = refused(data)
    assert_problem(err, "borehole", "(missing)", "required")
    assert_problem(err, "sections", "[]", "at least 1")


def test_refuses_bad_choice(data):
    data["simulation"]["method"] = "rk4"
    data["model"]["nonlinear"] = "some"
    err = refused(data)
    assert_problem(err, "simulation.method", "'rk4'", "dopri5", "bs32", "ark43", "ark32", "erk32")
    assert_problem(err, "model.nonlinear", "'some'", "bit_and_contact", "full")


def test_lists_every_problem_one_per_line(data):
    data["sections"][0]["length"] = -1
    data["fluid"]["density"] = -5
    data["damping"]["modal_damping_ratio"] = 1.0
    err = refused(data)
    assert len(err.problems) == 3
    lines = str(err).splitlines()
    assert len(lines) == 4  # a heading, then one line per problem
    assert "<dict>" in lines[0]
    assert_problem(err, "fluid.density", "-5", "must be >= 0")
    assert_problem(err, "damping.modal_damping_ratio", "1.0", "must be < 1")


def test_direct_construction_raises_case_error():
    with pytest.raises(CaseError) as info:
        Section(name="s", length=1.0, outer_diameter=0.1, inner_diameter=0.1)
    assert_problem(info.value, "inner_diameter", "0.1", "outer_diameter")
    with pytest.raises(CaseError):
        Material(young_modulus=1, density=1, poisson_ratio=0.5)
    with pytest.raises(CaseError):
        Fluid(colour=1)
    with pytest.raises(CaseError):
        Simulation(t_end=1.0, output_step=2.0)


def test_case_from_dict_names_its_source(data):
    data["sections"][0]["length"] = -1
    with pytest.raises(CaseError, match="my-source"):
        case_from_dict(data, source="my-source")
    with pytest.raises(CaseError, match="table"):
        case_from_dict([1, 2], source="x")  # type: ignore[arg-type]


# ------------------------------------------------------------------------------------------------ loading


def test_toml_syntax_error(tmp_path):
    bad = tmp_path / "broken.toml"
    bad.write_text('name = "x"\n[sections\n', encoding="utf-8")
    with pytest.raises(CaseError) as info:
        load_case(bad)
    msg = str(info.value)
    assert "broken.toml" in msg and "TOML syntax error" in msg and "line 2" in msg


def test_missing_file(tmp_path):
    missing = tmp_path / "nowhere.toml"
    with pytest.raises(CaseError) as info:
        load_case(missing)
    assert "not found" in str(info.value) and "nowhere.toml" in str(info.value)
    with pytest.raises(CaseError, match="nowhere.toml"):
        load_case(str(missing))


def test_unknown_builtin_name():
    with pytest.raises(CaseError) as info:
        load_case("no_such_case")
    msg = str(info.value)
    assert "no_such_case" in msg and "reference" in msg


def test_invalid_file_names_the_file_and_field(tmp_path, data):
    data["operation"]["weight_on_bit"] = "5 MN"
    import tomli_w

    path = tmp_path / "heavy.toml"
    path.write_text(tomli_w.dumps(data), encoding="utf-8")
    with pytest.raises(CaseError) as info:
        load_case(path)
    assert "heavy.toml" in str(info.value)
    assert_problem(info.value, "operation.weight_on_bit", "5000000.0", "weight")


def test_load_case_accepts_path_objects(tmp_path, reference):
    path = Path(tmp_path) / "ref.toml"
    path.write_text(reference.to_toml(), encoding="utf-8")
    assert load_case(path).name == "reference"


# ------------------------------------------------------------------------------- meshing and reduction


def test_refuses_a_string_shorter_than_one_element(data):
    """A 1 m string with the default 10 m elements: refused, naming the element length."""
    data["sections"] = [dict(data["sections"][1], length="1 m")]
    data["stabilizers"] = []
    data["mesh"]["probes"] = ["0.5 m"]
    data["operation"]["weight_on_bit"] = "1 kN"
    assert_problem(refused(data), "mesh.max_element_length", "10.0", "string length (1 m)")
    data["mesh"]["max_element_length"] = "0.1 m"
    data["reduced_model"] = {"axial_modes": 2, "torsional_modes": 2, "lateral_modes": 4}
    assert case_from_dict(data).element_count == 10


def test_refuses_an_element_longer_than_the_string(data):
    data["mesh"]["max_element_length"] = "5 km"
    assert_problem(refused(data), "mesh.max_element_length", "5000.0", "at most", "1600 m")


def test_refuses_a_mesh_with_too_many_elements_at_once(data):
    import time

    from drillstring.case import MAX_ELEMENTS

    data["mesh"]["max_element_length"] = "1 mm"
    start = time.perf_counter()
    err = refused(data)
    assert time.perf_counter() - start < 5.0  # refused, not meshed (it used to take 45 s, then MemoryError)
    assert_problem(err, "mesh.max_element_length", "0.001", "1,600,000 elements", f"{MAX_ELEMENTS:,}")
    data["mesh"]["max_element_length"] = "1e-12 m"
    assert_problem(refused(data), "mesh.max_element_length", "1e-12", "elements")


@pytest.mark.parametrize(("key", "most"), [("axial_modes", 160), ("torsional_modes", 160),
                                           ("lateral_modes", 320)])
def test_refuses_more_modes_than_the_mesh_has(data, key, most):
    """The reference mesh has 161 nodes: 161 axial DOFs (one of them the rigid mode), 160 torsional
    (top held), 320 lateral per plane; one more mode than that is refused, naming the field."""
    data["reduced_model"][key] = most + 1
    assert_problem(refused(data), f"reduced_model.{key}", str(most + 1), f"at most {most}", "161 nodes")
    data["reduced_model"][key] = 100000
    assert_problem(refused(data), f"reduced_model.{key}", "100000", f"at most {most}")


def test_as_many_modes_as_the_mesh_has_are_accepted_and_reduced(data):
    """At the limit, the case is valid and the reduced model has exactly the modes asked for."""
    from drillstring.dynamics.rom import case_reduced_model

    data["sections"] = [dict(data["sections"][0], length="60 m"), dict(data["sections"][1], length="20 m")]
    data["stabilizers"] = [{"position": "60 m", "stiffness": "17.5 MN/m"}]
    data["mesh"] = {"max_element_length": "10 m", "probes": ["70 m"]}
    data["operation"]["weight_on_bit"] = "20 kN"
    data["reduced_model"] = {"axial_modes": 8, "torsional_modes": 8, "lateral_modes": 16}  # 9 nodes
    case = case_from_dict(data)
    assert case.element_count == 6 + 1 + 1  # breaks at 60 m (section, stabilizer) and 70 m (probe)
    model = case_reduced_model(case)
    assert model.size == 1 + 8 + 8 + 2 * 16
    assert list(model.family).count("lateral_y") == 16


def test_gravity_off_is_a_valid_case_with_a_pushing_hook(data):
    data["model"]["gravity"] = False
    case = case_from_dict(data)
    assert case.weight == 0.0
    assert case.weight_on_hook == -case.operation.weight_on_bit


@pytest.mark.parametrize("axial_loads", [False, True])
@pytest.mark.parametrize("buoyancy", [False, True])
@pytest.mark.parametrize("gravity", [True, False])
def test_weight_is_the_statics_weight(reference, axial_loads, buoyancy, gravity):
    """One source of truth: Case.weight and weight_on_hook equal the finite-element statics' values for
    every combination of the switches (fluid axial loads used to make them differ by 8.7 kN)."""
    from drillstring.statics import case_static_state

    case = reference.model_copy(update={
        "fluid": reference.fluid.model_copy(update={"axial_loads": axial_loads}),
        "model": reference.model.model_copy(update={"buoyancy": buoyancy, "gravity": gravity}),
    })
    static = case_static_state(case)
    assert static.weight == pytest.approx(case.weight, rel=1e-13, abs=1e-9)
    assert static.weight_on_hook == pytest.approx(case.weight_on_hook, rel=1e-10, abs=1e-6)
    if axial_loads:  # the mud's skin friction is part of it: the annular flow drags the string up
        plain = reference.model_copy(update={"model": case.model})
        assert case.weight - plain.weight == pytest.approx(
            sum(q * s.length for q, s in zip(case.axial_load_per_length, case.sections))
            - sum(q * s.length for q, s in zip(plain.axial_load_per_length, plain.sections)), rel=1e-12)
        assert abs(case.weight - plain.weight) > 1e3


def test_fine_meshes_up_to_max_elements_are_accepted(data):
    """The set-up is sparse (no dense n × n matrix): 0.17 m elements on the 1600 m string (9,414 elements,
    which once died building a dense 2.6 GiB matrix) and 10,000 elements are accepted; one more is refused
    with the count."""
    data["mesh"]["max_element_length"] = "0.17 m"
    assert case_from_dict(data).element_count == 9_414
    data["mesh"]["max_element_length"] = "0.16 m"
    assert case_from_dict(data).element_count == 10_000
    data["mesh"]["max_element_length"] = "0.1599 m"
    assert_problem(refused(data), "mesh.max_element_length", "0.1599", "10,008 elements, more than the 10,000")


def test_refuses_an_eccentricity_or_a_bow_beyond_the_radial_gap(data):
    """The collar's radial gap is (300 − 228.6)/2 = 35.7 mm: a 1 m mass eccentricity or a 50 mm bow there
    would put the string beyond the borehole wall."""
    data["sections"][1]["eccentricity"] = "1 m"
    assert_problem(refused(data), "sections[1].eccentricity", "1.0", "must be less than the section's radial gap "
                   "(0.0357 m)")
    del data["sections"][1]["eccentricity"]
    data["bow"] = {"amplitude": "50 mm", "start": 1450.0, "end": 1550.0}
    assert_problem(refused(data), "bow.amplitude", "0.05", "must be less than the radial gap along the bow "
                   "(0.0357 m, section 'drill collar')")
    data["bow"]["amplitude"] = "30 mm"
    case_from_dict(data)


# ------------------------------------------------------------------------- Detournay law keys, aarsnes2019


DETOURNAY_KEYS = ("blades", "bit_radius", "intrinsic_specific_energy", "cutting_inclination", "contact_stress",
                  "wear_flat_length", "friction_coefficient", "bit_geometry", "contact_velocity", "friction_speed")


def _detournay_law(case: Case):
    from drillstring.forces.bit_rock import case_bit_rock

    return case_bit_rock(case)


def test_detournay_keys_with_units(data):
    data["bit_rock"] = {"law": "detournay", "blades": 6, "bit_radius": "4.25 in",
                        "intrinsic_specific_energy": "8702 psi", "cutting_inclination": 0.8,
                        "contact_stress": "0.05 GPa", "wear_flat_length": "1.2 cm", "friction_coefficient": 0.5,
                        "bit_geometry": 1.2, "contact_velocity": "0.036 m/h", "friction_speed": "0.01 rpm"}
    b = case_from_dict(data).bit_rock
    assert b.law == "detournay" and b.blades == 6
    assert b.bit_radius == pytest.approx(0.10795, rel=1e-12)
    assert b.intrinsic_specific_energy == pytest.approx(8702 * 6894.757293168361, rel=1e-12)
    assert b.contact_stress == pytest.approx(50e6, rel=1e-12)
    assert b.wear_flat_length == pytest.approx(0.012, rel=1e-12)
    assert b.contact_velocity == pytest.approx(1e-5, rel=1e-12)
    assert b.friction_speed == pytest.approx(0.01 * RPM, rel=1e-12)
    assert (b.cutting_inclination, b.friction_coefficient, b.bit_geometry) == (0.8, 0.5, 1.2)


def test_detournay_defaults_are_the_published_bit():
    b = load_case("reference").bit_rock
    assert b.law == "tucker_wang"
    assert [getattr(b, k) for k in DETOURNAY_KEYS] == [4, 0.108, 60e6, 0.6, 60e6, 0.011, 0.6, 1.0, 2.5e-4, 5e-3]
    for key in DETOURNAY_KEYS:  # every key documented with its unit
        description = type(b).model_fields[key].description
        assert description.startswith("detournay: ") and description.endswith("]"), key


@pytest.mark.parametrize(("key", "value", "shown", "fragment"), [
    ("blades", 0, "0", "must be >= 1"),
    ("blades", 2.5, "2.5", "integer"),
    ("bit_radius", "-1 m", "'-1 m'", "must be > 0"),
    ("bit_radius", "20 m", "20.0", "must be within [0.001, 10] m"),
    ("intrinsic_specific_energy", 0, "0", "must be > 0"),
    ("intrinsic_specific_energy", "1e15 Pa", "1000000000000000.0", "must be within [1e+06, 1e+12] Pa"),
    ("contact_stress", "60 mm", "'60 mm'", "pressure"),
    ("wear_flat_length", "-11 mm", "'-11 mm'", "must be >= 0"),
    ("friction_coefficient", 20.0, "20.0", "must be within [0, 10]"),
    ("cutting_inclination", -0.6, "-0.6", "must be >= 0"),
    ("contact_velocity", 0, "0", "must be > 0"),
    ("friction_speed", "1 N", "'1 N'", "angular speed"),
])
def test_detournay_keys_refused_with_the_field(data, key, value, shown, fragment):
    data["bit_rock"] = {"law": "detournay", key: value}
    assert_problem(refused(data), f"bit_rock.{key}", shown, fragment)


def test_unknown_bit_rock_law_lists_the_laws(data):
    """The case accepts any law name (a law added to the package or registered by a script needs no edit of the
    case); building the law refuses an unknown one, naming the key, its value and the registered laws."""
    from drillstring.forces.bit_rock import case_bit_rock

    data["bit_rock"]["law"] = "detourney"
    case = case_from_dict(data)
    # the package's laws, in order, with any a test registered between them
    with pytest.raises(ValueError, match=r"bit_rock.law = 'detourney': must be one of detournay, off_bottom, "
                                         r"(\w+, )*tucker_wang\b"):
        case_bit_rock(case)


def test_aarsnes2019_has_the_published_numbers(tmp_path):
    case = load_case("aarsnes2019")
    assert "aarsnes2019" in builtin_cases()
    (tmp_path / "a.toml").write_text(case.to_toml(), encoding="utf-8")
    assert load_case(tmp_path / "a.toml") == case
    steel = case.materials["steel"]
    assert (steel.young_modulus, steel.density) == (200e9, 8000.0)
    assert steel.shear_modulus == pytest.approx(77e9, rel=1e-12)
    pipe, bha = case.sections
    assert (pipe.length, pipe.outer_diameter, pipe.inner_diameter) == (2000.0, 0.127, 0.108)
    polar_inertia = steel.density * math.pi / 32.0 * (bha.outer_diameter**4 - bha.inner_diameter**4) * bha.length
    assert polar_inertia == pytest.approx(41.0, rel=1e-4)
    assert case.borehole.diameter == pytest.approx(2 * 0.108)
    b = case.bit_rock
    assert b.law == "detournay"
    assert [getattr(b, k) for k in DETOURNAY_KEYS[:8]] == [4, 0.108, 60e6, 0.6, 60e6, 0.011, 0.6, 1.0]
    assert case.operation.top_speed == pytest.approx(30.0 * RPM, rel=1e-12)
    assert case.top_drive.controller == "imposed_speed"
    assert case.stabilizers == []
    assert (case.reduced_model.lateral_modes, case.reduced_model.lateral_cutoff) == (0, 0.0)
    assert (case.simulation.t_end, case.simulation.output_step) == (30.0, 0.01)
    assert (case.initial.start, case.initial.weight_ramp_time) == ("ramp", 10.0)
    # the implicit-explicit step where it is faster at equal statistics (docs/model.md §9); the reference
    # study's method stays DOPRI5
    assert case.simulation.method == "ark43" and load_case("aarsnes2019_paper").simulation.method == "ark43"
    assert load_case("motor").simulation.method == "ark43" and load_case("reference").simulation.method == "dopri5"
    # the cases whose documented numbers are DOPRI5's name it (the default for new cases is "ark43")
    for name in ("reference", "reference_components", "contact", "stick_slip", "deviated"):
        assert load_case(name).simulation.method == "dopri5", name


def test_aarsnes2019_weight_on_bit_is_the_steady_state_of_30_m_per_h_at_30_rpm():
    case = load_case("aarsnes2019")
    steady = _detournay_law(case).steady_state(30.0 / 3600.0, case.operation.top_speed)
    assert steady.weight_on_bit == pytest.approx(136_080.0, rel=1e-12)
    assert case.operation.weight_on_bit == pytest.approx(steady.weight_on_bit, rel=1e-3)
    assert case.operation.weight_on_bit < case.weight  # the hook carries the rest


def test_aarsnes2019_statics_and_modes_build():
    from drillstring.api import static, modes

    case = load_case("aarsnes2019")
    state, margin = static(case)
    assert state.weight_on_bit == pytest.approx(case.operation.weight_on_bit, rel=1e-9)
    assert state.weight_on_hook == pytest.approx(case.weight - case.operation.weight_on_bit, rel=1e-9)
    # Without stabilizers the straight string is laterally buckled at 136 kN (critical ~31 kN); the case
    # keeps no lateral modes, so this does not enter its torsional-axial dynamics.
    assert margin.buckled
    found, _ = modes(case, count=3)
    assert found.axial.frequencies[0] == pytest.approx(0.0, abs=1e-6)  # free rigid translation
    # The torsional fundamental of a pipe held at the top with the BHA at the bit lies below the pipe's
    # quarter-wave frequency c / (4 L) (the BHA adds inertia): about 0.32 Hz here, 0.39 Hz for the bare pipe.
    bare = math.sqrt(77e9 / 8000.0) / (4.0 * 2000.0)
    assert 0.5 * bare < found.torsional.frequencies[0] < bare


def test_rock_and_bit_parameters_are_study_parameters():
    """Studies, maps and sensitivity runs draw the Detournay keys like any case field: the paths bind with
    their dimension and range, a drawn row makes a valid case, a law outside the range is refused."""
    from drillstring.stochastic.parameters import ParameterError
    from drillstring.stochastic.uncertainty import declared_uncertainty, uncertainty

    case = load_case("aarsnes2019")
    declared = declared_uncertainty(case)
    assert declared.paths == ("bit_rock.intrinsic_specific_energy", "bit_rock.contact_stress")
    assert declared.units == ("Pa", "Pa")
    law = uncertainty(case, {"bit_rock.friction_coefficient": "uniform 0.4 0.8",
                             "bit_rock.wear_flat_length": "uniform 5 15 mm",
                             "bit_rock.intrinsic_specific_energy": "uniform 45 75 MPa"})
    drawn = law.apply(case, [0.7, 0.012, 50e6])
    assert (drawn.bit_rock.friction_coefficient, drawn.bit_rock.wear_flat_length,
            drawn.bit_rock.intrinsic_specific_energy) == (0.7, 0.012, 50e6)
    with pytest.raises(ParameterError, match=r"^bit_rock\.friction_coefficient = 'normal 0\.1 0\.2'"):
        uncertainty(case, {"bit_rock.friction_coefficient": "normal 0.1 0.2"})
    with pytest.raises(ParameterError, match="unit 'mm' is a length unit"):
        uncertainty(case, {"bit_rock.contact_stress": "uniform 45 75 mm"})
    with pytest.raises(ParameterError, match="integer"):
        uncertainty(case, {"bit_rock.blades": "uniform 3 6"})
