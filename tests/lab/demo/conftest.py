"""A demo run shared by the demo's tests."""

from __future__ import annotations

import pytest

from sonarcarve.lab.demo import DemoResult, run_demo


@pytest.fixture(scope="package")
def doorway() -> DemoResult:
    """The demo on the doorway world: a 3 m drive straight at a 0.85 m door (167 readings)."""
    return run_demo("doorway", seed=0)
