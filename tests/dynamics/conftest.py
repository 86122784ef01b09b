import pytest

from drillstring.case import load_case


@pytest.fixture(scope="session")
def reference_case():
    return load_case("reference")


@pytest.fixture(scope="session")
def coarse_case(reference_case):
    """The reference string on a 40 m mesh: builds and runs several times faster."""
    mesh = reference_case.mesh.model_copy(update={"max_element_length": 40.0})
    return reference_case.model_copy(update={"mesh": mesh})
