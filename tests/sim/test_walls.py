"""The world itself: exact ray casting and distances checked by hand, the value's checks,
seeds, and walls and tour that must make sense together."""

from __future__ import annotations

import itertools
import json
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from sonarcarve.sim.walls import World, WorldError, _first_crossing, check_seed
from sonarcarve.sim.world import load_world

SQRT2 = math.sqrt(2.0)


# --- ray casting ------------------------------------------------------------------------------

def test_ray_hits_perpendicular_wall_at_its_distance() -> None:
    world = World(np.array([[2.0, -1.0, 2.0, 1.0]]))
    distance, wall = world.cast_rays([0.0, 0.0], [0.0])
    assert distance.tolist() == [2.0]
    assert wall.tolist() == [0]


def test_ray_against_wall_at_45_degrees() -> None:
    # The wall lies on y = x - 2 for x in [1, 3].
    world = World(np.array([[1.0, -1.0, 3.0, 1.0]]))
    origins = np.array([[0.0, 0.0], [2.0, -3.0], [0.0, 0.0], [0.0, 0.0]])
    angles = np.array([0.0, np.pi / 2, np.pi / 4, np.pi / 2])
    distance, wall = world.cast_rays(origins, angles)
    # +x meets the line at (2, 0); up from (2, -3) also at (2, 0); the 45° ray is parallel;
    # straight up from the origin meets the line's extension at (0, -2)... below, so misses.
    np.testing.assert_allclose(distance[:2], [2.0, 3.0])
    assert np.isinf(distance[2:]).all()
    assert wall.tolist() == [0, 0, -1, -1]


def test_ray_through_a_wall_end_point_hits_it() -> None:
    world = World(np.array([[1.0, -1.0, 1.0, 1.0]]))
    distance, wall = world.cast_rays([0.0, 0.0], [np.pi / 4, -np.pi / 4, np.pi / 4 + 1e-3])
    np.testing.assert_allclose(distance[:2], [SQRT2, SQRT2])
    assert wall.tolist()[:2] == [0, 0]
    assert np.isinf(distance[2])  # just past the end: miss


def test_ray_parallel_to_a_wall_never_hits_it() -> None:
    world = World(np.array([[1.0, 0.0, 3.0, 0.0], [1.0, 1.0, 3.0, 1.0]]))
    distance, wall = world.cast_rays([0.0, 0.0], [0.0])
    assert np.isinf(distance[0])
    assert wall[0] == -1


def test_nothing_hit_empty_world_and_behind() -> None:
    empty = World(np.zeros((0, 4)))
    distance, wall = empty.cast_rays([[0.0, 0.0], [1.0, 1.0]], [0.0, 1.0])
    assert np.isinf(distance).all()
    assert wall.tolist() == [-1, -1]
    world = World(np.array([[2.0, -1.0, 2.0, 1.0]]))
    distance, wall = world.cast_rays([0.0, 0.0], [np.pi, np.pi / 2])
    assert np.isinf(distance).all()
    assert wall.tolist() == [-1, -1]


def test_nearest_of_several_walls_and_max_range() -> None:
    world = World(np.array([[3.0, -1.0, 3.0, 1.0], [2.0, -1.0, 2.0, 1.0], [5.0, -1, 5.0, 1.0]]))
    distance, wall = world.cast_rays([0.0, 0.0], [0.0])
    assert (distance[0], wall[0]) == (2.0, 1)
    distance, wall = world.cast_rays([0.0, 0.0], [0.0], max_range=1.5)
    assert np.isinf(distance[0])
    assert wall[0] == -1


def test_cast_rays_chunks_agree_with_one_by_one() -> None:
    rng = np.random.default_rng(0)
    world = World(rng.uniform(-5, 5, (300, 4)))
    origins = rng.uniform(-5, 5, (4000, 2))  # 1.2 M pairs: several chunks
    angles = rng.uniform(-np.pi, np.pi, 4000)
    distance, wall = world.cast_rays(origins, angles)
    for i in range(0, 4000, 397):
        d1, w1 = world.cast_rays(origins[i], angles[i:i + 1])
        assert (d1[0], w1[0]) == (distance[i], wall[i])


