"""Worlds: exact ray casting and distances checked by hand, every loader, every bad file."""

from __future__ import annotations

import itertools
import json
import math
from pathlib import Path

import numpy as np
import pytest
import yaml
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from PIL import Image

from sonarcarve.sim.world import (
    World,
    WorldError,
    _first_crossing,
    builtin_worlds,
    check_seed,
    load_world,
    read_ros_map,
    read_world_json,
    segments_from_occupancy,
    write_world_json,
)

SQRT2 = math.sqrt(2.0)


def _densify(polyline: np.ndarray, step: float = 0.02) -> np.ndarray:
    pieces = []
    for a, b in itertools.pairwise(polyline):
        n = max(2, int(np.hypot(*(b - a)) / step) + 2)
        pieces.append(a + np.linspace(0.0, 1.0, n)[:, None] * (b - a))
    return np.vstack(pieces)


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


# --- JSON ---------------------------------------------------------------------------------------

def test_json_round_trip(tmp_path: Path) -> None:
    world = World(np.array([[0.0, 0.0, 10.0, 0.0], [0.1, 0.2, 0.30000000000000004, 7.0]]),
                  "mine", np.array([[1.0, 1.0], [2.5, 1.0]]),
                  np.array([[[3.0, 0.0], [4.0, 0.0]]]), "two walls")
    path = tmp_path / "w.json"
    write_world_json(world, path)
    back = load_world(path)
    np.testing.assert_array_equal(back.segments, world.segments)
    assert back.tour is not None
    np.testing.assert_array_equal(back.tour, world.tour)  # type: ignore[arg-type]
    np.testing.assert_array_equal(back.openings, world.openings)
    assert (back.name, back.description) == ("mine", "two walls")
    minimal = tmp_path / "minimal.json"
    minimal.write_text('{"segments": [[0, 0, 1, 1]]}')
    plain = load_world(str(minimal))
    assert (plain.name, plain.tour, plain.openings.shape) == ("minimal", None, (0, 2, 2))


BAD_JSON = {
    "bad_syntax": ('{"segments": [[0, 0, 1, 1]],}', "line 1, column"),
    "not_object": ("[[0, 0, 1, 1]]", "top level"),
    "missing_key": ('{"walls": []}', "missing key 'segments'"),
    "short_row": ('{"segments": [[0, 0, 1]]}', "segments[0] must be 4 numbers"),
    "not_a_list": ('{"segments": 5}', "segments must be a list"),
    "string_number": ('{"segments": [[0, 0, 1, 1], [0, "1", 2, 2]]}', "segments[1][1]"),
    "boolean": ('{"segments": [[0, true, 1, 1]]}', "segments[0][1] must be a number"),
    "nan": ('{"segments": [[0, NaN, 1, 1]]}', "must be finite"),
    "infinity": ('{"segments": [[0, 0, Infinity, 1]]}', "must be finite"),
    "tour_shape": ('{"segments": [], "tour": [[0, 0, 0]]}', "tour[0] must be 2 numbers"),
    "tour_short": ('{"segments": [], "tour": [[0, 0]]}', "at least 2 waypoints"),
    "opening": ('{"segments": [], "openings": [{"a": [0, 0]}]}', "openings[0]"),
    "opening_nan": ('{"segments": [], "openings": [{"a": [0, 0], "b": [NaN, 0]}]}', "finite"),
    "name_type": ('{"segments": [], "name": 3}', "must be strings"),
}


@pytest.mark.parametrize("case", sorted(BAD_JSON))
def test_bad_json_raises_one_line_naming_file(tmp_path: Path, case: str) -> None:
    text, expected = BAD_JSON[case]
    path = tmp_path / f"{case}.json"
    path.write_text(text)
    with pytest.raises(WorldError) as info:
        load_world(path)
    message = str(info.value)
    assert "\n" not in message
    assert str(path) in message
    assert expected in message


