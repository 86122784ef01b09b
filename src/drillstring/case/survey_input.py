"""Reading and checking a directional survey: a table in the case file or a CSV file it names.

A survey is a list of rows ``(measured depth, inclination, azimuth)``. In a case file (``[well]``) it is
``survey = [[md, inc, az], ...]`` in the units ``survey_units`` (default ``["m", "deg", "deg"]``), or
``survey_file = "path.csv"``: a CSV file whose first line names the columns with their units in brackets,

    measured_depth [ft], inclination [deg], azimuth [deg]

(``md``/``inc``/``azi`` are accepted as names; a column without a bracket takes the unit of
``survey_units``). Every unit is read by :mod:`drillstring.units` (pint), so feet and metres, degrees and
radians mix freely. :func:`survey_problems` lists what is wrong with a survey, one line per problem naming
its row: depths not increasing (out of order or repeated), an inclination outside [0, 180] deg, a missing or
non-numeric value (NaN, an empty cell: a gap), a survey that does not start at the surface (a gap above its
first station), too few stations.

A survey file must be a regular file of at most :data:`MAX_SURVEY_FILE_BYTES` and :data:`MAX_STATIONS` rows
(a FIFO or a device such as ``/dev/zero`` is refused without being read: :func:`drillstring.files.read_input_text`).

This module imports nothing from ``drillstring`` but :mod:`drillstring.units`, :mod:`drillstring.files` and
:mod:`drillstring.derived` (the dogleg of a course).
"""

from __future__ import annotations

import csv
import io
import math
import re
from pathlib import Path
from typing import Any, Sequence

from drillstring.derived import dogleg
from drillstring.files import read_input_text
from drillstring.units import ANGLE, LENGTH, to_si

__all__ = ["COLUMNS", "MAX_STATIONS", "SurveyProblem", "read_survey_csv", "survey_from_rows", "survey_problems"]

#: The survey's columns, in order.
COLUMNS = ("measured_depth", "inclination", "azimuth")
_ALIASES = {"md": 0, "measured_depth": 0, "depth": 0, "inc": 1, "incl": 1, "inclination": 1,
            "azi": 2, "az": 2, "azimuth": 2}
#: Most stations a survey may have (a 10 km well surveyed every half metre; directional surveys are taken
#: every 10-30 m). Every station is an element end of the soft-string analysis, whose time grows with their
#: number (`drillstring torque-drag`, every operation and the lock-up search: about 20 s at 10,000 stations,
#: 3 minutes at 100,000).
MAX_STATIONS = 20_000
#: Largest CSV file read [bytes] (20,000 rows of three numbers with room to spare).
MAX_SURVEY_FILE_BYTES = 4_000_000


class SurveyProblem(ValueError):
    """Problems of a survey: ``(row, value, message)`` triples (row None: the whole survey)."""

    def __init__(self, problems: list[tuple[int | None, Any, str]]) -> None:
        self.problems = problems
        super().__init__("; ".join(f"row {row}: {message}" for row, _, message in problems))


def _number(value: Any, unit: str, dimension) -> float:
    if isinstance(value, bool) or value is None or (isinstance(value, str) and not value.strip()):
        return math.nan
    if isinstance(value, str):
        value = value.strip()
        try:
            value = float(value)
        except ValueError:
            return to_si(value, dimension)
    return float(value) * to_si(f"1 {unit}", dimension)


def survey_from_rows(rows: Sequence[Any], units: Sequence[str]) -> tuple[list[float], list[float], list[float]]:
    """Depths [m], inclinations [rad] and azimuths [rad] of ``rows`` (each ``[md, inc, az]``: numbers in
    ``units``, or ``"value unit"`` strings; a missing or unreadable value becomes NaN, reported by
    :func:`survey_problems`). Raises :class:`SurveyProblem` for a row that is not three values."""
    problems: list[tuple[int | None, Any, str]] = []
    columns: tuple[list[float], list[float], list[float]] = ([], [], [])
    dims = (LENGTH, ANGLE, ANGLE)
    for i, row in enumerate(rows):
        if not isinstance(row, (list, tuple)) or len(row) != 3:
            problems.append((i, row, "must be three values: measured depth, inclination, azimuth (a gap?)"))
            continue
        for j in range(3):
            try:
                columns[j].append(_number(row[j], units[j], dims[j]))
            except (TypeError, ValueError) as exc:
                problems.append((i, row, f"{COLUMNS[j]}: {exc}"))
                columns[j].append(math.nan)
    if problems:
        raise SurveyProblem(problems)
    return columns


