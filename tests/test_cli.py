"""The command line: JSON payloads (SI), human-readable tables (units), user case files, errors."""

import json
import re
from importlib import resources

import numpy as np
import pytest
from typer.testing import CliRunner

from drillstring.cli import app
from drillstring.stochastic import execution
from drillstring.stochastic.locks import StudyLocked
from drillstring.units import significant

runner = CliRunner()

REFERENCE_WEIGHT = 1.1634e6  # N (SPEC §10)
REFERENCE_WOH = 1.0634e6  # N
REFERENCE_WOB = 1e5  # N
REFERENCE_LENGTH = 1600.0  # m


# Plain, wide, uncoloured tables whatever the terminal settings of the machine running the tests.
# The user's unit system ($DRILLSTRING_UNITS) is unset: tables in SI unless a test asks otherwise.
_ENV = {"COLUMNS": "120", "FORCE_COLOR": None, "TTY_COMPATIBLE": None, "TTY_INTERACTIVE": None,
        "DRILLSTRING_UNITS": None}


def _invoke(*args: str):
    return runner.invoke(app, list(args), env=_ENV)


def _json(*args: str):
    result = _invoke(*args)
    assert result.exit_code == 0, result.output
    return json.loads(result.stdout)  # nothing but the JSON on stdout


def _reference_toml() -> str:
    return resources.files("drillstring").joinpath("cases", "reference.toml").read_text(encoding="utf-8")


def _edited_reference(folder, old: str, new: str, name: str = "bad.toml"):
    """The reference case file with ``old`` replaced by ``new`` (which must be there), written in ``folder``."""
    text = _reference_toml()
    assert old in text
    path = folder / name
    path.write_text(text.replace(old, new, 1), encoding="utf-8")
    return path


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
    assert set(data) == {"weight", "weight_on_hook", "weight_on_bit", "neutral_point_height",
                         "critical_weight_on_bit", "axial_force"}
    # Issue 10 measured ≈ 114 kN; tests/test_buckling.py checks it against a shooting solution.
    assert data["critical_weight_on_bit"] == pytest.approx(114.13e3, rel=1e-4)
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
    for text in ("kN", "[m]", "[kN]", "weight-on-hook", "1,063.43", "neutral point", "top", "bit", "stabilizer",
                 "critical weight-on-bit", "114.13", "margin 14.13 kN"):
        assert text in out, text
    assert "drill pipe / drill collar" in out
    assert len(out.splitlines()) < 40  # a summary, not the full profile


KLBF = 4448.2216152605  # N (NIST)
FT = 0.3048  # m
PSI = 6894.757293168361  # Pa (NIST: lbf/in²)


def test_static_in_field_units_shows_klbf_and_ft():
    data = _json("static", "reference", "--json")
    result = _invoke("static", "reference", "--units", "field")
    assert result.exit_code == 0, result.output
    out = result.stdout
    for text in ("klbf", "ft", "[ft]", "[klbf]", "above bit [ft]"):
        assert text in out, text
    assert " kN" not in out and "[m]" not in out
    # The numbers are the SI ones over the defining factors: weight, weight-on-bit, neutral point, length.
    assert f"{data['weight'] / KLBF:,.2f}" in out  # 261.55
    assert f"{data['weight_on_bit'] / KLBF:,.2f}" in out  # 22.48
    assert f"{data['neutral_point_height'] / FT:,.2f}" in out  # 116.77
    assert f"{REFERENCE_LENGTH / FT:,.1f}" in out  # 5,249.3
    assert f"margin {(data['critical_weight_on_bit'] - data['weight_on_bit']) / KLBF:,.2f} klbf" in out


def test_units_setting_from_the_environment_and_the_option_wins():
    field = _invoke("static", "reference", "--units", "field").stdout
    env = runner.invoke(app, ["static", "reference"], env={**_ENV, "DRILLSTRING_UNITS": "field"})
    assert env.exit_code == 0 and env.stdout == field
    si = runner.invoke(app, ["static", "reference", "--units", "si"], env={**_ENV, "DRILLSTRING_UNITS": "field"})
    assert si.exit_code == 0 and si.stdout == _invoke("static", "reference").stdout and "kN" in si.stdout
    # JSON stays SI whatever the unit system.
    assert _json("static", "reference", "--json", "--units", "field") == _json("static", "reference", "--json")


def test_bad_units_are_refused():
    result = _invoke("static", "reference", "--units", "imperial")
    assert result.exit_code == 2
    assert "--units = 'imperial': must be one of si, field" in result.output
    bad_env = runner.invoke(app, ["modes", "reference"], env={**_ENV, "DRILLSTRING_UNITS": "cubits"})
    assert bad_env.exit_code == 2 and "DRILLSTRING_UNITS = 'cubits'" in bad_env.output


@pytest.mark.parametrize("command", ["static", "modes", "campbell", "stability", "simulate", "compare", "study",
                                     "map", "sensitivity"])
def test_every_table_command_has_the_shared_units_option(command):
    result = _invoke(command, "--help")
    assert result.exit_code == 0 and "--units" in result.stdout and "si|field" in result.stdout


def test_reference_components_gives_the_reference_static_state():
    assert _json("static", "reference_components", "--json") == _json("static", "reference", "--json")


def test_static_user_case_file(heavier_bit_case):
    reference = _json("static", "reference", "--json")
    data = _json("static", str(heavier_bit_case), "--json")
    assert data["weight"] == pytest.approx(reference["weight"], rel=1e-12)
    assert data["weight_on_bit"] == pytest.approx(150e3)
    assert data["weight_on_hook"] == pytest.approx(reference["weight_on_hook"] - 50e3, rel=1e-9)
    assert data["axial_force"][-1][1] == pytest.approx(-150e3, rel=1e-9)
    assert data["neutral_point_height"] > reference["neutral_point_height"]
    # The margin depends on the case, not on its weight-on-bit; 150 kN is beyond it.
    assert data["critical_weight_on_bit"] == pytest.approx(reference["critical_weight_on_bit"], rel=1e-9)
    result = _invoke("static", str(heavier_bit_case))
    assert result.exit_code == 0 and "BUCKLED" in result.stdout


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
    for text in ("axial [Hz]", "torsional [Hz]", "lateral [Hz]", "1.2006", "0.2313", "rigid",
                 "Lateral buckling at weight-on-bit 114.13 kN"):
        assert text in result.stdout, text


def test_modes_user_case_file(heavier_bit_case):
    reference = _json("modes", "reference", "--json", "--count", "3")
    data = _json("modes", str(heavier_bit_case), "--json", "--count", "3")
    # Mass and axial stiffness do not depend on the weight-on-bit.
    assert data["axial"] == pytest.approx(reference["axial"], rel=1e-9, abs=1e-12)
    # More compression lowers the lateral frequencies (geometric stiffness); 150 kN buckles the
    # string: its lowest lateral mode is unstable, reported as a negative frequency.
    assert data["lateral"][0] < 0.0 < reference["lateral"][0]
    assert "BUCKLED" in _invoke("modes", str(heavier_bit_case), "-n", "3").stdout


def test_modes_count_zero_is_refused():
    result = _invoke("modes", "--count", "0")
    assert result.exit_code == 2
    assert "--count" in result.output
    assert result.stdout == ""


# ---------------------------------------------------------------------------------------------- cases, errors


def test_cases_lists_reference_contact_and_stick_slip():
    result = _invoke("cases")
    assert result.exit_code == 0, result.output
    names = [line.split()[0] for line in result.stdout.splitlines()]
    assert names == ["aarsnes2019", "aarsnes2019_paper", "contact", "deviated", "motor", "reference",
                     "reference_components", "stick_slip"]
    assert "hits the wall" in result.stdout and "full stick-slip" in result.stdout
    assert "Aarsnes & van de Wouw (2019)" in result.stdout


