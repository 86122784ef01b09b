"""Soft-string torque and drag and buckling against closed forms and today's vertical statics."""

import math
from pathlib import Path

import numpy as np
import pytest

from drillstring.case import case_from_dict, load_case
from drillstring.fem.sections import hollow_circle
from drillstring.statics import case_static_state
from drillstring.well.buckling import buckled_intervals, critical_loads
from drillstring.well.torque_drag import case_torque_drag, lockup_depth, string_in_well, torque_drag

DEG = math.pi / 180.0


def _with_well(case, well, **changes):
    data = case.model_dump()
    data["well"] = well
    for path, value in changes.items():
        table, key = path.split(".")
        data[table][key] = value
    return case_from_dict(data)


def test_vertical_limit_is_the_statics(reference_case):
    results = case_torque_drag(reference_case)
    state = case_static_state(reference_case)
    drilling = results["drilling"]
    assert drilling.hook_load == pytest.approx(state.weight_on_hook, rel=1e-12)
    for op in ("trip_out", "trip_in", "rotating_off_bottom"):
        assert results[op].hook_load == pytest.approx(state.weight, rel=1e-12)
        assert results[op].surface_torque == 0.0
    force = np.interp(state.mesh.nodes, drilling.measured_depth, drilling.axial_force)
    assert np.allclose(force, state.axial_force, rtol=0, atol=1e-6 * state.weight)
    crossing = np.nonzero(np.diff(np.sign(drilling.axial_force)))[0][0]
    x, n = drilling.measured_depth, drilling.axial_force
    neutral = x[crossing] + (x[crossing + 1] - x[crossing]) * n[crossing] / (n[crossing] - n[crossing + 1])
    assert neutral == pytest.approx(state.neutral_point, abs=1e-6)


@pytest.mark.parametrize("mu", [0.0, 0.3])
def test_straight_inclined_hole(reference_case, mu):
    inc = 30 * DEG
    case = _with_well(reference_case, {"survey": [[0, 30, 10], [2000, 30, 10]], "open_hole_friction": mu})
    results = case_torque_drag(case, with_buckling=False)
    weight = case.weight
    assert results["trip_out"].hook_load == pytest.approx(weight * (math.cos(inc) + mu * math.sin(inc)), rel=1e-12)
    assert results["trip_in"].hook_load == pytest.approx(weight * (math.cos(inc) - mu * math.sin(inc)), rel=1e-12)
    assert results["rotating_off_bottom"].hook_load == pytest.approx(weight * math.cos(inc), rel=1e-12)
    w = np.array(case.axial_load_per_length)
    side = results["rotating_off_bottom"].side_force
    section = np.where(results["trip_out"].measured_depth <= case.sections[0].length, 0, 1)
    assert np.allclose(side, w[section] * math.sin(inc), rtol=1e-12)
    radius = np.array([s.outer_diameter / 2 for s in case.sections])
    torque = mu * math.sin(inc) * sum(wi * s.length * r for wi, s, r in zip(w, case.sections, radius))
    assert results["rotating_off_bottom"].surface_torque == pytest.approx(torque, rel=1e-12, abs=1e-9)


def test_weightless_string_around_an_arc_capstan(reference_case):
    """F0 exp(+mu theta) pulling out, F0 exp(-mu theta) running in, torque mu F0 theta r rotating."""
    case = _with_well(reference_case, {"survey": [[0, 0, 0], [100, 0, 0], [1000, 90, 45], [1700, 90, 45]]},
                      **{"model.gravity": False})
    string = string_in_well(case)
    mu, pull, theta = 0.3, 1e5, math.pi / 2
    out = torque_drag(string, "trip_out", cased_friction=mu, open_hole_friction=mu, bit_force=pull)
    into = torque_drag(string, "trip_in", cased_friction=mu, open_hole_friction=mu, bit_force=pull)
    spin = torque_drag(string, "rotating_off_bottom", cased_friction=mu, open_hole_friction=mu, bit_force=pull)
    assert out.hook_load == pytest.approx(pull * math.exp(mu * theta), rel=1e-7)
    assert into.hook_load == pytest.approx(pull * math.exp(-mu * theta), rel=1e-7)
    assert spin.hook_load == pytest.approx(pull, rel=1e-12)
    assert spin.surface_torque == pytest.approx(mu * pull * theta * 0.127 / 2, rel=1e-9)
    on_arc = (spin.measured_depth > 101) & (spin.measured_depth < 999)
    assert np.allclose(spin.side_force[on_arc], pull / (900 / theta), rtol=1e-9)  # F / R


