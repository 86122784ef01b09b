"""Where Numba keeps the compiled kernels: one folder per version of the kernels' sources.

Numba's on-disk cache (``cache=True``) checks only the time stamp and size of the file that defines a cached
function. The package's kernels call kernels of other files — the step loop (:mod:`drillstring.dynamics.
compiled`) compiles in the reduced model's right-hand side (:mod:`drillstring.dynamics.rom`), which compiles in
the force laws (:mod:`drillstring.forces`) — so after an edit or an in-place upgrade that changed a law but not
the loop's file, the cached loop would still run the old law: silently wrong results. The cache therefore
lives in a folder named after a hash of **every** source file of the package (:func:`kernel_cache_dir`), not
only those that import Numba: a module that compiles nothing can still change what the compiled kernels run (a
component registered in it changes the registry's table, which the compiled dispatch is written from). Any
change to any of them starts a fresh cache (one compilation, about 12–20 s), and the stale one is never read.

**The registry's table.** The compiled dispatch of each kind of component (:mod:`drillstring.forces.registry`)
is written from the table of the package's components, their names and codes. The first process that packs a
model into a cache folder writes that table there (:data:`MANIFEST`, :func:`check_registry`); every later one
compares its own table with it and refuses a mismatch (a component registered as part of the package at run
time, a folder reused under another version), naming the components that differ, instead of running cached
kernels written for another table.

The folder is ``$NUMBA_CACHE_DIR/kernels-<hash>`` when the user sets ``NUMBA_CACHE_DIR``, else
``$XDG_CACHE_HOME/drillstring/kernels-<hash>`` (``~/.cache/drillstring/...``). :func:`configure` is called when
the package is imported, before any kernel is compiled or loaded; worker processes (local or Dask) import the
package and find the same folder. Numba falls back to its own locations if the folder cannot be written.

**Concurrent writers.** Numba writes a cache entry without a lock (``IndexDataCacheFile.save``): it reads the
function's index, picks the first free data file's name, writes the index, then the data. Two processes that
compile one function for different signatures at once (two pytest-xdist workers, two study workers on a cold
cache) can both pick the same name, and the index can end naming a data file that holds the *other*
signature's code: a later process then runs code compiled for other argument types (numba/numba#10128:
segmentation faults). Measured with six processes compiling one cached function for six signatures at once, 40
trials: entries lost in 9, an index naming another signature's code in 3; with the lock below, all six entries,
each naming its own code, in 40 of 40. :func:`configure` therefore makes every cache write of the process
hold an exclusive lock on the cache folder (``fcntl.flock``; on a system without it Numba's own write is kept)
and write the data before the index names it (:func:`locked_save`).

**What the key does not hold.** Numba keys an entry on the function's signature and bytecode, not on the
compilation flags its callees were compiled with; a kernel compiled inside a caller takes on the caller's flags
unless it sets its own, so the code cached under one key can depend on what the writing process compiled
before (tests/dynamics/test_reference_counting.py). Each of the package's entry points compiles in its own
fixed order; the test suite, which calls kernels in many other orders, compiles into a cache of its own
(tests/conftest.py): a loop it had cached for the Detournay case made the next run of that case die of a
segmentation fault. Kernels that set their flags themselves would close this for any order (not done yet).
"""

from __future__ import annotations

import contextlib
import hashlib
import importlib.abc
import importlib.util
import itertools
import json
import os
import sys
from pathlib import Path

try:
    import fcntl
except ImportError:  # not a POSIX system: Numba's unlocked writes are kept
    fcntl = None

__all__ = ["MANIFEST", "check_registry", "configure", "kernel_cache_dir", "kernel_sources", "locked_save"]

#: Prefix of the cache folder's name; the rest is the sources' hash.
PREFIX = "kernels-"
#: The registry's table written in the cache folder (:func:`check_registry`).
MANIFEST = "registry.json"
#: Numba's module that writes its on-disk cache.
_NUMBA_CACHING = "numba.core.caching"
#: The file locked while a cache entry is written (:func:`locked_save`), one per folder of cached functions.
LOCK = ".write-lock"


def _package_root(package: Path | None) -> Path:
    return Path(__file__).resolve().parent if package is None else Path(package)


def _kernel_files(root: Path) -> list[tuple[Path, bytes]]:
    """``(path, contents)`` of every source file (``*.py``) under ``root``, sorted, each read once."""
    files = []
    for path in sorted(root.rglob("*.py")):
        try:
            files.append((path, path.read_bytes()))
        except OSError:
            continue
    return files


def kernel_sources(package: Path | None = None) -> list[Path]:
    """The package's source files the cache is keyed on: every one of them (module docstring), sorted."""
    return [path for path, _ in _kernel_files(_package_root(package))]


def kernel_cache_dir(base: Path, package: Path | None = None) -> Path:
    """``base / "kernels-<hash>"``, the hash (16 hex digits of SHA-256) over the relative paths and the bytes
    of :func:`kernel_sources`."""
    root = _package_root(package)
    digest = hashlib.sha256()
    for path, data in _kernel_files(root):
        digest.update(path.relative_to(root).as_posix().encode())
        digest.update(b"\0")
        digest.update(data)
        digest.update(b"\0")
    return Path(base) / f"{PREFIX}{digest.hexdigest()[:16]}"


