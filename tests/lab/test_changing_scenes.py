"""Changing-scene measures on hand-made sequences of maps, and on the door scene end to end."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from sonarcarve.lab.changing_scenes import (
    Change,
    change_latency,
    grid_tolerance,
    measure_track,
    plot_changing_scene,
    run_changing_scene,
    scene_changes,
    simulate_changing_scene,
)
from sonarcarve.sim import DynamicObstacle, Scene, World
from sonarcarve.sim.sonar import SonarPhysics

# A wall along y = 0 from x = 0 to 4; a 0.5 m box against it at x = 1-1.5, removed at t = 1 s.
WALL = World(np.array([[0.0, 0.0, 4.0, 0.0]]))
BOX = DynamicObstacle.box(1.0, 0.0, 1.5, 0.5, "box", vanish=1.0)
SCENE = Scene((BOX,))
GONE = Change(0, "box gone", "gone", 1.0, 1.5, 10.0, 3.0, BOX.segments, False)
APPEARED = Change(0, "box appeared", "appeared", 0.0, 0.0, 1.0, math.nan, BOX.segments, False)

ON_WALL = [2.5, 0.02]        # explained by the wall whatever happens
BOX_FACE = [1.25, 0.52]      # on the box's top side: right while the box is there
NEAR_PLACE = [1.25, 0.7]     # 0.2 m above where the box's top was: a phantom near the place
FAR_PHANTOM = [3.0, 2.0]     # a phantom far from everything


def snapshots(*rows: list[list[float]]) -> list[np.ndarray]:
    return [np.array(r, dtype=np.float64).reshape(-1, 2) for r in rows]


def test_gone_latency_counts_from_the_reference_until_the_map_stays_right() -> None:
    times = np.array([0.5, 1.0, 1.5, 2.0, 2.5, 3.0, 3.5])
    maps = snapshots([BOX_FACE, ON_WALL],           # 0.5: box there, right
                     [BOX_FACE, ON_WALL],           # 1.0: box gone, still marked
                     [BOX_FACE],                    # 1.5: still marked (reference)
                     [ON_WALL],                     # 2.0: cleared
                     [NEAR_PLACE, ON_WALL],         # 2.5: a phantom near the place
                     [ON_WALL, FAR_PHANTOM],        # 3.0: cleared for good (far phantom ok)
                     [ON_WALL])
    track = measure_track("hand", 0.1, maps, times, WALL, SCENE, [GONE])
    # Wrong at 1.5 and 2.5, right from 3.0 on: 3.0 - 1.5 = 1.5 s.
    assert track.cleared_at.tolist() == [3.0]
    assert track.latency.tolist() == [1.5]
    # Phantoms: 0.5 s: none; 1.0: the box face (box gone) of 2 points; 1.5: 1 of 1; 2.0: 0;
    # 2.5: 1 of 2; 3.0: 1 of 2; 3.5: 0.
    np.testing.assert_allclose(track.phantom, [0.0, 0.5, 1.0, 0.0, 0.5, 0.5, 0.0])
    assert track.mean_phantom == pytest.approx(2.5 / 7)


def test_a_place_still_marked_at_the_end_was_never_cleared() -> None:
    times = np.array([1.5, 2.0, 2.5])
    maps = snapshots([ON_WALL], [ON_WALL], [NEAR_PLACE])
    track = measure_track("hand", 0.1, maps, times, WALL, SCENE, [GONE])
    assert math.isnan(track.latency[0])


def test_appeared_latency_is_the_first_snapshot_marking_it_away_from_walls() -> None:
    times = np.array([0.2, 0.4, 0.6, 0.8])
    # At 0.2 only a wall point 0.02 m from the box's corner (within 0.25 m of the box, but
    # explained by the wall: the wall does not mark the box); at 0.6 the box's face.
    maps = snapshots([[1.1, 0.02]], [], [BOX_FACE], [])
    track = measure_track("hand", 0.1, maps, times, WALL, SCENE, [APPEARED])
    assert track.cleared_at.tolist() == [0.6]
    assert track.latency.tolist() == pytest.approx([0.6])


def test_change_latency_gone_and_appeared() -> None:
    t = np.arange(0.0, 6.0)
    right = np.array([1, 1, 0, 1, 0, 1], dtype=bool)
    gone = GONE._replace(t_ref=2.0, t_end=9.0)
    assert change_latency(gone, t, right) == 5.0
    assert math.isnan(change_latency(gone, t, np.array([1, 1, 0, 1, 1, 0], dtype=bool)))
    assert change_latency(gone._replace(kind="appeared"), t, right) == 3.0
    # Right at every snapshot of the window: the first snapshot from the reference.
    assert change_latency(gone, t, np.ones(6, dtype=bool)) == 2.0


def test_door_scene_changes_and_measures() -> None:
    _, sim = simulate_changing_scene("door", 0)
    changes = scene_changes(sim)
    assert [(c.label, c.kind, c.t) for c in changes] == [("door appeared", "appeared", 3.0),
                                                          ("door gone", "gone", 9.0)]
    # The robot faces the doorway all along: the first firing of its front sensor at or after
    # the change sees it (the ring fires every 0.64 s).
    assert 3.0 <= changes[0].t_ref < 3.0 + 0.64
    assert 9.0 <= changes[1].t_ref < 9.0 + 0.64
    # Closest approach after the door opened: the robot drives through the doorway at y = 6.
    assert changes[1].t_past == pytest.approx(6.0 / 0.4, abs=0.1)
    run = run_changing_scene("door", 0, methods=("carve",), grids=("carved grid",))
    assert [t.label for t in run.tracks] == ["carve", "carved grid"]
    for track in run.tracks:
        assert track.phantom.shape == run.times.shape
        assert track.latency.shape == (2,)
    fig = plot_changing_scene(run, ["carve", "carved grid"], 1)
    assert len(fig.axes) == 5
    # The carved grid marks the shut door from the first echo the front sensor gets of it (its
    # newest echo, which nothing on the map explains): at the next 0.2 s snapshot at the
    # latest, not after several firings of the ring (0.64 s apart).
    assert run.track("carved grid").latency[0] <= 0.2


def test_a_scene_can_be_simulated_with_the_amplitude_model() -> None:
    _, sim = simulate_changing_scene("door", 0, physics=SonarPhysics(echo_model="amplitude"))
    assert sim.physics.echo_model == "amplitude"
    assert scene_changes(sim)[0].label == "door appeared"


def test_scene_changes_needs_a_scene() -> None:
    _, sim = simulate_changing_scene("door", 0)
    with pytest.raises(ValueError, match="scene"):
        scene_changes(replace(sim, scene=None))


@pytest.mark.parametrize("h", [0.05, 0.1])
def test_a_cell_beside_one_a_wall_touches_is_explained_whatever_the_rounding(h: float) -> None:
    # The box scene's grids start 0.5 m left of the wall at x = -1.2, so the wall runs along a
    # cell boundary: the cells beside the two it touches have centres 1.5 cells from it, which
    # the module docstring calls explained; the centres as the grid computes them (rounded)
    # must be, on either side, and those one cell farther out must not be.
    xmin = -1.2 - 0.5
    centres = xmin + (np.arange(round(1.0 / h)) + 0.5) * h
    dist = np.abs(centres - (-1.2))
    beside = np.isclose(dist, 1.5 * h, rtol=0.0, atol=1e-12)
    farther = np.isclose(dist, 2.5 * h, rtol=0.0, atol=1e-12)
    assert beside.sum() == 2
    assert farther.sum() == 2
    assert np.all(dist[beside] <= grid_tolerance(h))
    assert np.all(dist[farther] > grid_tolerance(h))
