"""The shear tests' fixtures: the packing of tests/sheared_packing.py's SCENE and its shear
(the session fixture conftest.sheared computes them once; these hand them to each module)."""
from __future__ import annotations

import pytest
from sheared_packing import SCENE


@pytest.fixture(scope="module")
def packing(sheared):
    return sheared(SCENE)[0]


@pytest.fixture(scope="module")
def recorded(sheared):
    """(branch, ends) of SCENE's shear (conftest.sheared: shared with test_packing_dynamics)."""
    return sheared(SCENE)[1:]


@pytest.fixture(scope="module")
def branch(recorded):
    return recorded[0]