coordinate = st.floats(-10.0, 10.0, allow_nan=False)


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(coordinate, coordinate, coordinate, coordinate), min_size=1,
                max_size=6),
       st.tuples(coordinate, coordinate), st.floats(-np.pi, np.pi))
def test_cast_rays_matches_shapely(walls: list[tuple[float, ...]], origin: tuple[float, float],
                                   angle: float) -> None:
    shapely = pytest.importorskip("shapely")
    segments = np.array(walls)
    lengths = np.hypot(segments[:, 2] - segments[:, 0], segments[:, 3] - segments[:, 1])
    segments = segments[lengths > 1e-3]
    # Grazing a wall's end point within rounding is a coin toss for both sides: skip those.
    direction = np.array([math.cos(angle), math.sin(angle)])
    ends = segments.reshape(-1, 2) - origin
    assume(np.all(np.abs(ends @ np.array([-direction[1], direction[0]])) > 1e-6))
    world = World(segments)
    distance, _ = world.cast_rays(origin, [angle])
    far = 100.0
    ray = shapely.LineString([origin, (origin[0] + far * math.cos(angle),
                                       origin[1] + far * math.sin(angle))])
    best = math.inf
    for seg in segments:
        wall = shapely.LineString([seg[:2], seg[2:]])
        hit = ray.intersection(wall)
        if hit.is_empty or hit.geom_type != "Point":
            continue  # parallel overlaps are documented as misses
        d = math.hypot(hit.x - origin[0], hit.y - origin[1])
        if d > 1e-6:
            best = min(best, d)
    if math.isinf(best):
        assert math.isinf(distance[0]) or distance[0] < 1e-6 or distance[0] > far * 0.99
    else:
        assert distance[0] == pytest.approx(best, abs=1e-6)


# --- distance to walls --------------------------------------------------------------------------

def test_distance_to_walls_by_hand() -> None:
    world = World(np.array([[1.0, -1.0, 1.0, 1.0]]))
    points = [[0.0, 0.0], [0.0, 2.0], [1.0, 0.5], [3.0, -4.0]]
    # perpendicular foot; nearest end (1, 1); on the wall; nearest end (1, -1).
    np.testing.assert_allclose(world.distance_to_walls(points),
                               [1.0, SQRT2, 0.0, math.hypot(2.0, 3.0)])
    diagonal = World(np.array([[0.0, 2.0, 2.0, 0.0]]))
    np.testing.assert_allclose(diagonal.distance_to_walls([0.0, 0.0]), [SQRT2])
    two = World(np.array([[1.0, -1.0, 1.0, 1.0], [-0.5, -1.0, -0.5, 1.0]]))
    np.testing.assert_allclose(two.distance_to_walls([0.0, 0.0]), [0.5])
    assert np.isinf(World(np.zeros((0, 4))).distance_to_walls([0.0, 0.0])).all()


# --- World value -------------------------------------------------------------------------------

def test_world_keeps_two_argument_construction_and_validates_annotations() -> None:
    world = World(np.array([[0.0, 0.0, 4.0, 0.0], [0.0, 0.0, 0.0, 3.0]]), "l")
    assert world.name == "l"
    assert world.tour is None
    assert world.openings.shape == (0, 2, 2)
    assert world.size == (4.0, 3.0)
    assert world.area == 12.0
    assert world.start_pose is None
    with pytest.raises(WorldError, match="tour"):
        World(world.segments, "l", tour=np.zeros((1, 2)))
    with pytest.raises(WorldError, match="openings"):
        World(world.segments, "l", openings=np.zeros((2, 3)))
    with pytest.raises(WorldError, match="finite"):
        World(np.array([[0.0, 0.0, np.nan, 1.0]]), "l")
    toured = World(world.segments, "l", tour=np.array([[1.0, 1.0], [1.0, 1.0], [1.0, 2.0]]))
    assert toured.start_pose == (1.0, 1.0, pytest.approx(np.pi / 2))
    assert toured.tour_length == 1.0


# --- seeds --------------------------------------------------------------------------------------

