""":mod:`sonarcarve.lab.demo.table`: the summaries."""

from __future__ import annotations

from sonarcarve.lab.demo import DEMO_METHODS, DemoResult, summary_markdown


def test_summary_markdown_has_one_row_per_method(doorway: DemoResult) -> None:
    lines = summary_markdown(doorway).splitlines()
    rows = [line for line in lines if line.startswith("| ") and "---" not in line]
    assert len(rows) == 1 + len(DEMO_METHODS)  # header + methods
    assert all(row.count("|") == rows[0].count("|") for row in rows)
