"""The interactive report (drillstring.interactive): one self-contained offline page per study, map and
sensitivity run, checked in a real headless browser (Chromium): it loads without console messages and draws
every figure."""

import json
import math
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from drillstring import api
from drillstring.interactive import REALIZATIONS_SHOWN, map_figures, sensitivity_figures, study_figures
from drillstring.report import INTERACTIVE_PAGE, write_map_report, write_sensitivity_report

BROWSERS = ("chromium", "chromium-browser", "google-chrome")
#: Flags for a headless run on a machine without network, display or D-Bus.
BROWSER_FLAGS = ("--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                 "--disable-background-networking", "--disable-component-update", "--disable-sync")


def _browser() -> str:
    for name in BROWSERS:
        found = shutil.which(name)
        if found:
            return found
    pytest.skip("no Chromium on this machine (looked for chromium, chromium-browser, google-chrome): install "
                "Debian's package (apt-get install chromium); .ci/run installs it when it can")


def _open_in_browser(page: Path, profile: Path, *extra: str) -> tuple[str, str]:
    """(DOM after the scripts ran, browser log) of ``page`` opened in headless Chromium."""
    profile.mkdir()
    done = subprocess.run(
        [_browser(), *BROWSER_FLAGS, f"--user-data-dir={profile}", "--enable-logging=stderr", "--v=0",
         "--virtual-time-budget=15000", *extra, page.resolve().as_uri()],
        capture_output=True, text=True, timeout=180)
    assert done.returncode == 0, done.stderr[-2000:]
    return done.stdout, done.stderr


def _figure_count(page: Path) -> int:
    return page.read_text(encoding="utf-8").count('class="figure-spec"')


#: What the browser itself logs when it draws WebGL (a 3-D figure) in software, without a GPU: not the page's.
SOFTWARE_WEBGL = ('"Canvas2D: Multiple readback operations', '"[.WebGL-', '"[]Automatic fallback to software WebGL')


def _page_console(log: str) -> list[str]:
    """The console lines of the page's own scripts (the browser's software-WebGL notices left out)."""
    return [line for line in log.splitlines() if ":CONSOLE" in line
            and not any(f'] {notice}' in line for notice in SOFTWARE_WEBGL)]


def _check_rendered(page: Path, profile: Path) -> None:
    """Every figure drawn (plotly.js's SVG in each figure's element, the page's own count), nothing on the
    console (an error, a warning or a log line would be there)."""
    dom, log = _open_in_browser(page, profile, "--dump-dom")
    assert _page_console(log) == []
    count = _figure_count(page)
    assert count > 0
    assert f'data-plots-rendered="{count}"' in dom
    assert "data-plot-error" not in dom
    for k in range(count):
        drawn = re.search(rf'<div class="plot[^"]*" id="figure-{k}".*?class="main-svg"', dom, re.S)
        assert drawn, f"figure {k} has no SVG"
    assert dom.count('class="main-svg"') >= count


def _check_self_contained(page: Path) -> str:
    text = page.read_text(encoding="utf-8")
    assert "<script src" not in text and "<link" not in text and 'src="http' not in text
    assert text.count("<script>") == 2  # plotly.js and the drawing script, both inline
    for spec in re.findall(r'<script type="application/json" class="figure-spec"[^>]*>(.*?)</script>', text, re.S):
        json.loads(spec)  # valid JSON: no NaN, no stray </script>
    return text


# --- a study --------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def study(small_case, tmp_path_factory):
    out = tmp_path_factory.mktemp("interactive") / "study"
    outcome = api.monte_carlo_study(small_case, samples=3, t_end=1.0, workers=1, out=out)
    return out, outcome


def test_study_writes_an_interactive_page_beside_the_static_report(study):
    out, outcome = study
    page = out / INTERACTIVE_PAGE
    assert outcome.files["interactive"] == page
    text = _check_self_contained(page)
    assert f'href="{INTERACTIVE_PAGE}"' in (out / "report.html").read_text(encoding="utf-8")
    assert all((out / f"{name}.png").exists() for name in ("envelopes", "dispersion", "convergence"))
    specs = [json.loads(s) for s in re.findall(r'class="figure-spec"[^>]*>(.*?)</script>', text, re.S)]
    assert len(specs) == 7  # four observables, dispersion, convergence, indicators
    rop = specs[0]["data"]
    realizations = [t for t in rop if t["name"].startswith("realization ")]
    assert [t["name"] for t in realizations] == ["realization 0", "realization 1", "realization 2"]
    assert all(t["visible"] == "legendonly" for t in realizations)  # shown on demand
    stats = outcome.statistics
    mean = next(t for t in rop if t["name"] == "mean")
    np.testing.assert_allclose(mean["y"], stats.rate_of_penetration_mean.values * 3600.0, rtol=1e-5, atol=1e-9)
    assert "Case" in text and "Dispersion of the response" in text  # the report's own sections


def test_study_page_renders_in_a_headless_browser(study, tmp_path):
    out, _ = study
    _check_rendered(out / INTERACTIVE_PAGE, tmp_path / "profile")


def test_screenshot_of_the_study_page(study, tmp_path):
    """A screenshot of the whole page shows the plots drawn: thousands of coloured pixels (lines, envelopes),
    where the page's text and tables alone have a few hundred (its blue links; measured 586 above the figures,
    28,000 on the whole page)."""
    out, _ = study
    shot = tmp_path / "page.png"
    _open_in_browser(out / INTERACTIVE_PAGE, tmp_path / "profile", f"--screenshot={shot}", "--window-size=1400,8000")
    from matplotlib.image import imread

    image = imread(str(shot))[:, :, :3]
    assert image.shape[:2] == (8000, 1400)
    coloured = (image.max(axis=2) - image.min(axis=2)) > 80 / 255
    assert coloured.sum() > 5000


def test_realizations_are_capped():
    from drillstring.interactive import study_figures

    time = np.linspace(0.0, 1.0, 5)
    names = ("rate_of_penetration", "bit_speed", "torque_on_bit", "force_on_bit")
    stats = xr.Dataset({f"{n}_{k}": ("time", np.ones(5)) for n in names for k in
                        ("mean", "lower", "upper", "nominal", "dispersion")}, coords={"time": time})
    raw = xr.Dataset({n: (("realization", "time"), np.ones((30, 5))) for n in names},
                     coords={"time": time, "realization": np.arange(30)})
    figures = study_figures(stats, raw)
    shown = [t for t in figures[0]["data"] if t["name"].startswith("realization")]
    assert len(shown) == REALIZATIONS_SHOWN == 20


# --- a map and a sensitivity analysis (their figures from small stand-in results) ------------------------


@pytest.fixture
def map_dataset():
    speeds = np.array([60.0, 100.0, 140.0]) * 2 * math.pi / 60
    weights = np.array([60e3, 100e3, 140e3])
    grid = np.add.outer(np.arange(3.0), np.arange(3.0))
    status = np.ones((3, 3), dtype=int)
    status[2, 2] = 2  # a failed point: a gap
    variables = {name: (("top_speed", "weight_on_bit"), grid + 1.0) for name in (
        "mean_rate_of_penetration", "bit_speed_oscillation", "mechanical_specific_energy", "max_radial_displacement")}
    variables["growth_rate"] = (("top_speed", "weight_on_bit"), grid - 2.0)
    variables["status"] = (("top_speed", "weight_on_bit"), status)
    return xr.Dataset(variables, coords={"top_speed": speeds, "weight_on_bit": weights},
                      attrs={"critical_weight_on_bit": 114.13e3})


def test_map_figures_carry_the_values_with_gaps(map_dataset):
    figures = map_figures(map_dataset)
    assert len(figures) == 4  # no per-family growth rate in this map: no family figure
    family = map_dataset.assign(torsional_growth_rate=map_dataset.growth_rate - 0.5,
                                lateral_growth_rate=map_dataset.growth_rate * np.nan)
    torsion = map_figures(family)[4:]
    assert len(torsion) == 1 and torsion[0]["data"][0]["zmid"] == 0.0
    assert torsion[0]["data"][0]["z"][0][1] == pytest.approx(1.0 - 2.0 - 0.5)  # z[weight][speed]
    assert any(t["type"] == "contour" for t in torsion[0]["data"])
    heat = figures[0]["data"][0]
    assert heat["x"] == [60.0, 100.0, 140.0] and heat["y"] == [60.0, 100.0, 140.0]
    assert heat["z"][2][2] is None  # failed point
    assert heat["z"][1][0] == pytest.approx((1.0 + 1.0) * 3600.0)  # z[weight][speed]
    assert any(t["type"] == "contour" for t in figures[0]["data"])
    assert figures[0]["layout"]["shapes"][0]["y0"] == pytest.approx(114.13)


def test_map_figures_follow_the_unit_system(map_dataset):
    """In field units: weights-on-bit and the buckling limit in klbf, ROP in ft/h, MSE in psi, displacements in
    in (the SI values over the defining factors: 1 klbf = 4448.2216152605 N, 1 ft = 0.3048 m, 1 psi =
    6894.757293168361 Pa)."""
    klbf, ft, psi = 4448.2216152605, 0.3048, 6894.757293168361
    rop, oscillation, mse, radial, *_ = map_figures(map_dataset, units="field")
    heat = rop["data"][0]
    assert heat["y"] == pytest.approx([60e3 / klbf, 100e3 / klbf, 140e3 / klbf], rel=1e-5)  # 6 digits kept
    assert heat["z"][1][0] == pytest.approx(2.0 * 3600.0 / ft, rel=1e-5)
    assert "klbf" in heat["hovertemplate"] and rop["layout"]["yaxis"]["title"]["text"] == "weight-on-bit [klbf]"
    assert heat["colorbar"]["title"]["text"] == "mean rate of penetration [ft/h]"
    assert rop["layout"]["shapes"][0]["y0"] == pytest.approx(114.13e3 / klbf)
    assert "(25.66 klbf)" in rop["caption"]
    assert oscillation["data"][0]["z"][1][0] == pytest.approx(2.0)  # a plain number
    assert mse["data"][0]["colorbar"]["title"]["text"] == "mechanical specific energy [psi]"
    assert mse["data"][0]["z"][1][0] == pytest.approx(2.0 / psi, rel=1e-5)
    assert radial["data"][0]["z"][1][0] == pytest.approx(2.0 / 0.0254, rel=1e-5)


def test_study_figures_follow_the_unit_system():
    time = np.linspace(0.0, 1.0, 5)
    names = ("rate_of_penetration", "bit_speed", "torque_on_bit", "force_on_bit")
    stats = xr.Dataset({f"{n}_{k}": ("time", np.full(5, 2.0)) for n in names for k in
                        ("mean", "lower", "upper", "nominal", "dispersion")}, coords={"time": time})
    figures = study_figures(stats, units="field")
    expected = {"rate of penetration [ft/h]": 2.0 * 3600 / 0.3048, "bit speed [rpm]": 2.0 * 30 / math.pi,
                "torque-on-bit [kft·lbf]": 2.0 / 1355.8179483314004, "force-on-bit [klbf]": 2.0 / 4448.2216152605}
    for fig, (label, value) in zip(figures, expected.items()):
        assert fig["layout"]["yaxis"]["title"]["text"] == label
        mean = next(t for t in fig["data"] if t["name"] == "mean")
        assert mean["y"] == pytest.approx([value] * 5, rel=1e-5)


@pytest.fixture
def indices():
    parameters = {"operation.top_speed": "uniform 60 140 rpm", "operation.weight_on_bit": "uniform 80 120 kN"}
    entry = {"S1": {"operation.top_speed": 0.7, "operation.weight_on_bit": 0.2},
             "S1_ci": {"operation.top_speed": [0.6, 0.8], "operation.weight_on_bit": [None, None]},
             "ST": {"operation.top_speed": 0.75, "operation.weight_on_bit": None},
             "ST_ci": {"operation.top_speed": [0.7, 0.8], "operation.weight_on_bit": [0.1, 0.3]},
             "convergence": {"max_change": [0.1, 0.05]}}
    return {"parameters": parameters, "base_samples": 8, "runs": 32, "seed": 0, "confidence_level": 0.95,
            "resamples": 100, "outputs": {"mean_rate_of_penetration": entry, "bit_speed_oscillation": entry}}


def test_sensitivity_figures_have_bars_with_intervals(indices):
    s1, st = sensitivity_figures(indices)
    top = s1["data"][0]
    assert top["name"] == "top_speed" and top["y"] == [0.7, 0.7]
    assert top["error_y"]["array"] == [pytest.approx(0.1), pytest.approx(0.1)]
    assert s1["data"][1]["error_y"]["array"] == [None, None]  # no interval: no bar end
    assert st["data"][1]["y"] == [None, None]


def test_map_and_sensitivity_pages_render_in_a_headless_browser(tmp_path, map_dataset, indices, reference_case):
    toml = reference_case.to_toml()
    png = tmp_path / "figure.png"
    from matplotlib.figure import Figure

    Figure(figsize=(1, 1)).savefig(png)
    write_map_report(tmp_path / "map" / "report.html", title="Operating map", case_toml=toml, summary={},
                     figures={"map": png}, run_info={}, interactive=map_figures(map_dataset))
    write_sensitivity_report(tmp_path / "sobol" / "report.html", title="Sensitivity", case_toml=toml,
                             indices=indices, figures={"sobol": png}, run_info={},
                             interactive=sensitivity_figures(indices))
    for folder in ("map", "sobol"):
        page = tmp_path / folder / INTERACTIVE_PAGE
        _check_self_contained(page)
        _check_rendered(page, tmp_path / f"profile-{folder}")


def test_the_check_catches_a_page_that_fails(tmp_path):
    """The browser check is not vacuous: a page whose script throws is caught by the console scan."""
    page = tmp_path / "broken.html"
    page.write_text('<html><body><script>undefinedFunction();</script></body></html>', encoding="utf-8")
    _, log = _open_in_browser(page, tmp_path / "profile", "--dump-dom")
    assert any(":CONSOLE" in line and "undefinedFunction" in line for line in log.splitlines())


def test_torque_drag_page_renders_without_console_messages(tmp_path):
    """``torque-drag --html``: the 3-D path and the three panels drawn, no console message from the page (plotly.js
    warned "Invalid color specifier" four times for a legend entry of a line coloured by values)."""
    from typer.testing import CliRunner

    from drillstring.cli import app

    page = tmp_path / "td.html"
    result = CliRunner().invoke(app, ["torque-drag", "deviated", "--html", str(page)],
                                env={"COLUMNS": "120", "DRILLSTRING_UNITS": None})
    assert result.exit_code == 0, result.output
    assert _figure_count(page) == 4
    _check_rendered(page, tmp_path / "profile")
