"""Reading a surface record from a file: :func:`read_surface_record`, the one entry point (docs/estimation.md,
"Surface records").

A CSV file (or a Parquet file, when pandas and pyarrow are installed) with a time column and channel columns.
Lines starting with ``#`` are comments. The first line names the columns, each with its unit in brackets
(``HKLD [klbf]``, as the project's other CSV files: the survey, the hook-load measurements); a second line
holding only units (``s, rpm, kN*m, ...``, as many field exports write them) is read as the units too.

Columns are mapped to channels (:data:`~drillstring.estimation.surface.CHANNELS`) by the caller
(``columns={"top_speed": "RPM_TD"}``) or, for the channels not named there, by the drilling mnemonics of
:data:`MNEMONICS` (case-insensitive; spaces and hyphens read as ``_``). A channel no column matches is left
out of the record; a record needs a time column and at least one channel.

Time: numbers (seconds, or the unit of the time column's header) or ISO 8601 timestamps
(``2026-12-04T17:53:24.100Z``), read as seconds from the first sample. Sampling may be irregular; times must
increase. Units: from the header, or ``units={"hook_load": "klbf"}`` (which overrides the header); a channel
without a unit is refused (except a top speed in a column named ``RPM``-something: rpm), a unit of the wrong
dimension refused naming column and unit. Values are converted to SI with :func:`drillstring.units.unit_factor`.

Faults (:mod:`drillstring.estimation.faults`): gaps filled with missing samples, empty or non-numeric cells,
spikes, frozen stretches and values the case cannot explain are flagged, each writing one line of the record's
``notes``.
"""

from __future__ import annotations

import csv
import datetime as _dt
import io
import math
import re
from pathlib import Path

import numpy as np

from drillstring.estimation.faults import DIMENSION, fill_gaps, flag_faults, missing_note
from drillstring.estimation.surface import CHANNELS, MISSING, USABLE, SurfaceRecord
from drillstring.files import read_input_bytes, read_input_text
from drillstring.units import TIME, unit_factor

__all__ = ["MAX_RECORD_FILE_BYTES", "MNEMONICS", "NULL_VALUES", "read_surface_record"]

#: Largest record file read [bytes] (a day at 10 Hz of five channels is about 50 MB of CSV).
MAX_RECORD_FILE_BYTES = 100 * 1024 * 1024

#: The column names recognised for each channel and for the time (compared upper-case, spaces and hyphens as _).
MNEMONICS: dict[str, tuple[str, ...]] = {
    "time": ("TIME", "ETIM", "TIMESTAMP", "DATETIME", "DATE_TIME", "TIME_S", "ELAPSED_TIME"),
    "top_speed": ("TOP_SPEED", "RPM", "SURF_RPM", "TD_RPM", "ROTARY_RPM", "RPMA", "TD_SPEED", "QUILL_SPEED"),
    "surface_torque": ("SURFACE_TORQUE", "TQ", "STOR", "TORQUE", "SURF_TORQUE", "TQA", "TD_TORQUE"),
    "hook_load": ("HOOK_LOAD", "HKLD", "HKL", "HOOKLOAD", "HKLA"),
    "block_position": ("BLOCK_POSITION", "BPOS", "BLOCK_POS", "BLKPOS", "BLOCK_HEIGHT"),
    "standpipe_pressure": ("STANDPIPE_PRESSURE", "SPP", "SPPA", "STANDPIPE"),
}
#: Cell values read as missing (besides empty and non-numeric cells): the LAS null value.
NULL_VALUES = (-999.25,)

_HEADER = re.compile(r"\s*(?P<name>[^\[\]()]*?)\s*(?:[\[(]\s*(?P<unit>[^\])]*?)\s*[\])])?\s*")


def _key(name: str) -> str:
    return re.sub(r"[\s\-]+", "_", name.strip()).upper()


def _header_cell(cell: str) -> tuple[str, str]:
    match = _HEADER.fullmatch(cell)
    if match is None:
        return cell.strip(), ""
    return match["name"], (match["unit"] or "").strip()


def _table(path: Path, text: str) -> tuple[list[str], list[str], list[list[str]], list[int]]:
    """Names, units, the data rows (lists of cells) of a CSV text and their line numbers."""
    numbered = [(k, line) for k, line in enumerate(text.splitlines(), start=1)
                if line.strip() and not line.lstrip().startswith("#")]
    rows = list(csv.reader(line for _, line in numbered))
    lines = [k for k, _ in numbered]
    if not rows:
        raise ValueError(f"surface record {path}: no header (the first line must name the columns)")
    names, units = zip(*(_header_cell(cell) for cell in rows[0]))
    names, units = list(names), list(units)
    body, lines = rows[1:], lines[1:]
    if body and not any(units) and all(_is_unit_cell(cell) for cell in body[0]) and any(c.strip() for c in body[0]):
        units = [cell.strip().strip("[]()").strip() for cell in body[0]]
        units += [""] * (len(names) - len(units))
        body, lines = body[1:], lines[1:]
    return names, units, body, lines


