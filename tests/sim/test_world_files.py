"""World files: JSON round trips and every bad file, ROS map_server maps."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import yaml
from PIL import Image

from sonarcarve.sim.walls import World, WorldError
from sonarcarve.sim.world import load_world
from sonarcarve.sim.world_files import (
    read_ros_map,
    read_world_json,
    segments_from_occupancy,
    write_world_json,
)

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
            "resolution must lie in (0, 100] metres per pixel, got -1",
        yaml.safe_dump({"image": "map.pgm", "resolution": 1e300, "origin": [0, 0, 0]}):
            "resolution must lie in (0, 100] metres per pixel, got 1e+300",
        yaml.safe_dump({"image": "map.pgm", "resolution": 0.1, "origin": [1e300, 0, 0]}):
            "origin must lie within ±100000 m",
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


def test_a_ros_map_without_occupied_cells_has_no_walls(tmp_path: Path) -> None:
    path = _write_map(tmp_path, np.full((4, 4), 254))
    with pytest.raises(WorldError) as info:
        load_world(path)
    assert str(info.value) == (f"{path}: no walls: image map.pgm has no occupied cells "
                               "(occupied_thresh 0.65, negate 0, mode trinary)")




def test_world_json_with_absurd_coordinates_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "w.json"
    path.write_text('{"segments": [[0, 0, 1e300, 1e300], [0, 1, 1, 1]]}')
    with pytest.raises(WorldError) as info:
        load_world(path)
    assert str(info.value) == (f"{path}: segments[0] [0, 0, 1e+300, 1e+300] lies beyond "
                               "±100000 m (MAX_WORLD_COORDINATE) from the origin in x or y")


def test_world_json_yaml_bomb_and_size_cap(tmp_path: Path) -> None:
    bomb = tmp_path / "map.yaml"
    levels = "".join(f"{k}: &{k} [{', '.join([f'*{p}'] * 9)}]\n"
                     for p, k in zip("abcdefgh", "bcdefghi", strict=True))
    bomb.write_text("a: &a [1, 1, 1, 1, 1, 1, 1, 1, 1]\n" + levels + "image: *i\n")
    with pytest.raises(WorldError, match=r"aliases expand to more than 100,000 nodes\)$"):
        load_world(bomb)
    big = tmp_path / "big.json"
    with big.open("w") as handle:
        handle.write('{"segments": [' + "[0, 0, 1, 1], " * 1_200_000 + "[0, 0, 1, 1]]}")
    with pytest.raises(WorldError, match="larger than the limit of 16,777,216 bytes"):
        load_world(big)


# One occupied pixel, top-left, in a 3 x 3 image at 1 m per pixel and origin (0, 0): its walls
# are the square x in [0, 1], y in [2, 3] (image row 0 is the top of the map).
TOP_LEFT_CELL = (0.0, 2.0, 1.0, 3.0)


def _one_cell_map(tmp_path: Path, corner: int, rest: list[int], **meta: object) -> World:
    """A 3 x 3 map whose top-left pixel is ``corner`` and whose other pixels cycle ``rest``."""
    pixels = np.resize(np.array(rest), 9).reshape(3, 3)
    pixels[0, 0] = corner
    fields = {"resolution": 1.0, "origin": [0.0, 0.0, 0.0], **meta}
    return read_ros_map(_write_map(tmp_path, pixels, **fields))


def test_ros_map_occupancy_equal_to_occupied_thresh_is_not_occupied(tmp_path: Path) -> None:
    # map_server: occupied when occupancy > occupied_thresh. Pixel 51 is (255 - 51) / 255 = 0.8
    # exactly, pixel 50 is 0.804: with occupied_thresh 0.8 only the 50 is a wall.
    world = _one_cell_map(tmp_path, 50, [51], occupied_thresh=0.8)
    assert (len(world), world.bounds) == (4, TOP_LEFT_CELL)


def test_ros_map_without_occupied_thresh_takes_map_server_s_065(tmp_path: Path) -> None:
    # Pixel 76 is 0.702 occupied (> 0.65), pixel 102 is 0.6 (not, though it is > 0.5).
    fields = {"resolution": 1.0, "origin": [0.0, 0.0, 0.0]}
    path = _write_map(tmp_path, np.array([[76, 102, 102], [102, 254, 254], [102, 254, 254]]),
                      **fields)
    meta = yaml.safe_load(path.read_text())
    del meta["occupied_thresh"]
    path.write_text(yaml.safe_dump(meta))
    world = read_ros_map(path)
    assert (len(world), world.bounds) == (4, TOP_LEFT_CELL)


def test_ros_map_raw_mode_reads_pixels_as_percent_and_255_as_unknown(tmp_path: Path) -> None:
    # mode raw: the pixel is the occupancy in percent; 80 > 65 is occupied, 255 (-1 as int8:
    # unknown) and 10 are not.
    world = _one_cell_map(tmp_path, 80, [255, 10], mode="raw")
    assert (len(world), world.bounds) == (4, TOP_LEFT_CELL)


def test_ros_map_origin_yaw_turns_the_map_about_the_origin(tmp_path: Path) -> None:
    # Yaw +90 degrees: (x, y) -> (-y, x); the cell [0, 1] x [2, 3] goes to [-3, -2] x [0, 1].
    world = _one_cell_map(tmp_path, 0, [254], origin=[0.0, 0.0, float(np.pi / 2)])
    assert len(world) == 4
    assert world.bounds == pytest.approx((-3.0, 0.0, -2.0, 1.0), abs=1e-12)


def test_ros_map_negate_must_be_0_or_1(tmp_path: Path) -> None:
    with pytest.raises(WorldError, match="negate must be 0 or 1, got 2"):
        _one_cell_map(tmp_path, 0, [254], negate=2)
