""":mod:`sonarcarve.lab.demo.scenario`: a demo request is checked before anything runs."""

from __future__ import annotations

import pytest

from sonarcarve.errors import ConfigError
from sonarcarve.history import DEFAULT_HISTORY_SIZE
from sonarcarve.lab.demo.scenario import DemoError, demo_config


@pytest.mark.parametrize("size", [0, 100_001, 2.5, True])
def test_the_history_size_is_checked_by_method_config(size: object) -> None:
    """One rule for the history size, MethodConfig's (review finding 15): the lab names the
    parameter, and the command line rewords it as --history (tests/cli/test_demo_cli.py)."""
    with pytest.raises(ConfigError) as info:
        demo_config(size)  # type: ignore[arg-type]
    assert str(info.value).startswith(
        "history_size must be a whole number of arcs in [1, 100,000], got ")
    assert not isinstance(info.value, DemoError)


def test_the_default_is_the_library_default() -> None:
    assert demo_config().history_size == DEFAULT_HISTORY_SIZE


def test_other_bad_requests_are_demo_errors() -> None:
    with pytest.raises(DemoError, match="unknown demo method"):
        demo_config(methods=("carving",))
    with pytest.raises(DemoError, match="max_length must be a positive number"):
        demo_config(max_length=0.0)
