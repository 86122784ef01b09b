"""The kernels' cache folder (drillstring.kernel_cache): one per version of the package's sources, so a
changed force law never runs through a stale cached step loop, and the registry's table checked in it."""

import sys
from pathlib import Path

import pytest

import drillstring
from drillstring import kernel_cache


def _package(tmp_path: Path) -> Path:
    root = tmp_path / "pkg"
    (root / "forces").mkdir(parents=True)
    (root / "forces" / "law.py").write_text("from numba import njit\n\n@njit(cache=True)\ndef f(x):\n    return x\n")
    (root / "loop.py").write_text("import numba\n")
    (root / "cli.py").write_text("print('no kernels here')\n")
    return root


def test_the_folder_follows_every_source_file(tmp_path):
    root = _package(tmp_path)
    assert [p.relative_to(root).as_posix() for p in kernel_cache.kernel_sources(root)] == [
        "cli.py", "forces/law.py", "loop.py"]
    first = kernel_cache.kernel_cache_dir(tmp_path / "cache", root)
    assert first.parent == tmp_path / "cache" and first.name.startswith(kernel_cache.PREFIX)
    assert kernel_cache.kernel_cache_dir(tmp_path / "cache", root) == first  # the same sources: the same folder
    (root / "forces" / "law.py").write_text("from numba import njit\n\n@njit(cache=True)\ndef f(x):\n    return 2 * x\n")
    assert kernel_cache.kernel_cache_dir(tmp_path / "cache", root) != first  # a changed law: a fresh cache


def test_a_module_without_numba_changes_the_folder(tmp_path):
    """Issue 33: a law module that does not import Numba (its kernel imported from another file) registers a
    component, which changes the compiled dispatch: the cache must start afresh. On b1c1e75 the folder was
    keyed on the files importing Numba only, and a cached dispatch ran the off-bottom law for a Detournay case."""
    root = _package(tmp_path)
    first = kernel_cache.kernel_cache_dir(tmp_path / "cache", root)
    (root / "forces" / "aardvark.py").write_text("from .law import f as kernel  # registers a law, no numba import\n")
    assert kernel_cache.kernel_cache_dir(tmp_path / "cache", root) != first
    second = kernel_cache.kernel_cache_dir(tmp_path / "cache", root)
    (root / "cli.py").write_text("print('edited')\n")
    assert kernel_cache.kernel_cache_dir(tmp_path / "cache", root) != second


def test_a_cache_written_for_another_table_is_refused(tmp_path):
    """The registry's table (names -> codes) is written in the cache folder by the first process and checked
    by every later one: a folder whose kernels were compiled for other codes is refused, naming the law."""
    table = {"bit_law": {"detournay": 11.0, "off_bottom": 12.0}, "motor": {}}
    kernel_cache.check_registry(table, tmp_path)  # a fresh folder: the table is written
    assert (tmp_path / kernel_cache.MANIFEST).exists()
    kernel_cache.check_registry(table, tmp_path)  # the same table: accepted
    shifted = {"bit_law": {"aardvark": 11.0, "detournay": 12.0, "off_bottom": 13.0}, "motor": {}}
    with pytest.raises(RuntimeError, match="'detournay': code 11.0 in the cache, 12.0 here"):
        kernel_cache.check_registry(shifted, tmp_path)


def test_the_package_checks_its_table_against_its_cache_folder():
    """Packing a model checked (and wrote) this process's registry table in the kernels' folder."""
    import json
    import os

    from drillstring.forces.registry import _check_cache_table, registry_table

    _check_cache_table()
    written = json.loads((Path(os.environ["NUMBA_CACHE_DIR"]) / kernel_cache.MANIFEST).read_text())
    assert written == registry_table()


def test_configure_nests_under_the_users_folder_once(tmp_path, monkeypatch):
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "mine"))
    numba = sys.modules.get("numba")
    if numba is not None:  # restored after the test: the session's kernels keep their cache
        monkeypatch.setattr(numba.config, "CACHE_DIR", numba.config.CACHE_DIR)
    folder = kernel_cache.configure()
    assert folder.parent == tmp_path / "mine" and folder.name.startswith(kernel_cache.PREFIX)
    assert folder == kernel_cache.kernel_cache_dir(tmp_path / "mine")  # this package's own sources
    assert kernel_cache.configure() == folder  # a worker process inheriting the variable keeps it
    if numba is not None:
        assert numba.config.CACHE_DIR == str(folder)


def test_the_package_uses_such_a_folder():
    """Importing the package pointed Numba at a folder named after the current sources."""
    import os

    assert Path(os.environ["NUMBA_CACHE_DIR"]).name.startswith(kernel_cache.PREFIX)
    assert Path(drillstring.__file__).parent / "dynamics" / "rom.py" in kernel_cache.kernel_sources()
