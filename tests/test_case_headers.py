"""The numbers the built-in case files' headers quote are those the program computes for the case as written.

A header is the first thing a user reads of a case; when a change moves a result (standard gravity as the
default, issue 37), its quoted statics must move with it. The statics of ``aarsnes2019`` are checked against
the closed form of a hanging string without mud, from the file's own data; the motor case's buckling load
against :func:`drillstring.buckling.case_buckling_margin` (no closed form: a stabilised string in flowing mud).
"""

from __future__ import annotations

import math
import re
import tomllib
from importlib.resources import files

import pytest

from drillstring.api import static
from drillstring.buckling import case_buckling_margin
from drillstring.case import load_case

STANDARD_GRAVITY = 9.80665  # m/s^2, exact by definition (3rd CGPM, 1901): the default of a case's gravity
LENGTH = {"m": 1.0, "mm": 1e-3}


def _case_file(name: str) -> str:
    return files("drillstring.cases").joinpath(f"{name}.toml").read_text(encoding="utf-8")


def _metres(value: str) -> float:
    number, unit = value.split()
    return float(number) * LENGTH[unit]


def _quoted(header: str, label: str, unit: str) -> float:
    """The number the header prints after ``label`` (e.g. 'hook load 507.40 kN' -> 507.40)."""
    found = re.search(rf"{label}\s+([0-9.]+)\s+{unit}", header.replace("\n#  ", " "))
    assert found, f"the header quotes no '{label} ... {unit}'"
    return float(found.group(1))


def _closed_form_statics(data: dict) -> dict[str, float]:
    """Weight [kN], hook load [kN] and neutral point [m above the bit] of a vertical string hanging in air.

    Section i (top to bottom) weighs ``w_i = rho g pi (D_o^2 - D_i^2) / 4`` per metre; the axial force is the
    weight below minus the weight on bit, so it vanishes at the height ``h`` above the bit where the weight
    below equals the weight on bit: ``h = sum of the lower sections' lengths + (WOB - their weight) / w_k``
    in the section k that holds it.
    """
    assert data["fluid"]["density"].split()[0] == "0", "the closed form is the string in air (no mud)"
    density = float(data["materials"]["steel"]["density"].split()[0])
    sections = [(_metres(s["length"]),
                 density * STANDARD_GRAVITY * math.pi / 4
                 * (_metres(s["outer_diameter"]) ** 2 - _metres(s["inner_diameter"]) ** 2))
                for s in data["sections"]]
    weight_on_bit = float(data["operation"]["weight_on_bit"].split()[0]) * 1e3
    weight = sum(length * w for length, w in sections)
    height, below = 0.0, 0.0
    for length, w in reversed(sections):
        if below + length * w >= weight_on_bit:
            height += (weight_on_bit - below) / w
            break
        height, below = height + length, below + length * w
    return {"weight": weight / 1e3, "hook load": (weight - weight_on_bit) / 1e3, "neutral point": height}


def test_aarsnes2019_header_quotes_the_statics_of_standard_gravity():
    text = _case_file("aarsnes2019")
    header = "\n".join(line for line in text.splitlines() if line.startswith("#"))
    exact = _closed_form_statics(tomllib.loads(text))
    state, _ = static("aarsnes2019")
    computed = {"weight": state.weight / 1e3, "hook load": state.weight_on_hook / 1e3,
                "neutral point": state.neutral_point_height}
    for label, unit in (("weight", "kN"), ("hook load", "kN"), ("neutral point", "m")):
        assert computed[label] == pytest.approx(exact[label], rel=1e-9), label  # the FE statics are nodally exact
        assert _quoted(header, label, unit) == pytest.approx(exact[label], abs=0.005 + 1e-9), label  # 2 decimals


def test_motor_header_quotes_its_buckling_load():
    text = _case_file("motor")
    line = next(line for line in text.splitlines() if line.startswith("weight_on_bit"))
    quoted = float(re.search(r"\(([0-9.]+) kN\)", line).group(1))
    critical = case_buckling_margin(load_case("motor")).critical_weight_on_bit / 1e3
    assert quoted == pytest.approx(critical, abs=0.05 + 1e-9)  # printed to 0.1 kN
