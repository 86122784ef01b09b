"""`drillstring torque-drag`: JSON, figures, calibration, bad input."""

import json
from importlib import resources

import pytest
from typer.testing import CliRunner

from drillstring.cli import app

runner = CliRunner()
_ENV = {"COLUMNS": "120", "FORCE_COLOR": None, "DRILLSTRING_UNITS": None}


def _case_file(folder, well: str):
    text = resources.files("drillstring").joinpath("cases", "reference.toml").read_text(encoding="utf-8")
    text = text.replace("buoyancy = false", "buoyancy = true")
    path = folder / "well.toml"
    path.write_text(text + "\n[well]\n" + well, encoding="utf-8")
    return path


_WELL = 'survey = [[0, 0, 0], [300, 0, 0], [900, 45, 20], [1650, 45, 20]]\ncasing_shoe = "600 m"\n'


def test_json_operations_and_profiles(tmp_path):
    case = _case_file(tmp_path, _WELL)
    result = runner.invoke(app, ["torque-drag", str(case), "--json"], env=_ENV)
    assert result.exit_code == 0, result.output
    data = json.loads(result.stdout)
    assert set(data["operations"]) == {"trip_out", "trip_in", "rotating_off_bottom", "sliding", "drilling"}
    ops = data["operations"]
    assert ops["trip_out"]["hook_load"] > ops["rotating_off_bottom"]["hook_load"] > ops["trip_in"]["hook_load"]
    # no torque on bit given: the weight on bit lowers the tension around the build, hence its side force
    assert ops["rotating_off_bottom"]["surface_torque"] > ops["drilling"]["surface_torque"] > 0
    profile = ops["drilling"]["profile"]
    assert set(profile) == {"measured_depth", "axial_force", "torque", "side_force"}
    assert profile["measured_depth"][0] == 0.0 and profile["measured_depth"][-1] == 1600.0
    assert profile["axial_force"][-1] == pytest.approx(-1e5)
    assert data["well"]["stations"] == 4


def test_figures_and_calibration(tmp_path):
    case = _case_file(tmp_path, _WELL)
    measured = tmp_path / "hook.csv"
    measured.write_text("bit_depth [m],operation,hook_load [kN]\n800,trip_out,560\n800,trip_in,505\n"
                        "1600,trip_out,1010\n1600,trip_in,840\n1200,trip_out,800\n1200,trip_in,680\n")
    plot = tmp_path / "td.png"
    result = runner.invoke(app, ["torque-drag", str(case), "--plot", str(plot), "--measurements", str(measured),
                                 "--sigma", "10 kN", "--html", str(tmp_path / "td.html"), "--units", "field"],
                           env=_ENV)
    assert result.exit_code == 0, result.output
    for name in ("td.png", "td-path.png", "td-broomstick.png", "td.html"):
        assert (tmp_path / name).stat().st_size > 10_000
    assert "Calibrated friction factors" in result.stdout and "klbf" in result.stdout
    assert "scatter3d" in (tmp_path / "td.html").read_text()


@pytest.mark.parametrize("well, expected", [
    ('survey = [[0, 0, 0], [900, 45, 20], [800, 45, 20], [1700, 45, 20]]\n',
     "well.survey[2] = [800, 45, 20]: measured depth 800 m is less than the previous row's (900 m)"),
    ('survey = [[0, 0, 0], [900, 45, 20]]\n', "the string is 1600 m long, longer than the well"),
])
def test_bad_survey_exits_2_with_one_line(tmp_path, well, expected):
    result = runner.invoke(app, ["torque-drag", str(_case_file(tmp_path, well))], env=_ENV)
    assert result.exit_code == 2
    assert expected in result.output and "Traceback" not in result.output
    assert len([line for line in result.output.splitlines() if "well." in line]) == 1


def test_bad_measurements_file(tmp_path):
    bad = tmp_path / "m.csv"
    bad.write_text("bit_depth [m],operation,hook_load [kN]\n800,jarring,560\n")
    result = runner.invoke(app, ["torque-drag", str(_case_file(tmp_path, _WELL)), "--measurements", str(bad)],
                           env=_ENV)
    assert result.exit_code == 2 and "operation = 'jarring'" in result.output


@pytest.mark.parametrize("sigma", ["-5 kN", "5 m"])
def test_bad_sigma(tmp_path, sigma):
    measured = tmp_path / "m.csv"
    measured.write_text("bit_depth [m],operation,hook_load [kN]\n800,trip_out,560\n")
    result = runner.invoke(app, ["torque-drag", str(_case_file(tmp_path, _WELL)), "--measurements", str(measured),
                                 "--sigma", sigma], env=_ENV)
    assert result.exit_code == 2 and "--sigma" in result.output and "Traceback" not in result.output


def _html_specs(page):
    import re

    text = page.read_text(encoding="utf-8")
    specs = [json.loads(s) for s in re.findall(r'class="figure-spec"[^>]*>(.*?)</script>', text, re.S)]
    return text, specs


def test_html_page_is_the_report_with_every_panel_of_the_png(tmp_path):
    """The page has the report's style and sections, the 3-D path at full height, the three panels of the PNG
    (axial force, torque, side force) in its colours, no legend entry plotly.js cannot draw; the command names
    its files one a line."""
    from matplotlib.colors import to_hex

    from drillstring.outputs.torque_drag_plots import _COLORS

    case = _case_file(tmp_path, _WELL)
    page = tmp_path / "td.html"
    result = runner.invoke(app, ["torque-drag", str(case), "--html", str(page), "--plot", str(tmp_path / "td.png")],
                           env=_ENV)
    assert result.exit_code == 0, result.output
    lines = result.stdout.splitlines()
    assert f"figure: {tmp_path / 'td.png'}" in lines and f"figure: {tmp_path / 'td-broomstick.png'}" in lines
    assert f"interactive page: {page}" in lines
    assert "[" not in "".join(line for line in lines if "figure" in line)  # no Python list
    text, specs = _html_specs(page)
    assert "font-family: system-ui" in text and "<h2>Case</h2>" in text and "<h2>Loads</h2>" in text
    assert [s["layout"]["title"]["text"] for s in specs] == ["Well path", "Effective axial force", "Torque",
                                                             "Side force"]
    height = specs[0]["layout"]["height"]
    assert f'id="figure-0" style="height: {height}px"' in text  # the element as tall as the 3-D figure
    for spec in specs:
        for trace in spec["data"]:
            if isinstance(trace.get("line", {}).get("color"), list):
                assert trace["showlegend"] is False  # an array colour in a legend: "Invalid color specifier"
    names = {"trip out": "trip_out", "trip in": "trip_in", "rotating off bottom": "rotating_off_bottom",
             "sliding": "sliding", "drilling": "drilling"}
    for spec in specs[1:]:
        for trace in spec["data"]:
            if trace["name"] in names:
                assert trace["line"]["color"] == to_hex(_COLORS[names[trace["name"]]])
    axial, torque, side = specs[1:]
    assert {t["name"] for t in torque["data"]} == {"rotating off bottom", "drilling"}  # the PNG's torque panel
    assert {"sinusoidal buckling", "helical buckling"} <= {t["name"] for t in axial["data"]}
    assert len(side["data"]) == 5
