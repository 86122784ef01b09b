"""Campbell diagram (drillstring.critical_speeds): against the exact spinning Timoshenko shaft, the modes of the
prestressed string at rest, and the exact crossings of constant curves."""

import json
import math

import numpy as np
import pytest
from scipy.optimize import brentq

from drillstring.critical_speeds import (
    BHA_SHARE, campbell_diagram, case_campbell, turned_plane,
)
from drillstring.fem.fluid import FluidCoefficients
from drillstring.fem.mesh import build_mesh
from drillstring.modal import build_linear_system, case_linear_system, compute_modes, family_modes
from drillstring.statics import case_static_state, solve_statics
from exact_solutions import spinning_timoshenko_whirl

RPM = 2.0 * math.pi / 60.0  # rad/s per rpm
LENGTH = 4.0


@pytest.fixture
def shaft(drill_collar):
    """A 4 m pinned–pinned drill collar, no prestress, no fluid, no stabilizer, 32 elements."""
    mesh = build_mesh([LENGTH], [drill_collar], LENGTH / 32)
    static = solve_statics(mesh, [0.0], 0.0)
    return build_linear_system(mesh, static, [], [FluidCoefficients(0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0)])


def _exact(section, mode, spin):
    return spinning_timoshenko_whirl(mode, LENGTH, section.bending_stiffness, section.mass_per_length,
                                     section.density * section.second_moment, section.density * section.polar_moment,
                                     section.shear_stiffness, spin)


def test_spinning_shaft_campbell_diagram_against_exact_solution(shaft, drill_collar):
    """Forward and backward whirl of the first two modes up to 5000 rad/s equal the exact Timoshenko values to
    1e-4 (the finite-element discretisation error); forward rises, backward falls (split 12 % at 5000 rad/s)."""
    speeds = [0.0, 1000.0, 2000.0, 5000.0]
    diagram = campbell_diagram(shaft, speeds, (1,), max_frequency=2000.0, lateral_basis=64)
    for mode in (1, 2):
        forward = diagram.curve("lateral", mode, "forward").frequencies * 2 * math.pi
        backward = diagram.curve("lateral", mode, "backward").frequencies * 2 * math.pi
        exact = np.array([_exact(drill_collar, mode, s) for s in speeds])
        np.testing.assert_allclose(forward, exact[:, 0], rtol=1e-4)
        np.testing.assert_allclose(backward, exact[:, 1], rtol=1e-4)
        assert np.all(np.diff(forward) > 0) and np.all(np.diff(backward) < 0)
    forward, backward = (diagram.curve("lateral", 1, whirl).frequencies[-1] for whirl in ("forward", "backward"))
    assert forward / backward - 1 > 0.1


def test_spinning_shaft_critical_speed_against_exact_solution(shaft, drill_collar):
    """The 1× line crosses the first forward whirl where the exact ω_f(Ω) = Ω, and the first backward whirl where
    ω_b(Ω) = Ω: found on a 21-speed grid (linear interpolation between speeds 20 rad/s apart) to 2e-5; measured
    2.8e-6 for both, the finite-element error of the frequencies themselves."""
    speeds = np.linspace(0.0, 400.0, 21)
    diagram = campbell_diagram(shaft, speeds, (1,), max_frequency=100.0)
    for whirl, column in (("forward", 0), ("backward", 1)):
        exact = brentq(lambda s: _exact(drill_collar, 1, s)[column] - s, 50.0, 400.0, xtol=1e-10)
        found = [c for c in diagram.critical_speeds if (c.family, c.mode, c.whirl) == ("lateral", 1, whirl)]
        assert len(found) == 1
        assert found[0].speed == pytest.approx(exact, rel=2e-5)
        assert found[0].frequency == pytest.approx(exact / (2 * math.pi), rel=2e-5)
    assert [c.whirl for c in diagram.critical_speeds] == ["backward", "forward"]  # backward crosses first


def test_turned_plane_carries_the_modes_of_one_plane_to_the_other(shaft):
    """The z-plane shapes built from the y-plane ones (w = v, θy = −θz) are z-plane modes: same frequencies; the
    gyroscopic coupling between the two sets is symmetric."""
    y = family_modes(shaft, "lateral_y", 5)
    z = turned_plane(shaft.mesh, y.shapes)
    k = z.T @ (shaft.stiffness @ z)
    m = z.T @ (shaft.mass @ z)
    np.testing.assert_allclose(m, np.eye(5), atol=1e-10)
    np.testing.assert_allclose(np.diag(k), y.eigenvalues, rtol=1e-10)
    # the plane coupling H = Φ_yᵀ G Φ_z of the whirl problem is symmetric (the module's formulation needs it)
    from drillstring.fem.assembly import gyroscopic_matrix

    h = y.shapes.T @ (gyroscopic_matrix(shaft.mesh) @ z)
    assert np.abs(h - h.T).max() < 1e-12 * np.abs(h).max()


