"""Shared fixtures: small sections and meshes that build in milliseconds, and the reference case.

The suite compiles its kernels into a cache folder of its own (``NUMBA_CACHE_DIR`` set here, before the package
is imported, unless the caller set one): ``$XDG_CACHE_HOME/drillstring/tests`` (``~/.cache/drillstring/tests``),
under which :mod:`drillstring.kernel_cache` keeps one folder per version of the sources. Tests call kernels from
Python and in orders the package's runs never do, and a kernel compiled inside another inherits the caller's
compilation flags (tests/dynamics/test_reference_counting.py), which Numba's cache index does not record; a step
loop that the suite's workers cached so (its key the same as the package's own, its code not) made the next run
of a Detournay case, the documentation's notebook, die of a segmentation fault (measured: the notebook ran on a
cache it compiled itself, and died on the one the suite had written, through that one entry).

Dense linear algebra runs on one BLAS thread in every test, as it does inside the package's public functions
(:mod:`drillstring.blas_threads`): tests call the stability analysis, the statics and the model builders
directly, where no such limit is set, and with the suite's two xdist workers each running OpenBLAS's default
two threads on a 2-core machine, the threads wait for each other (measured on the 2-core machine, a cold
kernel cache, ``pytest -n auto``: the paper's stability case 93 s instead of 22 s, the whole suite 554 s instead
of 451 s). ``OPENBLAS_NUM_THREADS`` is set too (unless the caller set it), for the processes the tests start.
"""

import os
from pathlib import Path

if not os.environ.get("NUMBA_CACHE_DIR"):
    os.environ["NUMBA_CACHE_DIR"] = str(
        Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "drillstring" / "tests")

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import pytest  # noqa: E402

from drillstring.blas_threads import single_threaded_blas  # noqa: E402
from drillstring.case import load_case  # noqa: E402
from drillstring.fem.sections import hollow_circle  # noqa: E402


@pytest.fixture(scope="session", autouse=True)
def _single_threaded_blas():
    """One BLAS thread (``$DRILLSTRING_BLAS_THREADS``) for the whole session (module docstring)."""
    with single_threaded_blas():
        yield


@pytest.fixture
def drill_pipe():
    return hollow_circle(0.127, 0.095, 210e9, 7850.0, 0.29, 6.0 / 7.0)


@pytest.fixture
def drill_collar():
    return hollow_circle(0.2286, 0.0762, 210e9, 7850.0, 0.29, 6.0 / 7.0)


@pytest.fixture(scope="session")
def reference_case():
    return load_case("reference")


@pytest.fixture(scope="session")
def coarse_case(reference_case):
    """The reference string on a 40 m mesh with 20 lateral modes per plane (no frequency cut-off): builds and
    runs several times faster."""
    mesh = reference_case.mesh.model_copy(update={"max_element_length": 40.0})
    reduced = reference_case.reduced_model.model_copy(update={"lateral_cutoff": 0.0})
    return reference_case.model_copy(update={"mesh": mesh, "reduced_model": reduced})


def _coarse_reference(reference_case, axial_modes: int, torsional_modes: int, lateral_modes: int):
    """The reference string on a 50 m mesh with a small basis (no lateral frequency cut-off)."""
    return reference_case.model_copy(update={
        "mesh": reference_case.mesh.model_copy(update={"max_element_length": 50.0}),
        "reduced_model": reference_case.reduced_model.model_copy(update={
            "axial_modes": axial_modes, "torsional_modes": torsional_modes, "lateral_modes": lateral_modes,
            "lateral_cutoff": 0.0}),
    })


@pytest.fixture(scope="session")
def small_case(reference_case):
    """The reference string on a coarse mesh with a small basis (3 lateral modes): ~0.1 s per realization."""
    return _coarse_reference(reference_case, 2, 2, 3)


@pytest.fixture(scope="session")
def torsional_case(reference_case):
    """The reference string on a coarse mesh, lateral modes off (no contact can occur): 0.05–0.3 s for a
    150 s run."""
    return _coarse_reference(reference_case, 3, 3, 0)


def _can_create_in(folder) -> bool:
    import os

    probe = os.path.join(folder, ".drillstring-fixture-probe")
    try:
        with open(probe, "w"):
            pass
    except OSError:
        return False
    os.unlink(probe)
    return True


@pytest.fixture
def unwritable_folder(tmp_path):
    """A folder in which nothing can be created: a read-only temporary folder, or, for the superuser
    (whom permissions do not stop), /sys where the kernel refuses new files."""
    from pathlib import Path

    folder = tmp_path / "read-only"
    folder.mkdir()
    folder.chmod(0o500)
    if not _can_create_in(folder):
        yield folder
    elif Path("/sys").is_dir() and not _can_create_in("/sys"):
        yield Path("/sys")
    else:
        pytest.skip("no unwritable folder on this machine")
    folder.chmod(0o700)
