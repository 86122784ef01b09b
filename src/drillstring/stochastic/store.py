"""A resumable Zarr store of many independent runs (realizations, grid points, design rows).

One row per item along the store's *row dimension*, a ``status`` flag per row (:data:`PENDING`,
:data:`DONE`, :data:`FAILED`) written after the row's data, the failures' causes and the *sessions*
(runs that computed something) in the attributes. Every kind of run (Monte Carlo study, operating map,
sensitivity design) is a :class:`TaskStore` with its own arrays; the machinery is here once:

- a new store is built under a temporary name and renamed into place once complete, so a folder is a
  whole store or nothing (leftovers of a killed creation are removed);
- an existing store is checked when opened (:meth:`TaskStore.open_group`): a Zarr group with the
  required attributes and every array of its recorded layout, with the recorded sizes; anything else is
  refused with what is missing (:class:`StoreError`), never a traceback from inside Zarr;
- the *fingerprint* (a hash of the case and the settings) must match: a store is resumed only by the
  run that created it;
- :meth:`TaskStore.write_many` writes a batch of outcomes: data first, then the failures' causes, then
  the status flags, so a row counts only once its data is in.

Writers hold the store's lock (:class:`~drillstring.stochastic.locks.StudyLock`).
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import shutil
from collections import defaultdict
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar, Iterable

import numpy as np
import zarr

from drillstring._version import __version__

__all__ = ["ArraySpec", "StoreError", "TaskStore", "fingerprint", "DONE", "FAILED", "PENDING"]

#: Status of a row in a store: not computed yet, finished, failed (its cause in the ``failures`` attribute).
PENDING, DONE, FAILED = 0, 1, 2


class StoreError(ValueError):
    """A folder that is not a (complete, readable) drillstring store of the expected kind."""


@dataclass(frozen=True)
class ArraySpec:
    """One array of a store: its dimensions, dtype and fill value, optional constant ``data`` (written
    at creation: coordinates), ``attributes`` (units), and ``chunk_rows`` (rows per chunk along the first
    dimension; default: the whole array in one chunk, rewritten whole by each batch)."""

    dims: tuple[str, ...]
    dtype: str = "f8"
    fill: Any = math.nan
    data: Any = None
    attributes: dict = field(default_factory=dict)
    chunk_rows: int | None = None


def fingerprint(case_toml: str, settings: dict) -> str:
    """A short hash of a case and its run settings: a store holds one such pair."""
    text = case_toml + json.dumps(settings, sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


class TaskStore:
    """A store of ``total`` rows along ``row_dim`` (see the module docstring).

    Subclasses set ``kind`` (a word for messages: "study", "map", ...), ``row_dim``, ``noun`` (its rows,
    plural: "realizations", ...; also the count's key in each session), ``differ`` (what
    makes two runs different, for the refusal of a mismatched store) and build their layout; they may
    override :meth:`entries` (where an outcome's values go) and :meth:`status_entry`.
    """

    kind: ClassVar[str] = "task"
    row_dim: ClassVar[str] = "row"
    noun: ClassVar[str] = "rows"
    differ: ClassVar[str] = "case or settings differ"
    required_attrs: ClassVar[tuple[str, ...]] = ("fingerprint", "settings", "case")

    def __init__(self, path: str | Path, *, case_toml: str, settings: dict, layout: dict[str, ArraySpec],
                 sizes: dict[str, int], attrs: dict | None = None) -> None:
        self.path = Path(path)
        self.total = int(sizes[self.row_dim])
        layout = {"status": ArraySpec((self.row_dim,), "i1", PENDING),
                  "wall_time": ArraySpec((self.row_dim,), attributes={"units": "s"}), **layout}
        code = fingerprint(case_toml, settings)
        if self.path.exists() and not (self.path.is_dir() and not any(self.path.iterdir())):
            self.group = self.open_group(self.path, mode="a")
            if self.group.attrs.get("fingerprint") != code:
                raise ValueError(f"{self.path} holds a different {self.kind} ({self.differ}); use another --out "
                                 "folder or delete it to start over")
            return
        self.path.parent.mkdir(parents=True, exist_ok=True)
        for leftover in self.path.parent.glob(f".{self.path.name}.*.tmp"):  # from a killed creation
            shutil.rmtree(leftover, ignore_errors=True)
        temporary = self.path.with_name(f".{self.path.name}.{os.getpid()}.tmp")
        header = {
            "fingerprint": code,
            "kind": self.kind,
            "drillstring_version": __version__,
            "case": case_toml,
            "settings": settings,
            "layout": {name: list(spec.dims) for name, spec in layout.items()},
            "sizes": dict(sizes),
            "failures": {},
            "sessions": [],
            **(attrs or {}),
        }
        try:
            self._create(temporary, header, layout, sizes)
            if self.path.exists():  # an empty folder
                self.path.rmdir()
            os.rename(temporary, self.path)
        except BaseException:
            shutil.rmtree(temporary, ignore_errors=True)
            raise
        self.group = zarr.open_group(str(self.path), mode="a")

    @staticmethod
    def _create(path: Path, header: dict, layout: dict[str, ArraySpec], sizes: dict[str, int]) -> None:
        g = zarr.open_group(str(path), mode="w")
        g.attrs.update(header)
        for name, spec in layout.items():
            shape = tuple(int(sizes[d]) for d in spec.dims)
            if spec.data is not None:
                g.create_array(name, data=np.asarray(spec.data, dtype=spec.dtype), dimension_names=list(spec.dims),
                               attributes=dict(spec.attributes))
                continue
            chunks = shape if spec.chunk_rows is None or not shape else (
                (max(1, min(spec.chunk_rows, shape[0])),) + shape[1:])
            g.create_array(name, shape=shape, chunks=chunks or None, dtype=spec.dtype, fill_value=spec.fill,
                           dimension_names=list(spec.dims), attributes=dict(spec.attributes))

    # -- checking ----------------------------------------------------------------------------------------

    @classmethod
    def open_group(cls, path: str | Path, mode: str = "r") -> zarr.Group:
        """Open the store at ``path``, checking that it is one of this kind: a Zarr group with the
        required attributes and every array of its layout, with the recorded sizes. Raises
        :class:`StoreError` saying what is wrong otherwise."""
        path = Path(path)
        what = f"a drillstring {cls.kind} store"
        advice = "delete it (or use another --out folder) to start over"
        if not path.is_dir():
            raise StoreError(f"{path} is not {what} (no such folder)")
        if not (path / "zarr.json").is_file():
            raise StoreError(f"{path} is not {what} (no zarr.json); {advice}")
        try:
            group = zarr.open_group(str(path), mode=mode)
            attrs = dict(group.attrs)
        except Exception as error:  # any unreadable metadata: one line, not a traceback
            raise StoreError(f"{path} is not a readable Zarr store ({type(error).__name__}: {error}); "
                             f"{advice}") from None
        missing_attrs = [k for k in cls.required_attrs if k not in attrs]
        if missing_attrs:
            raise StoreError(f"{path} is not {what} (no {', '.join(missing_attrs)} attribute); {advice}")
        kind = attrs.get("kind", cls.kind)
        if kind != cls.kind or "layout" not in attrs or "sizes" not in attrs:
            found = f"a {kind} store" if kind != cls.kind else "a store of an older drillstring version"
            raise StoreError(f"{path} is not {what} (it is {found}); {advice}")
        try:
            names = set(group.array_keys())
        except Exception as error:
            raise StoreError(f"{path} is not a readable Zarr store ({type(error).__name__}: {error}); "
                             f"{advice}") from None
        layout = dict(attrs["layout"])
        missing = [name for name in layout if name not in names]
        if missing:
            raise StoreError(f"{path} is not a complete drillstring {cls.kind} store (missing array(s): "
                             f"{', '.join(missing)}); {advice}")
        try:
            sizes = {k: int(v) for k, v in dict(attrs["sizes"]).items()}
            for name, dims in layout.items():
                expected = tuple(sizes[d] for d in dims)
                if tuple(group[name].shape) != expected:
                    raise StoreError(f"{path} is not a consistent drillstring {cls.kind} store (array {name} has "
                                     f"shape {tuple(group[name].shape)}, expected {expected}); {advice}")
        except (KeyError, TypeError, ValueError) as error:
            if isinstance(error, StoreError):
                raise
            raise StoreError(f"{path} is not a consistent drillstring {cls.kind} store ({error}); {advice}") from None
        return group

    # -- rows --------------------------------------------------------------------------------------------

    def status(self) -> np.ndarray:
        return self.group["status"][:]

    def pending(self) -> list[int]:
        return [int(i) for i in np.nonzero(self.status() == PENDING)[0]]

    def counts(self) -> tuple[int, int]:
        """(rows done, rows failed)."""
        status = self.status()
        return int(np.sum(status == DONE)), int(np.sum(status == FAILED))

    def entries(self, outcome) -> Iterable[tuple[str, Any, Any]]:
        """``(array, index, value)`` of an outcome's data: by default each of ``outcome.values`` and the
        wall time in row ``outcome.index``."""
        for name, value in outcome.values.items():
            yield name, outcome.index, value
        yield "wall_time", outcome.index, outcome.wall_time

    def status_entry(self, outcome) -> tuple[str, Any]:
        """``(array, index)`` of an outcome's status flag."""
        return "status", outcome.index

    def failure_key(self, outcome) -> str:
        return str(outcome.index)

    def write(self, outcome) -> None:
        """Write one outcome (:meth:`write_many`)."""
        self.write_many([outcome])

    def write_many(self, outcomes: Iterable) -> None:
        """Write a batch of outcomes: their data, then the failures' causes, then their status flags."""
        data: dict[str, list] = defaultdict(list)
        flags: dict[str, list] = defaultdict(list)
        failures: dict[str, str] = {}
        for outcome in outcomes:
            for name, index, value in self.entries(outcome):
                data[name].append((index, value))
            name, index = self.status_entry(outcome)
            flags[name].append((index, outcome.status))
            if outcome.status != DONE:
                failures[self.failure_key(outcome)] = outcome.message
        self._assign(data)
        if failures:
            self.group.attrs["failures"] = {**self.failures(), **failures}
        self._assign(flags)

    def _assign(self, writes: dict[str, list]) -> None:
        for name, rows in writes.items():
            array = self.group[name]
            if array.ndim > 1 and array.chunks[0] == 1:  # one chunk per row: write each row
                for index, value in rows:
                    array[index] = value
            else:  # small arrays in one chunk: rewritten whole
                whole = array[...]
                for index, value in rows:
                    whole[index] = value
                array[...] = whole

    def failures(self) -> dict[str, str]:
        return dict(self.group.attrs.get("failures", {}))

    def record_session(self, started: str, wall_time: float, count: int, workers: int | str) -> None:
        """Append one run that computed ``count`` (> 0) rows in ``wall_time`` [s] to the store's
        ``sessions``: the computation time is their sum, whatever reruns follow."""
        sessions = list(self.group.attrs.get("sessions", []))
        sessions.append({"started": started, "wall_time": float(wall_time), self.noun: int(count),
                         "workers": workers})
        self.group.attrs["sessions"] = sessions

    def sessions(self) -> list[dict]:
        return list(self.group.attrs.get("sessions", []))
