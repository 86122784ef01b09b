"""`drillstring modes` of a case with [well]: the modes about the stiff string's static state along the well path
(drillstring.well.well_modes), named by family by their kinetic energy, and buckling along the path; a case
without [well] keeps the vertical string's modes (tests/test_cli.py)."""

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from drillstring import api
from drillstring.case import load_case
from drillstring.case.well_table import Well
from drillstring.cli import app
from drillstring.well.well_modes import WELL_MODE_FAMILIES, case_well_modes

runner = CliRunner()
_ENV = {"COLUMNS": "120", "FORCE_COLOR": None, "TTY_COMPATIBLE": None, "TTY_INTERACTIVE": None,
        "DRILLSTRING_UNITS": None}


def _vertical_well(case):
    """``case`` in a vertical hole given as a [well] (a survey of two vertical stations past the bit)."""
    length = sum(section.length for section in case.sections)
    return case.model_copy(update={"well": Well(measured_depth=[0.0, length + 100.0], inclination=[0.0, 0.0],
                                                azimuth=[0.0, 0.0])})


def test_modes_deviated_json_are_well_modes_own():
    """`modes deviated --json`: every listed frequency is one of well_modes' own (the coupled solve about the
    stiff string in the well, `case_well_modes`), the lowest modes of the whole string all listed, each in
    the family holding the largest share of its kinetic energy; buckling along the path, not the vertical
    string's (which says 'BUCKLED' at 80 kN)."""
    count = 4
    result = runner.invoke(app, ["modes", "deviated", "--json", "--count", str(count)], env=_ENV)
    assert result.exit_code == 0, result.output
    data = json.loads(result.stdout)
    own = case_well_modes(load_case("deviated"), 3 * count).eigenvalues
    # ω² compared to the dense solver's round-off, eps × the mesh's largest ω² (2.2e8 rad²/s²) ≈ 5e-8 rad²/s²
    # (measured: 2e-9 rad²/s² between a solve of all modes and one of the 12 lowest)
    close = {"rtol": 1e-9, "atol": 1e-7}
    listed = {name: np.sign(data[name]) * (2 * np.pi * np.array(data[name])) ** 2 for name in WELL_MODE_FAMILIES}
    assert all(len(values) == count for values in listed.values())
    # the whole string's lowest `count` modes each belong to a family that lists `count`: all are listed
    assert np.allclose(np.sort(np.concatenate(list(listed.values())))[:count], own[:count], **close)
    for found in listed.values():  # every listed one within the checked range is one of well_modes'
        below = found[found <= own[-1]]
        assert np.allclose(own[np.argmin(np.abs(own[:, None] - below), axis=0)], below, **close)
    for i, name in enumerate(WELL_MODE_FAMILIES):
        shares = np.array(data["kinetic_energy_share"][name])
        assert np.allclose(shares.sum(axis=1), 1.0) and np.all(np.argmax(shares, axis=1) == i)
    assert data["axial"][0] > 0.0  # the slide along the curved path is not a rigid mode
    assert data["buckling"]["buckled"] is False
    assert data["buckling"]["critical_weight_on_bit"] > 3e5  # along the path; the vertical string's: 74.91 kN


def test_vertical_well_gives_the_vertical_modes(coarse_case):
    """A [well] whose survey is vertical: the stiff string hangs on the axis, every frame is the identity, the
    families uncouple: the same axial, torsional and lateral frequencies as the case without [well] (the
    lateral pairs listed twice). rtol 1e-9: the stiff string's axial force is the vertical statics' to
    round-off (measured difference 1e-11 relative), as in test_well_modes."""
    count = 6
    vertical, _ = api.modes(coarse_case, count=count)
    in_well, margin = api.modes(_vertical_well(coarse_case), count=count)
    assert in_well.axial.frequencies[0] == 0.0  # the rigid translation, exact
    for name in ("axial", "torsional"):
        assert np.allclose(getattr(in_well, name).frequencies, getattr(vertical, name).frequencies,
                           rtol=1e-9, atol=1e-12)
        assert np.all(in_well.shares[name].max(axis=1) > 1.0 - 1e-9)  # one family each
    lateral = in_well.lateral.frequencies
    assert np.allclose(lateral[0::2], vertical.lateral.frequencies[:count // 2], rtol=1e-9)
    assert np.allclose(lateral[1::2], vertical.lateral.frequencies[:count // 2], rtol=1e-9)
    assert hasattr(margin, "sinusoidal_intervals")  # buckling along the path


def test_modes_table_of_a_well_has_no_vertical_verdict(coarse_case, tmp_path):
    """The table of a case with [well]: its title says what the modes are; buckling along the path, no
    verdict of the vertical string's criterion."""
    path = tmp_path / "vertical_well.toml"
    path.write_text(_vertical_well(coarse_case).to_toml(), encoding="utf-8")
    result = runner.invoke(app, ["modes", str(path), "-n", "3"], env=_ENV)
    assert result.exit_code == 0, result.output
    text = " ".join(result.stdout.split())
    assert "about the stiff string's static state along the well path" in text
    assert "The vertical string's lateral buckling criterion does not apply" in text
    assert "the straight string is statically unstable" not in text and "Lateral buckling at" not in text


def test_well_and_motor_are_refused():
    """A case with [well] and [motor]: one line naming both, before any work."""
    with pytest.raises(ValueError, match=r"\[well\] and \[motor\]"):
        api.modes(_vertical_well(load_case("motor")), count=3)
