"""Robot motion: time-stamped poses, and ways to make them (paths, exploration, odometry drift).

- :func:`follow_waypoints` drives a polyline at constant speed (turning in place, or on arcs),
- :func:`explore` wanders a world without colliding, preferring places it has not been,
- :func:`with_odometry_drift` turns a true trajectory into the dead-reckoned one a robot believes,
- :func:`with_localisation_noise` into the one a localiser (AMCL, a fused odometry) reports.

Defaults describe a Nomadic Scout2-like differential drive (the paper's platform): 0.41 m body
diameter, 0.4 m/s cruising speed, 1 rad/s turning in place. They are typical values chosen for
the simulator, not measurements of a real Scout2.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from sonarcarve.readings import wrap_angle
from sonarcarve.sim.world import World, WorldError, check_seed
from sonarcarve.typing import FloatArray

__all__ = [
    "DEFAULT_CORRELATION_TIME",
    "DEFAULT_DT",
    "DEFAULT_HEADING_SIGMA",
    "DEFAULT_POSITION_SIGMA",
    "DEFAULT_SPEED",
    "DEFAULT_TURN_RATE",
    "MAX_COORDINATE",
    "MAX_POSES",
    "PLAN_MARGIN",
    "ROBOT_RADIUS",
    "Trajectory",
    "explore",
    "follow_waypoints",
    "with_localisation_noise",
    "with_odometry_drift",
]



@dataclass(frozen=True, eq=False)
class Trajectory:
    """Robot poses over time, arrays of shape (n,), times strictly increasing.

    Attributes
    ----------
    t : ndarray
        Times, seconds.
    x, y : ndarray
        Robot centre in the world frame, metres.
    heading : ndarray
        Robot heading, radians counter-clockwise from +x, unwrapped (continuous).
    """

    t: FloatArray
    x: FloatArray
    y: FloatArray
    heading: FloatArray

    def __post_init__(self) -> None:
        arrays = [np.asarray(a, dtype=np.float64).reshape(-1) for a in
                  (self.t, self.x, self.y, self.heading)]
        if len({a.shape for a in arrays}) != 1 or arrays[0].shape[0] < 1:
            msg = "trajectory arrays must be non-empty and of equal length"
            raise WorldError(msg)
        if np.any(np.diff(arrays[0]) <= 0.0):
            msg = "trajectory times must be strictly increasing"
            raise WorldError(msg)
        for name, value in zip(("t", "x", "y", "heading"), arrays, strict=True):
            object.__setattr__(self, name, value)

    def __len__(self) -> int:
        return int(self.t.shape[0])

    @property
    def duration(self) -> float:
        """Seconds from the first pose to the last."""
        return float(self.t[-1] - self.t[0])

    @property
    def path_length(self) -> float:
        """Metres travelled."""
        return float(np.sum(np.hypot(np.diff(self.x), np.diff(self.y))))

    def pose_at(self, times: npt.ArrayLike) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Linearly interpolated ``(x, y, heading)`` at ``times`` (clamped to the ends)."""
        q = np.asarray(times, dtype=np.float64)
        return (np.interp(q, self.t, self.x), np.interp(q, self.t, self.y),
                np.interp(q, self.t, self.heading))

    def distance_at(self, times: npt.ArrayLike) -> FloatArray:
        """Metres travelled from the start until ``times``."""
        travelled = np.concatenate(([0.0], np.cumsum(np.hypot(np.diff(self.x), np.diff(self.y)))))
        return np.asarray(np.interp(np.asarray(times, dtype=np.float64), self.t, travelled))


#: Body radius of a Scout2-like robot, metres (0.41 m diameter).
ROBOT_RADIUS = 0.205
#: Cruising speed, m/s (the paper's platform moved at about 0.3-0.5 m/s).
DEFAULT_SPEED = 0.4
#: Pose sampling period, seconds.
DEFAULT_DT = 0.05
#: Turning rate in place, rad/s (assumed, comfortable for a Scout2-sized base).
DEFAULT_TURN_RATE = 1.0
#: Half the distance between the drive wheels, metres (assumed: wheels near a 0.41 m body's rim).
HALF_WHEEL_BASE = 0.17
#: Largest |x| or |y| of a waypoint, metres (100 km: any building, far from float trouble).
MAX_COORDINATE = 1e5
#: Most poses :func:`follow_waypoints` and :func:`explore` will make: 10 million poses are
#: 320 MB of trajectory arrays and, at the default 0.05 s, 139 hours of driving.
MAX_POSES = 10_000_000


def _check_pose_count(count: float, duration: float, dt: float, what: str) -> None:
    if count > MAX_POSES:
        msg = (f"{what} of {duration:.6g} s sampled every {dt:g} s needs {count:.4g} poses, more "
               f"than the limit of {MAX_POSES:,} (MAX_POSES); use a shorter {what} or a larger dt")
        raise WorldError(msg)


def _check_positive(**values: float) -> None:
    for name, value in values.items():
        if not (math.isfinite(value) and value > 0.0):
            msg = f"{name} must be a finite number > 0, got {value}"
            raise WorldError(msg)


