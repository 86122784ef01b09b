"""Tests for strings from components (drillstring.components, case.Component): the reference case written as
components builds the same model; weight per length, tool joints and stabilizers against hand calculations;
every refusal names the component field."""

from __future__ import annotations

import copy
import math
import tomllib
from importlib import resources

import numpy as np
import pytest

from drillstring.case import CaseError, case_from_dict, load_case
from drillstring.fem.assembly import stabilizer_stiffness, structural_matrices
from drillstring.fem.build import case_mesh, stabilizers
from drillstring.fem.dofs import U, dof

LB_PER_FT = 1.4881639435695537  # kg/m (NIST)
IN = 0.0254  # m
STEEL = 7850.0  # kg/m³


def _components_data() -> dict:
    text = resources.files("drillstring").joinpath("cases", "reference_components.toml").read_text("utf-8")
    return copy.deepcopy(tomllib.loads(text))


def _area(outer: float, inner: float) -> float:
    return math.pi * (outer**2 - inner**2) / 4.0


def test_reference_components_builds_exactly_the_reference_model():
    reference, components = load_case("reference"), load_case("reference_components")
    a, b = reference.model_dump(), components.model_dump()
    for key in ("name", "description"):
        a.pop(key), b.pop(key)
    assert a == b  # every number bit for bit: the same sections, stabilizers, materials, ...
    mesh_a, mesh_b = case_mesh(reference, 100.0), case_mesh(components, 100.0)
    for m_a, m_b in zip(structural_matrices(mesh_a), structural_matrices(mesh_b), strict=True):
        assert (m_a != m_b).nnz == 0
    assert (stabilizer_stiffness(mesh_a, stabilizers(reference))
            != stabilizer_stiffness(mesh_b, stabilizers(components))).nnz == 0


def test_component_names_default_to_their_type():
    case = load_case("reference_components")
    assert [s.name for s in case.sections] == ["drill pipe", "drill collar"]
    assert [(s.position, s.stiffness) for s in case.stabilizers] == [(1400.0, 17.5e6)]


def _string(*components: dict) -> dict:
    data = _components_data()
    data["components"] = list(components)
    data["mesh"]["probes"] = []
    data.pop("uncertainty", None)
    return data


PIPE = {"type": "drill_pipe", "length": "1000 m", "outer_diameter": "5 in", "inner_diameter": "4.276 in"}
COLLAR = {"type": "collar", "length": "100 m", "outer_diameter": "8 in", "inner_diameter": "2.8125 in"}


def test_weight_per_length_with_a_bore_is_the_linear_mass():
    """19.5 lb/ft nominal on a 5 in x 4.276 in body: the section's mass per length is 19.5 lb/ft, through a
    material of its own (density m / A), stiffness and every other property from steel."""
    pipe = dict(PIPE, weight_per_length="19.5 lb/ft")
    case = case_from_dict(_string(pipe, COLLAR))
    section = case.sections[0]
    material = case.material_of(section)
    assert material.density * section.area == pytest.approx(19.5 * LB_PER_FT, rel=1e-14)
    assert (material.young_modulus, material.poisson_ratio) == (210e9, 0.29)
    assert section.material == "steel (drill pipe)" and case.sections[1].material == "steel"
    g = case.environment.gravity
    collar = STEEL * _area(8 * IN, 2.8125 * IN) * 100.0
    assert case.weight == pytest.approx(g * (19.5 * LB_PER_FT * 1000.0 + collar), rel=1e-12)


def test_weight_per_length_without_a_bore_sets_the_bore():
    """A plain 8 in collar of 147 lb/ft: D_i = sqrt(D_o² - 4 m / (pi rho))."""
    collar = {"type": "collar", "length": "100 m", "outer_diameter": "8 in", "weight_per_length": "147 lb/ft"}
    case = case_from_dict(_string(PIPE, collar))
    section = case.sections[1]
    mass = 147 * LB_PER_FT
    assert section.inner_diameter == pytest.approx(math.sqrt((8 * IN) ** 2 - 4 * mass / (math.pi * STEEL)), rel=1e-14)
    assert section.material == "steel"
    assert STEEL * section.area == pytest.approx(mass, rel=1e-13)


def test_tool_joints_are_smeared_as_added_mass():
    """6.625 in x 3.25 in tool joints, 0.5 m long, one per 30 ft joint of pipe: mass per length
    rho (A + (A_tj - A) l_tj / spacing); the section keeps the body's diameters (its stiffness)."""
    joint = {"outer_diameter": "6.625 in", "inner_diameter": "3.25 in", "length": "0.5 m", "spacing": "30 ft"}
    case = case_from_dict(_string(dict(PIPE, tool_joint=joint), COLLAR))
    section = case.sections[0]
    body = _area(5 * IN, 4.276 * IN)
    expected = STEEL * (body + (_area(6.625 * IN, 3.25 * IN) - body) * 0.5 / (30 * 0.3048))
    assert case.material_of(section).density * section.area == pytest.approx(expected, rel=1e-13)
    assert (section.outer_diameter, section.inner_diameter) == pytest.approx((5 * IN, 4.276 * IN), rel=1e-15)
    # The FE mass matrix carries it: total axial mass of the string (rigid translation: 1^T M_axial 1).
    mesh = case_mesh(case, 50.0)
    _, mass = structural_matrices(mesh)
    axial = dof(np.arange(mesh.n_nodes), U)
    total = mass.toarray()[np.ix_(axial, axial)].sum()
    assert total == pytest.approx(expected * 1000.0 + STEEL * _area(8 * IN, 2.8125 * IN) * 100.0, rel=1e-12)


