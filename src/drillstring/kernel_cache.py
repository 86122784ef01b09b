"""Where Numba keeps the compiled kernels: one folder per version of the kernels' sources.

Numba's on-disk cache (``cache=True``) checks only the time stamp and size of the file that defines a cached
function. The package's kernels call kernels of other files — the step loop (:mod:`drillstring.dynamics.
compiled`) compiles in the reduced model's right-hand side (:mod:`drillstring.dynamics.rom`), which compiles in
the force laws (:mod:`drillstring.forces`) — so after an edit or an in-place upgrade that changed a law but not
the loop's file, the cached loop would still run the old law: silently wrong results. The cache therefore
lives in a folder named after a hash of every source file of the package that uses Numba
(:func:`kernel_cache_dir`): any change to any of them starts a fresh cache (one compilation, about 12–20 s),
and the stale one is never read.

The folder is ``$NUMBA_CACHE_DIR/kernels-<hash>`` when the user sets ``NUMBA_CACHE_DIR``, else
``$XDG_CACHE_HOME/drillstring/kernels-<hash>`` (``~/.cache/drillstring/...``). :func:`configure` is called when
the package is imported, before any kernel is compiled or loaded; worker processes (local or Dask) import the
package and find the same folder. Numba falls back to its own locations if the folder cannot be written.
"""

from __future__ import annotations

import hashlib
import os
import sys
from pathlib import Path

__all__ = ["configure", "kernel_cache_dir", "kernel_sources"]

#: Prefix of the cache folder's name; the rest is the sources' hash.
PREFIX = "kernels-"


def _package_root(package: Path | None) -> Path:
    return Path(__file__).resolve().parent if package is None else Path(package)


def _kernel_files(root: Path) -> list[tuple[Path, bytes]]:
    """``(path, contents)`` of the source files under ``root`` that import Numba, sorted, each read once."""
    files = []
    for path in sorted(root.rglob("*.py")):
        try:
            data = path.read_bytes()
        except OSError:
            continue
        if b"from numba" in data or b"import numba" in data:
            files.append((path, data))
    return files


def kernel_sources(package: Path | None = None) -> list[Path]:
    """The package's source files that use Numba (they import it), sorted."""
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
    without a home folder or readable sources nothing is changed."""
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
