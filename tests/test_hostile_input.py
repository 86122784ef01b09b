"""Hostile input (issue 26): the shortest reproducers of a probe of ~600 inputs, each refused the way bad input
must be. Command line: exit code 2, one line on stderr naming the field, no traceback; an exponent tower in a
unit and a deeply dotted TOML key refused in under a second. API: TypeError or ValueError naming the
argument. (The store's metadata checksum: tests/stochastic/test_store.py; the stiff-term diagnosis:
tests/dynamics/test_stiffness.py; the boundary search: tests/dynamics/test_stability.py; BLAS threads:
tests/test_blas_threads.py; Campbell's size check: tests/test_campbell.py.)"""

from __future__ import annotations

import json
import time
import tomllib
from importlib import resources

import pytest
from typer.testing import CliRunner

from drillstring import api, units
from drillstring.case import CaseError, load_case
from drillstring.cli import app

runner = CliRunner()
_ENV = {"COLUMNS": "120", "FORCE_COLOR": None, "DRILLSTRING_UNITS": None}


def _reference_text() -> str:
    return resources.files("drillstring").joinpath("cases", "reference.toml").read_text(encoding="utf-8")


def _edited(folder, old: str, new: str, name: str = "hostile.toml"):
    text = _reference_text()
    assert old in text, old
    path = folder / name
    path.write_text(text.replace(old, new, 1), encoding="utf-8")
    return path


def _with_key(folder, table: str, key: str, value: str):
    """The reference case file with ``key = value`` in ``[table]`` (the line replaced, or added)."""
    lines = _reference_text().splitlines()
    start = lines.index(f"[{table}]")
    end = next((i for i in range(start + 1, len(lines)) if lines[i].startswith("[")), len(lines))
    for i in range(start + 1, end):
        if lines[i].split("=")[0].strip() == key:
            lines[i] = f"{key} = {value}"
            break
    else:
        lines.insert(start + 1, f"{key} = {value}")
    path = folder / "hostile.toml"
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def _refused(*args: str, env: dict | None = None) -> str:
    """Run the command line; assert exit code 2, one line on stderr, no traceback; return that line."""
    result = runner.invoke(app, list(args), env={**_ENV, **(env or {})})
    assert result.exit_code == 2, result.output
    assert result.exception is None or isinstance(result.exception, SystemExit), result.exception
    line = result.stderr.strip()
    assert "\n" not in line and "Traceback" not in result.output, result.output
    return line


# --- unit strings and numbers in case files ------------------------------------------------------------


@pytest.mark.parametrize(("old", "new", "fragments"), [
    ('weight_on_bit = "100 kN"', 'weight_on_bit = "100 kN*9**9**9/9**9**9"',
     ["operation.weight_on_bit", "a number (9) inside the unit"]),
    ('weight_on_bit = "100 kN"', 'weight_on_bit = "100 kN**2**2**2"', ["operation.weight_on_bit", "exponent tower"]),
    ('weight_on_bit = "100 kN"', 'weight_on_bit = "100 kN**9"', ["operation.weight_on_bit", "power 9", "at most 4"]),
    ('weight_on_bit = "100 kN"', 'weight_on_bit = "22,5 klbf"', ["operation.weight_on_bit", "comma"]),
    ('diameter = "0.3 m"', 'diameter = "1 200 m"', ["borehole.diameter", "digit groups"]),
    ('density = "1200 kg/m3"', 'density = "12,5 ppg"', ["fluid.density", "comma"]),
    ('inertia = "1000 kg*m2"', 'inertia = "1e308 kg*km2"', ["top_drive.inertia", "overflows to infinity"]),
    ('top_speed = "100 rpm"', 'top_speed = "1e-300 rpm"', ["operation.top_speed", "must be within [0.001, 1000]"]),
    ('weight_on_bit = "100 kN"', "weight_on_bit = 1" + "0" * 400, ["operation.weight_on_bit", "401 digits"]),
    ('max_element_length = "10 m"', 'max_element_length = "1 m' + "*m/m" * 20 + '"',
     ["mesh.max_element_length", "a value of 83 characters; at most 80"]),
    ('max_element_length = "10 m"', 'max_element_length = "1 m' + "*m/m" * 10 + '"',
     ["mesh.max_element_length", "unit of 41 characters; at most 40"]),
])
def test_unit_strings_and_numbers_refused_at_once(tmp_path, old, new, fragments):
    """pint is never handed an exponent tower (it computed 9**387420489 for 240 s), a digit group or a decimal
    comma is never multiplied in (1 200 m read 200 m; 22,5 klbf read 489 kN), an overflow or a huge integer
    is the one-line error of the field."""
    path = _edited(tmp_path, old, new)
    start = time.perf_counter()
    line = _refused("static", str(path))
    assert time.perf_counter() - start < 1.0
    assert all(fragment in line for fragment in fragments), line