def test_stabilizer_with_a_body_is_a_section_and_a_spring_at_its_middle():
    stab = {"type": "stabilizer", "length": "2 m", "outer_diameter": "8 in", "inner_diameter": "2.8125 in",
            "blade_diameter": "11.75 in", "stiffness": "17.5 MN/m", "name": "near-bit stabilizer"}
    bit = {"type": "bit", "length": "0.5 m", "outer_diameter": "8 in", "inner_diameter": "2 in"}
    case = case_from_dict(_string(PIPE, {"type": "stabilizer", "stiffness": "10 MN/m"}, COLLAR, stab, bit))
    assert [s.name for s in case.sections] == ["drill pipe", "drill collar", "near-bit stabilizer", "bit"]
    assert [s.position for s in case.stabilizers] == pytest.approx([1000.0, 1101.0], rel=1e-15)
    assert [s.stiffness for s in case.stabilizers] == pytest.approx([10e6, 17.5e6], rel=1e-15)
    assert case.length == pytest.approx(1102.5, rel=1e-15)


@pytest.mark.parametrize(
    ("components", "fragments"),
    [
        ([dict(PIPE, inner_diameter="6 in"), COLLAR],
         ["components[0].inner_diameter = 0.1524: must be less than outer_diameter (0.127 m)"]),
        ([{k: v for k, v in PIPE.items() if k != "inner_diameter"}, COLLAR],
         ["components[0].inner_diameter = (missing): give inner_diameter or weight_per_length"]),
        ([dict(PIPE, weight_per_length="20 psi"), COLLAR],
         ["components[0].weight_per_length = '20 psi'", "pressure unit, not a mass per length unit"]),
        ([PIPE, dict(COLLAR, stiffness="1 MN/m")], ["components[1].stiffness", "only for a stabilizer"]),
        ([PIPE, {"type": "stabilizer"}, COLLAR], ["components[1].stiffness = (missing): required for a stabilizer"]),
        ([PIPE, {"type": "stabilizer", "stiffness": 1e6, "blade_diameter": "13 in"}, COLLAR],
         ["components[1].blade_diameter", "at most the borehole diameter (0.3 m)"]),
        ([{"type": "stabilizer", "stiffness": 1e6}, PIPE], ["components[0].length", "below another component"]),
        ([dict(COLLAR, tool_joint={"outer_diameter": "9 in", "length": "0.5 m"}), PIPE],
         ["components[0].tool_joint", "only for drill_pipe and heavy_weight"]),
        ([dict(PIPE, weight_per_length="500 lb/ft", inner_diameter=None), COLLAR],
         ["components[0].weight_per_length", "must be less than a solid bar"]),
        ([{"type": "bit", "length": 0.3, "outer_diameter": 0.2, "inner_diameter": 0.05}, PIPE],
         ["components[0].type = 'bit': the bit must be the last component"]),
        ([dict(PIPE, type="casing"), COLLAR], ["components[0].type = 'casing'", "drill_pipe"]),
        ([dict(PIPE, material="titanium"), COLLAR], ["components[0].material = 'titanium': unknown material"]),
        ([dict(PIPE, colour="red")], ["components[0].colour = 'red': unknown key"]),
    ],
)
def test_component_refusals_name_the_field(components, fragments):
    components = [{k: v for k, v in c.items() if v is not None} for c in components]
    with pytest.raises(CaseError) as info:
        case_from_dict(_string(*components))
    assert all(f in str(info.value) for f in fragments), str(info.value)


def test_an_invalid_material_is_reported_with_the_components():
    data = _string(dict(PIPE, length="-3 ft"), COLLAR)
    data["materials"]["steel"]["density"] = "7850 psi"
    with pytest.raises(CaseError) as info:
        case_from_dict(data)
    assert info.value.problems[0].startswith("components[0].length = '-3 ft'")
    assert "materials.steel.density = '7850 psi': unit 'psi' is a pressure unit" in str(info.value)


def test_components_and_sections_together_are_refused():
    data = _components_data()
    data["sections"] = load_case("reference").model_dump()["sections"]
    with pytest.raises(CaseError, match="give either"):
        case_from_dict(data)


def test_components_round_trip_through_toml(tmp_path):
    joint = {"outer_diameter": "6.625 in", "length": "0.5 m"}
    case = case_from_dict(_string(dict(PIPE, tool_joint=joint), COLLAR))
    path = tmp_path / "case.toml"
    path.write_text(case.to_toml(), encoding="utf-8")
    assert load_case(path) == case