# --------------------------------------------------------------------------------------------
# Driving a polyline
# --------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class _Piece:
    """One piece of a drive: a straight ``line``, a ``turn`` in place or an ``arc``.

    ``point`` is the line's start, the turn's position or the arc's centre; ``heading`` the
    heading at the piece's start; ``delta`` the heading change; ``scale`` the line's speed or
    the arc's radius.
    """

    kind: str
    duration: float
    point: tuple[float, float]
    heading: float
    delta: float = 0.0
    scale: float = 0.0

    def evaluate(self, tau: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        fraction = tau / self.duration
        heading = self.heading + self.delta * fraction
        if self.kind == "line":
            travelled = self.scale * tau
            return (self.point[0] + travelled * math.cos(self.heading),
                    self.point[1] + travelled * math.sin(self.heading), heading)
        if self.kind == "turn":
            return np.full_like(tau, self.point[0]), np.full_like(tau, self.point[1]), heading
        # Arc about ``point``: the robot sits at centre + sign * r * (sin h, -cos h).
        side = math.copysign(self.scale, self.delta)
        return (self.point[0] + side * np.sin(heading), self.point[1] - side * np.cos(heading),
                heading)


def follow_waypoints(waypoints: npt.ArrayLike, speed: float = DEFAULT_SPEED,
                     dt: float = DEFAULT_DT, turn_rate: float = DEFAULT_TURN_RATE,
                     corner_radius: float = 0.0, t0: float = 0.0) -> Trajectory:
    """Drive a polyline at constant speed, turning at its corners.

    With ``corner_radius == 0`` (the default) the robot stops at each corner and turns in place
    at ``turn_rate``, so every pose lies exactly on the polyline (a tour's clearance holds for
    the whole trajectory). With ``corner_radius > 0`` it rounds each corner on a circular arc
    tangent to both legs (radius shrunk where a leg is too short for it, and turns sharper than
    170° still made in place), slowing down on an arc whose speed/radius would exceed
    ``turn_rate``; arcs cut corners, by up to r(1/cos(Δ/2) - 1) for a turn of Δ.

    Parameters
    ----------
    waypoints : array-like, shape (k, 2)
        Polyline, metres; consecutive duplicates are ignored; at least 2 distinct points.
    speed : float
        Linear speed, m/s.
    dt : float
        Sampling period, s; the last pose (the end of the polyline) is always included.
    turn_rate : float
        Angular speed when turning, rad/s.
    corner_radius : float
        Radius of the corner arcs, metres; 0 turns in place.
    t0 : float
        Time of the first pose, s.

    Returns
    -------
    Trajectory
        Starting at the first waypoint facing the first leg; heading unwrapped.

    Raises
    ------
    WorldError
        Bad parameters; waypoints that are not finite, lie farther than :data:`MAX_COORDINATE`
        from the origin in x or y, or hold fewer than 2 distinct points; a drive needing more
        than :data:`MAX_POSES` poses.

    Examples
    --------
    >>> tr = follow_waypoints([[0, 0], [1, 0], [1, 1]], speed=0.5, dt=0.5, turn_rate=np.pi / 2)
    >>> tr.duration, float(tr.heading[-1])
    (5.0, 1.5707963267948966)
    """
    _check_positive(speed=speed, dt=dt, turn_rate=turn_rate)
    if not (math.isfinite(corner_radius) and corner_radius >= 0.0):
        msg = f"corner_radius must be a finite number >= 0, got {corner_radius}"
        raise WorldError(msg)
    points = _distinct_points(waypoints)
    return _sample(_drive_pieces(points, speed, turn_rate, corner_radius), dt, t0)


def _distinct_points(waypoints: npt.ArrayLike) -> FloatArray:
    points = np.asarray(waypoints, dtype=np.float64)
    if points.ndim != 2 or points.shape[1] != 2 or not np.all(np.isfinite(points)):
        msg = f"waypoints must be finite numbers of shape (k, 2), got shape {points.shape}"
        raise WorldError(msg)
    far = np.flatnonzero(np.abs(points).max(axis=1, initial=0.0) > MAX_COORDINATE)
    if far.size:
        x, y = points[far[0]]
        msg = (f"waypoints[{far[0]}] ({x:g}, {y:g}) lies farther than the limit of "
               f"{MAX_COORDINATE:g} m (MAX_COORDINATE) from the origin in x or y")
        raise WorldError(msg)
    keep = np.concatenate(([True], np.hypot(*np.diff(points, axis=0).T) > 1e-9))
    points = points[keep]
    if points.shape[0] < 2:
        msg = "waypoints need at least 2 distinct points"
        raise WorldError(msg)
    return points


def _drive_pieces(points: FloatArray, speed: float, turn_rate: float,
                  corner_radius: float) -> list[_Piece]:
    steps = np.diff(points, axis=0)
    lengths = np.hypot(steps[:, 0], steps[:, 1])
    units = steps / lengths[:, None]
    turns = wrap_angle(np.diff(np.arctan2(steps[:, 1], steps[:, 0])))
    headings = math.atan2(steps[0, 1], steps[0, 0]) + np.concatenate(([0.0], np.cumsum(turns)))
    # Tangent length cut from both legs at each interior corner, and the arc radius there.
    cut = np.zeros(len(points))
    radius = np.zeros(len(points))
    for j, turn in enumerate(turns, start=1):
        if corner_radius > 0.0 and 1e-9 < abs(turn) < math.radians(170.0):
            half_tan = math.tan(abs(turn) / 2)
            cut[j] = min(corner_radius * half_tan, lengths[j - 1] / 2, lengths[j] / 2)
            radius[j] = cut[j] / half_tan
    pieces = []
    for i, (length, unit) in enumerate(zip(lengths, units, strict=True)):
        straight = length - cut[i] - cut[i + 1]
        start = points[i] + cut[i] * unit
        if straight > 1e-12:
            pieces.append(_Piece("line", straight / speed, (float(start[0]), float(start[1])),
                                 float(headings[i]), scale=speed))
        if i + 1 < len(lengths):
            pieces.extend(_corner(points[i + 1], unit, float(headings[i]), float(turns[i]),
                                  float(cut[i + 1]), float(radius[i + 1]), speed, turn_rate))
    return pieces


def _corner(vertex: FloatArray, unit: FloatArray, heading: float, turn: float, cut: float,
            radius: float, speed: float, turn_rate: float) -> list[_Piece]:
    if abs(turn) <= 1e-12:
        return []
    duration = abs(turn) / turn_rate
    if radius <= 1e-9:
        return [_Piece("turn", duration, (float(vertex[0]), float(vertex[1])), heading, turn)]
    start = vertex - cut * unit
    side = math.copysign(radius, turn)
    center = (float(start[0] - side * math.sin(heading)),
              float(start[1] + side * math.cos(heading)))
    return [_Piece("arc", max(radius * abs(turn) / speed, duration), center, heading, turn, radius)]


def _sample(pieces: Sequence[_Piece], dt: float, t0: float) -> Trajectory:
    bounds = np.concatenate(([0.0], np.cumsum([piece.duration for piece in pieces])))
    total = float(bounds[-1])
    steps = math.floor(total / dt + 1e-9)
    _check_pose_count(steps + 1 + (total - steps * dt > 1e-9), total, dt, "path")
    local = np.arange(steps + 1) * dt
    if total - local[-1] > 1e-9:
        local = np.append(local, total)
    local[-1] = min(local[-1], total)
    x, y, heading = np.empty_like(local), np.empty_like(local), np.empty_like(local)
    edges = np.searchsorted(local, bounds, side="left")
    edges[-1] = local.shape[0]
    for piece, lo, hi, start in zip(pieces, edges[:-1], edges[1:], bounds[:-1], strict=True):
        if hi > lo:
            x[lo:hi], y[lo:hi], heading[lo:hi] = piece.evaluate(local[lo:hi] - start)
    return Trajectory(np.asarray(t0 + local, dtype=np.float64), x, y, heading)


# --------------------------------------------------------------------------------------------
# Exploration
# --------------------------------------------------------------------------------------------

_GRID_RESOLUTION = 0.1   # planning cell side, metres
#: Metres the explorer's planner keeps from walls beyond the robot's radius.
PLAN_MARGIN = 0.12
_STEP_MARGIN = 0.02      # every executed pose keeps at least radius + this from walls
_VISIT_CELL = 1.0        # side of the visited-place memory's cells, metres
_VISIT_RADIUS = 1.5      # cells whose centre comes this close count as visited
_MIN_GOAL_DISTANCE = 3.0  # goals closer than this (path metres) only when nothing else is left
_OPEN_GOAL = 0.55        # goals need this much clearance (centres of rooms and corridors)
_SEARCH_LIMIT = 25.0     # first goal search stays within this path cost
_LOOKAHEAD = 0.5         # pure-pursuit look-ahead, metres
_GIVE_UP = 1.5           # seconds blocked before a goal is abandoned
#: Most planning-grid cells explore() builds: about a 316 m x 316 m world. The grid and its graph
#: take about 255 bytes a cell at peak (measured: 2.3 GB for the 9.1 million cells of
#: random_world(1, 300, 300), ru_maxrss before and after _PlanningGrid.build).
_MAX_GRID_CELLS = 10_000_000


@dataclass(frozen=True, eq=False)
class _PlanningGrid:
    """Free cells of a grid over the world (cell centres with enough clearance), as a graph."""

    origin: tuple[float, float]
    shape: tuple[int, int]          # (rows along y, columns along x)
    node_of_cell: npt.NDArray[np.int64]   # flat cell -> node, -1 when blocked
    xy: FloatArray                  # (nodes, 2) cell centres
    clearance: FloatArray           # (nodes,) approximate distance to the nearest wall
    visit_cell: npt.NDArray[np.int64]     # (nodes,) flat index into the visited-place memory
    visit_shape: tuple[int, int]
    graph: object                   # scipy.sparse.csr_matrix of path costs

    @classmethod
    def build(cls, world: World, keep: float) -> _PlanningGrid:
        from scipy import ndimage, sparse

        res = _GRID_RESOLUTION
        # Cell centres this far from every wall make edges to 8-neighbours keep ``keep``.
        threshold = keep + res * math.sqrt(2) / 2
        xmin, ymin, xmax, ymax = world.bounds
        x0, y0 = xmin - 0.5, ymin - 0.5
        nx = math.ceil((xmax - xmin + 1.0) / res)
        ny = math.ceil((ymax - ymin + 1.0) / res)
        if nx * ny > _MAX_GRID_CELLS:
            msg = (f"{world.name}: {xmax - xmin:.6g} m x {ymax - ymin:.6g} m is too big to "
                   f"explore: its {res:g} m planning grid would have {nx * ny:.3g} cells, more "
                   f"than the limit of {_MAX_GRID_CELLS:.3g}")
            raise WorldError(msg)
        blocked = _blocked_cells(world.segments, (x0, y0), (ny, nx), threshold)
        blocked[[0, -1], :] = True
        blocked[:, [0, -1]] = True
        free = ~blocked
        depth = np.asarray(ndimage.distance_transform_edt(free), dtype=np.float64)
        rows, cols = np.nonzero(free)
        node_of_cell = np.full(ny * nx, -1, dtype=np.int64)
        node_of_cell[rows * nx + cols] = np.arange(rows.shape[0])
        xy = np.column_stack((x0 + (cols + 0.5) * res, y0 + (rows + 0.5) * res))
        clearance = threshold + (depth[rows, cols] - 1.0) * res
        vnx = math.ceil(nx * res / _VISIT_CELL)
        vny = math.ceil(ny * res / _VISIT_CELL)
        visit_cell = ((rows * res) // _VISIT_CELL).astype(np.int64) * vnx + (
            (cols * res) // _VISIT_CELL).astype(np.int64)
        # Path cost per metre grows near walls, so paths keep to the middle of corridors and
        # doors (like the generalized Voronoi graph the paper's robot traced).
        cost = 1.0 + 4.0 * np.clip(1.0 - clearance, 0.0, None)
        heads, tails, weights = [], [], []
        for dr, dc in ((0, 1), (1, 0), (1, 1), (1, -1)):
            lo, hi = max(0, -dc), nx - max(0, dc)
            ra, ca = np.nonzero(free[: ny - dr, lo:hi] & free[dr:, lo + dc:hi + dc])
            ca = ca + lo
            na = node_of_cell[ra * nx + ca]
            nb = node_of_cell[(ra + dr) * nx + ca + dc]
            heads.append(na)
            tails.append(nb)
            weights.append(res * math.hypot(dr, dc) * (cost[na] + cost[nb]) / 2)
        n = rows.shape[0]
        graph = sparse.csr_matrix(
            (np.concatenate(weights), (np.concatenate(heads), np.concatenate(tails))), shape=(n, n))
        return cls((x0, y0), (ny, nx), node_of_cell, xy, clearance, visit_cell, (vny, vnx), graph)

    def node_near(self, x: float, y: float) -> int:
        """The free cell nearest to ``(x, y)`` (-1 if the grid has none)."""
        if not self.xy.shape[0]:
            return -1
        ny, nx = self.shape
        col = int((x - self.origin[0]) // _GRID_RESOLUTION)
        row = int((y - self.origin[1]) // _GRID_RESOLUTION)
        if 0 <= row < ny and 0 <= col < nx and self.node_of_cell[row * nx + col] >= 0:
            return int(self.node_of_cell[row * nx + col])
        return int(np.argmin(np.hypot(self.xy[:, 0] - x, self.xy[:, 1] - y)))

    def visit_index(self, x: float, y: float) -> int:
        vny, vnx = self.visit_shape
        col = min(max(int((x - self.origin[0]) // _VISIT_CELL), 0), vnx - 1)
        row = min(max(int((y - self.origin[1]) // _VISIT_CELL), 0), vny - 1)
        return row * vnx + col


def _blocked_cells(segments: FloatArray, origin: tuple[float, float], shape: tuple[int, int],
                   threshold: float) -> npt.NDArray[np.bool_]:
    """Cells whose centre is closer than ``threshold`` to a wall (exact, per wall's box)."""
    res = _GRID_RESOLUTION
    ny, nx = shape
    blocked = np.zeros(shape, dtype=bool)
    for x1, y1, x2, y2 in segments:
        c0 = max(0, int((min(x1, x2) - threshold - origin[0]) // res))
        c1 = min(nx, int((max(x1, x2) + threshold - origin[0]) // res) + 1)
        r0 = max(0, int((min(y1, y2) - threshold - origin[1]) // res))
        r1 = min(ny, int((max(y1, y2) + threshold - origin[1]) // res) + 1)
        if c1 <= c0 or r1 <= r0:
            continue
        cx = origin[0] + (np.arange(c0, c1) + 0.5) * res
        cy = origin[1] + (np.arange(r0, r1) + 0.5) * res
        px, py = np.meshgrid(cx, cy)
        ex, ey = x2 - x1, y2 - y1
        length2 = max(ex * ex + ey * ey, 1e-24)
        u = np.clip(((px - x1) * ex + (py - y1) * ey) / length2, 0.0, 1.0)
        blocked[r0:r1, c0:c1] |= np.hypot(px - x1 - u * ex, py - y1 - u * ey) < threshold
    return blocked


class _Explorer:
    """Goal choice (visited-place memory) and path following (pure pursuit with a safety stop)."""

    def __init__(self, world: World, grid: _PlanningGrid, rng: np.random.Generator,
                 radius: float, speed: float, turn_rate: float) -> None:
        self.world, self.grid, self.rng = world, grid, rng
        self.radius, self.speed, self.turn_rate = radius, speed, turn_rate
        self.visited = np.zeros(grid.visit_shape[0] * grid.visit_shape[1], dtype=bool)
        self.path: FloatArray | None = None
        self.progress = 0
        self.blocked_for = 0.0
        self.goal_visit = -1
        vnx = grid.visit_shape[1]
        reach = math.ceil(_VISIT_RADIUS / _VISIT_CELL)
        offsets = [(dr, dc) for dr in range(-reach, reach + 1) for dc in range(-reach, reach + 1)
                   if math.hypot(dr, dc) * _VISIT_CELL <= _VISIT_RADIUS + _VISIT_CELL / 2]
        self.visit_offsets = np.array([dr * vnx + dc for dr, dc in offsets], dtype=np.int64)

    def mark(self, x: float, y: float) -> None:
        around = self.grid.visit_index(x, y) + self.visit_offsets
        self.visited[around[(around >= 0) & (around < self.visited.shape[0])]] = True

    def plan(self, x: float, y: float) -> None:
        """Path from (x, y) to the nearest-ish reachable open place not visited yet."""
        from scipy.sparse import csgraph

        self.path, self.progress = None, 0
        source = self.grid.node_near(x, y)
        if source < 0:
            return
        for attempt in range(3):
            limit = _SEARCH_LIMIT if attempt == 0 else np.inf
            dist, pred = csgraph.dijkstra(self.grid.graph, directed=False, indices=source,
                                          return_predecessors=True, limit=limit)
            goal = self._choose_goal(np.asarray(dist))
            if goal >= 0:
                break
            if attempt == 1:
                self.visited[:] = False  # everything reachable seen: start a new round
                self.mark(x, y)
        else:
            return
        nodes = [goal]
        while nodes[-1] != source:
            nodes.append(int(pred[nodes[-1]]))
        self.path = np.vstack(([x, y], self.grid.xy[nodes[::-1]]))
        self.goal_visit = int(self.grid.visit_cell[goal])

    def _choose_goal(self, dist: FloatArray) -> int:
        grid = self.grid
        reachable = np.isfinite(dist)
        fresh = reachable & ~self.visited[grid.visit_cell]
        open_fresh = fresh & (grid.clearance >= min(_OPEN_GOAL, float(grid.clearance.max())))
        for candidates in (open_fresh & (dist >= _MIN_GOAL_DISTANCE), open_fresh,
                           fresh & (dist >= _MIN_GOAL_DISTANCE)):
            if candidates.any():
                break
        else:
            return -1
        # Nearest unvisited place, randomised per visit cell so that seeds differ.
        noise = self.rng.uniform(1.0, 1.5, self.visited.shape[0])[grid.visit_cell]
        score = np.where(candidates, dist * noise - grid.clearance, np.inf)
        return int(np.argmin(score))

    def step(self, x: float, y: float, heading: float, dt: float) -> tuple[float, float, float]:
        """One control period: returns the next pose."""
        if self.path is None or np.hypot(*(self.path[-1] - (x, y))) < 0.15:
            self.plan(x, y)
        if self.path is None:  # nowhere to go: turn in place
            return x, y, heading + self.turn_rate * dt
        path = self.path
        window = path[self.progress:self.progress + 30]
        self.progress += int(np.argmin(np.hypot(window[:, 0] - x, window[:, 1] - y)))
        ahead = np.hypot(path[self.progress:, 0] - x, path[self.progress:, 1] - y)
        lookahead = 0.2 if self.blocked_for > 0.0 else _LOOKAHEAD
        far = np.flatnonzero(ahead >= lookahead)
        target = path[self.progress + (int(far[0]) if far.size else ahead.shape[0] - 1)]
        distance = float(np.hypot(*(target - (x, y))))
        alpha = float(wrap_angle(math.atan2(target[1] - y, target[0] - x) - heading))
        if abs(alpha) > 0.5 or distance < 1e-6:
            speed, omega = 0.0, float(np.clip(alpha / dt, -self.turn_rate, self.turn_rate))
        else:
            curvature = 2.0 * math.sin(alpha) / distance
            speed = self.speed
            if abs(speed * curvature) > self.turn_rate:
                speed = self.turn_rate / abs(curvature)
            omega = speed * curvature
        new_heading = heading + omega * dt
        mid = heading + omega * dt / 2
        nx, ny = x + speed * dt * math.cos(mid), y + speed * dt * math.sin(mid)
        if speed > 0.0:
            clear = float(self.world.distance_to_walls((nx, ny))[0])
            if clear < self.radius + _STEP_MARGIN:
                # The perfect proximity sensor says stop: turn only, then give up on the goal.
                self.blocked_for += dt
                if self.blocked_for > _GIVE_UP:
                    self.visited[self.goal_visit] = True
                    self.path, self.blocked_for = None, 0.0
                return x, y, new_heading
        self.blocked_for = 0.0
        return nx, ny, new_heading


def explore(world: World, seconds: float, seed: int, speed: float = DEFAULT_SPEED,
            dt: float = DEFAULT_DT, start: Sequence[float] | None = None, *,
            robot_radius: float = ROBOT_RADIUS, turn_rate: float = DEFAULT_TURN_RATE) -> Trajectory:
    """Wander a world for ``seconds`` without colliding, preferring places not visited yet.

    The explorer keeps a memory of visited 1 m cells. It picks as its goal the nearest
    reachable open place (clearance >= 0.55 m, so room and corridor middles) in a cell it has
    not visited, at least 3 m away by path, with seeded random weights breaking ties; it plans
    there on a 0.1 m grid whose cells keep ``robot_radius`` + 0.12 m from walls, with a cost that
    grows near walls, so paths follow corridor centre lines and pass doors in the middle, much
    like the generalized Voronoi graph the paper's robot traced; and it drives the path with a
    pure-pursuit controller (0.5 m look-ahead, turning in place for bearings over 0.5 rad). Its
    perfect proximity sensor (:meth:`World.distance_to_walls`) vetoes any step that would bring
    it closer than ``robot_radius`` + 0.02 m to a wall; after 1.5 s blocked it abandons the goal.
    When every reachable place is visited the memory is cleared and a new round begins.

    Openings narrower than about 2 (``robot_radius`` + 0.19) m (0.79 m for the default radius)
    are never planned through.

    Parameters
    ----------
    world : World
        Walls to explore; the grid covers their bounding box plus 0.5 m.
    seconds : float
        Duration, seconds; poses every ``dt``.
    seed : int
        Same seed and world, same trajectory.
    speed : float
        Cruising speed, m/s (slower only in tight turns).
    dt : float
        Control and sampling period, s.
    start : (x, y) or (x, y, heading), optional
        Default: the world's tour start (facing along it), else a seeded random open place.
    robot_radius : float
        Body radius, metres.
    turn_rate : float
        Maximum angular speed, rad/s.

    Returns
    -------
    Trajectory
        ``round(seconds / dt) + 1`` poses starting at ``t = 0``, each at least
        ``robot_radius`` + 0.02 m from every wall.

    Raises
    ------
    WorldError
        Bad parameters (a negative seed, say), more than :data:`MAX_POSES` poses, a world whose
        planning grid would exceed 10 million cells (about 316 m x 316 m, 2.5 GB), or a start
        closer than ``robot_radius`` + 0.02 m to a wall.
    """
    _check_explore_parameters(seconds, seed, speed, dt, robot_radius, turn_rate)
    rng = np.random.default_rng(seed)
    grid = _PlanningGrid.build(world, robot_radius + PLAN_MARGIN)
    # The start pose draws from ``rng`` before the explorer does (seeded runs depend on it).
    pose = _start_pose(world, grid, start, rng)
    _check_start_clear(world, pose, robot_radius)
    explorer = _Explorer(world, grid, rng, robot_radius, speed, turn_rate)
    return _drive_explorer(explorer, pose, round(seconds / dt), dt)


def _check_explore_parameters(seconds: float, seed: int, speed: float, dt: float,
                              robot_radius: float, turn_rate: float) -> None:
    """Raise :class:`WorldError` for :func:`explore` parameters it cannot use.

    Durations in seconds, speed in m/s, radius in metres, turn rate in rad/s must be finite and
    > 0, the seed an integer >= 0, and ``round(seconds / dt) + 1`` at most :data:`MAX_POSES`.
    """
    _check_positive(seconds=seconds, speed=speed, dt=dt, robot_radius=robot_radius,
                    turn_rate=turn_rate)
    check_seed(seed)
    _check_pose_count(round(seconds / dt) + 1, seconds, dt, "exploration")


def _check_start_clear(world: World, pose: tuple[float, float, float],
                       robot_radius: float) -> None:
    """Raise :class:`WorldError` when ``pose`` (x, y metres, heading) is too close to a wall.

    The limit is the one every explored step keeps, ``robot_radius`` + ``_STEP_MARGIN`` metres.
    """
    x, y, _ = pose
    if float(world.distance_to_walls((x, y))[0]) < robot_radius + _STEP_MARGIN:
        msg = (f"{world.name}: explore start ({x:g}, {y:g}) is closer than "
               f"{robot_radius + _STEP_MARGIN:g} m to a wall")
        raise WorldError(msg)


def _drive_explorer(explorer: _Explorer, pose: tuple[float, float, float], steps: int,
                    dt: float) -> Trajectory:
    """Run ``explorer`` for ``steps`` control periods of ``dt`` seconds from ``pose``.

    Parameters
    ----------
    explorer : _Explorer
        A fresh explorer (its visited-place memory is updated as it goes).
    pose : (x, y, heading)
        Start pose, metres and radians.
    steps : int
        Number of control periods.
    dt : float
        Control period, seconds.

    Returns
    -------
    Trajectory
        ``steps + 1`` poses at ``t = k * dt``, the start pose first.
    """
    x, y, heading = pose
    poses = np.empty((steps + 1, 3))
    poses[0] = x, y, heading
    for k in range(1, steps + 1):
        explorer.mark(x, y)
        x, y, heading = explorer.step(x, y, heading, dt)
        poses[k] = x, y, heading
    times = np.arange(steps + 1, dtype=np.float64) * dt
    return Trajectory(times, poses[:, 0], poses[:, 1], poses[:, 2])


def _start_pose(world: World, grid: _PlanningGrid, start: Sequence[float] | None,
                rng: np.random.Generator) -> tuple[float, float, float]:
    if start is not None:
        values = [float(v) for v in start]
        if len(values) not in (2, 3) or not all(math.isfinite(v) for v in values):
            msg = f"start must be finite (x, y) or (x, y, heading), got {tuple(start)}"
            raise WorldError(msg)
        return values[0], values[1], values[2] if len(values) == 3 else 0.0
    if world.start_pose is not None:
        return world.start_pose
    open_nodes = np.flatnonzero(grid.clearance >= min(_OPEN_GOAL, float(grid.clearance.max(
        initial=0.0))))
    if not open_nodes.size:
        msg = f"{world.name}: no place for the robot to start exploring"
        raise WorldError(msg)
    node = int(rng.choice(open_nodes))
    return float(grid.xy[node, 0]), float(grid.xy[node, 1]), float(rng.uniform(-np.pi, np.pi))


# --------------------------------------------------------------------------------------------
# Odometry
# --------------------------------------------------------------------------------------------

def with_odometry_drift(trajectory: Trajectory, seed: int, translation_noise: float = 0.01,
                        rotation_noise: float = 0.005, heading_bias: float = 0.001) -> Trajectory:
    """The dead-reckoned trajectory: true motion increments with odometry errors, integrated.

    Each step between two poses is read in the robot frame at the step's mid heading as a
    forward motion f, a lateral motion l (zero for a differential drive) and a turn δ. The
    odometer reports

    - f' = f + N(0, translation_noise² |f|): random wheel-travel error, std growing as √distance,
    - δ' = δ + heading_bias |f| + N(0, rotation_noise² (|f| + b/2 |δ|)): a systematic heading
      drift (unequal wheel diameters) and a random one from wheel slip, which grows with the
      wheels' travel, b/2 |δ| of it when turning in place (b/2 = :data:`HALF_WHEEL_BASE`),

    and the result integrates (f', l, δ') from the true first pose. Position error therefore
    grows with distance travelled (the heading error's effect, roughly quadratically).

    The defaults are assumed typical values for an uncalibrated Scout2-like base, not
    measurements: 0.01 m/√m (σ = 0.1 m after 100 m), 0.005 rad/√m (σ = 2.9° after 100 m) and a
    bias of 0.001 rad/m (5.7° after 100 m).

    Parameters
    ----------
    trajectory : Trajectory
        True poses.
    seed : int
        Same seed, same drift.
    translation_noise : float
        m/√m, >= 0.
    rotation_noise : float
        rad/√m of wheel travel, >= 0.
    heading_bias : float
        rad/m, either sign (positive drifts counter-clockwise).

    Returns
    -------
    Trajectory
        Same times; equal to ``trajectory`` when all three parameters are 0.

    Raises
    ------
    WorldError
        A negative seed, a negative or non-finite noise, a non-finite bias.
    """
    _check_drift_parameters(translation_noise, rotation_noise, heading_bias)
    check_seed(seed)
    rng = np.random.default_rng(seed)
    forward, lateral, turn = _step_increments(trajectory)
    travel = np.abs(forward)
    # One draw for both errors: row 0 perturbs travel, row 1 the turn (the order is part of
    # what a seed means).
    noise = rng.standard_normal((2, forward.shape[0]))
    forward_read = forward + translation_noise * np.sqrt(travel) * noise[0]
    turn_read = (turn + heading_bias * travel
                 + rotation_noise * np.sqrt(travel + HALF_WHEEL_BASE * np.abs(turn)) * noise[1])
    x, y, heading = _integrate_steps(trajectory, forward_read, lateral, turn_read)
    return Trajectory(trajectory.t.copy(), x, y, heading)


def _check_drift_parameters(translation_noise: float, rotation_noise: float,
                            heading_bias: float) -> None:
    """Raise :class:`WorldError` for a negative or non-finite noise or a non-finite bias."""
    for name, value in (("translation_noise", translation_noise),
                        ("rotation_noise", rotation_noise)):
        if not (math.isfinite(value) and value >= 0.0):
            msg = f"{name} must be a finite number >= 0, got {value}"
            raise WorldError(msg)
    if not math.isfinite(heading_bias):
        msg = f"heading_bias must be finite, got {heading_bias}"
        raise WorldError(msg)


def _step_increments(trajectory: Trajectory) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Each step between poses in the robot frame at the step's mid heading.

    Parameters
    ----------
    trajectory : Trajectory
        Poses, n of them.

    Returns
    -------
    forward, lateral : ndarray, shape (n - 1,)
        Motion along and across the mid heading, metres.
    turn : ndarray, shape (n - 1,)
        Heading change, radians.
    """
    dx, dy = np.diff(trajectory.x), np.diff(trajectory.y)
    turn = np.diff(trajectory.heading)
    mid = trajectory.heading[:-1] + turn / 2
    forward = dx * np.cos(mid) + dy * np.sin(mid)
    lateral = -dx * np.sin(mid) + dy * np.cos(mid)
    return forward, lateral, turn


def _integrate_steps(trajectory: Trajectory, forward: FloatArray, lateral: FloatArray,
                     turn: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Dead reckoning: step increments integrated from ``trajectory``'s first pose.

    Parameters
    ----------
    trajectory : Trajectory
        Supplies the first pose only.
    forward, lateral : ndarray, shape (n - 1,)
        Motion along and across each step's mid heading, metres.
    turn : ndarray, shape (n - 1,)
        Heading change of each step, radians.

    Returns
    -------
    x, y, heading : ndarray, shape (n,)
        Integrated poses, metres and radians (unwrapped).
    """
    heading = trajectory.heading[0] + np.concatenate(([0.0], np.cumsum(turn)))
    mid = heading[:-1] + turn / 2
    x = trajectory.x[0] + np.concatenate(([0.0], np.cumsum(
        forward * np.cos(mid) - lateral * np.sin(mid))))
    y = trajectory.y[0] + np.concatenate(([0.0], np.cumsum(
        forward * np.sin(mid) + lateral * np.cos(mid))))
    return x, y, heading


# --------------------------------------------------------------------------------------------
# Localisation noise
# --------------------------------------------------------------------------------------------

#: Stationary std of a localiser's position error in x and in y, metres (assumed typical of
#: AMCL or a fused odometry indoors, not a measurement).
DEFAULT_POSITION_SIGMA = 0.03
#: Stationary std of its heading error, radians (1°, assumed likewise).
DEFAULT_HEADING_SIGMA = math.radians(1.0)
#: How long its error takes to forget itself, seconds (assumed: a filter updating at a few Hz
#: whose estimate wanders rather than jumps).
DEFAULT_CORRELATION_TIME = 1.0
#: Mixed into the seed so that the same seed draws other numbers here than in
#: :func:`with_odometry_drift` (the two can be applied to one trajectory).
_LOCALISATION_STREAM = 0x10CA1


def with_localisation_noise(trajectory: Trajectory, seed: int,
                            position_sigma: float = DEFAULT_POSITION_SIGMA,
                            heading_sigma: float = DEFAULT_HEADING_SIGMA,
                            correlation_time: float = DEFAULT_CORRELATION_TIME) -> Trajectory:
    """The trajectory a localiser believes: the true one plus a slowly wandering error.

    The errors in x, in y (world frame) and in heading are three independent first-order
    Gauss-Markov (Ornstein-Uhlenbeck) processes, each stationary from the first pose:

        e(t_0) ~ N(0, σ²),   e(t_k) = a_k e(t_{k-1}) + σ √(1 − a_k²) ξ_k,   a_k = exp(−Δt_k / τ),

    with ξ_k standard normal and Δt_k the time between poses: the exact discretisation of
    de = −e/τ dt + σ √(2/τ) dW, so at any times e has std σ and corr(e(t), e(t + Δ)) =
    exp(−Δ/τ), however unevenly the poses are spaced. Unlike :func:`with_odometry_drift` the
    error does not grow: a localiser keeps the robot within a few centimetres of the truth, but
    not at the truth, and its error changes smoothly (a filter's estimate wanders).

    The defaults, 0.03 m, 1° and 1 s, are assumed typical localisation errors of a robot
    running AMCL against a good map or a fused wheel/IMU odometry indoors, not measurements.

    Parameters
    ----------
    trajectory : Trajectory
        True poses.
    seed : int
        Same seed, same error (a stream of its own: the same seed in
        :func:`with_odometry_drift` draws other numbers).
    position_sigma : float
        Stationary std of the x and of the y error, metres, >= 0.
    heading_sigma : float
        Stationary std of the heading error, radians, >= 0.
    correlation_time : float
        τ, seconds, > 0.

    Returns
    -------
    Trajectory
        Same times; equal to ``trajectory`` when both sigmas are 0.

    Raises
    ------
    WorldError
        A negative seed, a negative or non-finite sigma, a correlation time that is not a
        finite number > 0.

    Examples
    --------
    >>> truth = follow_waypoints([[0, 0], [10, 0]])
    >>> believed = with_localisation_noise(truth, seed=0)
    >>> bool(abs(believed.x - truth.x).max() < 0.2), bool((believed.t == truth.t).all())
    (True, True)
    """
    _check_localisation_parameters(position_sigma, heading_sigma, correlation_time)
    seed = check_seed(seed)
    rng = np.random.default_rng([_LOCALISATION_STREAM, seed])
    # One draw for the three errors: rows x, y, heading (the order is part of what a seed means).
    shocks = rng.standard_normal((3, len(trajectory)))
    decay = np.exp(-np.diff(trajectory.t) / correlation_time)
    unit = _gauss_markov(shocks, decay)
    return Trajectory(trajectory.t.copy(), trajectory.x + position_sigma * unit[0],
                      trajectory.y + position_sigma * unit[1],
                      trajectory.heading + heading_sigma * unit[2])


def _gauss_markov(shocks: FloatArray, decay: FloatArray) -> FloatArray:
    """Unit-variance stationary Gauss-Markov sequences driven by ``shocks``.

    Parameters
    ----------
    shocks : ndarray, shape (m, n)
        Standard normal draws, one row per sequence.
    decay : ndarray, shape (n - 1,)
        exp(−Δt / τ) of each step, in (0, 1].

    Returns
    -------
    ndarray, shape (m, n)
        e[:, 0] = shocks[:, 0]; e[:, k] = decay[k-1] e[:, k-1] + √(1 − decay²) shocks[:, k].
    """
    innovation = np.sqrt(1.0 - decay * decay)
    out = np.empty_like(shocks)
    out[:, 0] = shocks[:, 0]
    for k in range(1, shocks.shape[1]):
        out[:, k] = decay[k - 1] * out[:, k - 1] + innovation[k - 1] * shocks[:, k]
    return out


def _check_localisation_parameters(position_sigma: float, heading_sigma: float,
                                   correlation_time: float) -> None:
    """Raise :class:`WorldError` for a negative or non-finite sigma or a bad correlation time."""
    for name, value in (("position_sigma", position_sigma), ("heading_sigma", heading_sigma)):
        if not (math.isfinite(value) and value >= 0.0):
            msg = f"{name} must be a finite number >= 0, got {value}"
            raise WorldError(msg)
    _check_positive(correlation_time=correlation_time)