def test_buoyancy_with_mud_inside_and_outside(reference_case):
    rho_s, rho_o, rho_i, g = 7850.0, 1200.0, 1500.0, 9.81
    case = _with_well(reference_case, {"survey": [[0, 0, 0], [1600, 0, 0]], "inner_fluid_density": rho_i},
                      **{"model.buoyancy": True})
    results = case_torque_drag(case)
    expected = sum(g * (rho_s * s.area + rho_i * s.inner_area - rho_o * s.outer_area) * s.length
                   for s in case.sections)
    assert results["trip_out"].hook_load == pytest.approx(expected, rel=1e-12)
    bit = case.sections[-1]
    p_o, p_i = rho_o * g * 1600.0, rho_i * g * 1600.0
    assert results["trip_out"].axial_force[-1] == 0.0  # effective tension is 0 at a free bit
    assert results["trip_out"].true_axial_force[-1] == pytest.approx(-p_o * bit.outer_area + p_i * bit.inner_area)
    same = _with_well(reference_case, {"survey": [[0, 0, 0], [1600, 0, 0]]}, **{"model.buoyancy": True})
    assert case_torque_drag(same)["trip_out"].hook_load == pytest.approx(same.weight, rel=1e-12)  # (rho_s - rho_f) A g


def test_friction_factors_per_interval(reference_case):
    inc = 60 * DEG
    well = {"survey": [[0, 60, 0], [1600, 60, 0]], "casing_shoe": 700.0, "cased_hole_friction": 0.1,
            "open_hole_friction": 0.4}
    case = _with_well(reference_case, well)
    w = case.axial_load_per_length
    load = [(w[0], 700.0, 0.1), (w[0], 700.0, 0.4), (w[1], 200.0, 0.4)]
    expected = sum(q * length * (math.cos(inc) + mu * math.sin(inc)) for q, length, mu in load)
    assert case_torque_drag(case, with_buckling=False)["trip_out"].hook_load == pytest.approx(expected, rel=1e-12)


@pytest.fixture(scope="module")
def deviated():
    return load_case("deviated")


@pytest.fixture(scope="module")
def deviated_results(deviated):
    return case_torque_drag(deviated, string=string_in_well(deviated, max_step=10.0))


def test_operations_ordered_as_physics_says(deviated_results):
    hook = {op: r.hook_load for op, r in deviated_results.items()}
    assert hook["trip_out"] > hook["rotating_off_bottom"] > hook["trip_in"] > hook["sliding"]
    assert hook["rotating_off_bottom"] > hook["drilling"]
    torque = {op: r.surface_torque for op, r in deviated_results.items()}
    assert torque["drilling"] > torque["rotating_off_bottom"] > 0.0
    assert torque["trip_out"] == torque["trip_in"] == torque["sliding"] == 0.0
    assert np.all(np.diff(deviated_results["trip_out"].axial_force) < 0)  # tension falls towards the bit


def test_buckling_criteria_closed_forms(reference_case):
    inc = 60 * DEG
    case = _with_well(reference_case, {"survey": [[0, 60, 0], [1600, 60, 0]]}, **{"model.buoyancy": True})
    string = string_in_well(case, max_step=50.0)
    critical = critical_loads(string)
    pipe = case.sections[0]
    beam = hollow_circle(pipe.outer_diameter, pipe.inner_diameter, 210e9, 7850.0, 0.29)
    w = case.axial_load_per_length[0]
    r = (case.borehole.diameter - pipe.outer_diameter) / 2
    dawson_paslay = 2 * math.sqrt(beam.bending_stiffness * w * math.sin(inc) / r)
    assert critical["sinusoidal"][1] == pytest.approx(dawson_paslay, rel=1e-12)
    assert critical["helical"][1] == pytest.approx(math.sqrt(2) * dawson_paslay, rel=1e-12)  # Chen et al.
    # a build section: the compression presses the pipe outwards too (Wu & Juvkam-Wold 1995 closed form)
    rate = 3 * DEG / 30
    built = _with_well(reference_case, {"survey": [[0, 0, 0], [100, 0, 0], [1700, 160, 0]]},
                       **{"model.buoyancy": True})
    string = string_in_well(built, max_step=50.0)
    critical = critical_loads(string)
    k = 10  # a node on the build, drill pipe
    cos_i = string.inclination_cos[k - 1, 1]
    ei = beam.bending_stiffness
    curved = 2 * ei * rate / r * (1 + math.sqrt(1 + r * w * math.sqrt(1 - cos_i**2) / (ei * rate**2)))
    assert critical["sinusoidal"][k] == pytest.approx(curved, rel=1e-9)
    assert curved > 2 * math.sqrt(ei * w * math.sqrt(1 - cos_i**2) / r)