@pytest.fixture(scope="module")
def reference_diagram(reference_case):
    system = case_linear_system(reference_case, case_static_state(reference_case))
    speeds = np.array([0.0, 50.0, 100.0, 150.0]) * RPM
    diagram = campbell_diagram(system, speeds, (1, 3), operating_speed=reference_case.operation.top_speed,
                               max_frequency=1.0)
    return system, diagram


def test_reference_diagram_at_rest_is_the_modes_of_the_prestressed_string(reference_diagram):
    """At Ω = 0 every curve is a natural frequency of `drillstring modes` (prestress and fluid included), every
    mode below the highest frequency is there, and the forward and backward whirl coincide."""
    system, diagram = reference_diagram
    modes = compute_modes(system, axial=5, torsional=5, lateral=80)
    for family, found in (("axial", modes.axial), ("torsional", modes.torsional), ("lateral", modes.lateral)):
        expected = found.frequencies[found.frequencies <= diagram.max_frequency]
        for whirl in (("forward", "backward") if family == "lateral" else ("",)):
            curves = [c for c in diagram.curves if c.family == family and c.whirl == whirl]
            at_rest = np.array([c.frequencies[0] for c in curves if c.frequencies[0] <= diagram.max_frequency])
            np.testing.assert_allclose(at_rest, expected, rtol=1e-9, atol=1e-12)
    assert len(expected) > 20  # many lateral modes below 1 Hz on a 1600 m string


def test_reference_diagram_families_and_gyroscopic_split(reference_diagram):
    """Axial and torsional curves are flat; the gyroscopic split of the lateral pairs grows with the speed,
    forward above backward, and stays below 1e-3 at 150 rpm (the split measured in tests/fem/test_assembly.py
    at 100 rpm is < 3e-4)."""
    _, diagram = reference_diagram
    for c in diagram.curves:
        if c.family != "lateral":
            assert np.all(c.frequencies == c.frequencies[0])
    lateral = [(diagram.curve("lateral", j, "forward"), diagram.curve("lateral", j, "backward")) for j in range(1, 11)]
    for forward, backward in lateral:
        split = (forward.frequencies - backward.frequencies) / forward.frequencies[0]
        assert split[0] == pytest.approx(0.0, abs=1e-9)
        assert np.all(np.diff(split) > 0) and split[-1] < 1e-3
        assert forward.bha_energy_share == backward.bha_energy_share
        assert 0.0 <= forward.bha_energy_share <= 1.0
    shares = [c.bha_energy_share for c in diagram.curves if c.family == "lateral"]
    assert min(shares) < 0.1 and max(shares) > 0.9  # both drill-pipe and BHA modes


def test_reference_critical_speeds_of_constant_curves_are_exact(reference_diagram):
    """For the flat axial and torsional curves the crossing of line k is exactly Ω = 2πf/k; every listed crossing
    lies on its line, inside the speed range."""
    _, diagram = reference_diagram
    torsional_1 = diagram.curve("torsional", 1).frequencies[0]
    crossings = {(c.family, c.mode, c.order): c for c in diagram.critical_speeds if c.family != "lateral"}
    assert crossings[("torsional", 1, 1)].speed == 2 * math.pi * torsional_1
    assert crossings[("torsional", 1, 3)].speed == pytest.approx(2 * math.pi * torsional_1 / 3, rel=1e-15)
    for c in diagram.critical_speeds:
        assert c.frequency == pytest.approx(c.order * c.speed / (2 * math.pi), rel=1e-12)
        assert diagram.speeds[0] <= c.speed <= diagram.speeds[-1]
    speeds = [c.speed for c in diagram.critical_speeds]
    assert speeds == sorted(speeds)


