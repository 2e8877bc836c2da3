"""``sonarcarve demo`` and :mod:`sonarcarve.lab.demo`: small worlds, short runs, independent
checks."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
import shapely
from PIL import Image

from sonarcarve.cli import main
from sonarcarve.lab.demo import (
    APPROACH_DISTANCE,
    DEMO_METHODS,
    FIGURE_FILES,
    METHOD_LABELS,
    SAMPLE_EVERY,
    DemoResult,
    run_demo,
    summary_markdown,
)
from sonarcarve.methods import MethodConfig, make_method
from sonarcarve.sim.sonar import EchoKind

PERCENT_FIELDS = ("unprocessed_pct", "fully_carved_pct", "spurious_removed_pct", "true_lost_pct")


@pytest.fixture(scope="module")
def doorway() -> DemoResult:
    """The demo on the doorway world: a 3 m drive straight at a 0.85 m door (167 readings)."""
    return run_demo("doorway", seed=0)


# -- the CLI ----------------------------------------------------------------------------------


def test_cli_writes_every_figure_and_summary(tmp_path: Path,
                                             capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "nested" / "demo"
    assert main(["demo", "--world", "doorway", "--seed", "1", "--out", str(out)]) == 0
    names = sorted(p.name for p in out.iterdir())
    assert names == sorted([*FIGURE_FILES.values(), "summary.json", "summary.md"])
    for name in FIGURE_FILES.values():
        with Image.open(out / name) as png:
            assert png.format == "PNG"
            assert min(png.size) >= 400  # a real figure, not an empty canvas

    summary = json.loads((out / "summary.json").read_text())
    rows = summary["methods"]
    assert [row["method"] for row in rows] == list(DEMO_METHODS)
    by_name = {row["method"]: row for row in rows}
    assert by_name["centerline"]["unprocessed_pct"] == 0.0
    # Centerline keeps every reading: one point each, nothing removed.
    assert by_name["centerline"]["map_points"] == summary["readings"]
    for row in rows:
        assert row["readings"] == summary["readings"]
        for name in PERCENT_FIELDS:
            assert row[name] is None or 0.0 <= row[name] <= 100.0
        assert 0.0 <= row["median_error_m"] <= row["p90_error_m"]
        assert row["readings_per_second"] > 0.0

    printed = capsys.readouterr().out
    table_rows = [line for line in printed.splitlines()
                  if line.split() and line.split()[0] in METHOD_LABELS.values()]
    assert [line.split()[0] for line in table_rows] == [METHOD_LABELS[m] for m in DEMO_METHODS]
    assert "How to read" in printed
    markdown = (out / "summary.md").read_text()
    assert sum(line.startswith(f"| {METHOD_LABELS[m]} |") for m in DEMO_METHODS
               for line in markdown.splitlines()) == len(DEMO_METHODS)


def test_cli_help_teaches_the_columns() -> None:
    from typer.testing import CliRunner

    from sonarcarve.cli.app import app

    result = CliRunner().invoke(app, ["demo", "--help"], terminal_width=100)
    assert result.exit_code == 0
    for phrase in ("unprocessed", "spurious removed", "true lost", "Example", "--history"):
        assert phrase in result.output


@pytest.mark.parametrize(("args", "message"), [
    (["--world", "no-such-world"], "no-such-world"),
    (["--world", "doorway", "--history", "0"], "--history must be at least 1"),
])
def test_cli_bad_input_is_one_line_and_writes_nothing(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], args: list[str], message: str,
) -> None:
    fresh = tmp_path / "fresh"
    assert main(["demo", *args, "--out", str(fresh)]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err
    assert len(err.splitlines()) == 1
    assert not fresh.exists()

    kept = tmp_path / "kept"
    kept.mkdir()
    (kept / "mine.txt").write_text("untouched")
    assert main(["demo", *args, "--out", str(kept)]) == 2
    assert [p.name for p in kept.iterdir()] == ["mine.txt"]
    assert (kept / "mine.txt").read_text() == "untouched"


def test_cli_out_that_is_a_file_is_refused(tmp_path: Path,
                                           capsys: pytest.CaptureFixture[str]) -> None:
    blocker = tmp_path / "file"
    blocker.write_text("x")
    assert main(["demo", "--world", "doorway", "--out", str(blocker / "sub")]) == 2
    assert "not a directory" in capsys.readouterr().err
    assert blocker.read_text() == "x"


# -- the measures, checked independently ------------------------------------------------------


def test_error_is_the_distance_to_the_true_walls(doorway: DemoResult) -> None:
    # Reference: shapely's point-to-line distance against the world's walls.
    walls = shapely.MultiLineString([s.reshape(2, 2) for s in doorway.world.segments])
    for row in doorway.methods:
        xy = doorway.global_maps[row.method].xy
        distance = shapely.distance(shapely.points(xy), walls)
        assert row.median_error_m == pytest.approx(float(np.median(distance)), abs=1e-9)
        assert row.p90_error_m == pytest.approx(float(np.percentile(distance, 90)), abs=1e-9)


def test_removed_shares_are_readings_missing_from_the_map(doorway: DemoResult) -> None:
    kind = doorway.simulation.truth.kind
    spurious = kind != EchoKind.DIRECT
    assert spurious.any()
    assert (~spurious).any()
    for row in doorway.methods:
        kept = np.zeros(len(kind), dtype=bool)
        kept[doorway.global_maps[row.method].reading_id] = True
        assert row.spurious_removed_pct == pytest.approx(100.0 * np.mean(~kept[spurious]))
        assert row.true_lost_pct == pytest.approx(100.0 * np.mean(~kept[~spurious]))
        assert row.map_points == int(kept.sum())
    assert doorway.summary("centerline").fully_carved_pct == 0.0


def test_unprocessed_share_matches_the_methods_own_measure(doorway: DemoResult) -> None:
    # Reference: feed the readings one by one and ask the method (SonarMethod.measures) every
    # SAMPLE_EVERY readings; the doorway run never fills a 250-arc history, so every sample
    # counts and all have to be weighted by their history length.
    readings = doorway.simulation.readings
    for name in ("carve", "atm"):
        method = make_method(name, MethodConfig(history_size=250))
        unprocessed = total = 0.0
        for i, reading in enumerate(readings, start=1):
            method.add(reading)
            if i % SAMPLE_EVERY == 0:
                m = method.measures()
                unprocessed += m.unprocessed_share * m.in_history
                total += m.in_history
        assert doorway.summary(name).unprocessed_pct == pytest.approx(100.0 * unprocessed / total)


def _robot_y(result: DemoResult, reading: int) -> float:
    """The robot's y when reading ``reading`` (0-based) was taken."""
    sim = result.simulation
    return float(sim.trajectory.pose_at(sim.readings.t[reading])[1])