@pytest.mark.parametrize(("table", "key", "value", "fragment"), [
    ("top_drive", "proportional_gain", '"1e308 kN*m*s/rad"', "overflows"),
    ("top_drive", "ramp_time", '"1e308 h"', "overflows"),
    ("top_drive", "ramp_time", '"1e6 s"', "must be within [0, 100000] s"),
    ("top_drive", "max_torque", "1e300", "must be within [1, 1e+09] N*m"),
    ("bow", "angle", '"1e308 krad"', "overflows"),
    ("simulation", "t_end", "1e300", "must be within [1e-09, 1e+07] s"),
    ("simulation", "max_steps", "1" + "0" * 30, "must be <= 1000000000000"),
    ("initial", "seed", str(2**64), "must be <= 18446744073709551615"),
])
def test_every_field_bounded_infinite_values_included(tmp_path, table, key, value, fragment):
    """Fields that had no range failed at build time (an infinite top-drive inertia, gain, ramp time or angle):
    each is refused by the case, naming it."""
    path = _with_key(tmp_path, table, key, value)
    line = _refused("static", str(path))
    assert f"{table}.{key}" in line and fragment in line, line


def test_section_angle_overflow_refused():
    data = {"name": "x", "sections": [{"name": "a", "length": 100.0, "outer_diameter": 0.1, "inner_diameter": 0.05,
                                       "eccentricity_angle": "1e308 krad"}], "borehole": {"diameter": 0.2},
            "mesh": {"probes": [50.0]}}
    from drillstring.case import case_from_dict

    with pytest.raises(CaseError, match=r"sections\[0\]\.eccentricity_angle = '1e308 krad': overflows"):
        case_from_dict(data)


# --- the TOML text before the parser ---------------------------------------------------------------------


@pytest.mark.parametrize("parts", [100_000, 20_000, 17])
def test_deeply_dotted_key_refused_before_parsing(tmp_path, parts):
    """A dotted key of 100,000 parts ran the TOML parser out of memory after 58 s (20,000: refused after 25 s);
    the text is scanned first."""
    path = tmp_path / "deep.toml"
    path.write_text(_reference_text() + "\n" + ".".join(["k"] * parts) + " = 1\n", encoding="utf-8")
    start = time.perf_counter()
    line = _refused("static", str(path))
    assert time.perf_counter() - start < 1.0
    assert "a dotted key of more than 16 parts" in line and "line " in line, line


def test_long_key_and_dotted_header_refused(tmp_path):
    path = tmp_path / "long.toml"
    path.write_text(_reference_text() + "\n[" + "x" * 500 + "]\n", encoding="utf-8")
    assert "a key longer than 400 characters" in _refused("static", str(path))
    path.write_text(_reference_text() + "\n[[" + ".".join(["t"] * 40) + "]]\n", encoding="utf-8")
    assert "more than 16 parts" in _refused("static", str(path))


def test_dots_in_values_strings_and_arrays_are_not_keys():
    from drillstring.case.loading import _toml_key_problem

    text = ('description = """\n' + ".".join(["a"] * 40) + ' = 1\n"""\n"' + ".".join(["q"] * 40) + '" = 2\n'
            "probes = [\n" + "1.5, " * 200 + "\n]\n")
    assert _toml_key_problem(text) is None


# --- geometry against the hole, meaningless law parameters ---------------------------------------------


