""":mod:`sonarcarve.lab.demo.runs`: each measure of the table, checked independently."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import shapely

from sonarcarve.lab.demo import SAMPLE_EVERY, DemoResult, run_demo
from sonarcarve.methods import MethodConfig, make_method
from sonarcarve.sim.sonar import EchoKind

PERCENT_FIELDS = ("unprocessed_pct", "fully_carved_pct", "spurious_removed_pct", "true_lost_pct")


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


def test_same_seed_same_numbers(doorway: DemoResult) -> None:
    again = run_demo("doorway", seed=0, methods=("carve",))
    first = doorway.summary("carve")
    second = again.summary("carve")
    for name in ("median_error_m", "p90_error_m", *PERCENT_FIELDS, "map_points"):
        a, b = getattr(first, name), getattr(second, name)
        assert a == b or (math.isnan(a) and math.isnan(b))


def test_doors_tell_apart_when_a_drawn_method_closes_one(doorway: DemoResult) -> None:
    import dataclasses

    from sonarcarve.lab.demo.doors import doors_tell_apart

    door = doorway.doors[0]
    assert door.passable["centerline"] is False  # the doorway world: centerline closes it
    assert doors_tell_apart((door,))
    assert doors_tell_apart(())  # nothing to show: the tour's own figure stays
    all_open = dataclasses.replace(door, passable=dict.fromkeys(door.passable, True))
    assert not doors_tell_apart((all_open, all_open))
    # Closed only by a method fig. 4 does not draw (evidence carving): nothing to see there.
    only_evidence = dataclasses.replace(all_open, passable={**all_open.passable,
                                                            "evidence": False})
    assert not doors_tell_apart((only_evidence,))


def test_open_doors_bring_the_doorway_scene_for_fig_4(monkeypatch: pytest.MonkeyPatch,
                                                      tmp_path: Path) -> None:
    """When no door of the tour tells the methods apart, fig. 4 and the animation are drawn
    from a drive at the doorway world's door (the paper's Fig. 2), with fig. 4's methods."""
    from sonarcarve.lab.demo import outputs, runs

    real = runs.doors_tell_apart
    asked: list[int] = []

    def tour_open_scene_real(doors: tuple) -> bool:  # the tour's doors all open; the scene's
        asked.append(len(doors))
        return real(doors) if len(asked) > 1 else False

    monkeypatch.setattr(runs, "doors_tell_apart", tour_open_scene_real)
    steps: list[str] = []
    result = run_demo("t-junction", seed=0, methods=("centerline",), grid_resolution=None,
                      on_progress=lambda step, done, total: steps.append(step))
    scene = result.door_scene
    assert scene is not None
    assert result.door_source is scene
    assert scene.world.name == "doorway"
    assert [row.method for row in scene.methods] == ["centerline", "carve", "combined"]
    assert scene.door_scene is None  # no scene of a scene
    assert "door scene" in steps
    drawn: list[DemoResult] = []
    monkeypatch.setattr(outputs, "animation_gif", lambda r: drawn.append(r) or b"GIF")
    plot = outputs.plot_door_closeup
    monkeypatch.setattr(outputs, "plot_door_closeup", lambda r: drawn.append(r) or plot(r))
    outputs.write_demo_outputs(result, tmp_path, animation=True)
    assert drawn == [scene, scene]
    # Without the option, or on the doorway world itself, no scene.
    assert run_demo("t-junction", seed=0, methods=("centerline",), grid_resolution=None,
                    door_scene=False).door_scene is None
    assert run_demo("doorway", seed=0, methods=("centerline",),
                    grid_resolution=None).door_scene is None


def test_no_scene_when_the_doorway_door_stays_open_too(monkeypatch: pytest.MonkeyPatch) -> None:
    """With a history too short for any map to close the doorway's door (review rev6: --history
    50), the scene would show three open doors again: fig. 4 stays the tour's own."""
    from sonarcarve.lab.demo import runs

    calls: list[int] = []

    def tour_never_scene_never(doors: tuple) -> bool:  # the tour's doors, then the scene's
        calls.append(len(doors))
        return False

    monkeypatch.setattr(runs, "doors_tell_apart", tour_never_scene_never)
    result = run_demo("t-junction", seed=0, methods=("centerline",), grid_resolution=None)
    assert result.door_scene is None
    assert len(calls) == 2  # asked of the tour, then of the scene, which was dropped


def test_the_occlusion_filter_summary_is_the_filtered_evidence_map() -> None:
    # Reference: the mask computed from the readings' own origins, and the shares counted
    # from it, not through filter_map and point_origins; a part of the office tour where the
    # filter drops points, so that a summary of the unfiltered map would fail.
    from sonarcarve.filters import OCCLUSION_DEPTH, occlusion_mask

    result = run_demo("office", seed=0, max_length=40.0, grid_resolution=None,
                      door_scene=False)
    assert result.occlusion is not None
    points = result.global_maps["evidence"]
    readings = result.simulation.readings
    origin = np.column_stack([readings.x, readings.y])[points.reading_id]
    keep = occlusion_mask(points.xy, origin, points.max_error, OCCLUSION_DEPTH)
    assert 0 < keep.sum() < len(keep)
    kind = result.simulation.truth.kind
    kept = np.zeros(len(kind), dtype=bool)
    kept[points.reading_id[keep]] = True
    summary = result.occlusion
    assert (summary.method, summary.depth_m, summary.map_points) == (
        "evidence", OCCLUSION_DEPTH, int(keep.sum()))
    assert summary.spurious_removed_pct == pytest.approx(
        100.0 * np.mean(~kept[kind > EchoKind.DIRECT]))
    assert summary.true_lost_pct == pytest.approx(100.0 * np.mean(~kept[kind == EchoKind.DIRECT]))
    assert summary.spurious_removed_pct > result.summary("evidence").spurious_removed_pct
