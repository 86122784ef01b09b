"""`drillstring static` of a case with [well]: the stiff string along the path and buckling in the deviated hole
(well/buckling.py eq. (3)); a case without [well] keeps the vertical statics."""

import json
import math

import numpy as np
import pytest
from typer.testing import CliRunner

from drillstring import api
from drillstring.buckling import BucklingMargin
from drillstring.case import load_case
from drillstring.cli import app
from drillstring.statics import StaticState
from drillstring.well.buckling import margin_along_path
from drillstring.well.stiff_string import (
    StiffStringState,
    case_stiff_string,
    case_well_buckling_margin,
)

runner = CliRunner()
_ENV = {"COLUMNS": "120", "FORCE_COLOR": None, "TTY_COMPATIBLE": None, "TTY_INTERACTIVE": None,
        "DRILLSTRING_UNITS": None}


@pytest.fixture(scope="module")
def deviated():
    return load_case("deviated")


@pytest.fixture(scope="module")
def stiff(deviated):
    return case_stiff_string(deviated)


def test_static_json_is_the_stiff_strings(deviated, stiff):
    """The JSON of `static deviated`: the stiff string's hook load (727.95 kN, not the vertical 911.59 kN),
    weight on bit, axial force along measured depth, side forces summing to its total, and the well's
    buckling margin as the critical weight on bit."""
    result = runner.invoke(app, ["static", "deviated", "--json"], env=_ENV)
    assert result.exit_code == 0, result.output
    data = json.loads(result.stdout)
    assert data["weight_on_hook"] == data["hook_load"] == stiff.hook_load
    assert data["weight_on_hook"] == pytest.approx(727.95e3, abs=10.0)
    assert data["weight_on_hook"] < data["weight"] - data["weight_on_bit"] - 150e3  # the wall carries the rest
    assert data["weight_on_bit"] == stiff.weight_on_bit == 80e3
    assert np.array_equal(np.array(data["axial_force"]), np.column_stack([stiff.measured_depth, stiff.axial_force]))
    side = np.array(data["side_force"])[:, 1]
    assert math.fsum(side) == pytest.approx(data["total_side_force"], rel=1e-12)
    assert data["max_side_force"] == side.max() and data["max_side_force_measured_depth"] == 2999.0
    margin = case_well_buckling_margin(deviated, stiff)
    assert data["critical_weight_on_bit"] == data["buckling"]["critical_weight_on_bit"] == margin.critical_weight_on_bit
    assert data["buckling"]["buckled"] is False and data["buckling"]["sinusoidal_intervals"] == []


def test_static_table_has_no_vertical_buckled_verdict(stiff):
    """The table: the stiff string's hook load, the side forces, the buckling check in the well; no verdict
    of the vertical string's criterion (74.91 kN, 'BUCKLED' at the case's 80 kN)."""
    result = runner.invoke(app, ["static", "deviated"], env=_ENV)
    assert result.exit_code == 0, result.output
    text = result.stdout
    assert f"{stiff.hook_load / 1e3:,.2f}" in text and "911.59" not in text
    assert "BUCKLED" not in text and "74.91" not in text
    assert "stiff string along the well path" in text and "side force" in text
    assert "sinusoidal buckling in the well" in text and "does not apply in the deviated hole" in text


def test_api_static_selects_the_model_by_well():
    """api.static: the vertical statics and the straight string's margin without [well], the stiff string and
    the margin along the path with it."""
    state, margin = api.static("reference")
    assert type(state) is StaticState and type(margin) is BucklingMargin
    state, margin = api.static("deviated")
    assert isinstance(state, StiffStringState) and margin.critical_weight_on_bit > margin.weight_on_bit
    assert state.weight_on_hook == state.hook_load
    assert state.neutral_point_height == state.static_state().neutral_point_height