def test_buckled_intervals_and_lockup_when_sliding(reference_case):
    well = {"survey": [[0, 0, 0], [200, 0, 0], [1100, 90, 0], [1600, 90, 0]], "open_hole_friction": 0.6}
    case = _with_well(reference_case, well, **{"operation.weight_on_bit": 4e5})
    string = string_in_well(case, max_step=10.0)
    critical = critical_loads(string)
    sliding = torque_drag(string, "sliding", cased_friction=0.6, open_hole_friction=0.6,
                          weight_on_bit=4e5, helical=critical["helical"])
    assert buckled_intervals(sliding.measured_depth, sliding.axial_force, critical["helical"])
    depth = lockup_depth(case, [400, 800, 1200, 1600])
    assert depth in (800, 1200, 1600)
    shallower = string_in_well(case, bit_depth=depth - 400, max_step=10.0)
    assert torque_drag(shallower, "sliding", cased_friction=0.6, open_hole_friction=0.6, weight_on_bit=4e5,
                       helical=critical_loads(shallower)["helical"]).hook_load > 0.0
    frictionless = _with_well(reference_case, {**well, "open_hole_friction": 0.0, "cased_hole_friction": 0.0},
                              **{"operation.weight_on_bit": 5e4})
    assert lockup_depth(frictionless, [400, 800, 1200, 1600]) is None


def test_bad_arguments(reference_case):
    string = string_in_well(reference_case, max_step=100.0)
    with pytest.raises(ValueError, match="operation = 'jarring'"):
        torque_drag(string, "jarring", cased_friction=0.2, open_hole_friction=0.2)
    with pytest.raises(ValueError, match="weight_on_bit = -1"):
        torque_drag(string, "drilling", cased_friction=0.2, open_hole_friction=0.2, weight_on_bit=-1.0)
    with pytest.raises(ValueError, match="bit_depth = 2000"):
        string_in_well(reference_case, bit_depth=2000.0)


# --- buoyancy follows the steel's volume, tool joints included (Archimedes) -----------------------------------

_JOINTED = {"name": "jointed", "materials": {"steel": {"young_modulus": 207e9, "density": 7850.0,
                                                       "poisson_ratio": 0.3}},
            "components": [
                {"type": "drill_pipe", "length": 1500.0, "outer_diameter": 0.127, "inner_diameter": 0.1086,
                 "tool_joint": {"outer_diameter": 0.168, "inner_diameter": 0.0826, "length": 0.5, "spacing": 9.144}},
                {"type": "collar", "length": 100.0, "outer_diameter": 0.165, "inner_diameter": 0.0714}],
            "borehole": {"diameter": 0.216}, "fluid": {"density": 1250.0}, "operation": {"weight_on_bit": 50e3},
            "model": {"buoyancy": True}}


def _tube(outer, inner):
    return math.pi / 4 * (outer**2 - inner**2)


def test_a_vertical_jointed_string_weighs_its_steel_less_the_mud_it_displaces():
    """Hook load of a vertical string = (rho_s - rho_m) g V_steel, V_steel the pipe body's and the tool joints'
    steel, computed here from the component data alone; the statics' weight is the same number."""
    from drillstring.constants import STANDARD_GRAVITY as g

    case = case_from_dict(_JOINTED)
    rho_s, rho_m = 7850.0, 1250.0
    body = _tube(0.127, 0.1086)
    joint_extra = (_tube(0.168, 0.0826) - body) * 0.5 / 9.144  # steel per metre of pipe beyond the body
    steel_volume = (body + joint_extra) * 1500.0 + _tube(0.165, 0.0714) * 100.0
    expected = (rho_s - rho_m) * g * steel_volume
    assert case.weight == pytest.approx(expected, rel=1e-12)
    assert case_static_state(case).weight == pytest.approx(expected, rel=1e-9)
    results = case_torque_drag(case)
    for op in ("trip_out", "trip_in", "rotating_off_bottom"):
        assert results[op].hook_load == pytest.approx(expected, rel=1e-12)
    # at the free bit the effective tension is 0 and the steel's -p (A_o - A_i), the mud pressure on the collar's end
    assert results["trip_out"].true_axial_force[-1] == pytest.approx(-rho_m * g * 1600.0 * _tube(0.165, 0.0714),
                                                                     rel=1e-9)