def test_check_seed_accepts_non_negative_integers_only() -> None:
    assert check_seed(0) == 0
    assert check_seed(np.int64(5)) == 5
    assert check_seed(2**70) == 2**70  # numpy seeds take big integers
    for bad in (-1, True, 1.5, "3", None):
        with pytest.raises(WorldError) as info:
            check_seed(bad, "the seed")
        assert str(info.value) == f"the seed must be an integer >= 0, got {bad!r}"


# --- walls and tour must make sense together ---------------------------------------------------

_BOX = [[0, 0, 10, 0], [10, 0, 10, 6], [10, 6, 0, 6], [0, 6, 0, 0]]
_INNER = [4, 0, 4, 4]  # segments[4]: a wall from the bottom up to y = 4, at x = 4


@pytest.mark.parametrize(
    ("world", "expected"),
    [
        ({"segments": []}, "no walls: 'segments' is empty (give [x1, y1, x2, y2] walls)"),
        ({"segments": [*_BOX, [3, 3, 3, 3]]},
         "segments[4] is a wall of zero length (both ends at (3, 3))"),
        ({"segments": _BOX, "tour": [[1, 1], [1, 1.0], [1, 1]]},
         "tour needs at least 2 distinct waypoints, all 3 are (1, 1)"),
        ({"segments": _BOX, "tour": [[1, 1], [5, 1], [5, 7.5]]},
         "tour[2] (5, 7.5) lies outside the walls' bounding box x in [0, 10], y in [0, 6]"),
        # Leg 1 runs along y = 2 from x = 2 to 8: it crosses x = 4, below the wall's top (y = 4).
        ({"segments": [*_BOX, _INNER], "tour": [[2, 5], [2, 2], [8, 2]]},
         "tour leg 1 (tour[1] -> tour[2]) runs into wall segments[4] at (4, 2)"),
    ],
)
def test_world_json_geometry_problems_name_file_and_key(tmp_path: Path, world: dict[str, object],
                                                       expected: str) -> None:
    path = tmp_path / "w.json"
    path.write_text(json.dumps(world))
    with pytest.raises(WorldError) as info:
        load_world(path)
    assert str(info.value) == f"{path}: {expected}"


def _boxed(folder: Path, tour: list[list[float]]) -> Path:
    """A world file: the box with the inner wall (segments[4]) and the given tour."""
    path = folder / "box.json"
    path.write_text(json.dumps({"segments": [*_BOX, _INNER], "tour": tour}))
    return path


def test_world_value_checks_walls_and_tour_points_but_not_tour_against_walls() -> None:
    with pytest.raises(WorldError, match=r"^box: segments\[1\] is a wall of zero length"):
        World(np.array([[0.0, 0.0, 1.0, 0.0], [2.0, 2.0, 2.0, 2.0]]), "box")
    with pytest.raises(WorldError, match=r"^box: tour needs at least 2 distinct waypoints"):
        World(np.array(_BOX, dtype=float), "box", tour=np.array([[1.0, 1.0], [1.0, 1.0]]))
    # A world of some of another's walls keeps the whole tour (the sonar simulator does this).
    part = World(np.array([_INNER], dtype=float), "part", tour=np.array([[2.0, 1.0], [8.0, 1.0]]))
    assert part.tour is not None


def test_tour_crossing_is_found_in_tour_order(tmp_path: Path) -> None:
    path = _boxed(tmp_path, [[2, 5], [8, 5], [8, 1], [1, 1]])
    with pytest.raises(WorldError) as info:
        load_world(path)
    # Leg 2 goes left along y = 1 from x = 8 and meets x = 4 first.
    assert str(info.value) == (f"{path}: tour leg 2 (tour[2] -> tour[3]) runs into wall "
                               "segments[4] at (4, 1)")
    # Clear of the inner wall: over its top (y = 5 > 4) and down the far side.
    ok = load_world(_boxed(tmp_path, [[2, 1], [2, 5], [8, 5], [8, 1]]))
    assert ok.tour_length == pytest.approx(4.0 + 6.0 + 4.0)


