"""Waypoint files: the path a simulated robot follows (``sonarcarve simulate --path FILE``).

Two formats, told apart by the file name's suffix; coordinates in metres, world frame:

- **CSV** (``.csv``): a header naming at least the columns ``x`` and ``y`` (others are ignored),
  then one waypoint per row. Blank lines and lines starting with ``#`` are skipped::

      x,y
      1.0,1.0
      6.5,1.0
      6.5,4.0

- **JSON** (``.json``): ``{"waypoints": [[x, y], ...]}`` or just ``[[x, y], ...]``.

A path needs at least two distinct waypoints; the robot drives through them in order. Every
coordinate must be finite and within :data:`~sonarcarve.sim.motion.MAX_COORDINATE` (100 km) of
the origin.
"""

from __future__ import annotations

import csv
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from sonarcarve.io.errors import (
    MAX_CONFIG_BYTES,
    InputError,
    finite_number,
    parse_json,
    parse_number,
    read_text,
    shorten,
)
from sonarcarve.sim.motion import MAX_COORDINATE
from sonarcarve.sim.walls import World, first_wall_crossing

__all__ = ["check_path_in_world", "read_waypoint_places", "read_waypoints"]

#: Waypoints closer than this, metres, are the same point (as in ``follow_waypoints``).
_SAME_POINT = 1e-9


def read_waypoints(path: str | Path) -> npt.NDArray[np.float64]:
    """Waypoints from a CSV or JSON file, shape (k, 2), metres.

    Raises
    ------
    InputError
        One line naming the file and the place (line, column or entry) of the first problem.
    """
    return read_waypoint_places(path)[0]


def read_waypoint_places(path: str | Path) -> tuple[npt.NDArray[np.float64], list[str]]:
    """:func:`read_waypoints`, with where each waypoint is in the file: ``"line 3"`` (CSV) or
    ``"waypoint 2"`` (JSON, from 0), for messages about a waypoint."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in {".csv", ".json"}:
        msg = f"{path}: waypoint files must end in .csv (header x,y) or .json ([[x, y], ...])"
        raise InputError(msg)
    text = read_text(path, InputError, MAX_CONFIG_BYTES)
    if suffix == ".csv":
        points, places = _from_csv(path, text)
    else:
        points = _from_json(path, text)
        places = [f"waypoint {i}" for i in range(points.shape[0])]
    if points.shape[0] < 2:
        msg = f"{path}: a path needs at least 2 waypoints, found {points.shape[0]}"
        raise InputError(msg)
    if not np.any(np.hypot(*(points[1:] - points[0]).T) > _SAME_POINT):
        x, y = points[0]
        msg = (f"{path}: a path needs at least 2 distinct waypoints, all {points.shape[0]} are "
               f"({x:g}, {y:g})")
        raise InputError(msg)
    return points, places


def check_path_in_world(points: npt.NDArray[np.float64], places: list[str], world: World,
                        path: str | Path) -> None:
    """Refuse a path the robot could not drive in ``world``: a waypoint outside the walls'
    bounding box, or a leg that meets a wall (the rule the worlds' own tours obey,
    :func:`~sonarcarve.sim.walls.geometry_problem`); the error names the waypoint's place.

    Refused rather than warned about: a robot driven through a wall or outside the building
    records readings no robot could (echoes from inside a wall, kilometres of floor echoes).
    A world with no walls accepts any path.
    """
    if not len(world):
        return
    xmin, ymin, xmax, ymax = world.bounds
    for (x, y), place in zip(points, places, strict=True):
        if not (xmin - _SAME_POINT <= x <= xmax + _SAME_POINT
                and ymin - _SAME_POINT <= y <= ymax + _SAME_POINT):
            msg = (f"{path}: {place}, waypoint ({x:g}, {y:g}) lies outside world "
                   f"{world.name!r} (x in [{xmin:g}, {xmax:g}], y in [{ymin:g}, {ymax:g}])")
            raise InputError(msg)
    crossing = first_wall_crossing(points, world.segments)
    if crossing is not None:
        leg, (x, y) = crossing
        msg = (f"{path}: {places[leg]}, the leg to the next waypoint ({places[leg + 1]}) runs "
               f"into a wall of world {world.name!r} at ({x:g}, {y:g})")
        raise InputError(msg)


def _from_csv(path: Path, text: str) -> tuple[npt.NDArray[np.float64], list[str]]:
    rows = [(number, row) for number, row in enumerate(csv.reader(text.splitlines()), start=1)
            if row and any(cell.strip() for cell in row) and not row[0].lstrip().startswith("#")]
    if not rows:
        msg = f"{path}: empty file, expected a header x,y and one waypoint per line"
        raise InputError(msg)
    header_line, header = rows[0]
    names = [cell.strip() for cell in header]
    if "x" not in names or "y" not in names:
        msg = (f"{path}: line {header_line}, header must name columns x and y, got "
               f"{shorten(','.join(names))}")
        raise InputError(msg)
    ix, iy = names.index("x"), names.index("y")
    points = [[_cell(path, number, row, ix, "x"), _cell(path, number, row, iy, "y")]
              for number, row in rows[1:]]
    places = [f"line {number}" for number, _ in rows[1:]]
    return np.array(points, dtype=np.float64).reshape(-1, 2), places


def _cell(path: Path, line: int, row: list[str], index: int, name: str) -> float:
    text = row[index].strip() if index < len(row) else ""
    value = parse_number(text, f"{path}: line {line}", name)
    if abs(value) > MAX_COORDINATE:
        msg = (f"{path}: line {line}, column {name!r} must lie within ±{MAX_COORDINATE:g} m, "
               f"got {shorten(repr(text))}")
        raise InputError(msg)
    return value


def _from_json(path: Path, text: str) -> npt.NDArray[np.float64]:
    data: Any = parse_json(text, path, InputError)
    if isinstance(data, dict):
        data = data.get("waypoints")
    if not isinstance(data, list):
        msg = f"{path}: expected {{\"waypoints\": [[x, y], ...]}} or a list [[x, y], ...]"
        raise InputError(msg)
    points = np.empty((len(data), 2))
    for i, point in enumerate(data):
        xy = [finite_number(v) for v in point] if isinstance(point, list) else []
        if len(xy) != 2 or None in xy:
            msg = f"{path}: waypoint {i} must be [x, y] with finite numbers, got {_short(point)}"
            raise InputError(msg)
        points[i] = xy
        if np.abs(points[i]).max() > MAX_COORDINATE:
            msg = (f"{path}: waypoint {i} must lie within ±{MAX_COORDINATE:g} m of the origin "
                   f"in x and y, got {_short(point)}")
            raise InputError(msg)
    return points


def _short(value: Any) -> str:
    return shorten(repr(value), 60)