def test_detournay_parameters_and_bit_radius_refused(tmp_path):
    path = _edited(tmp_path, 'law = "tucker_wang"', 'law = "detournay"')
    text = path.read_text().replace("cutting_inclination = 0.6", "cutting_inclination = 0")
    path.write_text(text)
    line = _refused("stability", str(path))
    assert "bit_rock.cutting_inclination = 0.0: must be within [0.1, 10]" in line, line  # ROP 4.7e9 m/h before
    path.write_text(text.replace("cutting_inclination = 0", "cutting_inclination = 0.6")
                    .replace('bit_radius = "0.108 m"', 'bit_radius = "5 m"'))
    line = _refused("stability", str(path))
    assert "bit_rock.bit_radius = 5.0: must be at most the borehole radius (0.15 m): the bit cuts the hole" in line, line


def test_tool_joints_and_bodies_wider_than_the_hole_refused():
    """0.5 m tool joints in a 0.3 m hole doubled the string's weight, silently."""
    text = resources.files("drillstring").joinpath("cases", "reference_components.toml").read_text()
    data = tomllib.loads(text)
    from drillstring.case import case_from_dict

    pipe = next(i for i, c in enumerate(data["components"]) if c["type"] == "drill_pipe")
    data["components"][pipe]["tool_joint"] = {"outer_diameter": "0.5 m", "length": "0.5 m"}
    with pytest.raises(CaseError, match=rf"components\[{pipe}\]\.tool_joint\.outer_diameter = 0\.5: must be "
                                        r"less than the borehole diameter"):
        case_from_dict(data)
    data = tomllib.loads(text)
    data["components"][-1]["outer_diameter"] = "0.4 m"
    with pytest.raises(CaseError, match=r"outer_diameter = 0\.4: must be less than the borehole diameter"):
        case_from_dict(data)


# --- models too large to solve, too many speeds, grids and laws outside the case -----------------------


def test_model_too_large_is_exit_2_like_modes(tmp_path):
    """The dense-fallback refusal (7.9 GiB for the 0.17 m mesh) was an uncaught ValueError in static;
    modes already said it in one line."""
    path = _edited(tmp_path, 'max_element_length = "10 m"', 'max_element_length = "0.17 m"')
    line = _refused("static", str(path))
    assert "no sparse solution" in line and "GiB dense" in line, line


def test_campbell_speed_count_refused_before_work():
    line = _refused("campbell", "reference", "--top-speed", "5:300:100000")
    assert line.startswith("error: --top-speed = '5:300:100000': 100,000 speeds, more than the 10,000"), line


def test_map_grid_beyond_the_case_refused_before_any_point(tmp_path):
    """A grid whose top speeds leave the case's range ran every point, all failed, and exited 0."""
    line = _refused("map", "reference", "--top-speed", "100:20000:3", "--out", str(tmp_path / "map"))
    assert "--top-speed = 1052.43 rad/s: must be within [0.001, 1000] rad/s" in line and "no point was run" in line
    assert not (tmp_path / "map" / "map.zarr").exists()


def test_random_law_beyond_the_field_refused_before_any_realization(tmp_path):
    line = _refused("study", "reference", "--param", "bit_rock.a2=uniform 1e-9 1e-2", "--samples", "4",
                    "--out", str(tmp_path / "study"))
    assert "bit_rock.a2 = 'uniform 1e-09 0.01': the law puts probability 0.9 outside the allowed range" in line
    line = _refused("study", "reference", "--param", "operation.weight_on_bit=uniform 100 1500 kN",
                    "--samples", "4", "--out", str(tmp_path / "study"))
    assert "outside the allowed range (> 0 and < 1.16343e+06 N)" in line, line
    assert not (tmp_path / "study").exists() or not any((tmp_path / "study").iterdir())


