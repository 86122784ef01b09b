"""Shared fixtures: small sections and meshes that build in milliseconds, and the reference case."""

import pytest

from drillstring.case import load_case
from drillstring.fem.sections import hollow_circle


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
    """The reference string on a 40 m mesh: builds and runs several times faster."""
    mesh = reference_case.mesh.model_copy(update={"max_element_length": 40.0})
    return reference_case.model_copy(update={"mesh": mesh})
