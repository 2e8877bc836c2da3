"""Fixtures of the grid tests."""

from __future__ import annotations

import math

import pytest

from sonarcarve.grids.carved import grid as carved


@pytest.fixture
def carving_alone_under_the_grid(monkeypatch: pytest.MonkeyPatch) -> None:
    """A carved grid made without a method runs specular-aware carving at 30°, the grid's
    default method before combined carving: the expected values of the tests that use this are
    worked out by hand for it. The default itself is pinned by
    ``test_carved.py::test_the_default_method_is_combined_carving``."""
    monkeypatch.setattr(carved, "DEFAULT_METHOD", "carve")
    monkeypatch.setattr(carved, "DEFAULT_MAX_INCIDENCE", math.radians(30.0))