def test_unusable_units_environment_does_not_block_json():
    result = runner.invoke(app, ["static", "reference", "--json"], env={**_ENV, "DRILLSTRING_UNITS": "cubits"})
    assert result.exit_code == 0, result.output
    assert json.loads(result.stdout)["weight_on_bit"] == pytest.approx(1e5)
    assert "DRILLSTRING_UNITS = 'cubits'" in result.stderr and "ignored" in result.stderr
    tables = runner.invoke(app, ["static", "reference"], env={**_ENV, "DRILLSTRING_UNITS": "cubits"})
    assert tables.exit_code == 2 and "DRILLSTRING_UNITS = 'cubits'" in tables.output  # a usage error there


# --- the Python API: the command line's checks, naming the argument -------------------------------------


def test_api_arguments_named():
    with pytest.raises(ValueError, match=r"^an integer of 401 digits: too large"):
        units.to_si(10**400, units.FORCE)
    with pytest.raises(TypeError, match=r"^dim = 'density': must be a drillstring.units.Dimension"):
        units.to_si("1 ppg", "density")
    with pytest.raises(ValueError, match=r"^kind = 'bogus': must be one of force, length"):
        units.display_unit("bogus", "si")
    with pytest.raises(TypeError, match=r"^system = 3: must be a string"):
        units.display_unit("force", 3)


def test_api_weight_on_bit_checked_as_the_case(reference_case):
    with pytest.raises(ValueError, match=r"^weight_on_bit = 2000000.0 N: must be less than the string's weight"):
        api.stability(reference_case, weight_on_bit=2e6)
    with pytest.raises(ValueError, match=r"^weight_on_bit = 1000000000.0 N: must be less than the string's"):
        api.simulate(reference_case, weight_on_bit=1e9)
    with pytest.raises(ValueError, match=r"^weight_on_bit = 2000000000.0 N: must be within \[0, 1e\+09\] N"):
        api.simulate(reference_case, weight_on_bit=2e9)
    with pytest.raises(TypeError, match=r"^weight_on_bit = '100 kN' N: must be a number"):
        api.stability(reference_case, weight_on_bit="100 kN")


def test_model_copy_refuses_an_update_of_the_wrong_kind(reference_case):
    with pytest.raises(CaseError, match=r"simulation = 5: must be a Simulation \(or a table of its keys\), not int"):
        reference_case.model_copy(update={"simulation": 5})
    copy = reference_case.model_copy(update={"simulation": {"t_end": 2.0}})
    assert copy.simulation.t_end == 2.0 and copy.simulation.output_step == reference_case.simulation.output_step
    with pytest.raises(CaseError, match=r"simulation\.t_end = -1: must be > 0"):
        reference_case.copy_with({"simulation": {"t_end": -1}})
    with pytest.raises(CaseError, match=r"operation\.weight_on_bit = 2000000.0: must be less than the string's"):
        reference_case.copy_with({"operation": reference_case.operation.model_copy(update={"weight_on_bit": 2e6})})


def test_boundary_found_from_far_above_it(reference_case):
    """From 300 kN (and up to the string's weight) `stability --boundary` said no crossing exists although
    the growth rate crosses 0 at 95.98 kN: its growing steps jumped past it into the range without steady
    drilling and stopped there."""
    case = reference_case.copy_with({"operation": {"top_speed": reference_case.operation.top_speed,
                                                   "weight_on_bit": 300e3}})
    assert api.stability_boundary(case)["weight_on_bit"] == pytest.approx(95.98e3, abs=30.0)


def test_reference_case_still_loads():
    assert load_case("reference").operation.weight_on_bit == 1e5


@pytest.mark.parametrize(("text", "dimension", "si"), [
    ("60 1/min", units.ANGULAR_SPEED, 2.0 * 3.141592653589793),  # a frequency: revolutions per minute
    ("2 °", units.ANGLE, 2.0 * 3.141592653589793 / 180.0),
    ("3 kg*m²", units.MOMENT_OF_INERTIA, 3.0),
    ("1 m^-1*m**2", units.LENGTH, 1.0),
    ("5.672e-8 m/(N*s)", units.PENETRATION_PER_FORCE, 5.672e-8),
    ("2 µm", units.LENGTH, 2e-6),
    ("1e-3 kN*m*s/rad", units.ROTATIONAL_DAMPING, 1.0),
])
def test_units_a_person_writes_still_read(text, dimension, si):
    """The tokeniser refuses expressions, not units: every unit form of the docs still reads."""
    assert units.to_si(text, dimension) == pytest.approx(si, rel=1e-12)