def configure() -> Path:
    """Point Numba's cache at :func:`kernel_cache_dir` (module docstring) and return that folder. A
    ``NUMBA_CACHE_DIR`` that already names such a folder (set by this function in a parent process) is kept;
    without a home folder or readable sources nothing is changed. Either way Numba's cache writes are locked
    (module docstring)."""
    _lock_cache_writes()
    given = os.environ.get("NUMBA_CACHE_DIR", "")
    if given and Path(given).name.startswith(PREFIX):
        return Path(given)
    try:
        base = Path(given) if given else (
            Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "drillstring")
        folder = kernel_cache_dir(base)
    except (OSError, RuntimeError):  # no home folder, unreadable sources: leave Numba's own choice
        return Path(given) if given else Path()
    os.environ["NUMBA_CACHE_DIR"] = str(folder)
    numba = sys.modules.get("numba")
    if numba is not None:  # imported before the package: its configuration was read already
        numba.config.CACHE_DIR = str(folder)
    return folder


@contextlib.contextmanager
def _folder_lock(folder: str):
    """Hold an exclusive ``flock`` on ``folder``'s :data:`LOCK` file (created when missing) until the block ends."""
    with open(os.path.join(folder, LOCK), "a") as handle:
        fcntl.flock(handle, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(handle, fcntl.LOCK_UN)


def locked_save(cache_file, key, data) -> None:
    """Numba's ``IndexDataCacheFile.save(key, data)`` under an exclusive lock on the cache folder (module
    docstring): the index is read, the entry's data file named (its own name when the key has one, else the first
    free one), the data written, and only then the index naming it, all while no other process writes there. A
    process reading meanwhile sees the old index or the new one, each naming whole files of its own entries."""
    with _folder_lock(cache_file._cache_path):
        overloads = cache_file._load_index()
        name = overloads.get(key)
        if name is None:
            taken = set(overloads.values())
            name = next(n for n in map(cache_file._data_name, itertools.count(1)) if n not in taken)
        cache_file._save_data(name, data)
        if overloads.get(key) != name:
            overloads[key] = name
            cache_file._save_index(overloads)


def _lock(index_data_cache_file) -> None:
    """Make ``IndexDataCacheFile.save`` (Numba's class, given) :func:`locked_save`."""
    index_data_cache_file.save = locked_save


class _LockWhenImported(importlib.abc.MetaPathFinder):
    """Finds Numba's caching module as the other finders would and locks its writes once it has run: the package
    does not import Numba itself until a kernel is needed (a command's ``--help`` stays quick)."""

    def find_spec(self, name, path=None, target=None):
        if name != _NUMBA_CACHING:
            return None
        sys.meta_path.remove(self)
        spec = importlib.util.find_spec(name)
        if spec is None or spec.loader is None:
            return spec
        run = spec.loader.exec_module

        def exec_module(module):
            run(module)
            _lock(module.IndexDataCacheFile)

        spec.loader.exec_module = exec_module
        return spec


def _lock_cache_writes() -> None:
    """Make every Numba cache write of this process :func:`locked_save`: now if Numba is imported, else when it
    is; nothing without ``fcntl``."""
    if fcntl is None:
        return
    caching = sys.modules.get(_NUMBA_CACHING)
    if caching is not None:
        _lock(caching.IndexDataCacheFile)
    elif not any(isinstance(finder, _LockWhenImported) for finder in sys.meta_path):
        sys.meta_path.insert(0, _LockWhenImported())


def check_registry(table: dict, folder: Path | None = None) -> None:
    """Compare the registry's ``table`` (kind -> {name: code} of the package's compiled components) with the one
    written in the cache ``folder`` (Numba's cache folder by default): write it when there is none, RuntimeError
    naming the differing components when it differs (module docstring). Nothing is checked when the folder
    cannot be read or written (Numba then compiles afresh: nothing stale is read either)."""
    if folder is None:
        given = os.environ.get("NUMBA_CACHE_DIR", "")  # set by configure() when the package is imported
        if not given:
            return
        folder = Path(given)
    path = Path(folder) / MANIFEST
    mine = {kind: {name: float(code) for name, code in sorted(entries.items())}
            for kind, entries in sorted(table.items())}
    try:
        written = json.loads(path.read_text())
    except FileNotFoundError:
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            temporary = path.with_name(f"{MANIFEST}.{os.getpid()}")
            temporary.write_text(json.dumps(mine, indent=1))
            os.replace(temporary, path)  # atomic: a concurrent reader sees the whole table or none
        except OSError:
            pass
        return
    except (OSError, ValueError):
        return
    if written != mine:
        differ = []
        for kind in sorted(set(written) | set(mine)):
            theirs, ours = written.get(kind, {}), mine.get(kind, {})
            differ += [f"{kind} {name!r}: code {theirs.get(name)} in the cache, {ours.get(name)} here"
                       for name in sorted(set(theirs) | set(ours)) if theirs.get(name) != ours.get(name)]
        raise RuntimeError(f"the compiled kernels in {folder} were written for another table of components "
                           f"({'; '.join(differ)}): refusing to run them; remove that folder or register "
                           f"components from outside the package (docs/extending.md)")