def test_simulate_contact_hits_the_wall(tmp_path):
    """The built-in contact case as the README runs it (first 10 s): impacts > 0 in --json, contact forces,
    and the figure with the whirl orbit and the contact force."""
    nc, png = tmp_path / "c.nc", tmp_path / "c.png"
    data = _json("simulate", "contact", "--t-end", "10", "--out", str(nc), "--plot", str(png), "--json")
    assert data["impacts"] > 0 and data["max_contact_force"] > 0 and data["contact_time_fraction"] > 0
    assert data["max_radial_displacement"][0] > data["gap"][0]
    from drillstring.results import read_netcdf

    ds = read_netcdf(nc)
    assert ds.contact_force.max() > 0 and ds.lateral_displacement.sizes["direction"] == 2
    assert png.stat().st_size > 50_000


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


@pytest.mark.parametrize("old, new, field", [
    ("lateral_modes = 20", "lateral_modes = 100000", "reduced_model.lateral_modes = 100000"),
    ('max_element_length = "10 m"', 'max_element_length = "1 mm"', "mesh.max_element_length = 0.001"),
    ('max_element_length = "10 m"', 'max_element_length = "2 km"', "mesh.max_element_length = 2000.0"),
])
def test_cases_that_cannot_be_meshed_or_reduced_exit_2_naming_the_field(tmp_path, old, new, field):
    path = _edited_reference(tmp_path, old, new)
    for command in ("static", "modes", "simulate"):
        result = _invoke(command, str(path), "--json")
        assert result.exit_code == 2, result.output
        assert field in result.stderr
        assert "Traceback" not in result.output
        assert result.exception is None or isinstance(result.exception, SystemExit)


def test_gravity_off_runs_with_a_pushing_hook(tmp_path):
    text = _reference_toml()
    path = tmp_path / "weightless.toml"
    path.write_text(text.replace("\ngravity = true", "\ngravity = false"), encoding="utf-8")
    static = _json("static", str(path), "--json")
    assert static["weight"] == 0.0 and static["weight_on_hook"] == pytest.approx(-REFERENCE_WOB)
    assert all(n == pytest.approx(-REFERENCE_WOB) for _, n in static["axial_force"])  # compressed
    run = _json("simulate", str(path), "--t-end", "0.2", "--json", "--out", str(tmp_path / "w.nc"),
                "--plot", str(tmp_path / "w.png"))
    assert run["status"] == "success" and run["mean_rate_of_penetration"] > 0


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


# ---------------------------------------------------------------------------------------- simulate, study


@pytest.fixture(scope="module")
def coarse_case(tmp_path_factory):
    """The reference case on a 40 m mesh: a 1 s run takes a fraction of a second."""
    from drillstring.case import load_case

    case = load_case("reference")
    case = case.model_copy(update={"mesh": case.mesh.model_copy(update={"max_element_length": 40.0}),
                                   "reduced_model": case.reduced_model.model_copy(update={"lateral_cutoff": 0.0})})
    path = tmp_path_factory.mktemp("cases") / "coarse.toml"
    path.write_text(case.to_toml(), encoding="utf-8")
    return path


def test_simulate_json_writes_netcdf_and_figure(coarse_case, tmp_path):
    from drillstring.results import read_netcdf

    nc, png = tmp_path / "run.nc", tmp_path / "run.png"
    data = _json("simulate", str(coarse_case), "--t-end", "1", "--out", str(nc), "--plot", str(png), "--json")
    for key in ("mean_rate_of_penetration", "bit_speed_min", "bit_speed_max", "stick_slip",
                "stick_time_fraction", "bit_speed_oscillation", "max_radial_displacement", "gap", "impacts", "n_rhs", "n_accepted", "n_rejected",
                "wall_time", "netcdf", "figure"):
        assert key in data, key
    assert data["netcdf"] == str(nc) and data["figure"] == str(png)
    assert png.read_bytes().startswith(b"\x89PNG")
    ds = read_netcdf(nc)
    assert float(ds.time[-1]) == pytest.approx(1.0)
    assert ds.attrs["status"] == "success"
    top = 100.0 * 2.0 * 3.141592653589793 / 60.0
    assert 1e-4 < data["mean_rate_of_penetration"] < 1e-2  # m/s: 0.36 to 36 m/h
    assert 0.0 < data["bit_speed_min"] <= data["bit_speed_max"] < 2.0 * top  # rad/s
    assert data["stick_slip"] is False and data["stick_time_fraction"] == 0.0
    assert data["stick_slip"] == (data["bit_speed_min"] < 0.1 * top)
    oscillation = (data["bit_speed_max"] - data["bit_speed_min"]) / (2 * top)
    assert data["bit_speed_oscillation"] == pytest.approx(oscillation, rel=1e-12)
    assert len(data["max_radial_displacement"]) == len(data["gap"]) == 1
    assert 0.0 <= data["max_radial_displacement"][0] < data["gap"][0] == pytest.approx(0.0357)
    assert data["impacts"] >= 0 and data["n_rejected"] >= 0
    assert data["n_rhs"] >= data["n_accepted"] > 0
    assert data["wall_time"] > 0.0


def test_simulate_table_has_units(coarse_case, tmp_path):
    result = _invoke("simulate", str(coarse_case), "--t-end", "0.5", "--out", str(tmp_path / "a.nc"),
                     "--plot", str(tmp_path / "a.png"))
    assert result.exit_code == 0, result.output
    for text in ("rate of penetration", "m/h", "rpm", "bit speed oscillation", "stick time", "mm",
                 "impacts", "steps",
                 str(tmp_path / "a.nc")):
        assert text in result.stdout, text
    # In field units: the surface torque in kft·lbf (1 kft·lbf = 1355.8179483314004 N·m).
    args = ("simulate", str(coarse_case), "--t-end", "0.5", "--out", str(tmp_path / "b.nc"), "--plot",
            str(tmp_path / "b.png"))
    data = _json(*args, "--json")
    field = _invoke(*args, "--units", "field")
    assert field.exit_code == 0, field.output
    row = next(line for line in field.stdout.splitlines() if "surface torque min / max" in line)
    low, high = (data[f"surface_torque_{k}"] / 1355.8179483314004 for k in ("min", "max"))
    assert f"{low:,.2f} / {high:,.2f}" in row and "kft·lbf" in row


def test_simulate_failure_keeps_the_partial_run(coarse_case, tmp_path):
    from drillstring.case import load_case
    from drillstring.results import read_netcdf

    case = load_case(coarse_case)
    case = case.model_copy(update={"simulation": case.simulation.model_copy(update={"max_steps": 50})})
    path = tmp_path / "few_steps.toml"
    path.write_text(case.to_toml(), encoding="utf-8")
    nc = tmp_path / "partial.nc"
    result = _invoke("simulate", str(path), "--t-end", "1", "--out", str(nc), "--plot", str(tmp_path / "p.png"))
    assert result.exit_code == 1, result.output
    assert "stopped" in result.stderr and "t = " in result.stderr  # when it stopped
    assert "Traceback" not in result.output
    ds = read_netcdf(nc)
    assert ds.attrs["status"] == "failed"
    assert 0 < float(ds.time[-1]) < 1.0


def test_simulate_bad_t_end(coarse_case):
    result = _invoke("simulate", str(coarse_case), "--t-end", "-1")
    assert result.exit_code == 2
    assert "--t-end" in result.stderr


def _study(case_path, out, *extra):
    return _invoke("study", str(case_path), "--samples", "3", "--t-end", "1", "--workers", "1",
                   "--out", str(out), *extra)


