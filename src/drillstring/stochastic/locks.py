"""The lock of a study store (light: the command line takes it before loading the study engine, so that
a second study on the same folder is refused at once).

A study running on ``<folder>/study.zarr`` holds ``<folder>/study.zarr.lock`` exclusively until its
statistics, figures and report are written; reading a store for statistics takes it shared, so it is
refused while a study writes the store (see :class:`drillstring.files.FileLock` for stale locks).

One folder holds one kind of run (:data:`STORE_NAMES`): each kind writes its own ``report.html`` there, so
a writer is refused in a folder that holds the store of another kind, or where another kind is running.
"""

from __future__ import annotations

from pathlib import Path

from drillstring.files import FileLock, LockedError, lock_in_use

#: The store of each kind of run in its output folder (one kind per folder).
STORE_NAMES = {"study.zarr": "study", "map.zarr": "map", "sensitivity.zarr": "sensitivity run"}


class StudyLocked(LockedError):
    """Another study runs on this store (or reads it); the message says who and what to do."""


class StudyLock:
    """Context manager holding the lock of the store at ``store_path`` (exclusive, or ``shared`` for
    readers); a refusal raises :class:`StudyLocked` naming the store (a ``what`` store: study, map,
    sensitivity) and the holder. ``note`` is set
    when a stale lock (its holder died) was taken over. Re-entrant in one thread."""

    def __init__(self, store_path: str | Path, *, shared: bool = False, what: str = "study") -> None:
        self.store_path = Path(store_path)
        self.shared = shared
        self.what = what
        self.note: str | None = None
        self._lock = FileLock(self.store_path.with_name(self.store_path.name + ".lock"), shared=shared,
                              purpose="its finished realizations are kept")

    def __enter__(self) -> "StudyLock":
        try:
            self.note = self._lock.acquire()
        except LockedError as error:
            advice = (f"results are read from a store only when no {self.what} is writing it"
                      if self.shared else f"wait for that {self.what} to finish or use another --out folder")
            if self.shared and self.what == "study":
                advice = "statistics are computed from a store only when no study is writing it"
            raise StudyLocked(f"{self.what} store {self.store_path} is {error}; {advice}") from None
        if not self.shared:
            try:
                self._check_folder()
            except BaseException:
                self._lock.release()
                raise
        return self

    def _check_folder(self) -> None:
        """Refuse a folder holding (or being written by) another kind of run: its report.html would be
        replaced."""
        folder = self.store_path.parent
        for name, kind in STORE_NAMES.items():
            if name == self.store_path.name:
                continue
            other = folder / name
            if other.exists() or lock_in_use(other.with_name(name + ".lock")):
                raise StudyLocked(f"{folder} holds a {kind} ({other}); one kind of run per folder (each writes "
                                  f"its own report.html there): use another --out folder for this {self.what}")

    def __exit__(self, *exc) -> None:
        self._lock.release()
