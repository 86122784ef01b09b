"""Minimum-curvature well paths against closed forms, the ISCWSA test well #1, and bad surveys."""

import math

import numpy as np
import pytest

from drillstring.case import CaseError, case_from_dict
from drillstring.well.survey import dogleg, ratio_factor, trajectory, wrap_angle

DEG = math.pi / 180.0


def test_vertical_well_is_exact():
    md = np.array([0.0, 123.4, 500.0, 1777.7])
    path = trajectory(md, np.zeros(4), np.zeros(4))
    assert np.array_equal(path.position[:, 2], md)
    assert np.array_equal(path.position[:, :2], np.zeros((4, 2)))
    assert np.array_equal(path.dogleg, np.zeros(3))


def test_constant_build_arc_matches_the_circle():
    rate = 3.0 * DEG / 30.0  # 3 deg/30 m
    radius = 1.0 / rate
    azimuth = 37.0 * DEG
    md = np.concatenate([[0.0], 100.0 + np.arange(0, 61) * 15.0])  # to 90 deg... 100 + 900 m
    inc = np.where(md <= 100.0, 0.0, (md - 100.0) * rate)
    path = trajectory(md, inc, np.full_like(md, azimuth))
    arc = md >= 100.0
    theta = inc[arc]
    horizontal = radius * (1.0 - np.cos(theta))
    assert np.allclose(path.position[arc, 2], 100.0 + radius * np.sin(theta), rtol=0, atol=1e-9)
    assert np.allclose(path.position[arc, 0], horizontal * math.cos(azimuth), rtol=0, atol=1e-9)
    assert np.allclose(path.position[arc, 1], horizontal * math.sin(azimuth), rtol=0, atol=1e-9)
    assert np.allclose(path.dogleg_severity[1:], rate, rtol=1e-12)
    # inside a course: eq. (4) on the same circle; the curvature vector has magnitude 1/R
    s = np.array([107.5, 433.3, 999.9])
    position, tangent, curvature, _ = path.locate(s)
    t = (s - 100.0) * rate
    assert np.allclose(position[:, 2], 100.0 + radius * np.sin(t), atol=1e-9)
    assert np.allclose(np.hypot(position[:, 0], position[:, 1]), radius * (1 - np.cos(t)), atol=1e-9)
    assert np.allclose(tangent[:, 2], np.cos(t), atol=1e-12)
    assert np.allclose(np.linalg.norm(curvature, axis=1), rate, rtol=1e-9)


def test_constant_turn_arc_in_a_horizontal_hole():
    rate = 2.0 * DEG / 30.0
    md = np.arange(0, 41) * 30.0
    az = 10.0 * DEG + md * rate
    path = trajectory(md, np.full_like(md, math.pi / 2), az)
    radius = 1.0 / rate
    assert np.allclose(path.position[:, 0], radius * (np.sin(az) - math.sin(az[0])), atol=1e-9)
    assert np.allclose(path.position[:, 1], radius * (math.cos(az[0]) - np.cos(az)), atol=1e-9)
    assert np.allclose(path.position[:, 2], 0.0, atol=1e-12)
    assert np.allclose(path.turn_rate, rate, rtol=1e-12)
    assert np.allclose(path.build_rate, 0.0)


def _iscwsa_1():
    """ISCWSA test well #1 (Williamson 2000, SPE 67616; the ISCWSA error-model example workbook): vertical to
    1200 m, build 2 deg/30 m at azimuth 75 deg to 60 deg at 2100 m, hold to 5100 m, build 3 deg/30 m to 90 deg
    at 5400 m, hold to 8000 m; stations every 30 m."""
    md = np.append(np.arange(0.0, 8000.0, 30.0), 8000.0)
    inc = np.select([md <= 1200, md <= 2100, md <= 5100, md <= 5400],
                    [0.0, (md - 1200) / 30 * 2, 60.0, 60.0 + (md - 5100) / 30 * 3], 90.0)
    azi = np.where(md <= 1200, 0.0, 75.0)
    return trajectory(md, inc * DEG, azi * DEG)


