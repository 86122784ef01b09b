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


# ---------------------------------------------------------------------------------------- simulate, study


@pytest.fixture(scope="module")
def coarse_case(tmp_path_factory):
    """The reference case on a 40 m mesh: a 1 s run takes a fraction of a second."""
    from drillstring.case import load_case

    case = load_case("reference")
    case = case.model_copy(update={"mesh": case.mesh.model_copy(update={"max_element_length": 40.0})})
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
    for text in ("rate of penetration", "m/h", "rpm", "bit speed oscillation", "stick time fraction", "mm",
                 "impacts", "steps accepted",
                 str(tmp_path / "a.nc")):
        assert text in result.stdout, text


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
                 "envelopes.png", "dispersion.png"):
        assert (out / name).exists(), name
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
    assert second["wall_time"] < first["wall_time"]  # nothing left to run
    assert "resumed" in again.stderr

    table = _study(coarse_case, out)
    assert table.exit_code == 0, table.output
    for text in ("rate of penetration", "mean δ [%]", "δ_WOH", f"Figures and report: {out / 'report.html'}"):
        assert text in table.stdout, text


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
        raise montecarlo.StudyInterrupted(
            "study interrupted after 1 of 3 realizations; they are saved in x; run the same command again "
            "to resume")

    monkeypatch.setattr(montecarlo, "run_study", interrupted)
    result = _study(coarse_case, tmp_path / "i")
    assert result.exit_code == 130
    assert "resume" in result.stderr
    assert "Traceback" not in result.output


# ------------------------------------------------------------------------------------------------ compare


@pytest.fixture(scope="module")
def coarse_modes_case(tmp_path_factory):
    """The reference case on a 40 m mesh with 3 axial, 3 torsional and 4 lateral modes."""
    from drillstring.case import load_case

    case = load_case("reference")
    case = case.model_copy(update={
        "mesh": case.mesh.model_copy(update={"max_element_length": 40.0}),
        "reduced_model": case.reduced_model.model_copy(
            update={"axial_modes": 3, "torsional_modes": 3, "lateral_modes": 4}),
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


def test_stability_json_and_table(coarse_case):
    data = _json("stability", str(coarse_case), "--json")
    assert set(data) == {"stable", "steady_state", "modes"}
    assert data["stable"] is False  # free–free damping: the first torsional mode grows
    steady = data["steady_state"]
    assert steady["bit_speed"] == pytest.approx(100 * 3.141592653589793 / 30)
    assert 3e-3 < steady["rate_of_penetration"] < 4e-3 and steady["force_on_bit"] == pytest.approx(1e5, rel=1e-6)
    leading = max(data["modes"], key=lambda m: m["growth_rate"])
    assert leading["family"] == "torsional" and leading["growth_rate"] > 0
    result = _invoke("stability", str(coarse_case))
    assert result.exit_code == 0, result.output
    for text in ("rate of penetration", "m/h", "UNSTABLE", "torsional", "growth rate"):
        assert text in result.stdout, text


def test_stability_without_steady_drilling_is_one_line(tmp_path, coarse_case):
    from drillstring.case import load_case

    case = load_case(coarse_case)
    case = case.model_copy(update={"bit_rock": case.bit_rock.model_copy(update={"a1": 0.02})})
    path = tmp_path / "no_drilling.toml"
    path.write_text(case.to_toml(), encoding="utf-8")
    result = _invoke("stability", str(path))
    assert result.exit_code == 2
    assert "rate_of_penetration" in result.stderr and "Traceback" not in result.output
