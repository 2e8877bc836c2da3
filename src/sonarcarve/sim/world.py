"""A 2-D world of walls as line segments, exact ray casting against it, and world loaders.

A world is a set of zero-thickness walls (segments), plus two optional annotations that
experiments use: a *tour* (a collision-free waypoint path that shows the world off) and the
*openings* (door or passage gaps, each given by its two jamb endpoints).

Worlds come from :func:`load_world`, which accepts

- a built-in name (:func:`builtin_worlds` lists them; JSON files in ``sonarcarve/sim/worlds/``),
- ``random:SEED`` or ``random:SEED:WIDTHxHEIGHT`` (:func:`sonarcarve.sim.generate.random_world`),
- a ``.json`` file: ``{"segments": [[x1, y1, x2, y2], ...]}`` with optional keys ``name``,
  ``description``, ``tour`` (``[[x, y], ...]``) and ``openings`` (``[{"a": [x, y], "b": [x, y]},
  ...]``); metres,
- a ``.yaml``/``.yml`` ROS map_server map (``image``, ``resolution``, ``origin``,
  ``occupied_thresh``, ``negate``): the boundaries of its occupied cells become walls.

No :class:`World` has a wall of zero length, nor a tour with fewer than two distinct waypoints.
A world read from a file has at least one wall, and its tour stays inside the walls' bounding
box and meets no wall (checked by the loader only: a world made of some of another's walls, as
the sonar simulator makes, keeps the whole tour).
"""

from __future__ import annotations

import functools
import json
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any, NoReturn

import numpy as np
import numpy.typing as npt

from sonarcarve.errors import SonarcarveError
from sonarcarve.io.atomic import atomic_text
from sonarcarve.io.errors import finite_number, load_json, load_yaml
from sonarcarve.typing import BoolArray, FloatArray

__all__ = [
    "World",
    "WorldError",
    "builtin_worlds",
    "check_seed",
    "load_world",
    "read_ros_map",
    "read_world_json",
    "segments_from_occupancy",
    "write_world_json",
]


#: Ray/wall (or point/wall) pairs evaluated at once; bounds the temporaries to a few tens of MB.
_PAIRS_PER_CHUNK = 1 << 19

#: How to spell a random world (see :func:`sonarcarve.sim.generate.random_world`).
_RANDOM_SPEC_HELP = "random:SEED or random:SEED:WIDTHxHEIGHT (metres)"

#: Lengths and distances at or below this, metres, count as zero (walls, tour legs, contacts).
_TINY = 1e-9


class WorldError(SonarcarveError):
    """A world that cannot be loaded or built (bad file, unknown name, degenerate walls, a tour
    through a wall), or a simulation parameter out of range (seed, speed, duration)."""


def check_seed(seed: object, where: str = "seed") -> int:
    """``seed`` as an int if it can seed the simulator's random generator: an integer >= 0.

    Every seeded function of :mod:`sonarcarve.sim` calls this first, so a bad seed gives a
    one-line error instead of numpy's traceback.

    Parameters
    ----------
    seed : object
        The seed to check.
    where : str
        Names the seed in the message (e.g. ``"random:-1: seed"``).

    Raises
    ------
    WorldError
        ``<where> must be an integer >= 0, got <seed>``.

    Examples
    --------
    >>> check_seed(7)
    7
    >>> check_seed(-1)
    Traceback (most recent call last):
    ...
    sonarcarve.sim.world.WorldError: seed must be an integer >= 0, got -1
    """
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
        msg = f"{where} must be an integer >= 0, got {seed!r}"
        raise WorldError(msg)
    return int(seed)


def _no_openings() -> FloatArray:
    return np.zeros((0, 2, 2), dtype=np.float64)