def test_study_writes_everything_and_resumes(coarse_case, tmp_path):
    out = tmp_path / "study"
    result = _study(coarse_case, out, "--json")
    assert result.exit_code == 0, result.output
    first = json.loads(result.stdout)
    saved = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    assert saved == first
    for name in ("study.zarr", "summary.json", "statistics.nc", "report.html", "convergence.png",
                 "envelopes.png", "dispersion.png", "realizations.png"):
        assert (out / name).exists(), name
    assert {"realizations", "stability", "time_convergence"} <= set(first)
    assert first["realizations"]["stick_slip_index"]["n"] == 3
    assert first["stability"]["boundary"]["weight_on_bit"] > 0
    assert first["n_samples"] == 3 and first["n_failed"] == 0 and first["failures"] == {}
    assert first["seed"] == 0 and first["sigma"] == 5000.0  # the defaults
    assert first["workers"] == 1 and first["wall_time"] > 0.0
    assert first["t_transient"] == pytest.approx(0.5)  # min(10 s, t_end / 2)
    assert set(first["observables"]) == {"rate_of_penetration", "bit_speed", "torque_on_bit", "force_on_bit"}
    for entry in first["observables"].values():
        assert 0.0 < entry["dispersion_time_mean"] <= entry["dispersion_max"] < 1.0
        assert set(entry["ratio_time_mean"]) == {"weight_on_hook", "weight_on_bit"}
    html = (out / "report.html").read_text(encoding="utf-8")
    assert "data:image/png;base64," in html and "http" not in html

    again = _study(coarse_case, out, "--json")
    assert again.exit_code == 0, again.output
    second = json.loads(again.stdout)
    assert second["observables"] == first["observables"]
    assert second["n_samples"] == 3
    # Nothing left to run: the study's computation time is kept, the rerun is reported apart.
    assert second["wall_time"] == first["wall_time"] and second["workers"] == first["workers"]
    assert first["realizations_this_run"] == 3 and second["realizations_this_run"] == 0
    assert len(second["sessions"]) == 1 and second["sessions"][0]["realizations"] == 3
    assert second["wall_time_this_run"] < first["wall_time"]
    assert "resumed" in again.stderr

    table = _study(coarse_case, out)
    assert table.exit_code == 0, table.output
    buckling = first["buckling"]
    assert buckling["buckled_realizations"] == 0 and 0 < buckling["probability"] < 1e-2
    assert (buckling["warning"] is None) == (buckling["probability"] <= 1e-3)
    for text in ("rate of penetration", "mean δ [%]", "δ_WOH", f"Figures and report: {out / 'report.html'}",
                 "Per realization, after t = 0.5 s", "stick-slip index", "Steady drilling is unstable in",
                 "Buckling: none of the 3 realizations buckled",
                 f"wall time {first['wall_time']:,.1f} s", "this run only recomputed the statistics"):
        assert text in " ".join(table.stdout.split()), text  # sentences wrap at the terminal's width

    # Field units: the cycle-metric table, the report, the histograms and the interactive page (JSON stays SI).
    field = _study(coarse_case, out, "--units", "field")
    assert field.exit_code == 0, field.output
    rop, fob = first["realizations"]["mean_rate_of_penetration"], first["realizations"]["mean_force_on_bit"]
    tob, mse = first["realizations"]["mean_torque_on_bit"], first["realizations"]["mechanical_specific_energy"]
    rows = {line.split("│")[1].strip(): [c.strip() for c in line.split("│")[2:]]
            for line in field.stdout.splitlines() if line.count("│") >= 8}
    assert rows["ROP mean"][:2] == ["ft/h", significant(rop['mean'] * 3600 / FT)]
    assert rows["FOB mean"][:2] == ["klbf", significant(fob['mean'] / KLBF)]
    assert rows["TOB mean"][:2] == ["kft·lbf", significant(tob['mean'] / (KLBF * FT))]
    assert rows["MSE"][:2] == ["psi", significant(mse['mean'] / PSI)]
    assert rows["bit speed min"][0] == "rpm"
    boundary = first["stability"]["boundary"]["weight_on_bit"]
    assert f"unstable above a weight-on-bit of {boundary / KLBF:,.2f} klbf" in " ".join(field.stdout.split())
    report = (out / "report.html").read_text(encoding="utf-8")
    assert f"<td>ROP mean</td><td>ft/h</td><td class=\"num\">{rop['mean'] * 3600 / FT:.4g}</td>" in report
    assert "along the weight-on-bit [klbf]" in report
    page = (out / "interactive.html").read_text(encoding="utf-8")
    specs = [json.loads(t) for t in re.findall(r'class="figure-spec"[^>]*>(.*?)</script>', page, re.S)]
    assert specs[0]["layout"]["yaxis"]["title"]["text"] == "rate of penetration [ft/h]"
    assert specs[3]["layout"]["yaxis"]["title"]["text"] == "force-on-bit [klbf]"
    assert json.loads(_study(coarse_case, out, "--json", "--units", "field").stdout)["realizations"] == \
        first["realizations"]


def test_study_refuses_other_settings_on_the_same_store(coarse_case, tmp_path):
    out = tmp_path / "study"
    assert _study(coarse_case, out).exit_code == 0
    result = _study(coarse_case, out, "--sigma", "3000")
    assert result.exit_code == 2
    assert "different study" in result.stderr and "--out" in result.stderr
    assert "Traceback" not in result.output


def test_study_dispersion_sets_sigma(coarse_case, tmp_path):
    from drillstring.case import load_case
    from drillstring.stochastic.montecarlo import nominal_weight_on_hook

    result = _study(coarse_case, tmp_path / "d", "--dispersion", "0.01", "--json")
    assert result.exit_code == 0, result.output
    data = json.loads(result.stdout)
    assert data["sigma"] == pytest.approx(0.01 * nominal_weight_on_hook(load_case(coarse_case)))
    assert data["weight_on_hook_dispersion"] == pytest.approx(0.01)


def test_study_sigma_and_dispersion_together_refused(coarse_case, tmp_path):
    result = _study(coarse_case, tmp_path / "x", "--sigma", "1000", "--dispersion", "0.01")
    assert result.exit_code == 2
    assert "--sigma" in result.stderr and "--dispersion" in result.stderr
    assert not (tmp_path / "x" / "study.zarr").exists()


@pytest.mark.parametrize("args", [("--sigma", "-5"), ("--dispersion", "0"), ("--transient", "5")])
def test_study_bad_values_refused(coarse_case, tmp_path, args):
    result = _study(coarse_case, tmp_path / "bad", *args)
    assert result.exit_code == 2, result.output
    assert "error:" in result.stderr


def test_study_interrupted_exit_130(coarse_case, tmp_path, monkeypatch):
    from drillstring.stochastic import montecarlo

    def interrupted(*args, **kwargs):
        raise execution.Interrupted(
            "study interrupted after 1 of 3 realizations; they are saved in x; run the same command again "
            "to resume")

    monkeypatch.setattr(montecarlo, "run_study", interrupted)
    result = _study(coarse_case, tmp_path / "i")
    assert result.exit_code == 130
    assert "resume" in result.stderr
    assert "Traceback" not in result.output


def _one_line_error(result, *expected):
    """Refused as bad input: exit code 2, one line on stderr naming the problem, no traceback."""
    assert result.exit_code == 2, result.output
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), result.stderr
    for text in expected:
        assert text in lines[0], (text, lines[0])
    assert "Traceback" not in result.output