def _header(cell: str, default: str) -> tuple[int | None, str]:
    match = re.fullmatch(r"\s*([A-Za-z_ ]+?)\s*(?:[\[(]\s*([^\])]+?)\s*[\])])?\s*", cell)
    if not match:
        return None, default
    name = match.group(1).strip().lower().replace(" ", "_")
    return _ALIASES.get(name), match.group(2) or default


def read_survey_csv(path: str | Path, units: Sequence[str] = ("m", "deg", "deg")) -> tuple[list[float], ...]:
    """The survey of a CSV file (header line naming the columns, units in brackets; module docstring):
    depths [m], inclinations [rad], azimuths [rad]. Raises :class:`SurveyProblem` (row numbers count data
    rows from 0) or ValueError for an unreadable file or header."""
    path = Path(path)
    text = read_input_text(path, what="survey file", max_bytes=MAX_SURVEY_FILE_BYTES)
    lines = [line for line in text.splitlines() if line.strip() and not line.lstrip().startswith("#")]
    if not lines:
        raise ValueError(f"survey file {path} is empty")
    if len(lines) - 1 > MAX_STATIONS:
        raise ValueError(f"survey file {path} has {len(lines) - 1:,} rows, more than the {MAX_STATIONS:,} "
                         "stations allowed")
    reader = list(csv.reader(io.StringIO("\n".join(lines))))
    order: list[int | None] = []
    column_units = list(units)
    for cell in reader[0]:
        index, unit = _header(cell, "")
        order.append(index)
        if index is not None and unit:
            column_units[index] = unit
    if sorted(i for i in order if i is not None) != [0, 1, 2]:
        raise ValueError(f"survey file {path}: the header {reader[0]!r} must name the columns measured_depth, "
                         "inclination and azimuth (units in brackets, e.g. 'measured_depth [ft]')")
    rows = []
    for record in reader[1:]:
        row: list[Any] = [None, None, None]
        for index, value in zip(order, record):
            if index is not None:
                row[index] = value
        rows.append(row)
    return survey_from_rows(rows, column_units)


def survey_problems(measured_depth: Sequence[float], inclination: Sequence[float],
                    azimuth: Sequence[float]) -> list[tuple[int | None, str]]:
    """What is wrong with a survey [m, rad, rad]: ``(row, message)`` pairs, one per problem, rows from 0."""
    problems: list[tuple[int | None, str]] = []
    n = len(measured_depth)
    if n < 2:
        return [(None, f"has {n} station{'s' if n != 1 else ''}: at least 2 are needed")]
    if n > MAX_STATIONS:
        return [(None, f"has {n:,} stations, more than the {MAX_STATIONS:,} allowed")]
    previous = None
    for i, (s, inc, azi) in enumerate(zip(measured_depth, inclination, azimuth)):
        bad = [name for name, v in zip(COLUMNS, (s, inc, azi)) if not math.isfinite(v)]
        if bad:
            problems.append((i, f"{', '.join(bad)} missing or not a finite number (a gap in the survey)"))
            continue
        if i == 0 and s != 0.0:
            problems.append((i, f"measured depth {s:g} m: the survey must start at the surface (0 m); "
                                "a gap above its first station"))
        if not 0.0 <= inc <= math.pi:
            problems.append((i, f"inclination {math.degrees(inc):g} deg: must be in [0, 180] deg"))
        if previous is not None:
            if s == previous:
                problems.append((i, f"measured depth {s:g} m repeats the previous row's"))
            elif s < previous:
                problems.append((i, f"measured depth {s:g} m is less than the previous row's ({previous:g} m): "
                                    "stations must be in order of increasing depth"))
        previous = s if previous is None or s > previous else previous
    if not problems:  # a course turning the hole right round has no minimum-curvature arc
        beta = dogleg(inclination[:-1], azimuth[:-1], inclination[1:], azimuth[1:])
        for i in map(int, (beta > math.pi - 1e-9).nonzero()[0]):
            problems.append((i + 1, "turns the hole through 180 deg from the previous row: the arc is undefined"))
    return problems