def test_critical_weight_on_bit_is_where_the_stiff_string_reaches_the_critical_load(deviated, stiff):
    """Eq. (3): the stiff string solved again at the predicted critical weight on bit (362.3 kN, at the drill
    pipe above the heavy-weight pipe) has its compression at the sinusoidal critical load there: reserve
    0.11 N measured, within 50 N (the stiff string's axial force is not exactly shifted by the weight on bit);
    5 kN less it is not buckled, 5 kN more it is, at that depth."""
    margin = case_well_buckling_margin(deviated, stiff)
    assert 300e3 < margin.critical_weight_on_bit < margin.helical_weight_on_bit
    at = case_well_buckling_margin(deviated, case_stiff_string(deviated,
                                                                 weight_on_bit=margin.critical_weight_on_bit))
    assert at.margin == pytest.approx(0.0, abs=50.0)
    assert at.critical_measured_depth == margin.critical_measured_depth
    below = case_well_buckling_margin(deviated, case_stiff_string(
        deviated, weight_on_bit=margin.critical_weight_on_bit - 5e3))
    above = case_well_buckling_margin(deviated, case_stiff_string(
        deviated, weight_on_bit=margin.critical_weight_on_bit + 5e3))
    assert not below.buckled and above.buckled
    (top, bottom), = above.sinusoidal_intervals
    assert top <= margin.critical_measured_depth <= bottom


def test_margin_along_a_straight_inclined_hole_is_the_dawson_paslay_load():
    """A uniform pipe in a straight inclined hole: critical compression C_s the same everywhere and the
    compression largest at the bit, so the critical weight on bit is C_s itself, reached at the bit, whatever
    the state's weight on bit; above it the bottom interval is buckled."""
    md = np.linspace(0.0, 1000.0, 101)
    w_axial, critical = 200.0, {"sinusoidal": np.full(101, 60e3), "helical": np.full(101, 85e3)}
    for wob in (10e3, 70e3, 90e3):
        force = w_axial * (md[-1] - md) - wob
        margin = margin_along_path(md, force, critical, weight_on_bit=wob, weight=w_axial * 1000.0)
        assert margin.critical_weight_on_bit == pytest.approx(60e3, rel=1e-12)
        assert margin.helical_weight_on_bit == pytest.approx(85e3, rel=1e-12)
        assert margin.critical_measured_depth == 1000.0
        assert margin.buckled == (wob > 60e3) and bool(margin.helical_intervals) == (wob > 85e3)
        if margin.buckled:
            assert margin.sinusoidal_intervals[0][1] == 1000.0
            assert margin.sinusoidal_intervals[0][0] == pytest.approx(1000.0 - (wob - 60e3) / w_axial, abs=10.0)


def test_studies_and_maps_compare_with_the_wells_critical_weight_on_bit(deviated, stiff):
    """The critical weight-on-bit of a study or a map: the straight string's without [well] (unchanged), the
    well path's with it (362.3 kN for `deviated`, against the vertical string's 74.9 kN); the study names the
    criterion only for a well, and its default weight-on-hook law (σ 5 kN around 80 kN on bit) gives no
    warning: 282 kN of margin is 56 σ."""
    from drillstring.api.studies import study_settings
    from drillstring.buckling import case_buckling_margin, case_critical_weight_on_bit
    from drillstring.stochastic.montecarlo import (
        WELL_BUCKLING_CRITERION,
        study_buckling_margin,
    )

    reference = load_case("reference")
    assert case_critical_weight_on_bit(reference) == case_buckling_margin(reference).critical_weight_on_bit
    assert "criterion" not in study_buckling_margin(reference, study_settings(reference, samples=2)[0])
    well = case_well_buckling_margin(deviated, stiff).critical_weight_on_bit
    assert case_critical_weight_on_bit(deviated) == well
    assert case_buckling_margin(deviated).critical_weight_on_bit < 80e3 < well  # the vertical verdict: buckled
    buckling = study_buckling_margin(deviated, study_settings(deviated, samples=2)[0])
    assert buckling["critical_weight_on_bit"] == well and buckling["criterion"] == WELL_BUCKLING_CRITERION
    assert buckling["probability"] < 1e-12 and buckling["warning"] is None