def _minimum_curvature_tvd(md, inc, azi):
    """TVD at any measured depth of a survey by the minimum-curvature method (each course a circular arc),
    written here independently of drillstring.well.survey: on a course of length L and dogleg b from tangent
    t1 to t2, z(u) = z1 + L / (b sin b) [(cos((1 - u) b) - cos b) t1_z + (1 - cos(u b)) t2_z]."""
    def tangent(k):
        return np.array([math.sin(inc[k]) * math.cos(azi[k]), math.sin(inc[k]) * math.sin(azi[k]), math.cos(inc[k])])

    tops = [0.0]
    for k in range(1, len(md)):
        tops.append(tops[-1] + _course_depth(md[k] - md[k - 1], tangent(k - 1), tangent(k), 1.0))

    def tvd(depth):
        k = min(max(int(np.searchsorted(md, depth, side="right")) - 1, 0), len(md) - 2)
        length = md[k + 1] - md[k]
        return tops[k] + _course_depth(length, tangent(k), tangent(k + 1), (depth - md[k]) / length)

    return tvd


def _course_depth(length, t1, t2, u):
    b = math.acos(max(-1.0, min(1.0, float(t1 @ t2))))
    if b < 1e-9:
        return length * u * t1[2]
    return length / (b * math.sin(b)) * ((math.cos((1 - u) * b) - math.cos(b)) * t1[2] + (1 - math.cos(u * b)) * t2[2])


def test_deviated_rotating_hook_loads_against_the_closed_form(deviated):
    """Rotating (no axial friction), the hook load is sum_i w_i (TVD at the section's bottom - at its top), w_i the
    buoyed weight g m_i (1 - rho_m / rho_s) of each section's steel (tool joints' steel included), from the
    case file's components and survey read here; drilling: that less the weight on bit. The old buoyancy
    (mud displaced by the pipe body alone) made these 830.9 and 750.9 kN, 2.8 % high."""
    import drillstring
    from drillstring.constants import STANDARD_GRAVITY as g

    ft, deg, inch = 0.3048, math.pi / 180, 0.0254
    survey = Path(drillstring.__file__).parent / "cases" / "deviated_survey.csv"
    rows = np.array([[float(x) for x in line.split(",")] for line in survey.read_text().splitlines()
                     if line[:1].isdigit()])
    tvd = _minimum_curvature_tvd(rows[:, 0] * ft, rows[:, 1] * deg, rows[:, 2] * deg)
    rho_s, rho_m = 7850.0, 10.4 * 119.826427
    dp, hw = _tube(5 * inch, 4.276 * inch), _tube(5 * inch, 3 * inch)
    mass = [  # (length [m], mass per length [kg/m]) from the top
        (2610.0, rho_s * (dp + (_tube(6.625 * inch, 3.25 * inch) - dp) * 0.5 / (30 * ft))),
        (280.0, rho_s * (hw + (_tube(6.5 * inch, 3 * inch) - hw) * 1.2 / (30 * ft))),
        (110.0, rho_s * _tube(6.5 * inch, 2.8125 * inch))]  # collar 108 m and the 2 m near-bit stabilizer
    top, hook = 0.0, 0.0
    for length, m in mass:
        hook += g * m * (1 - rho_m / rho_s) * (tvd(top + length) - tvd(top))
        top += length
    results = case_torque_drag(deviated)  # default 1 m elements: exact on straight parts, O(h^2) on arcs
    assert results["rotating_off_bottom"].hook_load == pytest.approx(hook, rel=1e-7)  # 3e-8 measured
    assert results["drilling"].hook_load == pytest.approx(hook - 80e3, rel=1e-7)