@pytest.mark.parametrize(("laws", "fragment"), [
    ({"sections[1].outer_diameter": "uniform 0.2 0.31 m"},
     "the case refuses the law's 0.999999 quantile, 0.31 m (must be less than the borehole diameter (0.3 m))"),
    ({"initial.lateral_perturbation": "uniform 0 0.1 m"}, "must be less than the smallest radial gap"),
])
def test_laws_the_case_refuses_at_their_extremes(reference_case, laws, fragment):
    """A law within its field's own range whose draws the case's cross-field rules refuse (a collar as wide as
    the hole) is refused at declaration, not realization after realization."""
    from drillstring.stochastic.parameters import ParameterError
    from drillstring.stochastic.uncertainty import uncertainty

    with pytest.raises(ParameterError) as info:
        uncertainty(reference_case, laws)
    assert fragment in str(info.value) and "\n" not in str(info.value)
    assert uncertainty(reference_case, {"sections[1].outer_diameter": "uniform 0.2 0.25 m"}).size == 1


# --- issue 37: torque and drag, its input files, the downhole motor ------------------------------------------


def _case_file(folder, name: str, old: str = "", new: str = "", survey: str | None = None):
    """The built-in case ``name`` copied into ``folder`` (with its survey file), ``old`` replaced by ``new``."""
    cases = resources.files("drillstring").joinpath("cases")
    text = cases.joinpath(f"{name}.toml").read_text(encoding="utf-8")
    if name == "deviated":
        (folder / "deviated_survey.csv").write_text(cases.joinpath("deviated_survey.csv").read_text(), "utf-8")
    if survey is not None:
        (folder / "survey.csv").write_text(survey, encoding="utf-8")
        old, new = 'survey_file = "deviated_survey.csv"', 'survey_file = "survey.csv"'
    assert old in text, old
    path = folder / f"{name}_hostile.toml"
    path.write_text(text.replace(old, new, 1), encoding="utf-8")
    return path


def _quickly_refused(*args: str, seconds: float = 3.0) -> str:
    start = time.perf_counter()
    line = _refused(*args)
    assert time.perf_counter() - start < seconds, line
    return line


def test_torque_on_bit_beyond_any_rig_refused(tmp_path):
    path = _case_file(tmp_path, "deviated", 'torque_on_bit = "4 kN*m"', "torque_on_bit = 1e14")
    line = _quickly_refused("torque-drag", str(path))
    assert "well.torque_on_bit" in line and "[0, 1e+06] N*m" in line


def test_corkscrew_survey_loads_unbounded_not_a_traceback(tmp_path):
    """A survey turning ~170 deg every 10 m: the capstan law multiplies the tension beyond any number; the table
    says "unbounded", the JSON null."""
    rows = ["measured_depth [m],inclination [deg],azimuth [deg]", "0,0,0"]
    rows += [f"{10 * k},90,{170 * k % 360}" for k in range(1, 301)]
    path = _case_file(tmp_path, "deviated", survey="\n".join(rows) + "\n")
    result = runner.invoke(app, ["torque-drag", str(path)], env=_ENV)
    assert result.exit_code == 0, result.output
    assert "unbounded" in result.stdout
    result = runner.invoke(app, ["torque-drag", str(path), "--json"], env=_ENV)
    assert result.exit_code == 0, result.output
    assert json.loads(result.stdout)["operations"]["trip_out"]["hook_load"] is None


def _fifo(tmp_path):
    import os

    fifo = tmp_path / "fifo.csv"
    os.mkfifo(fifo)
    return str(fifo)


