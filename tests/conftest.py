"""Shared fixtures: small sections and meshes that build in milliseconds."""

import pytest

from drillstring.fem.sections import hollow_circle


@pytest.fixture
def drill_pipe():
    return hollow_circle(0.127, 0.095, 210e9, 7850.0, 0.29, 6.0 / 7.0)


@pytest.fixture
def drill_collar():
    return hollow_circle(0.2286, 0.0762, 210e9, 7850.0, 0.29, 6.0 / 7.0)
