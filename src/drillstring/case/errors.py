"""The errors of a case: :class:`CaseError` and its problem lines ``<dotted.field.path> = <value>: <what is
allowed>``, built from pydantic's validation errors and from the cross-field rules' problems.

This module imports nothing from ``drillstring``.
"""

from __future__ import annotations

import typing
from typing import Annotated, Any

from pydantic import BaseModel, ValidationError


class CaseError(ValueError):
    """An invalid case, or a case file that cannot be read.

    Attributes
    ----------
    problems:
        One line per problem, ``<dotted.field.path> = <value>: <what is allowed>`` (or a plain sentence for
        file-level problems such as a TOML syntax error).
    source:
        Where the case came from (a file name, ``"<dict>"``, ...).
    """

    problems: list[str]
    source: str

    def __init__(self, problems: list[str] | list[_Entry] | str, source: str = "<case>") -> None:
        if isinstance(problems, str):
            problems = [problems]
        self.entries: list[_Entry] = [((), None, p) if isinstance(p, str) else p for p in problems]
        self.problems: list[str] = [_format_entry(e) for e in self.entries]
        self.source: str = source
        n = len(self.problems)
        if n == 1:  # one problem, one line
            super().__init__(f"invalid case {source}: {self.problems[0]}")
            return
        head = f"invalid case {source}: {n} problems"
        super().__init__("\n".join([head, *(f"  {p}" for p in self.problems)]))

    def __reduce__(self) -> Any:  # picklable (worker processes)
        return (type(self), (self.entries, self.source))


#: One problem: (location, value as shown or None, what is allowed).
_Entry = tuple[tuple[str | int, ...], str | None, str]


def _format_entry(entry: _Entry) -> str:
    loc, value, message = entry
    if value is None:
        return f"{_loc_to_path(loc)}: {message}" if loc else message
    return f"{_loc_to_path(loc)} = {value}: {message}"


class _Problems(ValueError):
    """Cross-field problems raised from a model validator: ``(relative loc, value, message)`` triples.

    Pydantic wraps it in a ``value_error`` whose context keeps this object, so :class:`CaseError` can expand it
    into one line per problem with the full field path.
    """

    def __init__(self, problems: list[tuple[tuple[str | int, ...], Any, str]]) -> None:
        self.entries: list[_Entry] = [(tuple(loc), _fmt_value(v), m) for loc, v, m in problems]
        super().__init__("; ".join(_format_entry(e) for e in self.entries))


def _loc_to_path(loc: tuple[str | int, ...]) -> str:
    """``('sections', 1, 'inner_diameter')`` -> ``'sections[1].inner_diameter'``."""
    out = ""
    for item in loc:
        if isinstance(item, int):
            out += f"[{item}]"
        else:
            out += f".{item}" if out else str(item)
    return out or "<case>"


def _fmt_value(value: Any) -> str:
    if isinstance(value, bool):
        text = repr(value)
    elif isinstance(value, float):
        text = repr(float(f"{value:.12g}"))  # 0.30479999999999996 -> 0.3048
    elif isinstance(value, BaseModel):
        text = repr(value.model_dump())
    else:
        text = repr(value)
    return text if len(text) <= 80 else text[:77] + "..."


def _fmt_limit(value: Any) -> str:
    if isinstance(value, int) and not isinstance(value, bool) and abs(value) >= 10**6:
        return str(value)  # an integer limit exactly (a seed's 2**64 - 1, not 1.84467e+19)
    return f"{value:g}" if isinstance(value, (int, float)) and not isinstance(value, bool) else repr(value)


def _unwrap(tp: Any) -> Any:
    """Strip ``Annotated[...]`` and ``Optional[...]`` from a type annotation."""
    while True:
        origin = typing.get_origin(tp)
        if origin is Annotated:
            tp = typing.get_args(tp)[0]
        elif origin is typing.Union:
            args = [a for a in typing.get_args(tp) if a is not type(None)]
            if len(args) != 1:
                return tp
            tp = args[0]
        else:
            return tp


