""":mod:`sonarcarve.lab.demo.table`: the summaries."""

from __future__ import annotations

from sonarcarve.lab.demo import DEMO_METHODS, DemoResult, summary_markdown


def _table_rows(lines: list[str]) -> list[str]:
    return [line for line in lines if line.startswith("| ") and "---" not in line]


def test_summary_markdown_has_one_row_per_method_then_per_grid(doorway: DemoResult) -> None:
    text = summary_markdown(doorway)
    methods, grids = text.split("## Occupancy grids")
    rows = _table_rows(methods.splitlines())
    assert len(rows) == 1 + len(DEMO_METHODS)  # header + methods
    assert all(row.count("|") == rows[0].count("|") for row in rows)
    rows = _table_rows(grids.splitlines())
    assert [row.split("|")[1].strip() for row in rows] == [
        "grid", "carved grid", "ROS RangeSensorLayer (defaults)"]
    assert all(row.count("|") == 7 for row in rows)  # grid and five measures


def test_caption_states_what_each_carving_left_out(doorway: DemoResult) -> None:
    from sonarcarve.lab.demo.table import caption

    text = caption(doorway)
    for method, name in (("carve", "Carving"), ("evidence", "Evidence carving")):
        row = doorway.summary(method)
        assert (f"{name} left out {row.spurious_removed_pct:.0f}% of the spurious readings"
                in text)
        assert f"{row.true_lost_pct:.0f}% of the true ones." in text
