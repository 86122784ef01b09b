"""The ``[well]`` table of a deviated well: its survey (read by :mod:`drillstring.case.survey_input`), casing
and friction factors, and the well's cross-field rules.
"""

from __future__ import annotations

import math
from typing import Any, Mapping

from pydantic import Field

from drillstring.case.base import Angle, Density, Dimensionless, Length, Torque, _Base
from drillstring.case.errors import _MISSING, CaseError, _Entry, _fmt_value, _Problems
from drillstring.case.survey_input import SurveyProblem, read_survey_csv, survey_from_rows, survey_problems


def _survey_entries(problems: list[tuple[int | None, Any, str]], key: str,
                    rows: Any = None) -> list[_Entry]:
    """Case-error entries ``well.<key>[row] = <row>: message`` of survey problems."""
    out: list[_Entry] = []
    for row, value, message in problems:
        loc: tuple[str | int, ...] = (key,) if row is None else (key, row)
        if value is _MISSING and rows is not None and row is not None and row < len(rows):
            value = rows[row]
        out.append((loc, None if value is _MISSING else _fmt_value(value), message))
    return out


class Well(_Base):
    """A deviated well (:mod:`drillstring.well`): its directional survey, casing and friction factors.

    The survey is given as ``survey = [[md, inc, az], ...]`` in ``survey_units`` (default m, deg, deg), or as
    ``survey_file`` (a CSV file, its path relative to the case file; units in its header), or, as ``to_toml``
    writes it, as the SI lists ``measured_depth`` [m], ``inclination`` [rad], ``azimuth`` [rad]
    (:mod:`drillstring.case.survey_input`). It starts at the surface and reaches at least the bit."""

    measured_depth: list[Length] = Field(description="survey stations' measured depths [m], from 0, increasing")
    inclination: list[Angle] = Field(description="inclination from the vertical at each station [rad], in [0, pi]")
    azimuth: list[Angle] = Field(description="azimuth from north at each station [rad]")
    casing_shoe: Length = Field(0.0, ge=0, description="measured depth of the casing shoe [m]; cased above")
    casing_inner_diameter: Length | None = Field(
        None, gt=0, description="casing bore [m] (buckling clearance in the cased hole); the borehole's by default")
    cased_hole_friction: Dimensionless = Field(0.25, ge=0, le=2, description="friction factor in the casing [-]")
    open_hole_friction: Dimensionless = Field(0.30, ge=0, le=2, description="friction factor in the open hole [-]")
    torque_on_bit: Torque = Field(0.0, ge=0, description="torque on bit when drilling [N*m]")
    inner_fluid_density: Density | None = Field(
        None, ge=0, description="mud density inside the string [kg/m^3]; fluid.density by default")
    tool_joints: dict[str, Length] = Field(
        default_factory=dict, description="tool-joint outer diameter by section name [m]: the torque arm")

    @staticmethod
    def _columns(data: dict[str, Any]) -> tuple[dict[str, Any], tuple[str, Any]]:
        """``data`` with ``survey`` or ``survey_file`` read into the SI lists; which key gave them."""
        given = [k for k in ("survey", "survey_file", "measured_depth") if k in data]
        if len(given) > 1:
            raise _Problems([((given[1],), _MISSING, f"give one of survey, survey_file or measured_depth/"
                                                       f"inclination/azimuth, not {' and '.join(given)}")])
        units = data.pop("survey_units", ["m", "deg", "deg"])
        if not (isinstance(units, list) and len(units) == 3 and all(isinstance(u, str) for u in units)):
            raise _Problems([(("survey_units",), units, 'must be three units, e.g. ["ft", "deg", "deg"]')])
        if "survey" in data:
            rows = data.pop("survey")
            if not isinstance(rows, list):
                raise _Problems([(("survey",), rows, "must be a list of [md, inc, az] rows")])
            try:
                columns = survey_from_rows(rows, units)
            except SurveyProblem as exc:
                raise CaseError(_survey_entries(exc.problems, "survey", rows)) from None
            origin: tuple[str, Any] = ("survey", rows)
        elif "survey_file" in data:
            path = data.pop("survey_file")
            try:
                columns = read_survey_csv(path, units)
            except SurveyProblem as exc:
                raise CaseError(_survey_entries(exc.problems, "survey_file")) from None
            except (TypeError, ValueError) as exc:
                raise _Problems([(("survey_file",), path, str(exc))]) from None
            origin = ("survey_file", None)
        else:
            return data, ("survey", None)
        Well._check(columns, *origin)
        data["measured_depth"], data["inclination"], data["azimuth"] = columns
        return data, origin

    @staticmethod
    def _check(columns: Any, key: str, raw: Any) -> None:
        """Raise a CaseError naming each bad row of the survey (:func:`survey_problems`)."""
        problems = survey_problems(*columns)
        if problems:
            values = raw if raw is not None else [
                [s, round(math.degrees(i), 9), round(math.degrees(a), 9)] for s, i, a in zip(*columns)]
            raise CaseError(_survey_entries([(r, _MISSING, m) for r, m in problems], key, values),
                            source="<Well>")

    def __init__(self, /, **data: Any) -> None:
        try:
            data, (key, raw) = self._columns(dict(data))
        except _Problems as exc:
            raise CaseError(exc.entries, source="<Well>") from None
        super().__init__(**data)
        if len({len(self.measured_depth), len(self.inclination), len(self.azimuth)}) != 1:
            raise CaseError([(("measured_depth",), None, "measured_depth, inclination and azimuth must have "
                                                           "the same length")], source="<Well>")
        if key == "survey" and raw is None:  # given as the SI lists
            self._check((self.measured_depth, self.inclination, self.azimuth), key, None)

    @classmethod
    def model_validate(cls, obj: Any, *args: Any, **kwargs: Any) -> Any:  # type: ignore[override]
        if isinstance(obj, Mapping):
            return cls(**dict(obj))
        return super().model_validate(obj, *args, **kwargs)

    @property
    def depth(self) -> float:
        """Measured depth of the last survey station [m]."""
        return self.measured_depth[-1]


def _well_problems(case: Any) -> list[tuple[tuple[str | int, ...], Any, str]]:
    """Cross-field rules of ``[well]``: the string fits in the well, the shoe is in it, tool joints name
    sections and are at most the hole's diameter."""
    well = case.well
    if well is None:
        return []
    problems: list[tuple[tuple[str | int, ...], Any, str]] = []
    last = len(well.measured_depth) - 1
    if case.length > well.depth * (1.0 + 1e-12):
        problems.append((("well", "survey", last), [well.depth, round(math.degrees(well.inclination[-1]), 9),
                                                    round(math.degrees(well.azimuth[-1]), 9)],
                         f"the last station ({well.depth:g} m) is above the bit: the string is "
                         f"{case.length:g} m long, longer than the well"))
    if well.casing_shoe > well.depth:
        problems.append((("well", "casing_shoe"), well.casing_shoe, f"must be within the well, <= {well.depth:g} m"))
    names = {s.name for s in case.sections}
    for name, diameter in well.tool_joints.items():
        if name not in names:
            problems.append((("well", "tool_joints", name), diameter,
                             f"unknown section; sections: {', '.join(sorted(names))}"))
        elif diameter >= case.borehole.diameter:
            problems.append((("well", "tool_joints", name), diameter,
                             f"must be less than the borehole diameter ({case.borehole.diameter:g} m)"))
    return problems