@pytest.fixture
def nothing_runs(monkeypatch):
    """Any simulation or study started by a command fails the test: refusals must come first."""
    from drillstring import api
    from drillstring.stochastic import montecarlo, operating_map, sensitivity_study

    def forbidden(*args, **kwargs):
        raise AssertionError("computation started before the input was checked")

    for module, name in ((api, "simulate"), (api, "compare"), (montecarlo, "run_study"),
                         (montecarlo, "run_realization"), (operating_map, "run_map"),
                         (sensitivity_study, "run_sensitivity")):
        monkeypatch.setattr(module, name, forbidden)


@pytest.mark.parametrize("args, expected", [
    (("--samples", "1"), ["samples = 1: must be an integer >= 2"]),
    (("--sigma", "1e6"), ["sigma = 1e+06 N:", "probability", "at most 32,360 N (32.36 kN)"]),
    (("--sigma", "nan"), ["sigma = nan N: must be a finite number > 0"]),
    (("--sigma", "-1"), ["sigma = -1.0 N: must be a finite number > 0"]),
    (("--dispersion", "inf"), ["dispersion = inf: must be a finite number > 0"]),
    (("--dispersion", "0.5"), ["sigma = 531716 N", "probability"]),
    (("--t-end", "inf"), ["t_end = inf s: must be a finite number > 0"]),
    (("--t-end", "-2"), ["t_end = -2.0 s"]),
    (("--seed", "-1"), ["seed = -1: must be an integer in [0, 2**64 - 1"]),
    (("--seed", "18446744073709551616"), ["seed = 18446744073709551616: must be an integer in [0, 2**64 - 1"]),
    (("--samples", "1000000000"), ["samples = 1000000000 realizations of 101 output times", "GiB, above the limit "
                                   "of 4 GiB"]),
    (("--t-end", "1e9"), ["t_end = 1e+09 s at output_step = 0.01 s: 100000000001 output times, above the limit "
                          "of 2000000"]),
    (("--transient", "nan"), ["transient = nan s"]),
    (("--param", "simulation.t_end=uniform 20 30"), ["simulation.t_end = 'uniform 20 30': cannot be random"]),
    (("--param", "uncertainty.model.stiffness_dispersion=1.5"),
     ["uncertainty.model.stiffness_dispersion = 1.5: must be a number in [0, 1)"]),
    (("--param", "uncertainty.model.mass_dispersion=lots"),
     ["--param uncertainty.model.mass_dispersion = 'lots': must be a number in [0, 1)"]),
    (("--param", "uncertainty.model.stiffness=0.1"), ["uncertainty.model.stiffness: unknown key"]),
])
def test_study_impossible_settings_refused_before_running(coarse_case, tmp_path, nothing_runs, args, expected):
    out = tmp_path / "bad"
    _one_line_error(_study(coarse_case, out, *args), *expected)
    assert not out.exists()  # nothing created


@pytest.mark.parametrize("args, expected", [
    (("simulate", "--t-end", "1e7"), "--t-end = 1e+07 s at output_step = 0.01 s: 1000000001 output times, above "
                                     "the limit of 2000000"),
    (("simulate", "--t-end", "1e12"), "--t-end = 1e+12 s at output_step = 0.01 s:"),
    (("map", "--top-speed", "40:200:999999999999"), "--top-speed = '40:200:999999999999': N = 999999999999 values, "
                                                    "above the limit of 100000 grid points"),
    (("sensitivity", "--param", "operation.top_speed=uniform 60 140 rpm", "--samples", "1099511627776"),
     "samples = 1099511627776: above the limit of 262144 (2**18) base samples"),
])
def test_absurd_sizes_refused_before_anything(coarse_case, tmp_path, nothing_runs, args, expected):
    command, *rest = args
    out = ["--out", str(tmp_path / ("run.nc" if command == "simulate" else "run"))]
    _one_line_error(_invoke(command, str(coarse_case), *rest, *out), expected)
    assert not (tmp_path / "run").exists() and not (tmp_path / "run.nc").exists()


def test_study_workers_zero_refused(coarse_case, tmp_path, nothing_runs):
    result = _invoke("study", str(coarse_case), "--workers", "0", "--out", str(tmp_path / "w"))
    _one_line_error(result, "workers = 0: must be an integer >= 1")


def test_study_output_folder_checked_before_running(coarse_case, tmp_path, unwritable_folder, nothing_runs):
    a_file = tmp_path / "a_file"
    a_file.write_text("x")
    _one_line_error(_study(coarse_case, a_file), f"--out = {a_file}: is a file, not a folder")
    _one_line_error(_study(coarse_case, a_file / "sub"), f"{a_file} is a file, not a folder")
    _one_line_error(_study(coarse_case, unwritable_folder / "study"), f"cannot write in {unwritable_folder}")


def test_study_store_that_is_not_a_study_refused(coarse_case, tmp_path):
    import zarr

    out = tmp_path / "study"
    assert _study(coarse_case, out).exit_code == 0
    del zarr.open_group(str(out / "study.zarr"), mode="a")["status"]
    _one_line_error(_study(coarse_case, out), "study.zarr is not a complete drillstring study store",
                    "missing array(s): status")


def test_study_stale_lock_is_taken_over_with_a_note(coarse_case, tmp_path):
    import socket

    out = tmp_path / "study"
    out.mkdir()
    # The record of a study killed with -9 (nobody holds the lock any more).
    (out / "study.zarr.lock").write_text(json.dumps({"pid": 4_000_000, "host": socket.gethostname(),
                                                     "started": "2026-01-01T00:00:00+00:00"}))
    result = _study(coarse_case, out)
    assert result.exit_code == 0, result.output
    assert "note: took over a stale lock (pid 4000000 on host" in result.stderr
    assert not (out / "study.zarr.lock").exists()


def test_study_calls_the_api_with_its_defaults(coarse_case, tmp_path, monkeypatch):
    """The command line parses and formats; defaults and checks are the API's (one definition)."""
    from drillstring import api

    seen = {}

    def record(case, **kwargs):
        seen.update(kwargs)
        raise ValueError("stop here")

    monkeypatch.setattr(api, "monte_carlo_study", record)
    result = _invoke("study", str(coarse_case), "--out", str(tmp_path / "s"))
    _one_line_error(result, "stop here")
    inputs, window, run = seen["inputs"], seen["window"], seen["run"]
    assert inputs == api.RandomInputs()  # nothing declared: the API's default law
    assert window == api.SimulationWindow()  # the case's window, the API's transient
    assert run.workers is None and run.scheduler is None and run.out == tmp_path / "s"
    from drillstring.stochastic import DEFAULT_SAMPLES, DEFAULT_SEED
    import inspect

    defaults = inspect.signature(api.study).parameters
    assert seen["samples"] == DEFAULT_SAMPLES == defaults["samples"].default
    assert seen["seed"] == DEFAULT_SEED == defaults["seed"].default


@pytest.mark.parametrize("error, code", [
    ("workers_lost", 1), ("failed", 1), ("locked", 2),
])
def test_study_run_errors_are_one_line(coarse_case, tmp_path, monkeypatch, error, code):
    """Errors of a study that started (workers gone, too few realizations) exit 1; a lock taken by
    another study between the command's check and the engine's exits 2; one line each."""
    from drillstring import api

    raised = {"workers_lost": execution.WorkersLost("the Dask cluster at tcp://x:1 has had no worker "
                                                          "for 30 s; the finished realizations are saved"),
              "failed": api.StudyFailed("only 1 finished realization(s): statistics need at least 2"),
              "locked": StudyLocked("study store s is in use by pid 1 on host h")}[error]

    def fail(*args, **kwargs):
        raise raised

    monkeypatch.setattr(api, "monte_carlo_study", fail)
    result = _study(coarse_case, tmp_path / "s")
    assert result.exit_code == code, result.output
    lines = result.stderr.strip().splitlines()
    assert lines == [f"error: {raised}"]
    assert "Traceback" not in result.output