# Published coordinates of ISCWSA test well #1 (north, east, TVD [m], rounded to 1 mm), as tabulated with the
# ISCWSA's error-model example (reproduced in welleng's tests/ISCWSA_code_ex1.csv).
ISCWSA_1 = {
    1230.0: (0.136, 0.506, 1229.994),
    1500.0: (13.415, 50.064, 1493.945),
    2100.0: (111.219, 415.076, 1944.294),
    3000.0: (312.949, 1167.941, 2394.294),
    5100.0: (783.651, 2924.625, 3444.294),
    5250.0: (819.416, 3058.103, 3501.533),
    5400.0: (857.797, 3201.342, 3521.056),
    8000.0: (1530.727, 5712.749, 3521.056),
}


def test_iscwsa_test_well_1_to_the_published_millimetre():
    path = _iscwsa_1()
    for md, expected in ISCWSA_1.items():
        k = int(np.nonzero(path.measured_depth == md)[0][0])
        assert np.allclose(path.position[k], expected, rtol=0, atol=5.01e-4), (md, path.position[k])


def test_azimuth_across_north_is_a_small_turn():
    md = [0.0, 1000.0, 1030.0, 1060.0]
    across = trajectory(md, [0.0, 30 * DEG, 30 * DEG, 30 * DEG], [0.0, 359.98 * DEG, 0.02 * DEG, 0.06 * DEG])
    rotated = trajectory(md, [0.0, 30 * DEG, 30 * DEG, 30 * DEG], [0.0, 9.98 * DEG, 10.02 * DEG, 10.06 * DEG])
    assert np.allclose(across.dogleg, rotated.dogleg, rtol=1e-9, atol=1e-15)
    assert across.dogleg[1] < 0.04 * DEG * 0.5 + 1e-12  # sin(30 deg) * 0.04 deg, not 359.96 deg
    assert np.allclose(across.turn_rate[1:], 0.04 * DEG / 30.0, rtol=1e-9)
    angle = -10 * DEG  # rotate the second path back about the vertical
    back = rotated.position @ np.array([[math.cos(angle), -math.sin(angle), 0], [math.sin(angle), math.cos(angle), 0],
                                        [0, 0, 1]]).T
    assert np.allclose(across.position, back, atol=1e-9)
    assert wrap_angle(359.96 * DEG) == pytest.approx(-0.04 * DEG)


@pytest.mark.parametrize("inc1, azi1, inc2, azi2, expected", [
    (0.5, 1.0, 0.5 + 1e-8, 1.0, 1e-8),                   # pure build
    (math.pi / 2, 1.0, math.pi / 2, 1.0 + 1e-8, 1e-8),   # pure turn, horizontal
    (0.3, 0.2, 0.3, 0.2, 0.0),                           # straight
])
def test_tiny_doglegs_keep_their_precision(inc1, azi1, inc2, azi2, expected):
    beta = float(dogleg(inc1, azi1, inc2, azi2))
    assert beta == pytest.approx(expected, rel=1e-7, abs=0)
    # arccos of the dot product rounds such a dogleg to 0 or to ~1.5e-8 (cos beta = 1 - 5e-17)
    path = trajectory([0.0, 10.0], [inc1, inc2], [azi1, azi2])
    exact_tvd = 10.0 * (math.cos(inc1) + math.cos(inc2)) / 2.0  # RF = 1 + 8e-18
    assert path.position[1, 2] == pytest.approx(exact_tvd, rel=1e-15)


def test_ratio_factor_series_meets_the_closed_form():
    for b in (1e-3 * (1 - 1e-9), 1e-3 * (1 + 1e-9), 0.3, 2.0):
        assert float(ratio_factor(b)) == pytest.approx(math.tan(b / 2) / (b / 2), rel=1e-15)
    assert float(ratio_factor(0.0)) == 1.0


