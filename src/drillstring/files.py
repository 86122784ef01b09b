"""Output files: atomic writes, output paths checked before computing, and folder locks.

No physics here and no drillstring imports: any layer that writes files may use it.

- :func:`atomic_output` yields a temporary path next to the target and renames it onto the target
  only once it is complete, so a reader never sees a half-written file (rename is atomic on POSIX
  within one filesystem); it replaces only a regular file (or nothing): a device, FIFO or socket at the
  target is refused (:class:`NotARegularFile`), never replaced.
- :func:`remove_stale_temporaries` removes the temporary files left in a folder by a process that was
  killed while writing (their names carry the writer's pid).
- :func:`strict_json` writes JSON without NaN (undefined values are ``null``).
- :func:`write_error_message` says in one line why an output write failed (disk full, no permission,
  read-only filesystem) and what to do.
- :func:`output_file_problem` and :func:`output_folder_problem` say, before any computation, why an
  output path cannot be written (a folder where a file is expected, a file where a folder is expected,
  no permission), or return None.
- :func:`read_input_bytes` and :func:`read_input_text` read an input file (a case file, a survey, measurements)
  only when it is a regular file of bounded size: a FIFO, a device (``/dev/zero``, ``/dev/urandom``), a socket
  or a folder is refused at once, without blocking on it or reading it.
- :class:`FileLock` is an exclusive (writer) or shared (reader) lock held on a lock file with
  ``flock``: a second writer is refused at once with who holds the lock; a lock left by a process that
  died (``kill -9``, power loss) is released by the kernel and detected as stale from the holder's
  record left in the file (pid, host, start time). Where ``flock`` is not available, the record alone
  decides: a dead pid on this host is stale, a holder on another host is refused with how to clear it.
"""

from __future__ import annotations

import datetime as _dt
import errno
import json
import math
import os
import re
import socket
import stat
import tempfile
import threading
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator

try:  # POSIX
    import fcntl
except ImportError:  # pragma: no cover - Windows
    fcntl = None  # type: ignore[assignment]


# --- atomic writes -------------------------------------------------------------------------------


class NotARegularFile(ValueError):
    """An output path names something that is not a regular file (a device, a FIFO, a socket): it is
    never replaced."""