def _is_unit_cell(cell: str) -> bool:
    text = cell.strip()
    if not text:
        return True
    try:
        float(text)
        return False
    except ValueError:
        pass
    return _timestamp(text) is None


def _timestamp(text: str) -> _dt.datetime | None:
    try:
        return _dt.datetime.fromisoformat(text.strip().replace(" ", "T", 1))
    except ValueError:
        return None


def _parquet(path: Path, raw: bytes) -> tuple[list[str], list[str], list[list]]:
    try:
        import pandas as pd
    except ImportError:
        raise ValueError(f"surface record {path}: reading Parquet needs pandas and pyarrow (pip install pandas "
                         "pyarrow), or save the record as CSV") from None
    try:
        frame = pd.read_parquet(io.BytesIO(raw))
    except ImportError:
        raise ValueError(f"surface record {path}: reading Parquet needs pyarrow (pip install pyarrow), or save the "
                         "record as CSV") from None
    except Exception as error:  # pyarrow's errors for a damaged file
        raise ValueError(f"surface record {path}: not a readable Parquet file ({error})") from None
    names, units = zip(*(_header_cell(str(c)) for c in frame.columns))
    columns = []
    for c in frame.columns:
        series = frame[c]
        if pd.api.types.is_datetime64_any_dtype(series):
            columns.append([None if pd.isna(v) else v.isoformat() for v in series])
        else:
            columns.append(["" if pd.isna(v) else str(v) for v in series])
    return list(names), list(units), [list(r) for r in zip(*columns)]


def _find(names: list[str], wanted: str, what: str, path: Path) -> int:
    keys = [_key(n) for n in names]
    target = _key(_header_cell(wanted)[0])
    if target in keys:
        return keys.index(target)
    raise ValueError(f"surface record {path}: {what} column {wanted!r} is not in the header; the columns are "
                     f"{', '.join(names)}")


def _channel_mapping(option: str, mapping: dict[str, str] | None, must: str) -> dict[str, str]:
    """``mapping`` (channel or ``time`` -> a string) checked: a copy; ValueError naming ``option`` otherwise."""
    mapping = dict(mapping or {})
    for name, value in mapping.items():
        if name != "time" and name not in CHANNELS:
            raise ValueError(f"{option}: unknown channel {name!r}; channels are time, {', '.join(CHANNELS)}")
        if not isinstance(value, str):
            raise ValueError(f"{option}[{name!r}] = {value!r}: must be {must}")
    return mapping


def _map_columns(path: Path, names: list[str], columns: dict[str, str] | None) -> dict[str, int]:
    """Channel (and ``time``) -> column index."""
    columns = _channel_mapping("columns", columns, "a column name (a string)")
    found = {name: _find(names, column, name, path) for name, column in columns.items()}
    keys = [_key(n) for n in names]
    for name, mnemonics in MNEMONICS.items():
        if name in found:
            continue
        hits = [i for i, k in enumerate(keys) if k in mnemonics and i not in found.values()]
        if len(hits) > 1:
            shown = ", ".join(names[i] for i in hits)
            raise ValueError(f"surface record {path}: columns {shown} could each be the {name}; name one with "
                             f"columns={{'{name}': '{names[hits[0]]}'}}")
        if hits:
            found[name] = hits[0]
    if "time" not in found:
        raise ValueError(f"surface record {path}: no time column (named one of {', '.join(MNEMONICS['time'])}, or "
                         "given as columns={'time': 'NAME'})")
    if len(found) == 1:
        raise ValueError(f"surface record {path}: no channel column; the header names {', '.join(names)}; map "
                         "columns to channels with columns={'top_speed': 'NAME', ...} (channels: "
                         f"{', '.join(CHANNELS)})")
    return found


def _numbers(cells: list[str]) -> np.ndarray:
    out = np.empty(len(cells))
    for i, cell in enumerate(cells):
        try:
            value = float(cell)
        except (TypeError, ValueError):
            value = math.nan
        out[i] = value if math.isfinite(value) and value not in NULL_VALUES else math.nan
    return out


def _times(path: Path, cells: list[str], unit: str, lines: list[int]) -> tuple[np.ndarray, str | None]:
    """Times [s] from the first sample, and the first timestamp (None for numbers)."""
    numbers = _numbers(cells)
    if np.all(np.isfinite(numbers)):
        factor = unit_factor(unit or "s", TIME) if unit else 1.0
        return (numbers - numbers[0]) * factor, None
    stamps = [_timestamp(cell) for cell in cells]
    for cell, line, number, stamp in zip(cells, lines, numbers, stamps):
        if stamp is None and not np.isfinite(number):
            raise ValueError(f"surface record {path}, line {line}: time {cell!r} is neither a number nor an ISO "
                             "8601 timestamp")
    if any(stamp is None for stamp in stamps):
        line = lines[next(k for k, stamp in enumerate(stamps) if stamp is None)]
        raise ValueError(f"surface record {path}, line {line}: the time column mixes numbers and timestamps")
    if len({s.tzinfo is None for s in stamps}) > 1:
        raise ValueError(f"surface record {path}: the timestamps mix times with and without a time zone")
    return np.array([(s - stamps[0]).total_seconds() for s in stamps]), stamps[0].isoformat()


