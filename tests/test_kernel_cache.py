"""The kernels' cache folder (drillstring.kernel_cache): one per version of the sources that use Numba, so a
changed force law never runs through a stale cached step loop."""

import sys
from pathlib import Path

import drillstring
from drillstring import kernel_cache


def _package(tmp_path: Path) -> Path:
    root = tmp_path / "pkg"
    (root / "forces").mkdir(parents=True)
    (root / "forces" / "law.py").write_text("from numba import njit\n\n@njit(cache=True)\ndef f(x):\n    return x\n")
    (root / "loop.py").write_text("import numba\n")
    (root / "cli.py").write_text("print('no kernels here')\n")
    return root


def test_the_folder_follows_the_kernel_sources_only(tmp_path):
    root = _package(tmp_path)
    assert [p.relative_to(root).as_posix() for p in kernel_cache.kernel_sources(root)] == ["forces/law.py", "loop.py"]
    first = kernel_cache.kernel_cache_dir(tmp_path / "cache", root)
    assert first.parent == tmp_path / "cache" and first.name.startswith(kernel_cache.PREFIX)
    (root / "cli.py").write_text("print('still no kernels')\n")  # not a kernel source: same folder
    assert kernel_cache.kernel_cache_dir(tmp_path / "cache", root) == first
    (root / "forces" / "law.py").write_text("from numba import njit\n\n@njit(cache=True)\ndef f(x):\n    return 2 * x\n")
    assert kernel_cache.kernel_cache_dir(tmp_path / "cache", root) != first  # a changed law: a fresh cache


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