def test_missing_files_and_unknown_names(tmp_path: Path) -> None:
    for spec in (tmp_path / "nope.json", tmp_path / "nope.yaml"):
        with pytest.raises(WorldError, match="no such file") as info:
            load_world(spec)
        assert str(spec) in str(info.value)
    with pytest.raises(WorldError) as info:
        load_world("atlantis")
    message = str(info.value)
    assert "'atlantis'" in message
    for name in builtin_worlds():
        assert name.split(":")[0] in message
    for spec, expected in (("random:x", "seed must be an integer"),
                           ("random:1:40by30", "WIDTHxHEIGHT"), ("random:1:40xz", "WIDTHxHEIGHT"),
                           ("random:1:5x5", "size")):
        with pytest.raises(WorldError, match=expected):
            load_world(spec)


# --- built-in worlds ----------------------------------------------------------------------------

def test_builtin_worlds_listed_and_loadable() -> None:
    names = builtin_worlds()
    assert set(names) == {"t-junction", "narrow-hallway", "doorway", "office", "random:SEED"}
    assert all(text for text in names.values())
    for name in names:
        world = load_world(name.replace("SEED", "11"))
        assert len(world) > 0
        assert world.tour is not None
        assert world.openings.shape[0] >= 1


@pytest.mark.parametrize("name", ["t-junction", "narrow-hallway", "doorway", "office"])
def test_builtin_tours_keep_clear_of_walls(name: str) -> None:
    world = load_world(name)
    assert world.tour is not None
    assert world.distance_to_walls(_densify(world.tour)).min() >= 0.45 - 1e-9


@pytest.mark.parametrize("name", ["t-junction", "narrow-hallway", "doorway", "office"])
def test_builtin_openings_are_gaps_between_walls(name: str) -> None:
    world = load_world(name)
    ends = world.openings.reshape(-1, 2)
    # Both ends touch a wall; the middle is free, half the gap's width from the nearest wall.
    np.testing.assert_allclose(world.distance_to_walls(ends), 0.0, atol=1e-9)
    middles = world.openings.mean(axis=1)
    half_widths = np.linalg.norm(world.openings[:, 1] - world.openings[:, 0], axis=1) / 2
    np.testing.assert_allclose(world.distance_to_walls(middles), half_widths, atol=1e-9)


def test_builtin_copies_are_independent() -> None:
    first = load_world("doorway")
    first.segments[0, 0] = 1e6
    assert load_world("doorway").segments[0, 0] != 1e6


def test_paper_scenes_shapes() -> None:
    doorway = load_world("doorway")
    width = np.linalg.norm(doorway.openings[0, 1] - doorway.openings[0, 0])
    assert 0.8 <= width <= 0.9
    t = load_world("t-junction")
    # Corridors about 2 m wide: rays across the stem from its centre line.
    d, _ = t.cast_rays([0.0, 5.0], [0.0, np.pi])
    assert d.sum() == pytest.approx(2.0)


# --- ROS map_server maps ------------------------------------------------------------------------

def _unit_edges_of_segments(segments: np.ndarray, res: float, origin: tuple[float, float]
                            ) -> set[tuple[int, int, int, int]]:
    """Split axis-aligned segments into unit grid edges, as integer cell-corner coordinates."""
    edges = set()
    for x1, y1, x2, y2 in segments:
        a = np.round((np.array([x1, y1]) - origin) / res).astype(int)
        b = np.round((np.array([x2, y2]) - origin) / res).astype(int)
        assert a[0] == b[0] or a[1] == b[1], "walls of a grid map are axis-aligned"
        step = np.sign(b - a)
        for k in range(int(np.abs(b - a).max())):
            p, q = a + k * step, a + (k + 1) * step
            edges.add(tuple(int(v) for v in (*np.minimum(p, q), *np.maximum(p, q))))
    return edges