def test_interpolation_at_stations_equals_the_stations():
    path = _iscwsa_1()
    position, tangent, _, _ = path.locate(path.measured_depth)
    assert np.allclose(position, path.position, atol=1e-9)
    assert np.allclose(tangent, path.tangent, atol=1e-12)


def _case(reference_case, well):
    data = reference_case.model_dump()
    data["well"] = well
    return case_from_dict(data)


def test_stations_in_feet_and_in_metres_agree(reference_case, tmp_path):
    rows_m = [[0.0, 0.0, 0.0], [304.8, 0.0, 0.0], [914.4, 20.0, 45.0], [1828.8, 20.0, 45.0]]
    in_m = _case(reference_case, {"survey": rows_m})
    in_ft = _case(reference_case, {"survey": [[r[0] / 0.3048, r[1], r[2]] for r in rows_m],
                                   "survey_units": ["ft", "deg", "deg"]})
    csv = tmp_path / "survey.csv"
    csv.write_text("measured_depth [ft], inclination [deg], azimuth [rad]\n"
                   + "".join(f"{r[0] / 0.3048!r},{r[1]},{r[2] * DEG!r}\n" for r in rows_m))
    in_csv = _case(reference_case, {"survey_file": str(csv)})
    for other in (in_ft, in_csv):
        assert np.allclose(other.well.measured_depth, in_m.well.measured_depth, rtol=1e-14)
        assert np.allclose(other.well.azimuth, in_m.well.azimuth, rtol=1e-14)
    assert case_from_dict(in_csv.model_dump()) == in_csv  # written back as SI lists


@pytest.mark.parametrize("rows, expected", [
    ([[0, 0, 0], [500, 0, 0], [400, 10, 0], [1700, 10, 0]],
     "well.survey[2] = [400, 10, 0]: measured depth 400 m is less than the previous row's (500 m)"),
    ([[0, 0, 0], [500, 0, 0], [500, 10, 0], [1700, 10, 0]],
     "well.survey[2] = [500, 10, 0]: measured depth 500 m repeats the previous row's"),
    ([[0, 0, 0], [500, 0, 0], [900, 181, 0], [1700, 10, 0]],
     "well.survey[2] = [900, 181, 0]: inclination 181 deg: must be in [0, 180] deg"),
    ([[0, 0, 0], [500, 0, 0], [900, float("nan"), 0], [1700, 10, 0]],
     "well.survey[2] = [900, nan, 0]: inclination missing or not a finite number (a gap in the survey)"),
    ([[0, 0, 0], [500, 0], [1700, 10, 0]],
     "well.survey[1] = [500, 0]: must be three values"),
    ([[100, 0, 0], [1700, 10, 0]],
     "well.survey[0] = [100, 0, 0]: measured depth 100 m: the survey must start at the surface"),
    ([[0, 0, 0], [100, 0, 0], [200, 180, 0], [1700, 180, 0]],
     "well.survey[2] = [200, 180, 0]: turns the hole through 180 deg from the previous row"),
    ([[0, 0, 0], [1500, 10, 0]],
     "well.survey[1] = [1500.0, 10.0, 0.0]: the last station (1500 m) is above the bit: the string is 1600 m"),
])
def test_bad_surveys_name_the_row(reference_case, rows, expected):
    with pytest.raises(CaseError) as error:
        _case(reference_case, {"survey": rows})
    assert len(error.value.problems) == 1
    assert error.value.problems[0].startswith(expected), error.value.problems[0]


def test_bad_csv_row_is_named(reference_case, tmp_path):
    csv = tmp_path / "s.csv"
    csv.write_text("md [m],inc [deg],azi [deg]\n0,0,0\n800,,0\n1700,10,0\n")
    with pytest.raises(CaseError) as error:
        _case(reference_case, {"survey_file": str(csv)})
    assert "well.survey_file[1]" in str(error.value) and "a gap" in str(error.value)