@pytest.mark.parametrize("source", ["/dev/zero", "/dev/urandom", "fifo"])
def test_measurements_and_survey_that_are_not_regular_files_refused_unread(tmp_path, source):
    name = _fifo(tmp_path) if source == "fifo" else source
    line = _quickly_refused("torque-drag", "deviated", "--measurements", name)
    assert line.startswith(f"error: --measurements = {name}:") and "not a regular file" in line
    path = _case_file(tmp_path, "deviated", 'survey_file = "deviated_survey.csv"', f'survey_file = "{name}"')
    line = _quickly_refused("torque-drag", str(path))
    assert "well.survey_file" in line and "not a regular file" in line


@pytest.mark.parametrize(("rows", "fragment"), [
    (300_000, "more than the 1,000,000 allowed"),      # 300,000 rows: 8.3 GiB of predictions before
    (20_000, "more than the 2,000 allowed"),           # rows within the byte limit, beyond the count
    (1_000, "distinct bit depths, more than the 200"),  # 1,000 depths: minutes of work before
])
def test_measurements_bounded_before_any_work(tmp_path, rows, fragment):
    path = tmp_path / "measured.csv"
    step = 0.001 if rows > 1_000 else 2.0
    path.write_text("bit_depth [m],operation,hook_load [kN]\n"
                    + "".join(f"{500 + k * step:.3f},trip_out,500\n" for k in range(rows)), encoding="utf-8")
    line = _quickly_refused("torque-drag", "deviated", "--measurements", str(path))
    assert line.startswith(f"error: --measurements = {path}:") and fragment in line


def test_survey_with_more_stations_than_allowed_refused_before_parsing(tmp_path):
    rows = ["measured_depth [m],inclination [deg],azimuth [deg]"] + [f"{k * 0.3:.1f},0,0" for k in range(20_001)]
    path = _case_file(tmp_path, "deviated", survey="\n".join(rows) + "\n")
    assert "more than the 20,000 stations allowed" in _quickly_refused("torque-drag", str(path))


@pytest.mark.parametrize("sigma", ["1e300 kN", "1e-300 N"])
def test_calibration_noise_outside_its_range_refused(tmp_path, sigma):
    path = tmp_path / "measured.csv"
    path.write_text("bit_depth [m],operation,hook_load [kN]\n1000,trip_out,500\n", encoding="utf-8")
    line = _quickly_refused("torque-drag", "deviated", "--measurements", str(path), "--sigma", sigma)
    assert line == f"error: --sigma = {sigma}: must be a force within [0.001, 1e+08] N (e.g. '20 kN')"


def test_plot_whose_sibling_figure_is_a_folder_refused_before_work(tmp_path):
    (tmp_path / "sib" / "x-path.png").mkdir(parents=True)
    plot = tmp_path / "sib" / "x.png"
    line = _quickly_refused("torque-drag", "deviated", "--plot", str(plot))
    assert line == f"error: --plot = {tmp_path / 'sib' / 'x-path.png'}: is a folder; give a file name"


@pytest.mark.parametrize(("old", "new", "fragment"), [
    ('speed_per_flow = "0.2 rev/gal"', "speed_per_flow = 1e-300", "components[3].speed_per_flow = 1e-300: must be "
     "within [10, 1e+06] rad/m3"),
    ('speed_per_flow = "0.2 rev/gal"', 'displacement = "1e-12 m^3/rev"', "components[3].displacement"),
    ("volumetric_efficiency = 0.9 ", "volumetric_efficiency = 1e-9 ", "components[3].volumetric_efficiency = 1e-09: "
     "must be within [0.1, 1]"),
    ("mechanical_efficiency = 0.85", "mechanical_efficiency = 1e-12", "components[3].mechanical_efficiency"),
    ('max_differential_pressure = "1000 psi"', "max_differential_pressure = 1e-300",
     "components[3].max_differential_pressure"),
    ('flow_rate = "500 gpm"', 'flow_rate = "1e-6 gpm"', "fluid.flow_rate = 6.30901964e-11: gives the motor a no-load "
     "speed"),
])
def test_motor_keys_outside_a_motors_range_refused_naming_the_key(tmp_path, old, new, fragment):
    path = _case_file(tmp_path, "motor", old, new)
    with pytest.raises(CaseError) as caught:
        load_case(path)
    assert fragment in str(caught.value), str(caught.value)
    assert fragment in _quickly_refused("stability", str(path))