def test_study_scheduler_refused_port(coarse_case, tmp_path, monkeypatch):
    """The engine reaches the scheduler before it creates the store or computes anything."""
    import socket

    from drillstring.stochastic import montecarlo, study_model

    def forbidden(*args, **kwargs):
        raise AssertionError("computation started before the scheduler was reached")

    for name in ("run_realization", "StudyStore"):
        monkeypatch.setattr(montecarlo, name, forbidden)
    monkeypatch.setattr(study_model, "compile_kernels", forbidden)  # the study's preparation (prepare_runs)

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    result = _invoke("study", str(coarse_case), "--scheduler", f"tcp://127.0.0.1:{port}", "--out",
                     str(tmp_path / "s"))
    _one_line_error(result, f"scheduler = 'tcp://127.0.0.1:{port}': connection refused")
    assert not (tmp_path / "s").exists()


def _drillstring(*args, timeout=180):
    """The installed command in its own process (what a user runs), with a guard against hangs."""
    import subprocess
    import sys

    command = [sys.executable, "-c", "from drillstring.cli import app; app()", *args]
    return subprocess.run(command, capture_output=True, text=True, timeout=timeout,
                          env={**__import__("os").environ, "COLUMNS": "120"})


def test_study_scheduler_that_is_no_dask_server_fails_fast(coarse_case, tmp_path):
    """A TCP server that accepts and never answers (the reported 300 s+ hang): refused by the real
    command with one line after the greeting timeout (the subprocess timeout guards the hang)."""
    import socket

    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen()
    try:
        result = _drillstring("study", str(coarse_case), "--scheduler",
                              f"tcp://127.0.0.1:{server.getsockname()[1]}", "--out", str(tmp_path / "s"),
                              timeout=60)
    finally:
        server.close()
    assert result.returncode == 2, result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "sent no Dask greeting within 4 s (not a Dask scheduler)" in lines[0]


