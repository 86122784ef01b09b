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


def test_two_writers_of_one_functions_cache_keep_both_entries(tmp_path):
    """Numba writes a cache entry unlocked (read the index, pick a free data file, write): a writer that read
    the index before another wrote it picks the same file, and one entry is lost or names the other's code
    (numba/numba#10128). Here the first writer is held just after reading the index: the second must wait for
    it (the folder's lock), then add its own entry beside the first, data before the index that names it."""
    import threading

    from numba.core.caching import IndexDataCacheFile

    assert IndexDataCacheFile.save is kernel_cache.locked_save
    first, second, reader = (IndexDataCacheFile(str(tmp_path), "law.f-3.py311", ("stamp", 1)) for _ in range(3))
    read, resume = threading.Event(), threading.Event()
    load_index = first._load_index

    def held_after_reading():
        overloads = load_index()
        read.set()
        resume.wait(10)
        return overloads

    first._load_index = held_after_reading
    order = []
    save_data, save_index = second._save_data, second._save_index
    second._save_data = lambda name, data: (order.append(("data", name)), save_data(name, data))
    second._save_index = lambda overloads: (order.append(("index", dict(overloads))), save_index(overloads))

    writers = [threading.Thread(target=first.save, args=(("float64",), "code for float64")),
               threading.Thread(target=second.save, args=(("int64",), "code for int64"))]
    writers[0].start()
    assert read.wait(10)
    writers[1].start()
    writers[1].join(0.5)
    waited = writers[1].is_alive()
    resume.set()
    for writer in writers:
        writer.join(10)
    assert waited, "the second writer did not wait for the first"
    assert reader.load(("float64",)) == "code for float64"
    assert reader.load(("int64",)) == "code for int64"
    (data, name), (index, named) = order
    assert (data, index) == ("data", "index") and named[("int64",)] == name != named[("float64",)]


def test_cache_writes_are_locked_once_numba_is_imported():
    """The package does not import Numba on import (a command's --help stays quick); Numba's cache writes are
    locked when it is imported later, in any process that imported the package first."""
    import subprocess

    script = ("import sys, drillstring\n"
              "assert 'numba' not in sys.modules\n"
              "from numba.core.caching import IndexDataCacheFile\n"
              "from drillstring.kernel_cache import locked_save\n"
              "assert IndexDataCacheFile.save is locked_save\n")
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
