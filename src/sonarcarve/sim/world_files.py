"""World files: the world JSON format (read and write) and ROS map_server maps (read).

- a ``.json`` file: ``{"segments": [[x1, y1, x2, y2], ...]}`` with optional keys ``name``,
  ``description``, ``tour`` (``[[x, y], ...]``) and ``openings`` (``[{"a": [x, y], "b": [x, y]},
  ...]``); metres,
- a ``.yaml``/``.yml`` ROS map_server map (``image``, ``resolution``, ``origin``,
  ``occupied_thresh``, ``negate``): the boundaries of its occupied cells become walls.

Every reader checks what it reads and fails with one line naming the file and the field.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any, NoReturn

import numpy as np
import numpy.typing as npt

from sonarcarve.io.atomic import atomic_text
from sonarcarve.io.errors import finite_number, load_json, load_yaml, shorten
from sonarcarve.sim.walls import MAX_WORLD_COORDINATE, World, WorldError, geometry_problem
from sonarcarve.typing import BoolArray, FloatArray

__all__ = [
    "MAX_MAP_PIXELS",
    "MAX_MAP_RESOLUTION",
    "read_ros_map",
    "read_world_json",
    "segments_from_occupancy",
    "write_world_json",
]

#: Most pixels of a ROS map image read as a world (a 5792 x 5792 image): the boundary tracing
#: holds several arrays of this size. Larger maps: crop or coarsen them first.
MAX_MAP_PIXELS = 2**25
#: Largest ``resolution`` of a ROS map read as a world, metres per pixel.
MAX_MAP_RESOLUTION = 100.0


# --------------------------------------------------------------------------------------------
# JSON
# --------------------------------------------------------------------------------------------

def read_world_json(path: str | Path) -> World:
    """Read a world JSON file (format in the module docstring).

    Raises
    ------
    WorldError
        Missing file, invalid JSON, missing ``segments``, wrong shapes, non-numbers or
        non-finite numbers, no walls, a wall of zero length, a tour with fewer than two distinct
        waypoints or one that leaves the walls' bounding box or runs into a wall; the message
        names the file and the field.
    """
    path = Path(path)
    data = _read_json_object(path)
    if "segments" not in data:
        _fail(path, "missing key 'segments' (a list of [x1, y1, x2, y2] walls)")
    segments = _number_array(data["segments"], (4,), "segments", "[x1, y1, x2, y2]", path)
    tour = None
    if data.get("tour") is not None:
        tour = _number_array(data["tour"], (2,), "tour", "[x, y]", path)
        if tour.shape[0] < 2:
            _fail(path, "tour needs at least 2 waypoints")
    openings = _read_openings(data.get("openings", []), path)
    name = data.get("name", path.stem)
    description = data.get("description", "")
    if not isinstance(name, str) or not isinstance(description, str):
        _fail(path, "'name' and 'description' must be strings")
    name = shorten(name, 200)
    if not segments.shape[0]:
        _fail(path, "no walls: 'segments' is empty (give [x1, y1, x2, y2] walls)")
    problem = geometry_problem(segments, tour)
    if problem is not None:
        _fail(path, problem)  # here, not in World(), so that the message names the file
    return World(segments, name, tour, openings, description)


def write_world_json(world: World, path: str | Path) -> None:
    """Write ``world`` as JSON (one wall per line), atomically; :func:`read_world_json` reads it."""
    lines = ["{", f'  "name": {json.dumps(world.name)},',
             f'  "description": {json.dumps(world.description)},']
    lines.append(f'  "segments": {_rows_json([list(map(_num, row)) for row in world.segments])},')
    if world.tour is not None:
        lines.append(f'  "tour": {_rows_json([list(map(_num, row)) for row in world.tour])},')
    openings = [{"a": list(map(_num, ab[0])), "b": list(map(_num, ab[1]))}
                for ab in world.openings]
    lines.append(f'  "openings": {_rows_json(openings)}')
    lines.append("}")
    with atomic_text(path) as handle:
        handle.write("\n".join(lines) + "\n")


def _num(value: float) -> float | int:
    # Integral coordinates print as integers, the rest with their shortest round-trip repr.
    number = float(value)
    return int(number) if number.is_integer() and abs(number) < 1e15 else number


def _rows_json(rows: list[Any]) -> str:
    if not rows:
        return "[]"
    body = ",\n    ".join(json.dumps(row) for row in rows)
    return f"[\n    {body}\n  ]"


def _read_json_object(path: Path) -> dict[str, Any]:
    data = load_json(path, WorldError)
    if not isinstance(data, dict):
        _fail(path, "top level must be an object with a 'segments' key")
    return data


def _read_openings(value: Any, path: Path) -> FloatArray:
    if not isinstance(value, list):
        _fail(path, 'openings must be a list of {"a": [x, y], "b": [x, y]} objects')
    rows = []
    for i, item in enumerate(value):
        if not isinstance(item, dict) or "a" not in item or "b" not in item:
            _fail(path, f'openings[{i}] must be an object {{"a": [x, y], "b": [x, y]}}')
        ends = _number_array([item["a"], item["b"]], (2,), f"openings[{i}]", "a, b: [x, y]",
                             path)
        rows.append(ends)
    return np.array(rows, dtype=np.float64).reshape(-1, 2, 2)


def _number_array(value: Any, row_shape: tuple[int], key: str, expected: str,
                  path: Path) -> FloatArray:
    """Validate a JSON list of fixed-length number rows; return it as float array (n, k)."""
    if not isinstance(value, list):
        _fail(path, f"{key} must be a list of {expected} rows")
    (width,) = row_shape
    for i, row in enumerate(value):
        if not isinstance(row, list) or len(row) != width:
            _fail(path, f"{key}[{i}] must be {width} numbers {expected}, got {_short(row)}")
        for j, number in enumerate(row):
            if isinstance(number, bool) or not isinstance(number, int | float):
                _fail(path, f"{key}[{i}][{j}] must be a number, got {_short(number)}")
            if finite_number(number) is None:
                _fail(path, f"{key}[{i}][{j}] must be finite, got {_short(number)}")
    return np.array(value, dtype=np.float64).reshape(-1, width)


def _short(value: Any) -> str:
    try:
        text = json.dumps(value)
    except (TypeError, ValueError):  # YAML values: dates, sets, very long integers
        text = repr(value)
    return shorten(text, 40)


def _fail(where: str | Path, what: str) -> NoReturn:
    msg = f"{where}: {what}"
    raise WorldError(msg)


# --------------------------------------------------------------------------------------------
# ROS map_server maps
# --------------------------------------------------------------------------------------------

def read_ros_map(path: str | Path) -> World:
    """Read a ROS map_server map (YAML + PGM/PNG image); occupied cells' boundaries become walls.

    Follows map_server: with ``negate: 0`` a pixel value p in [0, 255] has occupancy
    (255 - p) / 255 (``negate: 1``: p / 255), and a cell is occupied when its occupancy exceeds
    ``occupied_thresh``; ``mode: raw`` takes p itself as occupancy in percent. Image row 0 is the
    top of the map; ``origin: [x, y, yaw]`` is the pose of the lower-left corner of the image.
    Unknown and free cells are both "not occupied". Colour images are converted to grey levels.

    Raises
    ------
    WorldError
        Missing or unreadable YAML or image, missing or invalid keys.
    """
    path = Path(path)
    meta = _read_yaml(path)
    for key in ("image", "resolution", "origin"):
        if key not in meta:
            _fail(path, f"missing key {key!r}")
    resolution = _yaml_number(meta, "resolution", path)
    if not 0.0 < resolution <= MAX_MAP_RESOLUTION:
        _fail(path, f"resolution must lie in (0, {MAX_MAP_RESOLUTION:g}] metres per pixel, got "
                    f"{resolution:g}")
    origin = meta["origin"]
    if (not isinstance(origin, list) or len(origin) not in (2, 3)
            or any(finite_number(v) is None for v in origin)):
        _fail(path, f"origin must be [x, y, yaw] finite numbers, got {_short(origin)}")
    if any(abs(float(v)) > MAX_WORLD_COORDINATE for v in origin):
        _fail(path, f"origin must lie within ±{MAX_WORLD_COORDINATE:g} m (and yaw within it "
                    f"too), got {_short(origin)}")
    thresh = _yaml_number(meta, "occupied_thresh", path, 0.65)
    negate = meta.get("negate", 0)
    if negate not in (0, 1, True, False):
        _fail(path, f"negate must be 0 or 1, got {_short(negate)}")
    mode = meta.get("mode", "trinary")
    if mode not in ("trinary", "scale", "raw"):
        _fail(path, f"mode must be trinary, scale or raw, got {_short(mode)}")
    image_path = path.parent / str(meta["image"])
    pixels = _read_grey_image(image_path, path)
    if mode == "raw":
        occupied = (pixels <= 100.0) & (pixels > 100.0 * thresh)
    else:
        occupancy = pixels / 255.0 if negate else (255.0 - pixels) / 255.0
        occupied = occupancy > thresh
    yaw = float(origin[2]) if len(origin) == 3 else 0.0
    segments = segments_from_occupancy(occupied, resolution, (float(origin[0]), float(origin[1])),
                                       yaw)
    if not segments.shape[0]:
        _fail(path, f"no walls: image {image_path.name} has no occupied cells "
                    f"(occupied_thresh {thresh:g}, negate {int(negate)}, mode {mode})")
    return World(segments, path.stem, description=f"ROS map {path.name}")


def _read_grey_image(image_path: Path, path: Path) -> FloatArray:
    """Grey levels in [0, 255] of the map image, shape (rows, cols); errors name the YAML."""
    from PIL import Image, UnidentifiedImageError

    try:
        with Image.open(image_path) as image:
            width, height = image.size  # from the header: nothing decoded yet
            if width * height > MAX_MAP_PIXELS:
                _fail(path, f"image {image_path}: {width} x {height} pixels, more than the "
                            f"limit of {MAX_MAP_PIXELS:,} (MAX_MAP_PIXELS); crop or coarsen it")
            return np.asarray(image.convert("L"), dtype=np.float64)
    except FileNotFoundError:
        _fail(path, f"image {image_path}: no such file")
    except IsADirectoryError:
        _fail(path, f"image {image_path}: is a directory")
    except (OSError, UnidentifiedImageError, ValueError, Image.DecompressionBombError) as err:
        _fail(path, f"image {shorten(str(image_path), 120)}: cannot read "
                    f"({shorten(' '.join(str(err).split()), 120)})")


def _read_yaml(path: Path) -> dict[str, Any]:
    data = load_yaml(path, WorldError)
    if not isinstance(data, dict):
        _fail(path, "top level must be a mapping with image, resolution and origin")
    return data


def _yaml_number(meta: dict[str, Any], key: str, path: Path, default: float | None = None) -> float:
    value = meta.get(key, default)
    number = finite_number(value)
    if number is None:
        _fail(path, f"{key} must be a finite number, got {_short(value)}")
    return number


def segments_from_occupancy(occupied: npt.ArrayLike, resolution: float,
                            origin: tuple[float, float] = (0.0, 0.0), yaw: float = 0.0
                            ) -> FloatArray:
    """Walls along the boundary between occupied and other cells of a grid, merged into runs.

    Each unit edge between an occupied cell and a non-occupied one (or the outside of the grid)
    is a wall; edges on one grid line that follow each other are merged into one segment, so a
    map has about as many walls as its outlines have straight runs.

    Parameters
    ----------
    occupied : array-like of bool, shape (rows, cols)
        Row 0 is the *top* of the map (image convention, as in ROS map_server).
    resolution : float
        Cell side, metres.
    origin : (float, float)
        World position of the lower-left corner of the grid, metres.
    yaw : float
        Rotation of the grid about ``origin``, radians.

    Returns
    -------
    ndarray, shape (n, 4)
        Walls ``[x1, y1, x2, y2]``, metres.

    Examples
    --------
    >>> segments_from_occupancy([[False, True], [False, True]], 1.0).tolist()
    [[1.0, 2.0, 2.0, 2.0], [1.0, 0.0, 2.0, 0.0], [1.0, 0.0, 1.0, 2.0], [2.0, 0.0, 2.0, 2.0]]
    """
    occ = np.asarray(occupied, dtype=bool)
    if occ.ndim != 2:
        msg = f"occupancy grid must be 2-D, got shape {occ.shape}"
        raise WorldError(msg)
    rows, _cols = occ.shape
    padded = np.pad(occ, 1)
    # Horizontal grid line k (0 = top) separates padded rows k and k+1, over columns 0..cols-1.
    horizontal = padded[:-1, 1:-1] != padded[1:, 1:-1]
    # Vertical grid line k (0 = left) separates padded columns k and k+1, over rows 0..rows-1.
    vertical = (padded[1:-1, :-1] != padded[1:-1, 1:]).T
    line_h, start_h, stop_h = _runs(horizontal)
    line_v, start_v, stop_v = _runs(vertical)
    # Grid (column, row-from-top) corners -> metres, y up: row k from the top is at rows - k.
    xy_h = np.column_stack((start_h, rows - line_h, stop_h, rows - line_h))
    xy_v = np.column_stack((line_v, rows - start_v, line_v, rows - stop_v))
    grid = np.vstack((xy_h, xy_v)).astype(np.float64) * resolution
    c, s = math.cos(yaw), math.sin(yaw)
    out = np.empty_like(grid)
    for i in (0, 2):
        out[:, i] = origin[0] + c * grid[:, i] - s * grid[:, i + 1]
        out[:, i + 1] = origin[1] + s * grid[:, i] + c * grid[:, i + 1]
    # Vertical runs were found top-down; list them bottom-up for readability.
    vertical_rows = slice(xy_h.shape[0], None)
    out[vertical_rows] = out[vertical_rows][:, [2, 3, 0, 1]]
    return out


def _runs(edges: BoolArray) -> tuple[npt.NDArray[np.int64], ...]:
    """Maximal runs of True along each row of ``edges``: (row, first, one-past-last)."""
    padded = np.pad(edges.astype(np.int8), ((0, 0), (1, 1)))
    change = np.diff(padded, axis=1)
    row_start, start = np.nonzero(change == 1)
    _, stop = np.nonzero(change == -1)
    return row_start.astype(np.int64), start.astype(np.int64), stop.astype(np.int64)