def test_two_studies_on_one_folder(coarse_case, tmp_path):
    """Two real processes on one --out: the second is refused at once while the first runs, naming it;
    the first finishes normally with sound statistics."""
    import subprocess
    import sys
    import time

    from drillstring.results import read_netcdf

    out = tmp_path / "study"
    args = ["study", str(coarse_case), "--samples", "6", "--t-end", "1", "--workers", "1", "--out", str(out),
            "--json"]
    first = subprocess.Popen([sys.executable, "-c", "from drillstring.cli import app; app()", *args],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    lock = out / "study.zarr.lock"
    deadline = time.time() + 120
    while time.time() < deadline and first.poll() is None and not (lock.exists() and lock.read_text().strip()):
        time.sleep(0.05)
    second = _drillstring(*args[:-1], timeout=120)
    stdout, stderr = first.communicate(timeout=300)
    assert first.returncode == 0, stderr
    assert second.returncode == 2, second.stderr
    lines = second.stderr.strip().splitlines()
    assert len(lines) == 1 and f"is in use by pid {first.pid} on host" in lines[0]
    assert "wait for that study to finish or use another --out folder" in lines[0]
    summary = json.loads(stdout)
    assert summary["n_samples"] == 6 and summary["n_failed"] == 0
    stats = read_netcdf(out / "statistics.nc")
    steady = stats.time.values >= 0.5
    for name in ("rate_of_penetration", "bit_speed", "torque_on_bit", "force_on_bit"):
        mean, nominal = stats[f"{name}_mean"].values[steady], stats[f"{name}_nominal"].values[steady]
        assert np.all(np.abs(nominal) > 0), name  # the reported failure: all-zero statistics
        np.testing.assert_allclose(mean, nominal, rtol=0.2, err_msg=name)  # around the nominal run
    assert sorted(p.name for p in out.iterdir()) == sorted(
        ["study.zarr", "summary.json", "statistics.nc", "report.html", "interactive.html", "convergence.png",
         "envelopes.png", "dispersion.png", "realizations.png", ".figures-key.json"])  # no lock, no temporary file left


def test_simulate_output_paths_checked_before_running(coarse_case, tmp_path, unwritable_folder, nothing_runs):
    ok_nc, ok_png = str(tmp_path / "a.nc"), str(tmp_path / "a.png")
    _one_line_error(_invoke("simulate", str(coarse_case), "--out", str(tmp_path), "--plot", ok_png),
                    f"--out = {tmp_path}: is a folder; give a file name")
    _one_line_error(_invoke("simulate", str(coarse_case), "--out", str(unwritable_folder / "x.nc"),
                            "--plot", ok_png), f"--out = {unwritable_folder / 'x.nc'}: cannot write in")
    _one_line_error(_invoke("simulate", str(coarse_case), "--out", ok_nc, "--plot",
                            str(unwritable_folder / "x.png")), f"--plot = {unwritable_folder / 'x.png'}: cannot write in")
    _one_line_error(_invoke("simulate", str(coarse_case), "--out", ok_nc, "--plot", ok_nc),
                    "--out and --plot are the same file")
    _one_line_error(_invoke("compare", str(coarse_case), "--plot", str(unwritable_folder / "c.png")),
                    f"--plot = {unwritable_folder / 'c.png'}: cannot write in")
    _one_line_error(_invoke("compare", str(coarse_case), "--plot", str(tmp_path)), "is a folder")


# ------------------------------------------------------------------------------------------------ compare


@pytest.fixture(scope="module")
def coarse_modes_case(tmp_path_factory):
    """The reference case on a 40 m mesh with 3 axial, 3 torsional and 4 lateral modes."""
    from drillstring.case import load_case

    case = load_case("reference")
    case = case.model_copy(update={
        "mesh": case.mesh.model_copy(update={"max_element_length": 40.0}),
        "reduced_model": case.reduced_model.model_copy(
            update={"axial_modes": 3, "torsional_modes": 3, "lateral_modes": 4, "lateral_cutoff": 0.0}),
    })
    path = tmp_path_factory.mktemp("cases") / "coarse_modes.toml"
    path.write_text(case.to_toml(), encoding="utf-8")
    return path


def test_compare_json_and_figure(coarse_modes_case, tmp_path):
    png = tmp_path / "cmp.png"
    data = _json("compare", str(coarse_modes_case), "--t-end", "1", "--plot", str(png), "--json")
    assert data["figure"] == str(png)
    assert png.read_bytes().startswith(b"\x89PNG")
    assert data["t_end"] == pytest.approx(1.0) and data["t_transient"] == pytest.approx(0.5)
    assert set(data["observables"]) == {"rate_of_penetration", "bit_speed", "torque_on_bit", "force_on_bit",
                                        "radial_displacement_0"}
    for entry in data["observables"].values():
        for key in ("max_abs_difference", "rms_relative_difference", "mean_difference",
                    "mean_relative_difference"):
            assert entry[key] is not None and entry[key] == entry[key], key  # finite, not null
    assert data["observables"]["rate_of_penetration"]["rms_relative_difference"] < 1e-6
    assert data["wall_time"]["full"] > 0 and data["wall_time"]["bit_and_contact"] > 0
    assert data["wall_time"]["ratio"] > 0


def test_compare_table_and_failure(coarse_modes_case, tmp_path):
    from drillstring.case import load_case

    result = _invoke("compare", str(coarse_modes_case), "--t-end", "0.5", "--plot", str(tmp_path / "c.png"))
    assert result.exit_code == 0, result.output
    for text in ("ROP [m/h]", "bit speed [rpm]", "kN·m", "r at x = 1560 m [mm]", "case 1 (full)",
                 "ratio case 1 / case 2", str(tmp_path / "c.png")):
        assert text in result.stdout, text

    case = load_case(coarse_modes_case)
    case = case.model_copy(update={"simulation": case.simulation.model_copy(update={"max_steps": 30})})
    path = tmp_path / "few_steps.toml"
    path.write_text(case.to_toml(), encoding="utf-8")
    result = _invoke("compare", str(path), "--t-end", "1", "--plot", str(tmp_path / "f.png"))
    assert result.exit_code == 1, result.output
    assert "case 1 (full) failed" in result.stderr
    assert "Traceback" not in result.output


#: Modules that only the simulating commands need.
_HEAVY = ("numba", "xarray", "matplotlib", "dask", "distributed", "scipy.stats", "zarr", "plotly")


@pytest.mark.parametrize("argv, unwanted", [
    ([], _HEAVY + ("scipy",)),  # importing the command line itself
    (["cases"], _HEAVY + ("scipy",)),
    (["static", "reference", "--json"], _HEAVY),
    (["modes", "reference", "--count", "2", "--json"], _HEAVY),
])
def test_light_commands_import_only_what_they_need(argv, unwanted):
    """Start-up cost: a command loads only the modules it uses (a fresh interpreter each)."""
    import subprocess
    import sys

    code = ("import sys\nfrom drillstring.cli import app\nsys.argv = ['drillstring', *sys.argv[1:]]\n"
            "if len(sys.argv) > 1:\n    try:\n        app()\n    except SystemExit as e:\n"
            "        assert not e.code, e.code\n"
            f"print([m for m in {unwanted!r} if m in sys.modules], file=sys.stderr)\n")
    done = subprocess.run([sys.executable, "-c", code, *argv], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stderr.strip().splitlines()[-1] == "[]"


def test_console_script_hides_dask_from_single_run_commands(tmp_path):
    """The console script's simulate runs without importing Dask (xarray would otherwise import
    dask.array and dask.distributed), and writes its NetCDF and figure; a study keeps Dask."""
    import subprocess
    import sys

    from drillstring.cli import NO_DASK_COMMANDS

    assert "simulate" in NO_DASK_COMMANDS and "study" not in NO_DASK_COMMANDS
    nc, png = tmp_path / "r.nc", tmp_path / "r.png"
    code = ("import sys\nfrom drillstring.cli import run\nsys.argv = ['drillstring', *sys.argv[1:]]\n"
            "try:\n    run()\nexcept SystemExit as e:\n    assert not e.code, e.code\n"
            "print([m for m in ('dask.array', 'dask.base', 'distributed') if m in sys.modules], file=sys.stderr)\n")
    done = subprocess.run([sys.executable, "-c", code, "simulate", "reference", "--t-end", "0.2", "--json",
                           "--out", str(nc), "--plot", str(png)], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert done.stderr.strip().splitlines()[-1] == "[]"
    from drillstring.results import read_netcdf

    assert float(read_netcdf(nc).time[-1]) == pytest.approx(0.2) and png.stat().st_size > 0


def test_simulate_reports_solver_and_compile_time_apart(tmp_path):
    numbers = _json("simulate", "reference", "--t-end", "0.5", "--json", "--out", str(tmp_path / "r.nc"),
                    "--plot", str(tmp_path / "r.png"))
    assert numbers["wall_time"] > 0 and numbers["compile_time"] >= 0
    assert isinstance(numbers["compiled"], bool)


def test_stability_json_and_table(coarse_case):
    data = _json("stability", str(coarse_case), "--json")
    assert set(data) == {"stable", "steady_state", "leading", "modes", "leading_by_family", "mixed_roots",
                         "convergence"}
    assert data["stable"] is False  # free–free damping: the first torsional mode grows
    steady = data["steady_state"]
    assert steady["bit_speed"] == pytest.approx(100 * 3.141592653589793 / 30)
    assert 3e-3 < steady["rate_of_penetration"] < 4e-3 and steady["force_on_bit"] == pytest.approx(1e5, rel=1e-6)
    leading = max(data["modes"], key=lambda m: m["growth_rate"])
    assert leading["family"] == "torsional" and leading["growth_rate"] > 0
    result = _invoke("stability", str(coarse_case))
    assert result.exit_code == 0, result.output
    for text in ("rate of penetration", "m/h", "UNSTABLE", "torsional", "growth rate", "Leading root of each family",
                 "energy a/t/l [%]"):
        assert text in result.stdout, text
    assert data["leading_by_family"]["torsional"]["growth_rate"] == leading["growth_rate"]
    assert data["leading_by_family"]["torsional"]["stable"] is False


def test_stability_with_the_delayed_law(tmp_path):
    """The published Detournay case (on a coarse basis): the same JSON with the steady state's depth of cut
    and delay and the delay system's facts; the table names the characteristic roots."""
    from drillstring.case import load_case

    case = load_case("aarsnes2019")
    case = case.model_copy(update={
        "mesh": case.mesh.model_copy(update={"max_element_length": 50.0}),
        "reduced_model": case.reduced_model.model_copy(update={"axial_modes": 3, "torsional_modes": 3})})
    path = tmp_path / "published.toml"
    path.write_text(case.to_toml(), encoding="utf-8")
    data = _json("stability", str(path), "--json")
    assert set(data) == {"stable", "steady_state", "leading", "modes", "delay", "leading_by_family", "mixed_roots",
                         "convergence"}
    steady = data["steady_state"]
    assert steady["rate_of_penetration"] == pytest.approx(30 / 3600, rel=1e-6)
    assert steady["delay"] == pytest.approx(0.5) and steady["depth_of_cut"] == pytest.approx(30 / 3600 * 0.5, rel=1e-6)
    assert data["delay"]["delay"] == pytest.approx(0.5) and len(data["delay"]["neutral_roots"]) == 1
    result = _invoke("stability", str(path))
    assert result.exit_code == 0, result.output
    for text in ("Characteristic roots", "depth of cut per blade", "delay (one blade passage)", "UNSTABLE"):
        assert text in result.stdout, text


def test_stability_boundary_along_the_weight_on_bit(coarse_case):
    """--boundary: the weight-on-bit where the leading growth rate crosses 0 (checked on both sides)."""
    from drillstring import api

    data = _json("stability", str(coarse_case), "--boundary", "--json")
    found = data["boundary"]
    wob = found["weight_on_bit"]
    assert found["nominal_weight_on_bit"] == pytest.approx(1e5) and found["nominal_growth_rate"] > 0
    assert api.stability(coarse_case, weight_on_bit=wob - 50.0).leading.growth_rate < 0 < api.stability(
        coarse_case, weight_on_bit=wob + 50.0).leading.growth_rate
    result = _invoke("stability", str(coarse_case), "--boundary")
    assert result.exit_code == 0, result.output
    assert (f"Stability boundary at the top speed 100 rpm: weight-on-bit {wob / 1e3:,.2f} kN (steady drilling "
            f"unstable above it); the case's 100.00 kN is {(1e5 - wob) / 1e3:,.2f} kN above it") in \
        " ".join(result.stdout.split())  # sentences wrap at the terminal's width
    field = _invoke("stability", str(coarse_case), "--boundary", "--units", "field")
    assert field.exit_code == 0, field.output
    assert (f"weight-on-bit {wob / KLBF:,.2f} klbf (steady drilling unstable above it); the case's "
            f"{1e5 / KLBF:,.2f} klbf is {(1e5 - wob) / KLBF:,.2f} klbf above it") in " ".join(field.stdout.split())
    assert " kN" not in field.stdout


def test_stability_without_steady_drilling_is_one_line(tmp_path, coarse_case):
    from drillstring.case import load_case

    case = load_case(coarse_case)
    case = case.model_copy(update={"bit_rock": case.bit_rock.model_copy(update={"a1": 0.02})})
    path = tmp_path / "no_drilling.toml"
    path.write_text(case.to_toml(), encoding="utf-8")
    result = _invoke("stability", str(path))
    assert result.exit_code == 2
    assert "rate_of_penetration" in result.stderr and "Traceback" not in result.output


def test_study_of_several_parameters_with_a_correlation(coarse_case, tmp_path):
    result = _study(coarse_case, tmp_path / "p", "--param", "operation.top_speed=normal 100 5 rpm",
                    "--param", 'fluid.inlet_velocity="uniform 1.2 1.8 m/s"', "--sigma", "4000",
                    "--correlation", "operation.top_speed,weight_on_hook=0.5", "--json")
    assert result.exit_code == 0, result.output
    data = json.loads(result.stdout)
    assert list(data["inputs"]) == ["weight_on_hook", "operation.top_speed", "fluid.inlet_velocity"]
    assert data["sigma"] == 4000.0 and data["inputs"]["weight_on_hook"]["std"] == 4000.0
    assert set(data["input_dispersion"]) == {"weight_on_hook", "operation.top_speed", "fluid.inlet_velocity",
                                            "weight_on_bit"}
    table = _study(coarse_case, tmp_path / "p", "--param", "operation.top_speed=normal 100 5 rpm",
                   "--param", 'fluid.inlet_velocity="uniform 1.2 1.8 m/s"', "--sigma", "4000",
                   "--correlation", "operation.top_speed,weight_on_hook=0.5")
    assert table.exit_code == 0, table.output
    for text in ("operation.top_speed: normal 100 5 rpm", "δ(top_speed)", "δ(inlet_velocity)", "δ_WOB"):
        assert text in table.stdout, text


@pytest.mark.parametrize("args, words", [
    (("--param", "operation.top_speed"), ["is not PATH=LAW"]),
    (("--param", "operation.top_speed=normal 100 rpm"), ["operation.top_speed", "normal"]),
    (("--param", "fluid.coriolis=uniform 0 1"), ["fluid.coriolis is not a numeric parameter"]),
    (("--param", "operation.top_speed=uniform 50 150 m/s"), ["operation.top_speed", "m/s"]),
    (("--correlation", "a,b"), ["is not PATH1,PATH2=R"]),
    (("--param", "operation.top_speed=uniform 50 150 rpm", "--correlation",
      "operation.top_speed,weight_on_hook=0.2"), ["weight_on_hook", "not a declared uncertain parameter"]),
])
def test_study_bad_laws_exit_2_with_one_line(coarse_case, tmp_path, args, words):
    result = _study(coarse_case, tmp_path / "bad", *args)
    assert result.exit_code == 2, result.output
    assert "Traceback" not in result.output and len(result.stderr.strip().splitlines()) == 1, result.stderr
    for word in words:
        assert word in result.stderr, result.stderr
    assert not (tmp_path / "bad").exists()


@pytest.fixture(scope="module")
def torsional_case_file(torsional_case, tmp_path_factory):
    """A coarse reference string without lateral modes: a 2 s run takes a few hundredths of a second."""
    path = tmp_path_factory.mktemp("cases") / "torsional.toml"
    path.write_text(torsional_case.to_toml(), encoding="utf-8")
    return path


def test_map_command_writes_the_map_and_resumes(torsional_case_file, tmp_path):
    import xarray as xr

    out = tmp_path / "m"
    args = ("map", str(torsional_case_file), "--top-speed", "80:160:2", "--weight-on-bit", "60 kN,90 kN",
            "--t-end", "2", "--workers", "1", "--out", str(out))
    result = _invoke(*args, "--json")
    assert result.exit_code == 0, result.output
    summary = json.loads(result.stdout)
    assert summary["top_speed"] == pytest.approx([80 * np.pi / 30, 160 * np.pi / 30])  # bare numbers: rpm
    assert summary["weight_on_bit"] == [6e4, 9e4] and summary["done"] == 4
    for name in ("map.zarr", "map.nc", "map.json", "map.png", "report.html"):
        assert (out / name).exists(), name
    with xr.open_dataset(out / "map.nc", engine="h5netcdf") as ds:
        assert ds.growth_rate.dims == ("top_speed", "weight_on_bit")
    table = _invoke(*args)
    assert table.exit_code == 0, table.output
    assert "resumed: 4 of 4 grid points" in table.stderr
    for text in ("Operating map", "largest mean ROP", "critical weight-on-bit", str(out / "report.html")):
        assert text in table.stdout, text


@pytest.mark.parametrize("args, words", [
    (("--top-speed", "40:200"), ["--top-speed = '40:200'", "A:B:N"]),
    (("--weight-on-bit", "2e6"), ["--weight-on-bit = 2e+06 N", "string's weight"]),
    (("--top-speed", "40 m:60 m:3"), ["--top-speed", "m"]),
])
def test_map_bad_grid_exits_2_with_one_line(torsional_case_file, tmp_path, args, words):
    result = _invoke("map", str(torsional_case_file), "--t-end", "1", "--out", str(tmp_path / "m"), *args)
    assert result.exit_code == 2, result.output
    assert len(result.stderr.strip().splitlines()) == 1 and "Traceback" not in result.output
    for word in words:
        assert word in result.stderr, result.stderr
    assert not (tmp_path / "m").exists()


def test_sensitivity_command(torsional_case_file, tmp_path):
    out = tmp_path / "s"
    args = ("sensitivity", str(torsional_case_file), "--param", "operation.top_speed=uniform 120 180 rpm",
            "--param", "operation.weight_on_bit=uniform 60 90 kN", "--samples", "8", "--t-end", "2",
            "--workers", "1", "--out", str(out))
    result = _invoke(*args, "--json")
    assert result.exit_code == 0, result.output
    payload = json.loads(result.stdout)
    assert payload["runs"] == 32 and payload["base_samples"] == 8
    assert json.loads((out / "sensitivity.json").read_text()) == payload
    table = _invoke(*args)
    assert table.exit_code == 0, table.output
    for text in ("Sobol' indices", "mean ROP", "top_speed", "weight_on_bit", "S1", "ST"):
        assert text in table.stdout, text
    flagged = [name for name, entry in payload["outputs"].items() if entry["sample_notes"]]
    assert flagged  # N = 8: intervals wider than the indices, at least
    assert "note: N = 8 base samples are too few for these indices: run again with --samples 16" in table.stdout
    refused = _invoke("sensitivity", str(torsional_case_file), "--out", str(tmp_path / "none"))
    assert refused.exit_code == 2 and "no uncertain parameter" in refused.stderr
    assert not (tmp_path / "none").exists()


def test_probabilistic_map_command_writes_the_files_and_resumes(torsional_case_file, tmp_path):
    import xarray as xr

    out = tmp_path / "pm"
    args = ("map", str(torsional_case_file), "--top-speed", "80:160:2", "--weight-on-bit", "60 kN,90 kN",
            "--t-end", "1", "--workers", "1", "--samples", "3", "--sigma", "4000",
            "--param", "operation.top_speed=uniform 0 10 rpm", "--out", str(out))
    refused = _invoke(*args, "--json")  # a law of a grid parameter
    assert refused.exit_code == 2 and "operation.top_speed: cannot carry a law on a map" in refused.stderr
    assert not out.exists()
    args = args[:-4] + ("--param", "fluid.inlet_velocity=uniform 1.2 1.8 m/s", "--out", str(out))
    result = _invoke(*args, "--json")
    assert result.exit_code == 0, result.output
    summary = json.loads(result.stdout)
    assert summary["samples"] == 3 and summary["done"] == 12 and summary["sigma"] == 4000.0
    assert summary["parameters"] == ["weight_on_hook", "fluid.inlet_velocity"]
    assert set(summary["probabilities"]) == {"stick_slip_probability", "buckling_probability", "impact_probability",
                                             "instability_probability", "bounce_probability",
                                             "torsional_instability_probability", "axial_instability_probability",
                                             "coexistence_probability"}
    for name in ("map.zarr", "map.nc", "map.json", "probabilities.png", "quantiles.png", "report.html",
                 "interactive.html"):
        assert (out / name).exists(), name
    with xr.open_dataset(out / "map.nc", engine="h5netcdf") as ds:
        assert ds.stick_slip_probability.dims == ("top_speed", "weight_on_bit")
        assert ds.rate_of_penetration_q.dims == ("top_speed", "weight_on_bit", "quantile")
        instability = ds.instability_probability.values
    page = (out / "interactive.html").read_text(encoding="utf-8")
    specs = [json.loads(t) for t in re.findall(r'class="figure-spec"[^>]*>(.*?)</script>', page, re.S)]
    assert [spec["layout"]["title"]["text"] for spec in specs][3] == "probability of unstable steady drilling"
    np.testing.assert_allclose(np.array(specs[3]["data"][0]["z"], dtype=float), instability.T, atol=1e-6)
    table = _invoke(*args)
    assert table.exit_code == 0, table.output
    assert "resumed: 12 of 12 realizations" in table.stderr
    for text in ("Probabilistic operating map", "P(buckled)", "3 realizations per point", "probabilities.png"):
        assert text in table.stdout, text
    # Field units: the table, the report and the interactive page (figures: tests/test_plots.py).
    field = _invoke(*args, "--units", "field")
    assert field.exit_code == 0, field.output
    rop = summary["quantiles"]["rate_of_penetration_q"]["50"][0][0] * 3600 / FT
    first_row = next(line.replace("│", " ").split() for line in field.stdout.splitlines()  # framed or not
                     if line.replace("│", " ").split()[:1] == ["80"])
    assert first_row[1] == f"{6e4 / KLBF:g}" and first_row[8].startswith(f"{rop:.3g}")  # after the five P columns (the rest may wrap)
    for text in ("WOB [klbf]", "[ft/h]", f"{summary['critical_weight_on_bit'] / KLBF:,.1f} klbf",
                 "(13.49–20.23 klbf)"):
        assert text in field.stdout, text
    assert " kN" not in field.stdout and "m/h" not in field.stdout
    report = (out / "report.html").read_text(encoding="utf-8")
    assert "<th>WOB [klbf]</th>" in report and "mean ROP [ft/h]" in report and "σ = 0.8992 klbf" in report
    page = (out / "interactive.html").read_text(encoding="utf-8")
    specs = [json.loads(t) for t in re.findall(r'class="figure-spec"[^>]*>(.*?)</script>', page, re.S)]
    assert specs[0]["layout"]["yaxis"]["title"]["text"] == "weight-on-bit [klbf]"
    assert specs[0]["data"][0]["y"] == pytest.approx([6e4 / KLBF, 9e4 / KLBF], rel=1e-5)  # 6 digits in the page
    lonely = _invoke("map", str(torsional_case_file), "--sigma", "4000", "--out", str(tmp_path / "none"))
    assert lonely.exit_code == 2 and "give --samples N" in lonely.stderr


@pytest.mark.parametrize("old, new, line", [
    # an overflow is refused while the unit is read, for every field (issue 26), then a range (next two)
    ('length = "1400 m"', 'length = "1e306 km"',
     "sections[0].length = '1e306 km': overflows to infinity in SI units (m); the largest number is about 1.8e308; "
     "must be within [0.001, 100000] m"),
    ('young_modulus = "210 GPa"', 'young_modulus = "1e300 GPa"', "materials.steel.young_modulus = '1e300 GPa': "
     "overflows to infinity in SI units (Pa); the largest number is about 1.8e308; must be within [1e+06, 1e+13] Pa"),
    ("atol = 1e-9", "atol = 1e-300", "simulation.atol = 1e-300: must be within [1e-20, 1000]"),
    ("a2 = 5.672e-8", "a2 = 5e-324", "bit_rock.a2 = 5e-324: must be within [1e-15, 0.001] m/(N*s)"),
])
def test_values_that_overflow_or_underflow_are_refused_naming_field_value_and_range(tmp_path, old, new, line):
    path = _edited_reference(tmp_path, old, new)
    result = _invoke("simulate", str(path), "--out", str(tmp_path / "run.nc"), "--plot", str(tmp_path / "run.png"))
    assert result.exit_code == 2, result.output
    assert result.stderr.splitlines() == [f"error: invalid case {path}: {line}"]
    assert not (tmp_path / "run.nc").exists()


@pytest.mark.parametrize("kind", ["fifo", "/dev/zero", "/dev/urandom", "folder", "too_large", "too_deep",
                                  "long_name"])
def test_only_sane_case_files_are_read(tmp_path, kind):
    """A FIFO, a device, a folder, a file over 1 MB, TOML nested deeper than 16 levels and a name over 200
    characters are refused at once, in one line, exit code 2."""
    import os

    path = tmp_path / "case.toml"
    expected = {"fifo": "is not a regular file", "/dev/zero": "is not a regular file",
                "/dev/urandom": "is not a regular file", "folder": "is not a regular file",
                "too_large": "more than the 1,000,000 allowed", "too_deep": "nested more than 16 levels deep",
                "long_name": "name = 'AAAA"}[kind]
    if kind == "fifo":
        os.mkfifo(path)
    elif kind.startswith("/dev/"):
        path = kind
    elif kind == "folder":
        path.mkdir()
    elif kind == "too_large":
        path.write_text(_reference_toml() + "#" * 1_000_000, encoding="utf-8")
    elif kind == "too_deep":
        path.write_text('name = "x"\nv = ' + "[" * 3000 + "]" * 3000 + "\n", encoding="utf-8")
    else:
        path.write_text(_reference_toml().replace('name = "reference"', f'name = "{"A" * 10_000}"'),
                        encoding="utf-8")
    result = _invoke("static", str(path))
    assert result.exit_code == 2, result.output
    lines = result.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"error: invalid case {path}: ") and expected in lines[0]
    if kind == "long_name":
        assert lines[0].endswith("must be at most 200 characters (it has 10,000)")


def test_a_collapsing_step_size_stops_the_run_early_naming_the_stiff_term(tmp_path):
    """a2 = 1e-12 m/(N·s) (within its range) makes the bit–rock law's axial resistance 1/(a2 Z²) stiff:
    the run stops after about 20,000 attempts, not at max_steps, exit code 1, one line with t, h and the
    bit–rock law as the stiff term; the partial run is written."""
    path = _edited_reference(tmp_path, "a2 = 5.672e-8 ", "a2 = 1e-12 ")
    coarse = path.read_text(encoding="utf-8").replace('max_element_length = "10 m"', 'max_element_length = "50 m"')
    path.write_text(coarse.replace("lateral_modes = 20", "lateral_modes = 3"), encoding="utf-8")
    out = tmp_path / "run.nc"
    result = _invoke("simulate", str(path), "--t-end", "1", "--out", str(out), "--plot", str(tmp_path / "run.png"))
    assert result.exit_code == 1, result.output
    errors = [row for row in result.stderr.splitlines() if row.startswith("error:")]
    assert len(errors) == 1
    assert "integration failed at t = " in errors[0] and "(h = " in errors[0]
    assert "step size collapsed" in errors[0] and "likely stiff term: bit–rock law" in errors[0]
    assert f"the partial run is in {out}" in errors[0] and out.exists()