def _model_at(root: type[BaseModel], loc: tuple[str | int, ...]) -> type[BaseModel] | None:
    """The model class found at ``loc`` below ``root`` (for listing allowed keys), or None."""
    tp: Any = root
    for item in loc:
        tp = _unwrap(tp)
        if isinstance(tp, type) and issubclass(tp, BaseModel):
            if isinstance(item, str) and item in tp.model_fields:
                tp = tp.model_fields[item].annotation
                continue
            return None
        origin = typing.get_origin(tp)
        args = typing.get_args(tp)
        if origin in (list, tuple) and isinstance(item, int) and args:
            tp = args[0]
        elif origin is dict and len(args) == 2:
            tp = args[1]
        else:
            return None
    tp = _unwrap(tp)
    return tp if isinstance(tp, type) and issubclass(tp, BaseModel) else None


_OPS = {"greater_than": ">", "greater_than_equal": ">=", "less_than": "<", "less_than_equal": "<="}


_NOT_FOUND = object()


def _lookup(raw: Any, loc: tuple[str | int, ...]) -> Any:
    """The raw input value at ``loc`` (before unit conversion), or ``_NOT_FOUND``."""
    for item in loc:
        try:
            raw = raw[item]
        except (KeyError, IndexError, TypeError):
            return _NOT_FOUND
    return raw


def _entries_from_validation_error(exc: ValidationError, root: type[BaseModel], raw: Any = None) -> list[_Entry]:
    """Pydantic's errors as :data:`_Entry` triples, with paths relative to ``root``.

    ``raw`` is the input that was validated: where a constraint failed after unit conversion, the value is shown
    as the user wrote it, followed by its SI value.
    """
    out: list[_Entry] = []
    for err in exc.errors(include_url=False):
        loc = tuple(err["loc"])
        kind = err["type"]
        ctx = err.get("ctx") or {}
        inner = ctx.get("error")
        # Structured problems from a model validator, or from a nested model's __init__ (see _Base).
        if isinstance(inner, (_Problems, CaseError)):
            out.extend((loc + tuple(rel), value, message) for rel, value, message in inner.entries)
            continue
        if kind == "missing":
            out.append((loc, "(missing)", "required"))
            continue
        value = _fmt_value(err.get("input"))
        original = _lookup(raw, loc)
        if isinstance(original, str) and not isinstance(err.get("input"), str):
            value = f"{_fmt_value(original)} (= {value} SI)"
        elif isinstance(original, (int, float)) and not isinstance(original, bool):
            value = _fmt_value(original)  # as written: 0, not 0.0
        if kind == "extra_forbidden":
            parent = _model_at(root, loc[:-1])
            allowed = ", ".join(parent.model_fields) if parent is not None else "?"
            out.append((loc, value, f"unknown key; allowed keys here: {allowed}"))
        elif kind in _OPS:
            out.append((loc, value, f"must be {_OPS[kind]} {_fmt_limit(next(iter(ctx.values())))}"))
        elif kind == "string_too_long":
            out.append((loc, value, f"must be at most {ctx['max_length']:,} characters "
                                    f"(it has {len(err.get('input', '')):,})"))
        elif kind == "too_short" and "min_length" in ctx:
            n = ctx["min_length"]
            out.append((loc, value, f"must have at least {n} item{'s' if n != 1 else ''}"))
        elif isinstance(inner, Exception) and kind in ("value_error", "assertion_error"):
            out.append((loc, value, str(inner)))
        else:
            msg = str(err["msg"])
            if msg.startswith("Input should be "):
                msg = "must be " + msg[len("Input should be ") :]
            out.append((loc, value, msg))
    return out


class _Missing:
    """A required field's value in a problem line."""

    def __repr__(self) -> str:
        return "(missing)"


_MISSING = _Missing()
