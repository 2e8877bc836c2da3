"""The RESULTS.md section writer: only the span between the markers changes."""

from __future__ import annotations

import math

import pytest

from sonarcarve.evaluation.report import (
    BEGIN_MARKER,
    END_MARKER,
    ReportError,
    _clean,
    replace_section,
)

NEW = f"{BEGIN_MARKER}\nnew\n{END_MARKER}"


def test_replaces_only_the_marked_span() -> None:
    text = f"head\n\n{BEGIN_MARKER}\nold 1\nold 2\n{END_MARKER}\n\ntail\n"
    assert replace_section(text, NEW) == f"head\n\n{NEW}\n\ntail\n"


def test_appends_when_there_are_no_markers() -> None:
    assert replace_section("", NEW) == f"{NEW}\n"
    assert replace_section("# Results\n", NEW) == f"# Results\n\n{NEW}\n"
    assert replace_section("# Results", NEW) == f"# Results\n\n{NEW}\n"


def test_is_idempotent() -> None:
    once = replace_section("a\n", NEW)
    assert replace_section(once, NEW) == once


@pytest.mark.parametrize("text", [
    f"x\n{BEGIN_MARKER}\nno end\n",
    f"x\n{END_MARKER}\n{BEGIN_MARKER}\n",
    f"{BEGIN_MARKER}\n{END_MARKER}\n{BEGIN_MARKER}\n{END_MARKER}\n",
])
def test_broken_markers_raise_naming_the_file(text: str) -> None:
    with pytest.raises(ReportError, match=r"docs/RESULTS.md: line \d+"):
        replace_section(text, NEW, "docs/RESULTS.md")


def test_clean_makes_strict_json() -> None:
    import numpy as np

    data = {"a": math.nan, "b": (1, np.float64(2.5), math.inf), "c": {"d": np.int64(3)},
            "e": True}
    assert _clean(data) == {"a": None, "b": [1, 2.5, None], "c": {"d": 3}, "e": True}