def test_buckled_string_leaves_out_its_unstable_mode_and_keeps_the_numbers(reference_case):
    """At 130 kN (beyond the critical 114 kN) the lowest lateral mode has ω² < 0: it has no whirl frequency, is
    left out with a note, and the other curves keep the numbers and (at rest) the frequencies of `modes`."""
    system = case_linear_system(reference_case, case_static_state(reference_case, weight_on_bit=130e3))
    diagram = campbell_diagram(system, [0.0, 10 * RPM], (1,), max_frequency=0.5)
    modes = compute_modes(system, axial=1, torsional=1, lateral=10).lateral.frequencies
    assert modes[0] < 0 < modes[1]
    assert len(diagram.notes) == 1 and diagram.notes[0].startswith("BUCKLED: 1 lateral mode(s)")
    lateral = [c for c in diagram.curves if c.family == "lateral" and c.whirl == "forward"]
    assert lateral[0].mode == 2
    np.testing.assert_allclose([c.frequencies[0] for c in lateral[:9]], modes[1:10], rtol=1e-9)
    assert diagram.to_dict()["notes"] == list(diagram.notes)


def test_one_section_string_is_all_bha(shaft):
    diagram = campbell_diagram(shaft, [0.0, 100.0], (1,), max_frequency=500.0)
    assert {c.bha_energy_share for c in diagram.curves if c.family == "lateral"} == {1.0}
    assert BHA_SHARE == 0.5


def test_campbell_rejects_bad_input(shaft):
    with pytest.raises(ValueError, match="speeds"):
        campbell_diagram(shaft, [-1.0, 10.0])
    with pytest.raises(ValueError, match="orders"):
        campbell_diagram(shaft, [1.0, 10.0], (0,))


def test_api_campbell_parses_speeds_and_blades(reference_case):
    import drillstring

    diagram = drillstring.campbell(reference_case, top_speed="6 rpm:12 rpm:3", blades=2)
    np.testing.assert_allclose(diagram.speeds, np.array([6.0, 9.0, 12.0]) * RPM)
    assert diagram.orders == (1, 2)
    assert diagram.operating_speed == pytest.approx(100 * RPM)
    assert diagram.max_frequency == pytest.approx(0.4)
    with pytest.raises(ValueError, match=r"^blades = 0: must be an integer in \[1, 24\]$"):
        drillstring.campbell(reference_case, blades=0)
    with pytest.raises(TypeError, match=r"^blades = 3.0: must be an integer, not float$"):
        drillstring.campbell(reference_case, blades=3.0)
    with pytest.raises(ValueError, match="top_speed"):
        drillstring.campbell(reference_case, top_speed="0:10:2")


def test_cli_campbell_json_table_plot_and_errors(tmp_path):
    from typer.testing import CliRunner

    from drillstring.cli import app

    runner = CliRunner()
    figure = tmp_path / "campbell.png"
    result = runner.invoke(app, ["campbell", "reference", "--top-speed", "10:20:5", "--blades", "1",
                                 "--plot", str(figure), "--json"])
    assert result.exit_code == 0, result.output
    payload = json.loads(result.stdout)
    assert payload["orders"] == [1] and len(payload["speeds"]) == 5
    assert payload["figure"] == str(figure) and figure.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    families = {c["family"] for c in payload["curves"]}
    assert families == {"axial", "torsional", "lateral"}
    assert {c["whirl"] for c in payload["curves"] if c["family"] == "lateral"} == {"forward", "backward"}
    torsional = [c for c in payload["critical_speeds"] if c["family"] == "torsional"]
    assert torsional and all(10 * RPM <= c["speed"] <= 20 * RPM for c in torsional)

    table = runner.invoke(app, ["campbell", "reference", "--top-speed", "10:20:5", "--blades", "1"])
    assert table.exit_code == 0, table.output
    assert "Critical speeds" in table.stdout and "Operating speed 100.0 rpm" in table.stdout
    # rpm and Hz in both unit systems: --units field is accepted and changes nothing; a bad system is refused.
    field = runner.invoke(app, ["campbell", "reference", "--top-speed", "10:20:5", "--blades", "1", "--units", "field"])
    assert field.exit_code == 0 and field.stdout == table.stdout
    bad = runner.invoke(app, ["campbell", "reference", "--units", "imperial"])
    said = " ".join(bad.output.replace("│", " ").split())  # the error box wraps at the terminal's width
    assert bad.exit_code == 2 and "--units = 'imperial': must be one of si, field" in said

    bad = runner.invoke(app, ["campbell", "reference", "--blades", "0"])
    assert bad.exit_code == 2 and "--blades = 0: must be an integer in [1, 24]" in bad.output
    bad = runner.invoke(app, ["campbell", "reference", "--top-speed", "10:5"])
    assert bad.exit_code == 2 and "--top-speed = '10:5'" in bad.output


