"""The command line: JSON payloads (SI), human-readable tables (units), user case files, errors."""

import json
from importlib import resources

import pytest
from typer.testing import CliRunner

from drillstring.cli import app

runner = CliRunner()

REFERENCE_WEIGHT = 1.1634e6  # N (SPEC §10)
REFERENCE_WOH = 1.0634e6  # N
REFERENCE_WOB = 1e5  # N
REFERENCE_LENGTH = 1600.0  # m


# Plain, wide, uncoloured tables whatever the terminal settings of the machine running the tests.
_ENV = {"COLUMNS": "120", "FORCE_COLOR": None, "TTY_COMPATIBLE": None, "TTY_INTERACTIVE": None}


def _invoke(*args: str):
    return runner.invoke(app, list(args), env=_ENV)


def _json(*args: str):
    result = _invoke(*args)
    assert result.exit_code == 0, result.output
    return json.loads(result.stdout)  # nothing but the JSON on stdout


def _reference_toml() -> str:
    return resources.files("drillstring").joinpath("cases", "reference.toml").read_text(encoding="utf-8")


@pytest.fixture
def heavier_bit_case(tmp_path):
    """A copy of the reference case with 150 kN on the bit instead of 100 kN."""
    text = _reference_toml()
    old = 'weight_on_bit = "100 kN"'
    assert old in text
    path = tmp_path / "heavier_bit.toml"
    path.write_text(text.replace(old, 'weight_on_bit = "150 kN"'), encoding="utf-8")
    return path


# ------------------------------------------------------------------------------------------------- static


def test_static_json_reference():
    data = _json("static", "reference", "--json")
    assert set(data) == {"weight", "weight_on_hook", "weight_on_bit", "neutral_point_height", "axial_force"}
    assert data["weight"] == pytest.approx(REFERENCE_WEIGHT, rel=1e-4)
    assert data["weight_on_hook"] == pytest.approx(REFERENCE_WOH, rel=1e-4)
    assert data["weight_on_bit"] == pytest.approx(REFERENCE_WOB)
    assert 35.0 < data["neutral_point_height"] < 37.0
    pairs = data["axial_force"]
    assert all(len(p) == 2 for p in pairs)
    xs = [p[0] for p in pairs]
    assert xs == sorted(xs)
    assert pairs[0][0] == 0.0
    assert pairs[0][1] == pytest.approx(data["weight_on_hook"], rel=1e-9)
    assert pairs[-1][0] == pytest.approx(REFERENCE_LENGTH)
    assert pairs[-1][1] == pytest.approx(-REFERENCE_WOB, rel=1e-9)


def test_static_default_case_is_reference():
    assert _json("static", "--json") == _json("static", "reference", "--json")


def test_static_human_readable_has_units_and_summary():
    result = _invoke("static", "reference")
    assert result.exit_code == 0, result.output
    out = result.stdout
    for text in ("kN", "[m]", "[kN]", "weight-on-hook", "1,063.43", "neutral point", "top", "bit", "stabilizer"):
        assert text in out, text
    assert "drill pipe / drill collar" in out
    assert len(out.splitlines()) < 40  # a summary, not the full profile


def test_static_user_case_file(heavier_bit_case):
    reference = _json("static", "reference", "--json")
    data = _json("static", str(heavier_bit_case), "--json")
    assert data["weight"] == pytest.approx(reference["weight"], rel=1e-12)
    assert data["weight_on_bit"] == pytest.approx(150e3)
    assert data["weight_on_hook"] == pytest.approx(reference["weight_on_hook"] - 50e3, rel=1e-9)
    assert data["axial_force"][-1][1] == pytest.approx(-150e3, rel=1e-9)
    assert data["neutral_point_height"] > reference["neutral_point_height"]


# -------------------------------------------------------------------------------------------------- modes


def test_modes_json_reference():
    data = _json("modes", "reference", "--json", "--count", "4")
    assert set(data) == {"axial", "torsional", "lateral"}
    for name in ("axial", "torsional", "lateral"):
        assert len(data[name]) == 4
        assert data[name] == sorted(data[name]), name
    assert data["axial"][0] == 0.0
    assert data["axial"][1] == pytest.approx(1.2006, rel=1e-3)
    assert data["torsional"][0] == pytest.approx(0.2313, rel=1e-3)
    assert data["lateral"][0] > 0.0


def test_modes_default_count_is_ten():
    data = _json("modes", "--json")
    assert [len(v) for v in data.values()] == [10, 10, 10]


def test_modes_human_readable_has_units():
    result = _invoke("modes", "reference", "-n", "3")
    assert result.exit_code == 0, result.output
    for text in ("axial [Hz]", "torsional [Hz]", "lateral [Hz]", "1.2006", "0.2313", "rigid"):
        assert text in result.stdout, text


def test_modes_user_case_file(heavier_bit_case):
    reference = _json("modes", "reference", "--json", "--count", "3")
    data = _json("modes", str(heavier_bit_case), "--json", "--count", "3")
    # Mass and axial stiffness do not depend on the weight-on-bit.
    assert data["axial"] == pytest.approx(reference["axial"], rel=1e-9, abs=1e-12)
    # More compression lowers the lateral frequencies (geometric stiffness).
    assert data["lateral"][0] < reference["lateral"][0]


def test_modes_count_zero_is_refused():
    result = _invoke("modes", "--count", "0")
    assert result.exit_code == 2
    assert "--count" in result.output
    assert result.stdout == ""


# ---------------------------------------------------------------------------------------------- cases, errors


def test_cases_lists_reference():
    result = _invoke("cases")
    assert result.exit_code == 0, result.output
    assert "reference" in result.stdout.split()


def test_invalid_case_file_exit_code_2(tmp_path):
    text = _reference_toml().replace('inner_diameter = "0.0762 m"', 'inner_diameter = "0.3 m"')
    path = tmp_path / "bad.toml"
    path.write_text(text, encoding="utf-8")
    for command in ("static", "modes"):
        result = _invoke(command, str(path), "--json")
        assert result.exit_code == 2, result.output
        assert result.stdout == ""
        assert "sections[1].inner_diameter" in result.stderr
        assert "Traceback" not in result.output
        assert result.exception is None or isinstance(result.exception, SystemExit)


@pytest.mark.parametrize(
    "content, expected",
    [
        ("name = 'x'\nsections = [\n", "TOML syntax error"),
        ("name = 'x'\n[borehole]\ndiameter = '0.3 m'\n", "sections"),
        ("name = 'x'\nbogus_key = 1\n", "bogus_key"),
    ],
)
def test_bad_toml_messages(tmp_path, content, expected):
    path = tmp_path / "case.toml"
    path.write_text(content, encoding="utf-8")
    result = _invoke("static", str(path))
    assert result.exit_code == 2
    assert expected in result.stderr
    assert "Traceback" not in result.output


def test_missing_file_and_unknown_name(tmp_path):
    result = _invoke("static", str(tmp_path / "nowhere.toml"))
    assert result.exit_code == 2
    assert "not found" in result.stderr
    result = _invoke("modes", "no_such_case")
    assert result.exit_code == 2
    assert "reference" in result.stderr  # lists the built-in cases