_KINDS = ((stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"), (stat.S_ISFIFO, "a FIFO"),
          (stat.S_ISSOCK, "a socket"), (stat.S_ISDIR, "a folder"))


def not_regular_problem(path: str | Path) -> str | None:
    """Why ``path`` (followed if a link) must not be replaced by an output file: it exists and is not a
    regular file (e.g. "is a character device, not a regular file; give a file name"), or None."""
    try:
        mode = os.stat(path).st_mode
    except (FileNotFoundError, NotADirectoryError):
        return None
    except OSError as error:
        return f"cannot be examined ({error.strerror or error})"
    if stat.S_ISREG(mode):
        return None
    kind = next((name for test, name in _KINDS if test(mode)), "not a regular file")
    return f"is {kind}, not a regular file; give a file name"


#: Temporary files of :func:`atomic_output`: ``.<name>.<pid>.<thread>.tmp``.
_TEMPORARY = re.compile(r"^\.(?P<name>.+)\.(?P<pid>\d+)\.(?P<thread>\d+)\.tmp$")


@contextmanager
def atomic_output(path: str | Path) -> Iterator[Path]:
    """Yield a temporary path in ``path``'s folder; on success rename it onto ``path``, on any error
    delete it (``path`` is then left as it was). The folder is created if missing. Only a regular file
    (or nothing) is replaced: anything else at ``path`` raises :class:`NotARegularFile`, before and
    after writing."""
    path = Path(path)
    problem = not_regular_problem(path)
    if problem:
        raise NotARegularFile(f"{path} {problem}")
    path.parent.mkdir(parents=True, exist_ok=True)
    temporary = path.with_name(f".{path.name}.{os.getpid()}.{threading.get_ident()}.tmp")
    try:
        yield temporary
        problem = not_regular_problem(path)  # created meanwhile
        if problem:
            raise NotARegularFile(f"{path} {problem}")
        os.replace(temporary, path)
    except BaseException as error:
        temporary.unlink(missing_ok=True)
        if isinstance(error, OSError) and error.errno is not None and error.filename in (None, str(temporary),
                                                                                         temporary):
            error.filename = str(path)  # name the output, not the temporary file (or nothing)
        raise


def write_text_atomic(path: str | Path, text: str) -> Path:
    """Write ``text`` (UTF-8) to ``path`` atomically; returns the path."""
    path = Path(path)
    with atomic_output(path) as temporary:
        temporary.write_text(text, encoding="utf-8")
    return path


def _finite(value):
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: _finite(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_finite(v) for v in value]
    return value


def strict_json(payload, indent: int | None = 2) -> str:
    """JSON text of ``payload`` that any parser reads: every non-finite float (NaN, ±inf: an undefined
    value) is written as ``null``, never as the non-standard ``NaN`` (``allow_nan=False``)."""
    return json.dumps(_finite(payload), indent=indent, allow_nan=False)


def remove_stale_temporaries(folder: str | Path) -> list[Path]:
    """Remove the temporary files of :func:`atomic_output` left in ``folder`` by writers that are no
    longer running (``kill -9`` while a file was being written); returns those removed. Files of a
    running writer are left alone."""
    removed = []
    try:
        entries = list(Path(folder).iterdir())
    except OSError:
        return removed
    for entry in entries:
        match = _TEMPORARY.match(entry.name)
        if match is None or int(match["pid"]) == os.getpid() or _pid_alive(int(match["pid"])):
            continue
        try:
            if entry.is_file() and not entry.is_symlink():
                entry.unlink()
                removed.append(entry)
        except OSError:
            pass
    return removed


#: What to do after a failed write, by errno.
_WRITE_ADVICE = {
    errno.ENOSPC: "free some space",
    errno.EDQUOT: "free some space (disk quota exceeded)",
    errno.EACCES: "give write permission",
    errno.EPERM: "give write permission",
    errno.EROFS: "use a writable location (read-only filesystem)",
}


def write_error_message(error: OSError, kept: str = "") -> str:
    """One line for an output write that failed with ``error``: what could not be written, why, and
    what to do (``kept``: what was saved, e.g. "finished realizations are kept in study.zarr")."""
    where = error.filename or "an output file"
    why = error.strerror or str(error)
    advice = _WRITE_ADVICE.get(error.errno, "fix the problem")
    text = f"cannot write {where}: {why}"
    if kept:
        return f"{text}; {kept}; {advice} and run the same command again to resume"
    return f"{text}; {advice} and run the command again"


# --- output paths checked before computing -------------------------------------------------------


def _existing_ancestor(path: Path) -> Path:
    """The nearest of ``path`` and its parents that exists (the folder where writing would start)."""
    path = Path(os.path.abspath(path))
    while not path.exists() and path != path.parent:
        path = path.parent
    return path


def folder_write_problem(folder: Path) -> str | None:
    """Why nothing can be created in the existing ``folder``, or None (tried for real: permissions,
    read-only filesystems and the superuser are all accounted for)."""
    try:
        handle, name = tempfile.mkstemp(prefix=".drillstring-write-test-", dir=folder)
    except OSError as error:
        return f"cannot write in {folder} ({error.strerror or error})"
    os.close(handle)
    os.unlink(name)
    return None


def output_folder_problem(path: str | Path) -> str | None:
    """Why the folder ``path`` cannot receive output files (created if missing), or None."""
    path = Path(path)
    if path.exists() and not path.is_dir():
        return "is a file, not a folder"
    start = _existing_ancestor(path)
    if not start.is_dir():
        return f"{start} is a file, not a folder"
    return folder_write_problem(start)


def output_file_problem(path: str | Path) -> str | None:
    """Why the file ``path`` cannot be written (its folder is created if missing), or None. Only a
    regular file is overwritten: a device (``/dev/null``), FIFO or socket there is a problem."""
    path = Path(path)
    if path.is_dir():
        return "is a folder; give a file name"
    if path.name in ("", ".", ".."):
        return "is not a file name"
    problem = not_regular_problem(path)
    if problem:
        return problem
    start = _existing_ancestor(path.parent)
    if not start.is_dir():
        return f"{start} is a file, not a folder"
    return folder_write_problem(start)


# --- input files ---------------------------------------------------------------------------------


def read_input_bytes(path: str | Path, *, what: str, max_bytes: int) -> bytes:
    """The bytes of the input file ``path`` (a case file, a survey, measurements): a regular file of at most
    ``max_bytes``. Raises ValueError with one line naming ``what`` (e.g. "survey file") and the path: not
    found, not a regular file (a FIFO or a device is refused from its ``stat``, never opened for reading
    beyond a non-blocking open), larger than ``max_bytes`` (checked again while reading: a file that grows
    is cut off), or unreadable."""
    path = Path(path)
    try:
        info = path.stat()
        if not stat.S_ISREG(info.st_mode):
            kind = next((name for test, name in _KINDS if test(info.st_mode)), "another kind of file")
            raise ValueError(f"{what} {path} is not a regular file ({kind})")
        if info.st_size > max_bytes:
            raise ValueError(f"{what} {path} has {info.st_size:,} bytes, more than the {max_bytes:,} allowed")
        # Read no more than the bound even if the file grew since (or its size was not reported).
        with open(path, "rb", opener=lambda name, flags: os.open(name, flags | os.O_NONBLOCK)) as handle:
            if not stat.S_ISREG(os.fstat(handle.fileno()).st_mode):  # replaced since the check
                raise ValueError(f"{what} {path} is not a regular file")
            raw = handle.read(max_bytes + 1)
    except FileNotFoundError:
        raise ValueError(f"{what} not found: {path}") from None
    except OSError as exc:
        raise ValueError(f"cannot read {what} {path}: {exc.strerror or exc}") from None
    if len(raw) > max_bytes:
        raise ValueError(f"{what} {path} has more than the {max_bytes:,} bytes allowed")
    return raw


def read_input_text(path: str | Path, *, what: str, max_bytes: int) -> str:
    """The text of the input file ``path`` (UTF-8, a byte-order mark dropped), read by :func:`read_input_bytes`;
    ValueError as there, or when it is not UTF-8 text."""
    raw = read_input_bytes(path, what=what, max_bytes=max_bytes)
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise ValueError(f"{what} {path} is not UTF-8 text (byte {exc.start:,}): a CSV file is expected") from None


# --- locks ---------------------------------------------------------------------------------------


class LockedError(RuntimeError):
    """The lock is held by another process (the message says which, and what to do)."""


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # exists, owned by someone else
        return True
    return True


def _describe(holder: dict) -> str:
    parts = [f"pid {holder.get('pid', '?')} on host {holder.get('host', '?')}"]
    if holder.get("started"):
        parts.append(f"started {holder['started']}")
    return ", ".join(parts)


#: Locks held by this process: resolved lock path -> [thread id, depth, file descriptor].
_HELD: dict[str, list] = {}
_HELD_GUARD = threading.Lock()


class FileLock:
    """An exclusive (``shared=False``, writers) or shared (``shared=True``, readers) lock on
    ``path`` (a lock file, created if missing), taken without waiting.

    Use as a context manager; :meth:`acquire` returns a note when it took over a stale lock (a
    holder that died without releasing it), else None. Re-entrant within one thread of one process
    (a study that reads its own store holds the lock already); another thread of the same process is
    refused like another process.
    """

    def __init__(self, path: str | Path, *, shared: bool = False, purpose: str = "") -> None:
        self.path = Path(path)
        self.shared = shared
        self.purpose = purpose
        self._key = os.path.realpath(self.path)
        self._nested = False

    def _read_holder(self, fd: int) -> dict:
        try:
            os.lseek(fd, 0, os.SEEK_SET)
            text = os.read(fd, 65536).decode("utf-8", "replace").strip()
            return json.loads(text) if text else {}
        except (OSError, ValueError):
            return {"pid": "?", "host": "?", "started": "(unreadable lock record)"}

    def _refuse(self, holder: dict) -> LockedError:
        who = _describe(holder) if holder.get("pid") else "another process (reading or writing it)"
        return LockedError(f"in use by {who}; lock file {self.path}")

    def acquire(self) -> str | None:
        with _HELD_GUARD:
            held = _HELD.get(self._key)
            if held is not None:
                if held[0] != threading.get_ident():
                    raise LockedError(f"in use by another thread of this process; lock file {self.path}")
                held[1] += 1
                self._nested = True
                return None
        if self.shared and not self.path.parent.is_dir():
            return None  # nothing there to read, nobody writing it
        self.path.parent.mkdir(parents=True, exist_ok=True)
        for _ in range(20):  # retried only if the file was replaced between open and lock
            try:
                fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
            except OSError:
                if self.shared:  # a read-only location: nobody can be writing there through us
                    return None
                raise
            try:
                note = self._lock(fd)
            except BaseException:
                os.close(fd)
                raise
            if note is _RETRY:
                os.close(fd)
                continue
            with _HELD_GUARD:
                _HELD[self._key] = [threading.get_ident(), 1, fd]
            return note
        raise LockedError(f"could not lock {self.path}: it keeps being replaced")

    def _lock(self, fd: int):
        flocked = False
        if fcntl is not None:
            try:
                fcntl.flock(fd, (fcntl.LOCK_SH if self.shared else fcntl.LOCK_EX) | fcntl.LOCK_NB)
                flocked = True
            except OSError as error:
                if error.errno in (errno.EWOULDBLOCK, errno.EAGAIN, errno.EACCES):
                    raise self._refuse(self._read_holder(fd)) from None
                # ENOLCK, EOPNOTSUPP, ...: a filesystem without flock; the record decides below.
        try:
            same_file = os.fstat(fd).st_ino == os.stat(self.path).st_ino
        except FileNotFoundError:
            same_file = False
        if not same_file:  # released and removed by its holder meanwhile: lock the new file
            return _RETRY
        holder = self._read_holder(fd)
        if self.shared:
            if not flocked and holder.get("pid") and self._record_is_live(holder):
                raise self._refuse(holder)
            return None
        note = None
        if holder.get("pid"):
            if not flocked and self._record_is_live(holder):
                raise self._refuse(holder)
            note = (f"took over a stale lock ({_describe(holder)}; that process is no longer "
                    f"running){': ' + self.purpose if self.purpose else ''}")
        record = {"pid": os.getpid(), "host": socket.gethostname(),
                  "started": _dt.datetime.now().astimezone().isoformat(timespec="seconds")}
        os.ftruncate(fd, 0)
        os.lseek(fd, 0, os.SEEK_SET)
        os.write(fd, (json.dumps(record) + "\n").encode())
        os.fsync(fd)
        return note

    def _record_is_live(self, holder: dict) -> bool:
        """Without flock: is the recorded holder still running? Unknowable on another host."""
        if holder.get("host") != socket.gethostname():
            raise LockedError(
                f"in use by {_describe(holder)} (another host, whose process cannot be checked from "
                f"here); if that study is no longer running, delete {self.path}")
        try:
            pid = int(holder["pid"])
        except (TypeError, ValueError):
            return False
        return pid != os.getpid() and _pid_alive(pid)

    def release(self) -> None:
        with _HELD_GUARD:
            held = _HELD.get(self._key)
            if held is None:
                return
            held[1] -= 1
            if held[1] > 0:
                return
            del _HELD[self._key]
        fd = held[2]
        try:
            if self.shared:  # remove the (empty) lock file if nobody else holds it now
                if fcntl is None:
                    return
                try:
                    fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
                except OSError:
                    return
                if os.fstat(fd).st_size != 0:
                    return  # the record of a holder that died: kept for the next writer's note
            else:  # a clean release leaves no record: the next holder sees no stale lock
                os.ftruncate(fd, 0)
            try:
                if os.fstat(fd).st_ino == os.stat(self.path).st_ino:
                    os.unlink(self.path)
            except FileNotFoundError:
                pass
        finally:
            os.close(fd)  # releases the flock

    def __enter__(self) -> "FileLock":
        self.note = self.acquire()
        return self

    def __exit__(self, *exc) -> None:
        self.release()


_RETRY = object()


def lock_in_use(path: str | Path) -> bool:
    """Whether the lock file ``path`` records a writer that is still running (on this host, or on
    another host where it cannot be checked), without taking the lock."""
    try:
        text = Path(path).read_text(encoding="utf-8", errors="replace").strip()
        holder = json.loads(text) if text else {}
    except (OSError, ValueError):
        return False
    if not isinstance(holder, dict) or not holder.get("pid"):
        return False
    if holder.get("host") != socket.gethostname():
        return True
    try:
        return _pid_alive(int(holder["pid"]))
    except (TypeError, ValueError):
        return False


def held_by_this_process(path: str | Path) -> bool:
    """Whether this process holds the lock on ``path``."""
    with _HELD_GUARD:
        return os.path.realpath(path) in _HELD