def test_doorway_closeup_looks_from_the_approach_distance(doorway: DemoResult) -> None:
    # The tour drives from (0, 0) to (0, 3) straight at the door centred on (0, 4): head-on, and
    # the view is taken at the first reading with the robot past y = 4 - 1.5 = 2.5.
    door = doorway.closeup
    assert door is not None
    assert door.how == "head-on"
    x, y, _ = door.view.robot
    assert x == pytest.approx(0.0, abs=1e-9)
    last = door.view.readings - 1
    assert y == _robot_y(doorway, last)
    assert _robot_y(doorway, last - 1) < 4.0 - APPROACH_DISTANCE <= y
    assert door.distance <= APPROACH_DISTANCE
    assert set(door.view.maps) == set(DEMO_METHODS)
    # The doorway world's local maps at that moment hold only readings already made.
    for local in door.view.maps.values():
        assert np.all(local.reading_id < door.view.readings)


def test_door_driven_through_is_seen_1_5_m_of_driving_before_it() -> None:
    # T junction: up x = 0 from y = 1 to y = 13, turn right, through the opening at x = 1
    # (jambs (1, 12) and (1, 14)). 1.5 m of driving before the crossing is (0, 12.5).
    # The view is the last reading before the robot passes that point.
    result = run_demo("t-junction", seed=0, methods=("centerline",))
    through = [d for d in result.doors if d.how == "through"]
    assert [d.opening for d in through] == [1]
    x, y, _ = through[0].view.robot
    last = through[0].view.readings - 1
    assert x == pytest.approx(0.0, abs=1e-9)
    assert y == _robot_y(result, last)
    assert y <= 12.5 < _robot_y(result, last + 1)
    assert result.closeup is through[0]


def test_summary_markdown_has_one_row_per_method(doorway: DemoResult) -> None:
    lines = summary_markdown(doorway).splitlines()
    rows = [line for line in lines if line.startswith("| ") and "---" not in line]
    assert len(rows) == 1 + len(DEMO_METHODS)  # header + methods
    assert all(row.count("|") == rows[0].count("|") for row in rows)


def test_same_seed_same_numbers(doorway: DemoResult) -> None:
    again = run_demo("doorway", seed=0, methods=("carve",))
    first = doorway.summary("carve")
    second = again.summary("carve")
    for name in ("median_error_m", "p90_error_m", *PERCENT_FIELDS, "map_points"):
        a, b = getattr(first, name), getattr(second, name)
        assert a == b or (math.isnan(a) and math.isnan(b))


def test_cli_world_without_tour_is_refused(tmp_path: Path,
                                           capsys: pytest.CaptureFixture[str]) -> None:
    walls = tmp_path / "walls.json"
    walls.write_text('{"name": "box", "segments": [[0, 0, 4, 0], [4, 0, 4, 4]]}')
    out = tmp_path / "out"
    assert main(["demo", "--world", str(walls), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert "has no tour" in err[0]
    assert not out.exists()
