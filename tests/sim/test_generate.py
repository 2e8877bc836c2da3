"""World generators: determinism, clearance of tours, reachability of rooms, parametric scenes."""

from __future__ import annotations

import itertools
import math
from pathlib import Path

import numpy as np
import pytest
from scipy import ndimage

from sonarcarve.sim.generate import (
    BUILTIN_RECIPES,
    corridor_opening_world,
    doorway_world,
    narrow_hallway_world,
    random_world,
    t_junction_world,
    write_builtin_worlds,
)
from sonarcarve.sim.motion import follow_waypoints
from sonarcarve.sim.world import World, WorldError, load_world, read_world_json


def _densify(polyline: np.ndarray, step: float = 0.02) -> np.ndarray:
    pieces = []
    for a, b in itertools.pairwise(polyline):
        n = max(2, int(np.hypot(*(b - a)) / step) + 2)
        pieces.append(a + np.linspace(0.0, 1.0, n)[:, None] * (b - a))
    return np.vstack(pieces)


def _doors_passed(tour: np.ndarray, openings: np.ndarray) -> int:
    """How many openings the tour goes through the middle of (within 5 cm)."""
    path = _densify(tour, 0.01)
    middles = openings.mean(axis=1)
    near = np.hypot(path[:, None, 0] - middles[None, :, 0], path[:, None, 1] - middles[None, :, 1])
    return int(np.sum(near.min(axis=0) < 0.05))