def _expected_unit_edges(occupied: np.ndarray) -> set[tuple[int, int, int, int]]:
    """By hand: each side of an occupied cell that borders a non-occupied cell or the outside.

    Cell (row r, column c) of an image with R rows covers x in [c, c+1] and, y pointing up,
    y in [R-1-r, R-r] (row 0 is the top of the map).
    """
    rows, cols = occupied.shape

    def occ(r: int, c: int) -> bool:
        return 0 <= r < rows and 0 <= c < cols and bool(occupied[r, c])

    edges = set()
    for r in range(rows):
        for c in range(cols):
            if not occupied[r, c]:
                continue
            bottom, top = rows - 1 - r, rows - r
            if not occ(r - 1, c):
                edges.add((c, top, c + 1, top))
            if not occ(r + 1, c):
                edges.add((c, bottom, c + 1, bottom))
            if not occ(r, c - 1):
                edges.add((c, bottom, c, top))
            if not occ(r, c + 1):
                edges.add((c + 1, bottom, c + 1, top))
    return edges


def _write_map(folder: Path, pixels: np.ndarray, image_name: str = "map.pgm",
               **meta: object) -> Path:
    Image.fromarray(pixels.astype(np.uint8), mode="L").save(folder / image_name)
    fields = {"image": image_name, "resolution": 0.05, "origin": [-1.0, 2.0, 0.0],
              "occupied_thresh": 0.65, "free_thresh": 0.196, "negate": 0}
    fields.update(meta)
    path = folder / "map.yaml"
    path.write_text(yaml.safe_dump(fields))
    return path


TINY = np.array([  # 1 = occupied; an L, a lone cell, and a block touching the image border
    [0, 0, 0, 0, 0, 1, 1],
    [0, 1, 0, 0, 0, 1, 1],
    [0, 1, 0, 0, 0, 0, 0],
    [0, 1, 1, 1, 0, 0, 1],
    [0, 0, 0, 0, 0, 0, 0],
], dtype=bool)


@pytest.mark.parametrize(("image_name", "negate"), [("map.pgm", 0), ("map.png", 1)])
def test_ros_map_walls_trace_the_occupied_cells(tmp_path: Path, image_name: str,
                                                negate: int) -> None:
    occupied_value, free_value = (0, 254) if not negate else (255, 1)
    pixels = np.where(TINY, occupied_value, free_value)
    pixels[4, 0] = 50 if negate else 205  # "unknown" grey: not occupied
    path = _write_map(tmp_path, pixels, image_name, negate=negate)
    world = load_world(path)
    origin = (-1.0, 2.0)
    assert _unit_edges_of_segments(world.segments, 0.05, origin) == _expected_unit_edges(TINY)
    # Merged runs: the L has 6 sides, the lone cell 4, the 2x2 block 4.
    assert len(world) == 14
    assert world.name == "map"
    # Row 0 (the top) ends at y = 2 + 5 x 0.05; the lowest occupied row, 3, starts one cell
    # above the origin; columns 1 to 6 are occupied.
    assert world.bounds == pytest.approx((-1.0 + 0.05, 2.0 + 0.05, -1.0 + 0.35, 2.25))


def test_ros_map_300x300_merges_into_few_walls(tmp_path: Path) -> None:
    occupied = np.zeros((300, 300), dtype=bool)
    occupied[:, :3] = occupied[:, -3:] = occupied[:3, :] = occupied[-3:, :] = True  # outer walls
    occupied[100:103, 3:200] = True       # a partition
    occupied[150:250, 150:250] = True     # a pillar
    occupied[200:203, 20:60] = True
    path = _write_map(tmp_path, np.where(occupied, 0, 254))
    world = read_ros_map(path)
    assert _unit_edges_of_segments(world.segments, 0.05, (-1.0, 2.0)) == _expected_unit_edges(
        occupied)
    assert len(world) < 50