def test_docs_table_of_the_reference_critical_speeds_is_the_command_s(reference_case):
    """docs/campbell.md lists the reference case's critical speeds (default speeds and lines): each row is a
    crossing the code finds, to the table's rounding, and every BHA, axial and torsional crossing is a row."""
    import re
    from pathlib import Path

    text = (Path(__file__).resolve().parents[1] / "docs" / "campbell.md").read_text(encoding="utf-8")
    block = text.split("<!-- reference critical speeds: begin -->")[1]
    block = block.split("<!-- reference critical speeds: end -->")[0]
    rows = [[cell.strip() for cell in line.strip("|").split("|")] for line in block.strip().splitlines()[2:]]
    diagram = case_campbell(reference_case, np.linspace(5.0, 300.0, 60) * RPM)
    found = {}
    for c in diagram.critical_speeds:
        if c.family != "lateral" or c.bha_energy_share >= BHA_SHARE:
            found[(f"{c.order}×", c.family, str(c.mode), c.whirl or "forward")] = c
    assert len(rows) == len({key[:3] for key in found})
    for line, family, mode, frequency, speed, backward, share in rows:
        forward = found[(line, family, mode, "forward")]
        assert f"{forward.frequency:.3f}" == frequency and f"{forward.speed / RPM:.1f}" == speed
        if family == "lateral":
            assert f"{found[(line, family, mode, 'backward')].speed / RPM:.1f}" == backward
            assert f"{forward.bha_energy_share:.0%}" == share
        assert re.fullmatch(r"\d+×", line)


def test_interpolated_whirl_equals_the_exact_roots_at_every_speed(reference_case):
    """The reference string's lateral whirl over 400 speeds, solved exactly at a few speeds and interpolated
    in between (checked Hermite interpolation), equals the exact roots (each speed solved) at 25 speeds drawn
    at random to 1e-9 of the largest root, and needs far fewer exact solutions than speeds."""
    from drillstring.critical_speeds import _whirl_roots, lateral_whirl
    from drillstring.fem.assembly import gyroscopic_matrix

    system = case_linear_system(reference_case, case_static_state(reference_case))
    basis = 60
    speeds = np.linspace(5.0, 300.0, 400) * RPM
    solutions = []
    forward, backward, _, lam = lateral_whirl(system, speeds, basis,
                                              progress=lambda done, total: solutions.append((done, total)))
    assert solutions[-1][1] == 400 and 9 <= solutions[-1][0] <= 60
    found = family_modes(system, "lateral_y", basis)
    h = found.shapes.T @ (gyroscopic_matrix(system.mesh) @ turned_plane(system.mesh, found.shapes))
    h = 0.5 * (h + h.T)
    for i in np.random.default_rng(1).choice(400, 25, replace=False):
        exact_forward, _, exact_backward, _ = _whirl_roots(np.sqrt(lam), h, speeds[i])
        assert np.abs(forward[i] - exact_forward).max() <= 1e-9 * np.sqrt(lam.max())
        assert np.abs(backward[i] - exact_backward).max() <= 1e-9 * np.sqrt(lam.max())
    # The slopes are the roots' own: a finite difference of the exact roots agrees with them.
    step = 1e-3
    f0, df0, b0, db0 = _whirl_roots(np.sqrt(lam), h, 10.0)
    f1, _, b1, _ = _whirl_roots(np.sqrt(lam), h, 10.0 + step)
    np.testing.assert_allclose((f1 - f0) / step, df0, rtol=1e-4, atol=1e-9)
    np.testing.assert_allclose((b1 - b0) / step, db0, rtol=1e-4, atol=1e-9)


def test_too_many_speeds_refused_before_any_work(reference_case, monkeypatch):
    import drillstring
    from drillstring import critical_speeds

    def no_work(*args, **kwargs):
        raise AssertionError("the system was built")

    monkeypatch.setattr("drillstring.modal.case_linear_system", no_work)
    with pytest.raises(ValueError, match=r"^top_speed = '5:300:100000': 100,000 speeds, more than the 10,000"):
        drillstring.campbell(reference_case, top_speed="5:300:100000", default_unit="rpm")
    with pytest.raises(ValueError, match="20,000 speeds"):
        critical_speeds.case_campbell(reference_case, np.linspace(1.0, 30.0, 20_000))