@pytest.mark.parametrize(
    ("tour", "leg", "point"),
    [
        ([[1, 5], [4, 5], [4, 4.5], [4, 4]], 2, (4, 4)),      # ends exactly on the wall's end
        ([[1, 5], [4, 5], [4, 4.5], [4, 3], [5, 3]], 2, (4, 4)),  # runs down along the wall
        ([[5, 1], [5, 2], [4, 2]], 1, (4, 2)),                # stops exactly on the wall
        ([[4, 5], [4, 3]], 0, (4, 4)),                        # from above, onto the wall
        ([[4, 2], [5, 2]], 0, (4, 2)),                        # starts on the wall
    ],
)
def test_touching_a_wall_counts_as_running_into_it(tmp_path: Path, tour: list[list[float]],
                                                   leg: int, point: tuple[float, float]) -> None:
    path = _boxed(tmp_path, tour)
    with pytest.raises(WorldError) as info:
        load_world(path)
    assert str(info.value) == (f"{path}: tour leg {leg} (tour[{leg}] -> tour[{leg + 1}]) runs "
                               f"into wall segments[4] at ({point[0]:g}, {point[1]:g})")


@pytest.mark.parametrize(
    "tour",
    [
        [[4, 4.5], [4, 5.5]],          # on the wall's line, beyond its top end
        [[3.5, 1], [3.5, 5], [3.999, 5]],  # parallel to it, 0.5 m and then 1 mm off
        [[3, 5], [5, 5], [5, 4.5], [5, 4.5], [5, 1]],  # a repeated waypoint, clear of walls
        [[0.5, 0.5], [0.5, 5.5]],      # inside the box, 0.5 m from its wall
    ],
)
def test_tours_that_keep_off_the_walls_are_accepted(tmp_path: Path,
                                                    tour: list[list[float]]) -> None:
    world = load_world(_boxed(tmp_path, tour))
    np.testing.assert_array_equal(world.tour, tour)  # type: ignore[arg-type]


small = st.integers(-4, 4)


@settings(max_examples=150, deadline=None)
@given(st.lists(st.tuples(small, small, small, small), min_size=1, max_size=5),
       st.lists(st.tuples(small, small), min_size=2, max_size=5))
def test_first_crossing_matches_shapely(walls: list[tuple[int, ...]],
                                        tour: list[tuple[int, int]]) -> None:
    """On an integer grid touching is exact, so the 1e-9 m tolerance plays no part."""
    shapely = pytest.importorskip("shapely")
    segments = np.array([w for w in walls if w[:2] != w[2:]], dtype=float).reshape(-1, 4)
    assume(segments.shape[0] > 0)
    points = np.array(tour, dtype=float)
    found = _first_crossing(points, segments)
    lines = [shapely.LineString([s[:2], s[2:]]) for s in segments]
    expected = None
    for leg, (a, b) in enumerate(itertools.pairwise(points)):
        piece = shapely.LineString([a, b]) if np.any(a != b) else shapely.Point(a)
        hits = [line.intersection(piece) for line in lines]
        starts = [min(math.hypot(x - a[0], y - a[1]) for x, y in _coords(hit))
                  for hit in hits if not hit.is_empty]
        if starts:
            expected = (leg, min(starts))
            break
    if expected is None:
        assert found is None
        return
    assert found is not None
    leg, wall, (x, y) = found
    assert leg == expected[0]
    assert math.hypot(x - points[leg, 0], y - points[leg, 1]) == pytest.approx(expected[1],
                                                                             abs=1e-9)
    assert lines[wall].distance(shapely.Point(x, y)) <= 1e-9


def _coords(geometry: object) -> list[tuple[float, float]]:
    parts = getattr(geometry, "geoms", [geometry])
    return [xy for part in parts for xy in part.coords]  # type: ignore[attr-defined]


def test_generated_and_builtin_worlds_pass_their_tour_checks() -> None:
    for name in ("office", "doorway", "t-junction", "narrow-hallway", "random:3", "random:4:30x20"):
        world = load_world(name)
        assert world.tour is not None
        assert _first_crossing(world.tour, world.segments) is None