@dataclass(frozen=True, eq=False)
class World:
    """Walls as segments, with an optional tour and the world's openings.

    Attributes
    ----------
    segments : ndarray, shape (n, 4)
        Wall ``i`` runs from ``(x1, y1)`` to ``(x2, y2)`` = ``segments[i]``, metres.
    name : str
        Where the world came from (built-in name or file).
    tour : ndarray, shape (k, 2), or None
        Waypoints of a collision-free path through the world (at least 2 distinct), metres;
        loaders check that it stays inside the walls' bounding box and meets no wall; for the
        built-in worlds every point of the polyline is at least 0.45 m from every wall.
    openings : ndarray, shape (k, 2, 2)
        Door or passage gaps: ``openings[i, 0]`` and ``openings[i, 1]`` are the two ends (jambs)
        of gap ``i``, metres. Empty, shape (0, 2, 2), when unknown.
    description : str
        One line saying what the world is.
    """

    segments: FloatArray
    name: str = "world"
    tour: FloatArray | None = None
    openings: FloatArray = field(default_factory=_no_openings)
    description: str = ""

    def __post_init__(self) -> None:
        seg = np.asarray(self.segments, dtype=np.float64).reshape(-1, 4)
        if not np.all(np.isfinite(seg)):
            msg = f"{self.name}: wall coordinates must be finite"
            raise WorldError(msg)
        object.__setattr__(self, "segments", seg)
        if self.tour is not None:
            tour = np.asarray(self.tour, dtype=np.float64)
            if tour.ndim != 2 or tour.shape[1] != 2 or tour.shape[0] < 2:
                msg = f"{self.name}: tour must have shape (k >= 2, 2), got {tour.shape}"
                raise WorldError(msg)
            if not np.all(np.isfinite(tour)):
                msg = f"{self.name}: tour coordinates must be finite"
                raise WorldError(msg)
            object.__setattr__(self, "tour", tour)
        openings = np.asarray(self.openings, dtype=np.float64)
        if openings.size == 0:
            openings = _no_openings()
        if openings.ndim != 3 or openings.shape[1:] != (2, 2):
            msg = f"{self.name}: openings must have shape (k, 2, 2), got {openings.shape}"
            raise WorldError(msg)
        if not np.all(np.isfinite(openings)):
            msg = f"{self.name}: opening coordinates must be finite"
            raise WorldError(msg)
        object.__setattr__(self, "openings", openings)
        problem = _geometry_problem(seg, self.tour, against_walls=False)
        if problem is not None:
            msg = f"{self.name}: {problem}"
            raise WorldError(msg)

    def __len__(self) -> int:
        return int(self.segments.shape[0])

    def __repr__(self) -> str:
        width, height = self.size
        tour = "yes" if self.tour is not None else "no"
        return (f"World({self.name!r}, {len(self)} walls, {width:.1f} m x {height:.1f} m, "
                f"{self.openings.shape[0]} openings, tour={tour})")

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        """``(xmin, ymin, xmax, ymax)`` of all walls, metres."""
        if not len(self):
            return 0.0, 0.0, 0.0, 0.0
        xs = self.segments[:, [0, 2]]
        ys = self.segments[:, [1, 3]]
        return float(xs.min()), float(ys.min()), float(xs.max()), float(ys.max())

    @property
    def size(self) -> tuple[float, float]:
        """``(width, height)`` of the walls' bounding box, metres."""
        xmin, ymin, xmax, ymax = self.bounds
        return xmax - xmin, ymax - ymin

    @property
    def area(self) -> float:
        """Area of the walls' bounding box, m² (the building's footprint for a rectangular plan)."""
        width, height = self.size
        return width * height

    @property
    def tour_length(self) -> float:
        """Length of the tour polyline, metres (0 without a tour)."""
        if self.tour is None:
            return 0.0
        return float(np.sum(np.hypot(*np.diff(self.tour, axis=0).T)))

    @property
    def start_pose(self) -> tuple[float, float, float] | None:
        """``(x, y, heading)`` at the tour's start, heading towards its next distinct waypoint."""
        if self.tour is None:
            return None
        steps = self.tour[1:] - self.tour[0]
        moving = np.flatnonzero(np.hypot(steps[:, 0], steps[:, 1]) > 1e-9)
        dx, dy = steps[moving[0]] if moving.size else (1.0, 0.0)
        return float(self.tour[0, 0]), float(self.tour[0, 1]), math.atan2(dy, dx)

    def cast_rays(
        self, origins: npt.ArrayLike, angles: npt.ArrayLike, max_range: float = np.inf
    ) -> tuple[FloatArray, npt.NDArray[np.int64]]:
        """Distance to the first wall along each ray, exactly (no sampling).

        A ray that passes exactly through a wall's end point hits that wall; a ray parallel to a
        wall never hits it (not even when it runs along it); a wall through the origin itself is
        ignored (hits at distance <= 1e-9 m do not count).

        Parameters
        ----------
        origins : array-like, shape (n, 2) or (2,)
            Ray starts, metres (one origin broadcast to every ray if shape (2,)).
        angles : array-like, shape (n,)
            Ray directions, radians counter-clockwise from +x.
        max_range : float
            Rays that hit nothing closer return ``inf``.

        Returns
        -------
        distance : ndarray, shape (n,)
            Distance to the first hit, or ``inf``.
        wall : ndarray of int64, shape (n,)
            Index of the wall hit, or -1.

        Examples
        --------
        >>> w = World(np.array([[1.0, -1.0, 1.0, 1.0]]))
        >>> d, i = w.cast_rays([0.0, 0.0], [0.0, np.pi])
        >>> d.tolist(), i.tolist()
        ([1.0, inf], [0, -1])
        """
        angle = np.atleast_1d(np.asarray(angles, dtype=np.float64))
        origin = np.broadcast_to(np.asarray(origins, dtype=np.float64), (angle.shape[0], 2))
        distance = np.full(angle.shape[0], np.inf)
        wall = np.full(angle.shape[0], -1, dtype=np.int64)
        if not len(self):
            return distance, wall
        step = max(1, _PAIRS_PER_CHUNK // len(self))
        for lo in range(0, angle.shape[0], step):
            hi = lo + step
            distance[lo:hi], wall[lo:hi] = _cast_chunk(
                self.segments, origin[lo:hi], angle[lo:hi], max_range)
        return distance, wall

    def distance_to_walls(self, points: npt.ArrayLike) -> FloatArray:
        """Euclidean distance from each point, shape (n, 2), to the nearest wall, shape (n,).

        ``inf`` for a world without walls.
        """
        p = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        if not len(self):
            return np.full(p.shape[0], np.inf)
        out = np.empty(p.shape[0])
        step = max(1, _PAIRS_PER_CHUNK // len(self))
        for lo in range(0, p.shape[0], step):
            out[lo:lo + step] = _point_segment_distance(p[lo:lo + step], self.segments).min(axis=1)
        return out


def _cast_chunk(segments: FloatArray, origin: FloatArray, angle: FloatArray,
                max_range: float) -> tuple[FloatArray, npt.NDArray[np.int64]]:
    direction = np.column_stack((np.cos(angle), np.sin(angle)))
    a = segments[:, :2]
    edge = segments[:, 2:] - a
    # Solve origin + s * direction = a + u * edge for every (ray, wall) pair (Cramer's rule).
    denom = _cross(direction[:, None, :], edge[None, :, :])
    delta = a[None, :, :] - origin[:, None, :]
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        s = _cross(delta, edge[None, :, :]) / denom
        u = _cross(delta, direction[:, None, :]) / denom
    hit = (np.abs(denom) > 1e-12) & (s > 1e-9) & (u >= 0.0) & (u <= 1.0) & (s <= max_range)
    s = np.where(hit, s, np.inf)
    wall = np.argmin(s, axis=1)
    distance = s[np.arange(angle.shape[0]), wall]
    return distance, np.where(np.isfinite(distance), wall, -1).astype(np.int64)


def _point_segment_distance(points: FloatArray, segments: FloatArray) -> FloatArray:
    """Distances, shape (n, m), from points (n, 2) to segments (m, 4)."""
    a = segments[None, :, :2]
    edge = segments[None, :, 2:] - a
    length2 = np.maximum(np.sum(edge * edge, axis=2), 1e-24)
    u = np.clip(np.sum((points[:, None, :] - a) * edge, axis=2) / length2, 0.0, 1.0)
    nearest = a + u[:, :, None] * edge
    return np.asarray(np.hypot(points[:, None, 0] - nearest[..., 0],
                               points[:, None, 1] - nearest[..., 1]))


def _cross(a: FloatArray, b: FloatArray) -> FloatArray:
    return np.asarray(a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0])


# --------------------------------------------------------------------------------------------
# Consistency of walls and tour
# --------------------------------------------------------------------------------------------

def _geometry_problem(segments: FloatArray, tour: FloatArray | None, *,
                      against_walls: bool = True) -> str | None:
    """What is wrong with the walls and the tour, as the tail of a message, or None.

    Checks that no wall has zero length and that a tour has two distinct waypoints; with
    ``against_walls`` (and walls to check against), also that the tour stays inside the walls'
    bounding box and meets no wall.
    """
    lengths = np.hypot(segments[:, 2] - segments[:, 0], segments[:, 3] - segments[:, 1])
    short = np.flatnonzero(lengths <= _TINY)
    if short.size:
        x, y = segments[short[0], :2]
        return f"segments[{short[0]}] is a wall of zero length (both ends at ({x:g}, {y:g}))"
    if tour is None:
        return None
    if not np.any(np.hypot(*(tour[1:] - tour[0]).T) > _TINY):
        x, y = tour[0]
        return (f"tour needs at least 2 distinct waypoints, all {tour.shape[0]} are "
                f"({x:g}, {y:g})")
    if not (against_walls and segments.shape[0]):
        return None
    low, high = segments.reshape(-1, 2).min(axis=0), segments.reshape(-1, 2).max(axis=0)
    outside = np.flatnonzero(np.any((tour < low - _TINY) | (tour > high + _TINY), axis=1))
    if outside.size:
        i = int(outside[0])
        return (f"tour[{i}] ({tour[i, 0]:g}, {tour[i, 1]:g}) lies outside the walls' bounding "
                f"box x in [{low[0]:g}, {high[0]:g}], y in [{low[1]:g}, {high[1]:g}]")
    crossing = _first_crossing(tour, segments)
    if crossing is not None:
        leg, wall, (x, y) = crossing
        return (f"tour leg {leg} (tour[{leg}] -> tour[{leg + 1}]) runs into wall "
                f"segments[{wall}] at ({x:g}, {y:g})")
    return None


def _first_crossing(tour: FloatArray, segments: FloatArray
                    ) -> tuple[int, int, tuple[float, float]] | None:
    """The first place, in tour order, where the tour polyline meets a wall.

    Returns ``(leg, wall, (x, y))``: leg ``i`` runs from ``tour[i]`` to ``tour[i + 1]``; touching
    a wall (an end point on it, or running along it) counts as meeting it. None if it meets none.
    Walls must have non-zero length.
    """
    start, step = tour[:-1], np.diff(tour, axis=0)
    rows = max(1, _PAIRS_PER_CHUNK // segments.shape[0])
    for lo in range(0, start.shape[0], rows):
        contact = _leg_contacts(start[lo:lo + rows], step[lo:lo + rows], segments)
        legs = np.flatnonzero(np.isfinite(contact).any(axis=1))
        if legs.size:
            leg = int(legs[0])
            wall = int(np.argmin(contact[leg]))
            x, y = start[lo + leg] + contact[leg, wall] * step[lo + leg]
            return lo + leg, wall, (float(x), float(y))
    return None


def _leg_contacts(start: FloatArray, step: FloatArray, segments: FloatArray) -> FloatArray:
    """Per (leg, wall) pair, shape (k, n): the leg parameter in [0, 1] of the first point the leg
    shares with the wall (within 1e-9 m), or ``inf`` where they share none.

    Leg ``i`` is ``start[i] + t * step[i]``, wall ``j`` is ``a[j] + u * edge[j]``, t and u in
    [0, 1]. Crossing legs solve both equations by Cramer's rule; parallel legs meet a wall only
    when they lie on its line, from where its overlap with the wall is read off directly.
    """
    a, edge = segments[:, :2], segments[:, 2:] - segments[:, :2]
    edge_len = np.hypot(edge[:, 0], edge[:, 1])[None, :]
    step_len = np.hypot(step[:, 0], step[:, 1])[:, None]
    tol_t = _TINY / np.maximum(step_len, _TINY)    # metres of slack as parameters
    tol_u = _TINY / edge_len
    denom = _cross(step[:, None, :], edge[None, :, :])
    delta = a[None, :, :] - start[:, None, :]
    off_line = _cross(delta, edge[None, :, :])     # edge_len times the start's distance to it
    parallel = np.abs(denom) <= 1e-12 * step_len * edge_len
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        t = off_line / denom
        u = _cross(delta, step[:, None, :]) / denom
        crossing = (~parallel & (t >= -tol_t) & (t <= 1 + tol_t)
                    & (u >= -tol_u) & (u <= 1 + tol_u))
        # Parallel: where the leg's ends fall along the wall (0 and 1 are the wall's ends).
        u0 = -np.sum(delta * edge[None, :, :], axis=2) / edge_len**2
        u1 = u0 + (step @ edge.T) / edge_len**2
        on_line = parallel & (np.abs(off_line) <= _TINY * edge_len)
        overlap = on_line & (np.maximum(u0, u1) >= -tol_u) & (np.minimum(u0, u1) <= 1 + tol_u)
        inside = (u0 >= -tol_u) & (u0 <= 1 + tol_u)
        reach = np.where(inside, 0.0, (np.where(u0 < 0.0, 0.0, 1.0) - u0) / (u1 - u0))
    contact = np.full(denom.shape, np.inf)
    contact[crossing] = np.clip(t[crossing], 0.0, 1.0)
    contact[overlap] = np.clip(reach[overlap], 0.0, 1.0)
    return contact


# --------------------------------------------------------------------------------------------
# Loading: one entry point, a dispatch table per kind of spec.
# --------------------------------------------------------------------------------------------

def load_world(spec: str | Path) -> World:
    """Load a world from a built-in name, ``random:SEED[:WxH]``, a ``.json`` or a ROS ``.yaml``.

    Parameters
    ----------
    spec : str or Path
        ``"office"``, ``"random:7"``, ``"random:7:40x30"``, ``"walls.json"``, ``"map.yaml"``.

    Raises
    ------
    WorldError
        With one line naming the spec or file and what is wrong.

    Examples
    --------
    >>> load_world("t-junction").name
    't-junction'
    >>> load_world("random:3:20x15").size
    (20.0, 15.0)
    """
    text = str(spec)
    if not isinstance(spec, Path) and text in _builtin_paths():
        return _load_builtin(text)
    scheme, colon, rest = text.partition(":")
    if not isinstance(spec, Path) and colon and scheme in _SCHEMES:
        return _SCHEMES[scheme](rest, text)
    loader = _FILE_LOADERS.get(Path(text).suffix.lower())
    if loader is None:
        known = ", ".join([*_builtin_paths(), _RANDOM_SPEC_HELP])
        msg = (f"unknown world {text!r}: use a built-in world ({known}), a .json file or a ROS "
               f"map .yaml file")
        raise WorldError(msg)
    return loader(Path(text))


def builtin_worlds() -> dict[str, str]:
    """Built-in world names and their one-line descriptions (``random:SEED`` last).

    Examples
    --------
    >>> sorted(builtin_worlds())
    ['doorway', 'narrow-hallway', 'office', 'random:SEED', 't-junction']
    """
    described = {name: _read_builtin(name).description for name in _builtin_paths()}
    described["random:SEED"] = (
        "seeded floor of corridors and rooms with doors; random:SEED:WxH for another size")
    return {name: str(text) for name, text in described.items()}


@functools.cache
def _builtin_paths() -> dict[str, Path]:
    folder = resources.files("sonarcarve.sim").joinpath("worlds")
    paths = {Path(str(entry)).stem: Path(str(entry)) for entry in folder.iterdir()
             if str(entry).endswith(".json")}
    return dict(sorted(paths.items()))


@functools.cache
def _read_builtin(name: str) -> World:
    return read_world_json(_builtin_paths()[name])


def _load_builtin(name: str) -> World:
    world = _read_builtin(name)
    # Worlds are frozen, but their arrays are not: hand out copies of the cached one.
    return World(world.segments.copy(), name,
                 None if world.tour is None else world.tour.copy(),
                 world.openings.copy(), world.description)


def _load_random(rest: str, spec: str) -> World:
    from sonarcarve.sim.generate import random_world

    seed_text, _, size_text = rest.partition(":")
    try:
        seed = int(seed_text)
    except ValueError:
        msg = f"{spec}: seed must be an integer ({_RANDOM_SPEC_HELP})"
        raise WorldError(msg) from None
    check_seed(seed, f"{spec}: seed")
    if not size_text:
        return random_world(seed)
    width_text, x, height_text = size_text.lower().partition("x")
    try:
        width, height = float(width_text), float(height_text)
    except ValueError:
        msg = f"{spec}: size must be WIDTHxHEIGHT in metres, e.g. 60x40"
        raise WorldError(msg) from None
    if not x:
        msg = f"{spec}: size must be WIDTHxHEIGHT in metres, e.g. 60x40"
        raise WorldError(msg)
    return random_world(seed, width=width, height=height)


_SCHEMES: dict[str, Callable[[str, str], World]] = {"random": _load_random}


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
    if not segments.shape[0]:
        _fail(path, "no walls: 'segments' is empty (give [x1, y1, x2, y2] walls)")
    problem = _geometry_problem(segments, tour)
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
    text = json.dumps(value)
    return text if len(text) <= 40 else text[:37] + "..."


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
    from PIL import Image, UnidentifiedImageError

    path = Path(path)
    meta = _read_yaml(path)
    for key in ("image", "resolution", "origin"):
        if key not in meta:
            _fail(path, f"missing key {key!r}")
    resolution = _yaml_number(meta, "resolution", path)
    if resolution <= 0.0:
        _fail(path, f"resolution must be > 0, got {resolution}")
    origin = meta["origin"]
    if (not isinstance(origin, list) or len(origin) not in (2, 3)
            or any(finite_number(v) is None for v in origin)):
        _fail(path, f"origin must be [x, y, yaw] finite numbers, got {_short(origin)}")
    thresh = _yaml_number(meta, "occupied_thresh", path, 0.65)
    negate = meta.get("negate", 0)
    if negate not in (0, 1, True, False):
        _fail(path, f"negate must be 0 or 1, got {negate!r}")
    mode = meta.get("mode", "trinary")
    if mode not in ("trinary", "scale", "raw"):
        _fail(path, f"mode must be trinary, scale or raw, got {mode!r}")
    image_path = path.parent / str(meta["image"])
    try:
        with Image.open(image_path) as image:
            pixels = np.asarray(image.convert("L"), dtype=np.float64)
    except FileNotFoundError:
        _fail(path, f"image {image_path}: no such file")
    except IsADirectoryError:
        _fail(path, f"image {image_path}: is a directory")
    except (OSError, UnidentifiedImageError, ValueError, Image.DecompressionBombError) as err:
        _fail(path, f"image {image_path}: cannot read ({' '.join(str(err).split())})")
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


_FILE_LOADERS: dict[str, Callable[[Path], World]] = {
    ".json": read_world_json,
    ".yaml": read_ros_map,
    ".yml": read_ros_map,
}
