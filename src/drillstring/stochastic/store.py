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
  run that created it; the *metadata checksum* (:func:`metadata_checksum`, a hash of every attribute
  fixed at creation: case, settings, the random parameters' laws, means and standard deviations) is
  checked whenever the store is opened, by readers too: edited metadata is refused (:class:`StoreError`;
  a store written before it had none and is read as before);
- every chunk is checked when a writer opens the store (:meth:`TaskStore.verify`; chunks carry a
  checksum, ``zstd`` with ``checksum=True``): a chunk that is missing where a finished row's data should
  be, or that cannot be decoded, is named in :attr:`TaskStore.repairs` and its rows are set back to
  pending, so that the run recomputes them; constant arrays (coordinates) are rewritten; a damaged array
  that belongs to no row is refused (:class:`StoreError`) unless the subclass says which status to reset
  (:meth:`TaskStore.owner_status`). Readers call :func:`damage` and refuse a damaged store: it is never
  read as data (a missing chunk would read as NaN);
- temporary chunk files left by a killed writer (Zarr's ``*.partial``) are removed when a writer opens
  the store, and a store that cannot be written (read-only) is refused before any run when it has
  something to write;
- :meth:`TaskStore.write_many` writes a batch of outcomes: data first, then the failures' causes, then
  the status flags, so a row counts only once its data is in.

Writers hold the store's lock (:class:`~drillstring.stochastic.locks.StudyLock`).
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import re
import shutil
from collections import defaultdict
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar, Iterable, Iterator

import numpy as np
import zarr

from drillstring._version import __version__
from drillstring.files import folder_write_problem

__all__ = ["ArraySpec", "StoreError", "TaskStore", "damage", "fingerprint", "DONE", "FAILED", "PENDING"]

#: Status of a row in a store: not computed yet, finished, failed (its cause in the ``failures`` attribute).
PENDING, DONE, FAILED = 0, 1, 2

#: Temporary files of Zarr's local store (``<key>.<uuid hex>.partial``), left by a killed writer.
_PARTIAL = re.compile(r"\.[0-9a-f]{32}\.partial$")


def _codecs() -> dict:
    """Chunk compression of new stores: Zstandard with its content checksum, so that a damaged chunk
    fails to decode instead of decoding to wrong numbers."""
    from zarr.codecs import ZstdCodec

    return {"compressors": [ZstdCodec(level=0, checksum=True)]}


@contextmanager
def _named(path: Path) -> Iterator[None]:
    """Give an OSError raised inside (a failed write: disk full, permission) the store's ``path`` as
    its file name when it names none (Zarr's writes do not say which store they write)."""
    try:
        yield
    except OSError as error:
        if error.filename is None and error.errno is not None:  # a system error, not a bare message
            error.filename = str(path)
        raise


def _chunk_damage(group: zarr.Group, name: str, decode: bool = True) -> list[tuple[tuple[int, ...], str]]:
    """The chunks of array ``name`` of ``group`` (a local store) that are missing or (when ``decode``)
    unreadable: ``(chunk index, "missing" | "unreadable")``, in chunk order."""
    array = group[name]
    root = Path(str(group.store.root)) / array.path
    if decode:
        try:
            array[...]  # one read of every chunk (concurrent); chunk by chunk only if one fails
            decode = False
        except Exception:
            pass
    found = []
    for index in np.ndindex(*array.cdata_shape):
        key = array.metadata.encode_chunk_key(index)
        if not (root / key).is_file():
            found.append((tuple(index), "missing"))
            continue
        if not decode:
            continue
        region = tuple(slice(i * c, min((i + 1) * c, n)) for i, c, n in zip(index, array.chunks, array.shape))
        try:
            array[region]
        except Exception:  # a checksum or decompression error, a truncated file, unreadable bytes
            found.append((tuple(index), "unreadable"))
    return found


def _chunk_file(group: zarr.Group, name: str, index: tuple[int, ...]) -> Path:
    array = group[name]
    return Path(str(group.store.root)) / array.path / array.metadata.encode_chunk_key(index)


def _describe_rows(rows) -> str:
    rows = sorted(int(r) for r in rows)
    return ", ".join(map(str, rows)) if len(rows) <= 10 else f"{', '.join(map(str, rows[:10]))}, ... ({len(rows)} in all)"


def _owner_done(group: zarr.Group, name: str, layout: dict) -> bool:
    """Whether the run owning the non-row array ``name`` has finished: a status array of one element
    sharing its name's prefix (``nominal_status`` for ``nominal_*``) says DONE; True without one
    (constant arrays are always written)."""
    prefix = name.split("_", 1)[0]
    owner = f"{prefix}_status"
    if owner == name or owner not in layout:
        return True
    try:
        return int(group[owner][0]) == DONE
    except Exception:
        return False


def damage(group: zarr.Group, decode: bool = True) -> list[str]:
    """The damaged chunks of a store opened for reading: for each array of its layout, the chunks that
    cannot be decoded (when ``decode``), and the missing chunks that hold data of a finished row (its
    status DONE), of a finished run that owns the array, or constant data; ``"array chunk-key
    (missing|unreadable)"``, empty when the store is whole."""
    attrs = dict(group.attrs)
    layout = dict(attrs.get("layout", {}))
    sizes = {k: int(v) for k, v in dict(attrs.get("sizes", {})).items()}
    row_dim = next((dims[0] for name, dims in layout.items() if name == "status"), None)
    try:
        status = group["status"][:]
    except Exception:
        return ["status (unreadable)"]
    found = []
    for name, dims in layout.items():
        array = group[name]
        for index, what in _chunk_damage(group, name, decode):
            key = array.metadata.encode_chunk_key(index)
            if what == "missing":
                if name == "status":
                    continue  # all pending: nothing is read as data
                if dims and dims[0] == row_dim:
                    rows = range(index[0] * array.chunks[0], min((index[0] + 1) * array.chunks[0], sizes[row_dim]))
                    if not np.any(status[list(rows)] == DONE):
                        continue
                elif name.endswith("status") or not _owner_done(group, name, layout):
                    continue
            found.append(f"{name} {key} ({what})")
    return found


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


#: Attributes a store's writers change as rows finish: outside the metadata checksum.
MUTABLE_ATTRIBUTES = ("failures", "sessions", "metadata_checksum")


def metadata_checksum(attrs: dict) -> str:
    """SHA-256 of a store's fixed attributes (the case, the settings, the layout and sizes, the random
    parameters' names, laws, means and standard deviations...: everything but
    :data:`MUTABLE_ATTRIBUTES`), written at creation and checked at every opening: a changed digit in
    the metadata is found as a damaged chunk is (the data chunks carry their own checksums)."""
    fixed = {k: v for k, v in attrs.items() if k not in MUTABLE_ATTRIBUTES}
    return hashlib.sha256(json.dumps(fixed, sort_keys=True, default=str).encode()).hexdigest()


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
        self._arrays: dict[str, zarr.Array] = {}  # opened for writing, by name (:meth:`_writable`)
        layout = {"status": ArraySpec((self.row_dim,), "i1", PENDING),
                  "wall_time": ArraySpec((self.row_dim,), attributes={"units": "s"}), **layout}
        code = fingerprint(case_toml, settings)
        #: One line per repair made when the store was opened (damaged chunks whose rows are recomputed).
        self.repairs: list[str] = []
        if self.path.exists() and not (self.path.is_dir() and not any(self.path.iterdir())):
            self.group = self.open_group(self.path, mode="a")
            if self.group.attrs.get("fingerprint") != code:
                raise ValueError(f"{self.path} holds a different {self.kind} ({self.differ}); use another --out "
                                 "folder or delete it to start over")
            self._remove_partial_chunks()
            with _named(self.path):
                self.verify(layout)
            statuses = {"status"} | {self.owner_status(name) for name in layout} - {None}
            if any(np.any(self.group[name][...] == PENDING) for name in statuses):
                self.check_writable()  # something left to write: refused now if it cannot be
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
            with _named(self.path):
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
        # The checksum of the attributes as they read back from disk (JSON: tuples become lists), as the
        # check on opening sees them.
        g.attrs["metadata_checksum"] = metadata_checksum(dict(zarr.open_group(str(path), mode="r").attrs))
        for name, spec in layout.items():
            shape = tuple(int(sizes[d]) for d in spec.dims)
            if spec.data is not None:
                g.create_array(name, data=np.asarray(spec.data, dtype=spec.dtype), dimension_names=list(spec.dims),
                               attributes=dict(spec.attributes), **_codecs())
                continue
            chunks = shape if spec.chunk_rows is None or not shape else (
                (max(1, min(spec.chunk_rows, shape[0])),) + shape[1:])
            g.create_array(name, shape=shape, chunks=chunks or None, dtype=spec.dtype, fill_value=spec.fill,
                           dimension_names=list(spec.dims), attributes=dict(spec.attributes), **_codecs())

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
        recorded = attrs.get("metadata_checksum")
        if recorded is not None and recorded != metadata_checksum(attrs):
            raise StoreError(f"{path}: its metadata (zarr.json attributes: case, settings, parameters' laws) "
                             f"changed since the store was created (checksum mismatch); {advice}")
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

    # -- damage ------------------------------------------------------------------------------------------

    def _remove_partial_chunks(self) -> None:
        """Remove the temporary chunk files of a writer that was killed (the caller holds the lock)."""
        for leftover in self.path.rglob("*.partial"):
            if _PARTIAL.search(leftover.name) and leftover.is_file():
                try:
                    leftover.unlink()
                except OSError:
                    pass  # a read-only store: refused below if it has anything to write

    def owner_status(self, name: str) -> str | None:
        """The status array (of one element) whose run owns array ``name`` when ``name`` is neither a row
        array nor a constant one (a study's nominal run), or None: its damage is then refused."""
        return None

    def owner_label(self, owner: str) -> str:
        """Words for the run whose status is ``owner`` (:meth:`owner_status`), in messages."""
        return f"the run of {owner}"

    def verify(self, layout: dict[str, ArraySpec]) -> None:
        """Check every chunk of the store (:func:`_chunk_damage`) and repair what can be recomputed: the
        rows of a damaged row chunk (missing where a finished row's data should be, or unreadable) are set
        back to pending, a damaged status chunk reads as all pending, constant arrays are rewritten, the
        run owning another damaged array (:meth:`owner_status`) is reset. Each repair is one line in
        :attr:`repairs`; raises :class:`StoreError` when the store cannot be repaired or written."""
        group = self.group
        reset: dict[str, set[int]] = defaultdict(set)  # status array -> rows to recompute
        named: list[str] = []
        statuses = {"status"} | {self.owner_status(name) for name in layout} - {None}
        lost: list[str] = []  # status arrays read back as all pending
        for name in sorted(statuses):  # first: the flags the other checks rely on
            for index, what in _chunk_damage(group, name):
                if what == "unreadable":
                    _chunk_file(group, name, index).unlink()  # reads as pending: every row recomputed
                    named.append(f"{name} {group[name].metadata.encode_chunk_key(index)} (unreadable)")
                    lost.append(name)
                elif name == "status" and self.sessions():
                    named.append(f"status {group[name].metadata.encode_chunk_key(index)} (missing)")
                    lost.append(name)
        status = self.status()
        for name, spec in layout.items():
            if name in statuses:
                continue
            array = group[name]
            for index, what in _chunk_damage(group, name):
                key = array.metadata.encode_chunk_key(index)
                if spec.data is not None:
                    array[...] = np.asarray(spec.data, dtype=spec.dtype)
                    named.append(f"{name} {key} ({what}; rewritten)")
                    break
                if spec.dims and spec.dims[0] == self.row_dim:
                    rows = np.arange(index[0] * array.chunks[0], min((index[0] + 1) * array.chunks[0], self.total))
                    wanted = status[rows] == DONE if what == "missing" else status[rows] != PENDING
                    rows = rows[wanted]
                    if what == "unreadable":
                        _chunk_file(group, name, index).unlink()
                    if rows.size:
                        reset["status"].update(int(r) for r in rows)
                        named.append(f"{name} {key} ({what})")
                    continue
                owner = self.owner_status(name)
                if owner is None:
                    raise StoreError(f"{self.path} is damaged: chunk {key} of {name} is {what}; delete the store "
                                     f"(or use another --out folder) to start over")
                if what == "unreadable":
                    _chunk_file(group, name, index).unlink()
                if what == "unreadable" or int(group[owner][0]) != PENDING:
                    reset[owner].add(0)
                    named.append(f"{name} {key} ({what})")
        if not named:
            return
        problem = folder_write_problem(self.path)
        if problem:
            raise StoreError(f"{self.path} is damaged ({'; '.join(named)}) and {problem}; make it writable and "
                             "run the same command again to recompute the damaged rows")
        for name, rows in reset.items():
            flags = group[name][...]
            flags[sorted(rows)] = PENDING
            group[name][...] = flags
        status = self.status()  # the failures of rows set back to pending are forgotten: they run again
        self.group.attrs["failures"] = {k: v for k, v in self.failures().items()
                                        if not k.isdigit() or status[int(k)] != PENDING}
        again = sorted(reset.get("status", ()))
        what = []
        if "status" in lost or len(again) == self.total:
            what.append(f"all {self.total} {self.noun} will be recomputed")
        elif again:
            noun = self.noun if len(again) > 1 else self.noun.removesuffix("s")
            what.append(f"{noun} {_describe_rows(again)} will be recomputed")
        what.extend(f"{self.owner_label(owner)} will be recomputed"
                    for owner in sorted(set(reset) | set(lost)) if owner != "status")
        self.repairs.append(f"{self.path} was damaged ({'; '.join(named)}): "
                            f"{'; '.join(what) or 'repaired'}")

    def check_writable(self) -> None:
        """Refuse (:class:`StoreError`) a store that cannot be written (read-only folder or
        filesystem)."""
        for folder in (self.path, self.path / "status"):
            problem = folder_write_problem(folder) if folder.is_dir() else None
            if problem:
                raise StoreError(f"{self.kind} store {self.path} is read-only ({problem}); make it writable "
                                 "(or use another --out folder) and run the same command again")

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
        with _named(self.path):
            self._assign(data)
            if failures:
                self.group.attrs["failures"] = {**self.failures(), **failures}
            self._assign(flags)

    def _assign(self, writes: dict[str, list]) -> None:
        # Every chunk written is stored, even one equal to the fill value (a finished row whose metric is
        # undefined, NaN): a missing chunk then always means damage (:func:`damage`). One Zarr write per
        # array and batch (each call costs about a millisecond of the driver's CPU, whatever it writes): the
        # batch's rows by an orthogonal selection, a row given twice taking its last value, as written in turn.
        with zarr.config.set({"array.write_empty_chunks": True}):
            for name, rows in writes.items():
                array = self._writable(name)
                last = dict(rows)
                if not all(isinstance(index, (int, np.integer)) for index in last):  # e.g. the whole array
                    for index, value in last.items():
                        array[index] = value
                    continue
                index = np.fromiter(last, dtype=np.int64, count=len(last))
                values = np.asarray(list(last.values()), dtype=array.dtype)
                array.oindex[index] = values.reshape((len(index),) + array.shape[1:])

    def _writable(self, name: str) -> zarr.Array:
        """The store's array ``name`` opened for writing, once per store object."""
        if name not in self._arrays:
            self._arrays[name] = zarr.open_array(self.group.store, path=self.group[name].path, mode="r+")
        return self._arrays[name]

    def failures(self) -> dict[str, str]:
        return dict(self.group.attrs.get("failures", {}))

    def record_session(self, started: str, wall_time: float, count: int, workers: int | str) -> None:
        """Append one run that computed ``count`` (> 0) rows in ``wall_time`` [s] to the store's
        ``sessions``: the computation time is their sum, whatever reruns follow."""
        sessions = list(self.group.attrs.get("sessions", []))
        sessions.append({"started": started, "wall_time": float(wall_time), self.noun: int(count),
                         "workers": workers})
        with _named(self.path):
            self.group.attrs["sessions"] = sessions

    def sessions(self) -> list[dict]:
        return list(self.group.attrs.get("sessions", []))
