"""Loading a case: a built-in name or a TOML file read within bounds (size, nesting, key length), or a
mapping, validated into a :class:`~drillstring.case.Case`.
"""

from __future__ import annotations

import tomllib
from importlib import resources
from pathlib import Path
from typing import Any, Mapping

from drillstring.case.bounds import MAX_CASE_DEPTH, MAX_CASE_FILE_BYTES, PHYSICAL_BOUNDS
from drillstring.case.drilling_case import Case
from drillstring.case.errors import CaseError, _Entry
from drillstring.files import read_input_bytes


def _depth(data: Any) -> int:
    """Nesting depth of tables and arrays in ``data`` (iterative: any depth is measured)."""
    deepest, stack = 0, [(data, 0)]
    while stack:
        node, level = stack.pop()
        if isinstance(node, Mapping):
            children = node.values()
        elif isinstance(node, (list, tuple)):
            children = node
        else:
            continue
        deepest = max(deepest, level + 1)
        if deepest > MAX_CASE_DEPTH:
            return deepest
        stack.extend((child, level + 1) for child in children)
    return deepest


def _cases_dir() -> Any:
    return resources.files("drillstring").joinpath("cases")


def builtin_cases() -> list[str]:
    """Names of the built-in cases (``drillstring/cases/<name>.toml``), sorted."""
    folder = _cases_dir()
    try:
        entries = list(folder.iterdir())
    except (FileNotFoundError, NotADirectoryError):
        return []
    return sorted(e.name[: -len(".toml")] for e in entries if e.name.endswith(".toml") and e.is_file())


def case_from_dict(data: Mapping[str, Any], source: str = "<dict>") -> Case:
    """Validate a (TOML-like) mapping into a :class:`Case`; raises :class:`CaseError` listing every problem."""
    if not isinstance(data, Mapping):
        raise CaseError(f"a case must be a table (mapping), got {type(data).__name__}", source=source)
    if _depth(data) > MAX_CASE_DEPTH:
        raise CaseError(f"tables and arrays nested more than {MAX_CASE_DEPTH} levels deep", source=source)
    try:
        return Case.model_validate(dict(data))
    except CaseError as exc:
        raise CaseError([_with_range(entry) for entry in exc.entries], source=source) from None


def _with_range(entry: _Entry) -> _Entry:
    """``entry`` with the field's plausible range (:data:`PHYSICAL_BOUNDS`) added when its value overflowed or
    underflowed while its unit was read (the range is otherwise checked after every field is read)."""
    loc, value, message = entry
    if not message.startswith(("overflows", "underflows")):
        return entry
    for path, low, high, unit in PHYSICAL_BOUNDS:
        if len(path) == len(loc) and all(p == "*" or p == item for p, item in zip(path, loc)):
            return loc, value, f"{message}; must be within [{low:g}, {high:g}] {unit}".rstrip()
    return entry


def _looks_like_path(source: str) -> bool:
    return source.endswith(".toml") or "/" in source or "\\" in source or Path(source).is_file()


def _read_case_file(path: Path, label: str) -> bytes:
    """The bytes of a case file: a regular file of at most :data:`MAX_CASE_FILE_BYTES` (a FIFO, a device
    such as /dev/zero or a folder is refused at once, without opening it: :func:`drillstring.files.
    read_input_bytes`), its refusal a :class:`CaseError`."""
    try:
        return read_input_bytes(path, what="case file", max_bytes=MAX_CASE_FILE_BYTES)
    except ValueError as exc:
        raise CaseError(str(exc), source=label) from None


#: Longest key of a case file, dotted parts together [characters], and most parts of a dotted key (a case
#: needs 3: ``[uncertainty.correlation]``; tomllib's time grows with the square of the parts: 20,000 took 25 s).
MAX_KEY_LENGTH, MAX_KEY_PARTS = 400, MAX_CASE_DEPTH


def _toml_key_problem(text: str) -> str | None:
    """Why the keys of the TOML ``text`` are too long or too deeply dotted for a case, or None; a linear scan
    before ``tomllib`` parses it (the parser takes minutes, or runs out of memory, on a key of 100,000 parts).

    Each line's key (a ``[table]``/``[[array]]`` header, or what comes before ``=``) is scanned outside quotes
    and outside multi-line strings; a ``"."`` inside a quoted key is not a separator."""
    delimiter = None  # the closing quotes of the multi-line string the scan is in, if any
    for number, line in enumerate(text.splitlines(), start=1):
        if delimiter is not None:  # inside a multi-line string: find its end, keys start on a later line
            if line.count(delimiter) % 2 == 1:
                delimiter = None
            continue
        stripped = line.lstrip()
        if not stripped or stripped[0] == "#":
            continue
        header = stripped[0] == "["
        parts, length, quote = 1, 0, None
        i = (2 if stripped.startswith("[[") else 1) if header else 0
        while i < len(stripped):
            char = stripped[i]
            if quote is not None:
                if char == "\\" and quote == '"':
                    i += 1
                elif char == quote:
                    quote = None
            elif char in "\"'":
                quote = char
            elif char == "." :
                parts += 1
            elif (char == "]" and header) or (char == "=" and not header):
                break
            elif not (char.isascii() and (char.isalnum() or char in "_- \t")):
                break  # not a key (a value line of a multi-line array): nothing to check
            i += 1
            length += 1
            if length > MAX_KEY_LENGTH:
                return f"line {number}: a key longer than {MAX_KEY_LENGTH} characters"
            if parts > MAX_KEY_PARTS:
                return f"line {number}: a dotted key of more than {MAX_KEY_PARTS} parts"
        if not header:
            value = stripped[i + 1:]
            for opening in ('"""', "'''"):
                if value.count(opening) % 2 == 1:
                    delimiter = opening
                    break
    return None


def load_case(source: str | Path) -> Case:
    """Load a case: a built-in name (see :func:`builtin_cases`, e.g. ``"reference"``) or a path to a TOML file.

    A string is read as a path when it ends in ``.toml``, contains a path separator or names an existing
    file; otherwise as a built-in name. Raises :class:`CaseError` for a missing file, an unknown built-in name,
    a TOML syntax error or an invalid case.
    """
    folder: Any = None  # where a [well] survey_file is looked for
    if isinstance(source, Path) or _looks_like_path(str(source)):
        path = Path(source)
        label = str(path)
        raw = _read_case_file(path, label)
        folder = path.parent
    else:
        name = str(source)
        resource = _cases_dir().joinpath(f"{name}.toml")
        label = f"{name} (built-in)"
        if not resource.is_file():
            known = ", ".join(builtin_cases()) or "none"
            raise CaseError(
                f"unknown built-in case {name!r}; built-in cases: {known} (or give the path to a .toml file)",
                source=repr(name),
            )
        raw = resource.read_bytes()
        folder = _cases_dir()
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise CaseError(f"{label}: not UTF-8 text ({exc.reason} at byte {exc.start})", source=label) from None
    problem = _toml_key_problem(text)
    if problem:
        raise CaseError(f"{label}: {problem}", source=label)
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise CaseError(f"{label}: TOML syntax error: {exc}", source=label) from None
    except RecursionError:
        raise CaseError(f"{label}: tables and arrays nested more than {MAX_CASE_DEPTH} levels deep",
                        source=label) from None
    well = data.get("well")
    if isinstance(well, dict) and isinstance(well.get("survey_file"), str) and folder is not None:
        if not Path(well["survey_file"]).is_absolute():  # relative to the case file
            well["survey_file"] = str(folder.joinpath(well["survey_file"]))
    return case_from_dict(data, source=label)