def _unit(path: Path, name: str, column: str, header_unit: str, units: dict[str, str], notes: list[str]) -> str:
    unit = units.get(name, "")
    if unit and header_unit and unit != header_unit:
        notes.append(f"{name}: unit {unit} given (the header of column {column} says {header_unit})")
    unit = unit or header_unit
    if not unit and name == "top_speed" and "RPM" in _key(column):
        unit = "rpm"
    if not unit:
        raise ValueError(f"surface record {path}: column {column} ({name}) has no unit; write it in the header "
                         f"('{column} [unit]') or give units={{'{name}': 'unit'}}")
    try:
        unit_factor(unit, DIMENSION[name] if name != "time" else TIME)
    except ValueError as error:
        raise ValueError(f"surface record {path}: column {column} ({name}): {error}") from None
    return unit


def read_surface_record(path: str | Path, *, columns: dict[str, str] | None = None,
                        units: dict[str, str] | None = None, case=None) -> SurfaceRecord:
    """The surface record in the CSV (or Parquet) file ``path`` (module docstring), its channels in SI units on
    one time axis [s], its faults flagged (:mod:`drillstring.estimation.faults`).

    Args:
        path: the file; ``.parquet`` or ``.pq`` is read as Parquet, anything else as CSV. At most
            :data:`MAX_RECORD_FILE_BYTES`.
        columns: channel (or ``"time"``) -> column name, for columns the mnemonics do not name.
        units: channel (or ``"time"``) -> unit, overriding the header's.
        case: a :class:`~drillstring.case.Case` (or its name or path) against which the values are checked (unit
            errors, a record it cannot explain); None: only the checks that need no case.

    Raises ``ValueError`` (one line) for a file that cannot be read as a record, a unit of the wrong dimension,
    or a record the case cannot explain.
    """
    path = Path(path)
    units = _channel_mapping("units", units, "a unit (a string such as 'klbf')")
    if case is not None and not hasattr(case, "operation"):
        from drillstring.case import load_case

        case = load_case(case)
    if path.suffix.lower() in (".parquet", ".pq"):
        raw = read_input_bytes(path, what="surface record", max_bytes=MAX_RECORD_FILE_BYTES)
        names, header_units, body = _parquet(path, raw)
        lines = list(range(1, len(body) + 1))  # rows of the table
    else:
        text = read_input_text(path, what="surface record", max_bytes=MAX_RECORD_FILE_BYTES)
        names, header_units, body, lines = _table(path, text)
    found = _map_columns(path, names, columns)
    notes: list[str] = []
    i_time = found["time"]
    keep = [k for k, row in enumerate(body) if i_time < len(row) and row[i_time].strip()]
    if len(keep) < len(body):
        notes.append(f"{len(body) - len(keep)} row(s) without a time dropped")
    body = [body[k] for k in keep]
    lines = [lines[k] for k in keep]
    if len(body) < 2:
        raise ValueError(f"surface record {path}: {len(body)} sample(s); at least 2 are needed")
    time_unit = units.get("time", "") or header_units[i_time]
    if time_unit:
        _unit(path, "time", names[i_time], header_units[i_time], units, notes)
    t, start = _times(path, [row[i_time] for row in body], time_unit, lines)
    steps = np.diff(t)
    if np.any(steps <= 0.0):
        k = int(np.nonzero(steps <= 0.0)[0][0])
        raise ValueError(f"surface record {path}, line {lines[k + 1]}: time {body[k + 1][i_time]!r} does not come "
                         f"after {body[k][i_time]!r}: times must increase")
    if start:
        notes.append(f"time: timestamps from {start}, read as seconds from the first sample")
    values, used_units, used_columns = {}, {}, {}
    for name, i in found.items():
        if name == "time":
            continue
        unit = _unit(path, name, names[i], header_units[i], units, notes)
        factor = unit_factor(unit, DIMENSION[name])
        values[name] = _numbers([row[i] if i < len(row) else "" for row in body]) * factor
        used_units[name], used_columns[name] = unit, names[i]
        notes.append(f"{name}: column {names[i]} [{unit}]")
    unused = [n for i, n in enumerate(names) if i not in found.values()]
    if unused:
        notes.append(f"columns not used: {', '.join(unused)}")
    full_time, measured, gaps = fill_gaps(t)
    channels, flags = {}, {}
    for name, v in values.items():
        out = np.full(len(full_time), np.nan)
        out[measured >= 0] = v
        flag = np.where(measured >= 0, USABLE, MISSING).astype(np.int8)
        empty = (measured >= 0) & ~np.isfinite(out)
        if empty.any():
            flag[empty] = MISSING
            notes.append(missing_note(name, full_time, empty))
        channels[name], flags[name] = out, flag
    for a, b, count in gaps:
        notes.append(f"gap from {a:.6g} s to {b:.6g} s: {count} missing sample(s) inserted in every channel")
    notes += flag_faults(full_time, channels, flags, units=used_units, columns=used_columns, case=case,
                         source=f"surface record {path}")
    return SurfaceRecord(full_time, channels, flags, str(path), tuple(notes))