def test_segments_from_occupancy_yaw_rotates_about_origin() -> None:
    grid = [[True]]
    plain = segments_from_occupancy(grid, 2.0, (1.0, 1.0))
    turned = segments_from_occupancy(grid, 2.0, (1.0, 1.0), yaw=np.pi / 2)
    # A quarter turn about (1, 1) maps (x, y) to (1 - (y - 1), 1 + (x - 1)).
    for seg_plain, seg_turned in zip(plain, turned, strict=True):
        for (x, y), (u, v) in zip(seg_plain.reshape(2, 2), seg_turned.reshape(2, 2), strict=True):
            assert (u, v) == pytest.approx((1 - (y - 1), 1 + (x - 1)))


def test_ros_map_bad_files(tmp_path: Path) -> None:
    good = np.full((4, 4), 254)
    path = _write_map(tmp_path, good)
    cases = {
        "image: [unclosed": "invalid YAML",
        "just text": "top level must be a mapping",
        yaml.safe_dump({"image": "map.pgm", "origin": [0, 0, 0]}): "missing key 'resolution'",
        yaml.safe_dump({"image": "map.pgm", "resolution": -1, "origin": [0, 0, 0]}):
            "resolution must be > 0",
        yaml.safe_dump({"image": "map.pgm", "resolution": ".nan", "origin": [0, 0, 0]}):
            "resolution must be a finite number",
        yaml.safe_dump({"image": "map.pgm", "resolution": 0.1, "origin": [0, "a"]}):
            "origin must be",
        yaml.safe_dump({"image": "gone.pgm", "resolution": 0.1, "origin": [0, 0, 0]}):
            "no such file",
        yaml.safe_dump({"image": "bad.pgm", "resolution": 0.1, "origin": [0, 0, 0]}):
            "cannot read",
        yaml.safe_dump({"image": "map.pgm", "resolution": 0.1, "origin": [0, 0], "mode": "x"}):
            "mode must be",
    }
    (tmp_path / "bad.pgm").write_text("not an image")
    for text, expected in cases.items():
        path.write_text(text)
        with pytest.raises(WorldError) as info:
            load_world(path)
        message = str(info.value)
        assert "\n" not in message
        assert str(path) in message
        assert expected in message, message


def test_json_written_file_is_json(tmp_path: Path) -> None:
    path = tmp_path / "t.json"
    write_world_json(load_world("t-junction"), path)
    data = json.loads(path.read_text())
    assert set(data) == {"name", "description", "segments", "tour", "openings"}
    assert read_world_json(path).segments.shape == (8, 4)


# --- seeds --------------------------------------------------------------------------------------

def test_check_seed_accepts_non_negative_integers_only() -> None:
    assert check_seed(0) == 0
    assert check_seed(np.int64(5)) == 5
    assert check_seed(2**70) == 2**70  # numpy seeds take big integers
    for bad in (-1, True, 1.5, "3", None):
        with pytest.raises(WorldError) as info:
            check_seed(bad, "the seed")
        assert str(info.value) == f"the seed must be an integer >= 0, got {bad!r}"


@pytest.mark.parametrize("spec", ["random:-1", "random:-7:40x30"])
def test_negative_random_seed_is_a_one_line_world_error(spec: str) -> None:
    with pytest.raises(WorldError) as info:
        load_world(spec)
    seed = spec.split(":")[1]
    assert str(info.value) == f"{spec}: seed must be an integer >= 0, got {seed}"


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


def test_a_ros_map_without_occupied_cells_has_no_walls(tmp_path: Path) -> None:
    path = _write_map(tmp_path, np.full((4, 4), 254))
    with pytest.raises(WorldError) as info:
        load_world(path)
    assert str(info.value) == (f"{path}: no walls: image map.pgm has no occupied cells "
                               "(occupied_thresh 0.65, negate 0, mode trinary)")


def test_generated_and_builtin_worlds_pass_their_tour_checks() -> None:
    for name in ("office", "doorway", "t-junction", "narrow-hallway", "random:3", "random:4:30x20"):
        world = load_world(name)
        assert world.tour is not None
        assert _first_crossing(world.tour, world.segments) is None