def _reachable_from(world: World, start: np.ndarray, points: np.ndarray,
                    keep: float = 0.3, res: float = 0.125) -> np.ndarray:
    """Flood fill of the places with >= ``keep`` clearance; which ``points`` share start's area."""
    xmin, ymin, xmax, ymax = world.bounds
    xs = np.arange(xmin + res / 2, xmax, res)
    ys = np.arange(ymin + res / 2, ymax, res)
    gx, gy = np.meshgrid(xs, ys)
    free = (world.distance_to_walls(np.column_stack((gx.ravel(), gy.ravel())))
            >= keep).reshape(gx.shape)
    labels, _ = ndimage.label(free, structure=np.ones((3, 3)))

    def label_of(p: np.ndarray) -> int:
        col, row = int((p[0] - xmin) // res), int((p[1] - ymin) // res)
        return int(labels[row, col])

    home = label_of(start)
    assert home > 0
    return np.array([label_of(p) == home for p in points])


@pytest.mark.parametrize(("seed", "size"), [(0, (60.0, 40.0)), (1, (20.0, 15.0)),
                                            (2, (12.0, 30.0)), (3, (10.0, 10.0))])
def test_random_world_deterministic_per_seed(seed: int, size: tuple[float, float]) -> None:
    first, again = random_world(seed, *size), random_world(seed, *size)
    np.testing.assert_array_equal(first.segments, again.segments)
    np.testing.assert_array_equal(first.openings, again.openings)
    np.testing.assert_array_equal(first.tour, again.tour)  # type: ignore[arg-type]
    other = random_world(seed + 100, *size)
    assert (other.segments.shape != first.segments.shape
            or not np.array_equal(other.segments, first.segments))
    assert first.bounds == (0.0, 0.0, *size)


@pytest.mark.parametrize(("seed", "size"), [(4, (60.0, 40.0)), (5, (30.0, 22.0)),
                                            (6, (14.0, 36.0))])
def test_random_world_tour_is_clear_and_every_door_leads_somewhere(
        seed: int, size: tuple[float, float]) -> None:
    world = random_world(seed, *size)
    assert world.tour is not None
    assert world.distance_to_walls(_densify(world.tour)).min() >= 0.45 - 1e-9
    # Each door is a real 1 m gap between two walls ...
    middles = world.openings.mean(axis=1)
    np.testing.assert_allclose(np.linalg.norm(world.openings[:, 1] - world.openings[:, 0],
                                              axis=1), 1.0)
    np.testing.assert_allclose(world.distance_to_walls(middles), 0.5, atol=1e-9)
    # ... and both of its sides are reachable from the tour's start, so every room is.
    along = world.openings[:, 1] - world.openings[:, 0]
    normal = np.column_stack((-along[:, 1], along[:, 0]))
    sides = np.vstack((middles + 0.6 * normal, middles - 0.6 * normal))
    assert _reachable_from(world, world.tour[0], sides).all()
    assert _doors_passed(world.tour, world.openings) >= 2  # the tour enters rooms


def test_random_world_rejects_bad_sizes() -> None:
    for size in ((5.0, 40.0), (40.0, 2000.0), (math.nan, 20.0)):
        with pytest.raises(WorldError, match="size"):
            random_world(0, *size)


def test_office_is_a_big_floor_with_a_long_clear_tour_through_rooms() -> None:
    office = load_world("office")
    assert office.area >= 5000.0
    assert office.tour is not None
    assert office.distance_to_walls(_densify(office.tour, 0.05)).min() >= 0.4
    minutes = follow_waypoints(office.tour, speed=0.4).duration / 60.0
    assert 5.0 <= minutes <= 15.0
    assert _doors_passed(office.tour, office.openings) >= 3


def test_builtin_files_are_what_the_recipes_make(tmp_path: Path) -> None:
    written = write_builtin_worlds(tmp_path)
    assert {path.stem for path in written} == set(BUILTIN_RECIPES)
    for path in written:
        fresh, shipped = read_world_json(path), load_world(path.stem)
        np.testing.assert_array_equal(fresh.segments, shipped.segments)
        np.testing.assert_array_equal(fresh.tour, shipped.tour)  # type: ignore[arg-type]
        np.testing.assert_array_equal(fresh.openings, shipped.openings)
        assert fresh.description == shipped.description


@pytest.mark.parametrize("door_width", [0.7, 0.85, 1.2])
def test_doorway_world_geometry(door_width: float) -> None:
    world = doorway_world(door_width, distance=4.0, stop=1.0, far_depth=4.0)
    (a, b), = world.openings
    assert np.linalg.norm(b - a) == pytest.approx(door_width)
    assert world.tour is not None
    np.testing.assert_allclose(world.tour, [[0.0, 0.0], [0.0, 3.0]])
    # Straight ahead through the door's middle a ray reaches the far room's wall at 4 + 4 m;
    # just beside the jamb it stops at the door's wall 4 m away.
    d, _ = world.cast_rays([[0.0, 0.0], [door_width / 2 + 0.01, 0.0]], [np.pi / 2, np.pi / 2])
    np.testing.assert_allclose(d, [8.0, 4.0])


@pytest.mark.parametrize("opening_width", [0.6, 1.0, 2.0])
def test_corridor_opening_world_geometry(opening_width: float) -> None:
    world = corridor_opening_world(opening_width, corridor_width=2.0, length=14.0,
                                   opening_at=7.0, side_depth=3.0)
    (a, b), = world.openings
    assert np.linalg.norm(b - a) == pytest.approx(opening_width)
    assert world.tour is not None
    assert world.tour.shape == (2, 2)
    assert np.all(world.tour[:, 0] == 0.0)  # straight along the centre line
    assert world.distance_to_walls(_densify(world.tour)).min() == pytest.approx(1.0)
    # Sideways at the opening a ray crosses into the side room (far wall at 1 + 3 m);
    # just past the opening it meets the corridor wall 1 m away.
    origins = [[0.0, 7.0], [0.0, 7.0 + opening_width / 2 + 0.01]]
    d, _ = world.cast_rays(origins, [0.0, 0.0])
    np.testing.assert_allclose(d, [4.0, 1.0])


def test_t_junction_and_narrow_hallway_parameters() -> None:
    t = t_junction_world(corridor_width=3.0, stem_length=10.0, arm_length=9.0)
    d, _ = t.cast_rays([[0.0, 5.0], [0.0, 5.0]], [0.0, np.pi / 2])
    np.testing.assert_allclose(d, [1.5, 8.0])  # half the stem; up to the far wall at y = 13
    narrow = narrow_hallway_world(corridor_width=2.0, narrow_width=1.1)
    (_, _), (a, b) = narrow.openings
    assert np.linalg.norm(b - a) == pytest.approx(1.1)
    with pytest.raises(WorldError):
        narrow_hallway_world(narrow_width=0.5)
    with pytest.raises(WorldError):
        doorway_world(door_width=9.0)
    with pytest.raises(WorldError):
        corridor_opening_world(opening_width=20.0)


def test_random_world_refuses_a_negative_seed() -> None:
    with pytest.raises(WorldError) as info:
        random_world(-2)
    assert str(info.value) == "seed must be an integer >= 0, got -2"
