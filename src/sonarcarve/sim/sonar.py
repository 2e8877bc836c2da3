"""Ultrasonic sensor physics: what a sonar hears when it fires at a world of walls.

A firing is traced as a fan of rays across the beam (paper, section 2: the main lobe of width φ).
Each ray stops at the first wall it meets. Walls are smooth, so sound is reflected
*specularly*: a ray comes back to the sensor only when it meets the wall within the critical
angle of the wall's normal, or when it meets the wall near a corner or a free wall end (edges
and corners scatter in every direction). Time of flight measures the *first* echo, so the
nearest echoing ray wins and its hit point is the reading's true reflection point.

On top of that come the failures the paper met on its Scout2 (Appendix B), each with a rate:

* **crosstalk**: the late echo of a previous ping (another sensor's, typically off a wall
  beyond its maximum range) arrives while this sensor listens; the range is that echo's path
  length minus the time between the two firings, usually wrong;
* **floor bounce**: while the robot tilts (random episodes), sensors facing down the tilt hear
  the floor at about 0.6 m;
* **multipath**: a ray reflected specularly off one wall meets a second wall head-on and comes
  back the same way: the range is the length of the bounced path, too long.

Every echo carries its truth: its :class:`EchoKind` and, where there is one, its reflection
point (a wall point for direct echoes, the second wall point for multipath ones).

That is the ``"specular"`` echo model (:attr:`SonarPhysics.echo_model`, the default). The
``"amplitude"`` model (:mod:`sonarcarve.sim.amplitude`) replaces the critical angle and the
echo probabilities by received levels against a detection threshold: walls answer by their
mirror image (heard when their normal falls in the transducer's beam pattern, main lobe or side
lobes, loudly enough for the range), by diffuse scattering ray by ray, and corners and wall
ends by retro-reflection or diffraction; multipath and crosstalk paths are followed the same way
and heard when loud enough. Floor echoes keep their episodes and probability in both models.

With a :class:`~sonarcarve.sim.scene.Scene` (``fire_sonars(..., scene=)``), each firing is traced
against the walls plus the scene's obstacles present at its time, where they are at that time;
everything else is the same (and without a scene, bit for bit what it was).
"""

from __future__ import annotations

import math
import weakref
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass, field, fields, replace
from enum import IntEnum

import numpy as np
import numpy.typing as npt
from scipy.spatial import cKDTree
from scipy.special import ndtri

from sonarcarve.robot import RobotDescription
from sonarcarve.sim.amplitude import (
    AmplitudeModel,
    SonarPhysicsError,
    diffuse_echo_db,
    mirror_echo_db,
    path_echo_db,
    point_echo_db,
)
from sonarcarve.sim.scene import Scene
from sonarcarve.sim.world import World
from sonarcarve.typing import BoolArray, FloatArray, IntArray

__all__ = [
    "DEFAULT_PHYSICS",
    "ECHO_MODELS",
    "NO_ECHO",
    "EchoKind",
    "Echoes",
    "Firings",
    "SonarPhysics",
    "SonarPhysicsError",
    "fire_sonars",
]


#: Kind code of a firing that heard nothing.
NO_ECHO = -1

#: Firings traced together: bounds the (rays x walls) arrays to a few tens of megabytes while
#: keeping each batch's robot positions close together, so the wall pre-filter stays tight.
_CHUNK_FIRINGS = 256

#: Distance (m) by which a bounced ray starts off its first wall, so it does not re-hit it.
_BOUNCE_OFFSET = 1e-7

#: The echo models :attr:`SonarPhysics.echo_model` accepts.
ECHO_MODELS = ("specular", "amplitude")

#: Amplitude model: candidate echoes more than this many noise deviations below the threshold
#: are dropped before the (costly) line-of-sight test; they would be heard once in 10⁹.
_PRUNE_SIGMAS = 6.0


class EchoKind(IntEnum):
    """What produced a reading: the code stored per reading in the truth arrays."""

    DIRECT = 0
    CROSSTALK = 1
    FLOOR = 2
    MULTIPATH = 3

    @property
    def label(self) -> str:
        """Lower-case name, as written in truth files: ``direct``, ``crosstalk``, ..."""
        return self.name.lower()


@dataclass(frozen=True)
class SonarPhysics:
    """How the simulated sensors behave; every effect can be switched off on its own.

    Attributes
    ----------
    rays_per_beam : int
        Rays traced evenly across the beam, edges included (odd: one on the axis). At 31
        rays a 22.5° beam has rays 0.75° apart, 8 cm apart at 6.5 m.
    specular : bool
        Smooth walls (True): a ray echoes only within ``critical_angle`` of the wall normal or
        near a corner. False: every wall echoes from any angle (the idealised "arc" sensor).
    critical_angle : float
        Largest incidence angle (between the ray and the wall normal), radians, at which a
        smooth wall still returns an echo. Default 17.5°: the middle of the 15-20° range
        commonly quoted for Polaroid transducers on smooth walls (assumed, not measured here).
    corner_radius : float
        Metres: a ray meeting a wall within this distance of a corner or a free wall end echoes
        whatever its incidence (edges and corners scatter sound back).
    corner_echoes : bool
        Corners and free wall ends inside the beam and in sight echo from the corner point
        itself (exactly, not only where a ray happens to land near them).
    range_noise : float
        Standard deviation of the Gaussian range noise, metres (default 1 cm).
    quantise : bool
        Round ranges to the robot's range resolution.
    crosstalk_probability : float
        Chance that a late echo of a recent ping, arriving while this sensor listens and from
        within ``crosstalk_acceptance`` of its axis, is loud enough to be heard. The default
        0.2 is a judgement (such echoes have travelled 14 m or more); on the office tour it
        makes about 5 % of scout2's readings crosstalk (``benchmarks/simulate_speed.py``).
    crosstalk_lookback : int
        How many previous firings can still be echoing (2: the last two pings).
    crosstalk_acceptance : float
        Half-angle, radians, about the sensor axis from which a sensor hears a stray echo
        (default 90°: the front half-plane; the robot body shadows the rest).
    floor_episode_rate : float
        Tilt episodes (bumps, ramps, door sills) per second of travel time.
    floor_episode_duration : float
        Mean length of a tilt episode, seconds (exponentially distributed).
    floor_probability : float
        Chance that a sensor facing down the tilt hears the floor during an episode.
    floor_range : float
        Mean range of a floor echo, metres: the paper's Scout2 sensors sit 10.25 in above the
        floor and hear it "at just over 2 feet" (Appendix B), so 0.62 m.
    floor_range_sd : float
        Standard deviation of the floor echo range, metres.
    floor_half_angle : float
        Sensors within this angle of the tilt direction, radians, see the floor.
    multipath_probability : float
        Chance that a bounced echo (specular off one wall, head-on at a second) is loud enough
        to be heard, when it arrives before any direct echo.
    sound_speed : float
        Speed of sound, m/s (343: dry air at 20 °C); converts firing gaps to ranges.
    echo_model : str
        ``"specular"`` (the default): rays across the beam, smooth walls echo within
        ``critical_angle``, spurious echoes by their probabilities. ``"amplitude"``: echo
        levels from the transducer's beam pattern, spreading, absorption and the walls'
        reflection against a noisy detection threshold, parameters in ``amplitude``
        (:mod:`sonarcarve.sim.amplitude`). The amplitude model ignores ``rays_per_beam``,
        ``specular``, ``critical_angle``, ``corner_radius`` and ``corner_echoes``, and uses
        ``crosstalk_probability`` and ``multipath_probability`` only as switches (0: off):
        loudness decides which of those echoes are heard.
    amplitude : AmplitudeModel
        Parameters of the amplitude model (unused by the specular one).
    """

    rays_per_beam: int = 31
    specular: bool = True
    critical_angle: float = math.radians(17.5)
    corner_radius: float = 0.05
    corner_echoes: bool = True
    range_noise: float = 0.01
    quantise: bool = True
    crosstalk_probability: float = 0.2
    crosstalk_lookback: int = 2
    crosstalk_acceptance: float = math.radians(90.0)
    floor_episode_rate: float = 1.0 / 30.0
    floor_episode_duration: float = 1.0
    floor_probability: float = 0.5
    floor_range: float = 0.62
    floor_range_sd: float = 0.05
    floor_half_angle: float = math.radians(60.0)
    multipath_probability: float = 0.5
    sound_speed: float = 343.0
    echo_model: str = "specular"
    amplitude: AmplitudeModel = field(default_factory=AmplitudeModel)

    def __post_init__(self) -> None:
        if self.echo_model not in ECHO_MODELS:
            choices = ", ".join(repr(name) for name in ECHO_MODELS)
            _bad("echo_model", self.echo_model, f"must be one of {choices}")
        if not isinstance(self.amplitude, AmplitudeModel):
            _bad("amplitude", self.amplitude, "must be an AmplitudeModel")
        if self.rays_per_beam < 1:
            _bad("rays_per_beam", self.rays_per_beam, "must be at least 1")
        if self.crosstalk_lookback < 0:
            _bad("crosstalk_lookback", self.crosstalk_lookback, "must be >= 0")
        if not 0.0 <= self.critical_angle <= math.pi / 2:
            _bad("critical_angle", self.critical_angle, "must lie in [0, π/2] radians")
        for name in ("crosstalk_probability", "floor_probability", "multipath_probability"):
            if not 0.0 <= getattr(self, name) <= 1.0:
                _bad(name, getattr(self, name), "must lie in [0, 1]")
        for name in ("corner_radius", "range_noise", "floor_episode_rate",
                     "floor_episode_duration", "floor_range", "floor_range_sd",
                     "floor_half_angle", "crosstalk_acceptance"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0.0):
                _bad(name, value, "must be a finite number >= 0")
        if not (math.isfinite(self.sound_speed) and self.sound_speed > 0.0):
            _bad("sound_speed", self.sound_speed, "must be > 0")

    @classmethod
    def clean(cls) -> SonarPhysics:
        """Specular walls and corners only: no noise, no quantisation, no spurious echoes."""
        return cls(range_noise=0.0, quantise=False, crosstalk_probability=0.0,
                   floor_episode_rate=0.0, multipath_probability=0.0)

    @classmethod
    def ideal(cls) -> SonarPhysics:
        """The arc model's sensor: every wall in the beam echoes; nothing else goes wrong."""
        return replace(cls.clean(), specular=False)


#: The default sensor model (every effect on, at the documented defaults).
DEFAULT_PHYSICS = SonarPhysics()


@dataclass(frozen=True, eq=False)
class Firings:
    """When and where sensors fired: struct of arrays, shape (n,), in time order.

    Attributes
    ----------
    t : ndarray
        Firing times, seconds.
    sensor : ndarray of int64
        Index of the sensor that fired.
    x, y, theta : ndarray
        The sensor's true origin (m) and axis (rad) in the world frame at that time.
    """

    t: FloatArray
    sensor: IntArray
    x: FloatArray
    y: FloatArray
    theta: FloatArray

    def __len__(self) -> int:
        return int(self.t.shape[0])

    def __getitem__(self, index: slice | IntArray | BoolArray) -> Firings:
        return Firings(**{f.name: getattr(self, f.name)[index] for f in fields(self)})


@dataclass(frozen=True, eq=False)
class Echoes:
    """What each firing heard: struct of arrays aligned with :class:`Firings`.

    Attributes
    ----------
    range : ndarray, shape (n,)
        Measured range (noise, quantisation), metres; NaN where the sensor heard nothing.
    true_range : ndarray, shape (n,)
        Noise-free range of the echo that was heard (half its path length, less the firing gap
        for crosstalk), metres; NaN where nothing was heard.
    kind : ndarray of int64, shape (n,)
        :class:`EchoKind` code, or :data:`NO_ECHO`.
    reflection : ndarray, shape (n, 2)
        True reflection point in the world frame, metres; NaN for floor and crosstalk echoes
        and where nothing was heard.
    obstacle : ndarray of int64, shape (n,)
        Index of the :class:`~sonarcarve.sim.scene.Scene` obstacle the echo came from (its
        reflection point lies on it), -1 for a static wall, no reflection point, or no scene.
    """

    range: FloatArray
    true_range: FloatArray
    kind: IntArray
    reflection: FloatArray
    obstacle: IntArray

    def __len__(self) -> int:
        return int(self.range.shape[0])

    @property
    def heard(self) -> BoolArray:
        """Firings that produced a reading."""
        return np.asarray(self.kind != NO_ECHO)


def fire_sonars(
    world: World,
    robot: RobotDescription,
    firings: Firings,
    physics: SonarPhysics | None = None,
    rng: np.random.Generator | None = None,
    on_progress: Callable[[int, int], None] | None = None,
    *,
    scene: Scene | None = None,
) -> Echoes:
    """Simulate every firing: trace its beam, add spurious echoes, keep the first one heard.

    Parameters
    ----------
    world : World
        The walls.
    robot : RobotDescription
        Beam widths, range limits, resolution and firing period of the sensors.
    firings : Firings
        Firing times and true sensor poses, in time order.
    physics : SonarPhysics, optional
        Which effects to simulate and how strongly (default :data:`DEFAULT_PHYSICS`).
    rng : numpy.random.Generator, optional
        Source of randomness (default: seeded with 0). Every random draw is made up front in
        a fixed order, so a seed fixes the output whatever the batching.
    on_progress : callable, optional
        Called as ``on_progress(done, total)`` (firings traced so far) after each batch.
    scene : Scene, optional
        Obstacles that appear, vanish or move (:mod:`sonarcarve.sim.scene`): each firing meets
        the walls plus the obstacles present at its time, at their position then. No draw
        depends on the scene, so a seed gives the same noise with or without one.

    Returns
    -------
    Echoes
        One entry per firing.
    """
    physics = DEFAULT_PHYSICS if physics is None else physics
    gen = np.random.default_rng(0) if rng is None else rng
    n = len(firings)
    draws = _Draws.make(gen, firings, physics)
    scenery = _Scenery.make(world, scene, firings)
    far_range = robot.max_range + physics.sound_speed * _max_gap(firings, physics) / 2.0
    model = _ECHO_MODEL_TRACERS[physics.echo_model]
    traced, crosstalk, multipath = model(scenery, robot, firings, physics, far_range, draws,
                                         gen, on_progress)
    floor = _floor(robot, firings, physics, draws)
    candidates = np.column_stack([traced.direct_range, crosstalk, floor, multipath])
    winner = np.argmin(candidates, axis=1)  # ties go to the lower code: direct first
    true_range = candidates[np.arange(n), winner]
    measured = _measure(true_range + physics.range_noise * draws.noise, robot, physics)
    heard = np.isfinite(true_range) & (measured >= robot.min_range) & (measured <= robot.max_range)
    reflection = _reflections(traced, heard, winner)
    obstacle = (np.full(n, -1, dtype=np.int64) if scene is None
                else scene.obstacle_hit(reflection, firings.t))
    return Echoes(
        range=np.where(heard, measured, np.nan),
        true_range=np.where(heard, true_range, np.nan),
        kind=np.where(heard, winner, NO_ECHO).astype(np.int64),
        reflection=reflection,
        obstacle=obstacle,
    )


#: Ranges a model's tracing yields: the beams (direct and multipath echoes, late-echo raw
#: material), then the crosstalk and multipath echo heard by each firing (inf: none).
_ModelEchoes = tuple["_Traced", FloatArray, FloatArray]


def _specular_echoes(scenery: _Scenery, robot: RobotDescription, firings: Firings,
                     physics: SonarPhysics, far_range: float, draws: _Draws,
                     rng: np.random.Generator,
                     on_progress: Callable[[int, int], None] | None) -> _ModelEchoes:
    """The specular model: ray tracing, then crosstalk and multipath by their probabilities."""
    traced = _Traced.empty(len(firings), physics.rays_per_beam)

    def trace(lo: int, hi: int) -> None:
        for a, b, geometry in scenery.pieces(lo, hi):
            _trace_chunk(geometry, robot, firings[a:b], physics, far_range, traced, a)

    _trace_all(traced, scenery.walls, trace, on_progress)
    crosstalk = _crosstalk(robot, firings, physics, traced)
    return (traced,
            np.where(draws.crosstalk < physics.crosstalk_probability, crosstalk, np.inf),
            np.where(draws.multipath < physics.multipath_probability, traced.multipath_range,
                     np.inf))


def _amplitude_echoes(scenery: _Scenery, robot: RobotDescription, firings: Firings,
                      physics: SonarPhysics, far_range: float, draws: _Draws,
                      rng: np.random.Generator,
                      on_progress: Callable[[int, int], None] | None) -> _ModelEchoes:
    """The amplitude model: every candidate echo heard or not by its level (module doc)."""
    # Drawn after every draw the specular model makes, so theirs keep their order.
    key = int(rng.integers(0, 2**63 - 1))
    tolerance = physics.amplitude.right_corner_tolerance
    traced = _Traced.empty(len(firings), 0)

    def trace(lo: int, hi: int) -> None:
        for a, b, geometry in scenery.pieces(lo, hi):
            _trace_amplitude_chunk(geometry, scenery.corners(geometry, tolerance), robot,
                                   firings[a:b], physics, traced, a, key)

    _trace_all(traced, scenery.walls, trace, on_progress)
    crosstalk = _crosstalk_amplitude(scenery, robot, firings, physics, far_range, key)
    return traced, crosstalk, traced.multipath_range


_ECHO_MODEL_TRACERS = {"specular": _specular_echoes, "amplitude": _amplitude_echoes}


def _reflections(traced: _Traced, heard: BoolArray, winner: IntArray) -> FloatArray:
    """True reflection point of each heard direct or multipath echo, shape (n, 2), metres.

    NaN rows for floor and crosstalk echoes (no wall point) and for firings not ``heard``;
    ``winner`` is the :class:`EchoKind` code of each firing's echo.
    """
    reflection = np.full((heard.shape[0], 2), np.nan)
    direct = heard & (winner == EchoKind.DIRECT)
    bounced = heard & (winner == EchoKind.MULTIPATH)
    reflection[direct] = traced.direct_point[direct]
    reflection[bounced] = traced.multipath_point[bounced]
    return reflection


def _measure(r: FloatArray, robot: RobotDescription, physics: SonarPhysics) -> FloatArray:
    """Quantise ranges to the robot's resolution (round to nearest) when asked."""
    if physics.quantise and robot.range_resolution > 0.0:
        return np.asarray(np.round(r / robot.range_resolution) * robot.range_resolution)
    return r


# --------------------------------------------------------------------------- random draws


@dataclass(frozen=True)
class _Draws:
    """Every random number of a simulation, drawn in one fixed order.

    ``tilt`` is the robot-frame direction the robot tilts towards at each firing (NaN: level).
    """

    noise: FloatArray
    crosstalk: FloatArray
    multipath: FloatArray
    floor_gate: FloatArray
    floor_range: FloatArray
    tilt: FloatArray

    @classmethod
    def make(cls, rng: np.random.Generator, firings: Firings, physics: SonarPhysics) -> _Draws:
        n = len(firings)
        noise = rng.standard_normal(n)
        crosstalk = rng.random(n)
        multipath = rng.random(n)
        floor_gate = rng.random(n)
        floor_range = physics.floor_range + physics.floor_range_sd * rng.standard_normal(n)
        t0, t1 = (float(firings.t[0]), float(firings.t[-1])) if n else (0.0, 0.0)
        count = int(rng.poisson(physics.floor_episode_rate * (t1 - t0)))
        starts = rng.uniform(t0, t1, count)
        ends = starts + rng.exponential(physics.floor_episode_duration, count)
        directions = rng.uniform(-math.pi, math.pi, count)
        tilt = np.full(n, np.nan)
        for start, end, direction in zip(starts, ends, directions, strict=True):
            lo, hi = np.searchsorted(firings.t, [start, end], side="left")
            tilt[lo:hi] = direction
        return cls(noise, crosstalk, multipath, floor_gate, floor_range, tilt)


def _max_gap(firings: Firings, physics: SonarPhysics) -> float:
    """Longest time back to a firing whose late echoes can still be heard (crosstalk)."""
    lag = physics.crosstalk_lookback
    if physics.crosstalk_probability <= 0.0 or lag == 0 or len(firings) <= lag:
        return 0.0
    return float(np.max(firings.t[lag:] - firings.t[:-lag]))


# --------------------------------------------------------------------------- walls


@dataclass(frozen=True, eq=False)
class _WallGeometry:
    """A world with what tracing needs precomputed: unit normals, bounding boxes, corners.

    ``scatter`` holds the corners and free wall ends (shape (m, 2)): every segment endpoint
    except where exactly two collinear walls continue each other (a wall split in two is still
    one smooth wall there).
    """

    world: World
    normals: FloatArray
    boxes: FloatArray
    scatter: FloatArray
    tree: cKDTree | None

    @classmethod
    def make(cls, world: World) -> _WallGeometry:
        seg = world.segments
        edge = seg[:, 2:] - seg[:, :2]
        length = np.maximum(np.hypot(edge[:, 0], edge[:, 1]), 1e-300)
        normals = np.column_stack((-edge[:, 1], edge[:, 0])) / length[:, None]
        xs, ys = seg[:, [0, 2]], seg[:, [1, 3]]
        boxes = np.column_stack((xs.min(axis=1), ys.min(axis=1), xs.max(axis=1), ys.max(axis=1)))
        scatter = _scatter_points(seg)
        tree = cKDTree(scatter) if scatter.shape[0] else None
        return cls(world, normals, boxes, scatter, tree)

    def near(self, xmin: float, ymin: float, xmax: float, ymax: float,
             margin: float) -> tuple[World, IntArray, FloatArray]:
        """Walls (as a world, plus their global indices) and corners in a box grown by margin."""
        b = self.boxes
        keep = ((b[:, 2] >= xmin - margin) & (b[:, 0] <= xmax + margin)
                & (b[:, 3] >= ymin - margin) & (b[:, 1] <= ymax + margin))
        index = np.flatnonzero(keep)
        s = self.scatter
        corner_keep = ((s[:, 0] >= xmin - margin) & (s[:, 0] <= xmax + margin)
                       & (s[:, 1] >= ymin - margin) & (s[:, 1] <= ymax + margin))
        return replace(self.world, segments=self.world.segments[index]), index, s[corner_keep]

    def near_corner(self, points: FloatArray, radius: float) -> BoolArray:
        """Which points, shape (k, 2), lie within ``radius`` of a corner or free wall end."""
        if self.tree is None or radius <= 0.0 or points.shape[0] == 0:
            return np.zeros(points.shape[0], dtype=bool)
        distance, _ = self.tree.query(points, k=1, distance_upper_bound=radius * (1 + 1e-12))
        return np.asarray(np.isfinite(distance))


#: Geometries of a scene's runs kept built at once (a moving obstacle makes one per firing).
_SCENERY_CACHE = 512


class _Scenery:
    """The walls each firing meets: the world's, or the world's plus a scene's obstacles.

    :meth:`pieces` cuts a range of firings into runs that meet the same walls, each with its
    :class:`_WallGeometry` (built once per run, the last :data:`_SCENERY_CACHE` kept). Without
    a scene there is one run, and one geometry, the world's, built up front.
    """

    def __init__(self, world: World, scene: Scene | None, times: FloatArray,
                 starts: IntArray) -> None:
        self.world = world
        self.scene = scene
        self.times = times
        self.starts = starts
        obstacle_walls = 0 if scene is None else sum(o.segments.shape[0] for o in scene.obstacles)
        #: Most walls any firing can meet (0: no firing meets any).
        self.walls = len(world) + obstacle_walls
        self._built: OrderedDict[int, _WallGeometry] = OrderedDict()
        self._corners: weakref.WeakKeyDictionary[_WallGeometry, _Corners] = (
            weakref.WeakKeyDictionary())
        if scene is None:
            self._built[0] = _WallGeometry.make(world)

    @classmethod
    def make(cls, world: World, scene: Scene | None, firings: Firings) -> _Scenery:
        if scene is None:
            return cls(world, None, firings.t, np.zeros(1, dtype=np.int64))
        return cls(world, scene, firings.t, scene.epochs(firings.t))

    def pieces(self, lo: int, hi: int) -> list[tuple[int, int, _WallGeometry]]:
        """Firings ``lo:hi`` as runs ``(a, b, geometry)`` that meet the same walls."""
        if self.scene is None:
            return [(lo, hi, self._built[0])]
        first = int(np.searchsorted(self.starts, lo, side="right")) - 1
        out = []
        run = first
        while run < self.starts.shape[0] and self.starts[run] < hi:
            a = max(lo, int(self.starts[run]))
            b = min(hi, int(self.starts[run + 1]) if run + 1 < self.starts.shape[0] else hi)
            geometry = self._geometry(run)
            if len(geometry.world):
                out.append((a, b, geometry))
            run += 1
        return out

    def corners(self, geometry: _WallGeometry, tolerance: float) -> _Corners:
        """The amplitude model's corners of ``geometry``, made once per geometry."""
        found = self._corners.get(geometry)
        if found is None:
            found = self._corners[geometry] = _Corners.make(geometry, tolerance)
        return found

    def _geometry(self, run: int) -> _WallGeometry:
        found = self._built.get(run)
        if found is not None:
            self._built.move_to_end(run)
            return found
        assert self.scene is not None  # a static world's one geometry is always built
        made = _WallGeometry.make(self.scene.world_at(self.world,
                                                      float(self.times[self.starts[run]])))
        self._built[run] = made
        if len(self._built) > _SCENERY_CACHE:
            self._built.popitem(last=False)
        return made


def _scatter_points(seg: FloatArray, tol: float = 1e-9) -> FloatArray:
    """Corners and free ends of the walls ``seg`` (n, 4), duplicates merged; shape (m, 2).

    An endpoint is *not* a corner only where exactly one other wall ends at it and continues
    it in a straight line, with no third wall touching the point.
    """
    n = seg.shape[0]
    if n == 0:
        return np.zeros((0, 2))
    ends = np.concatenate([seg[:, :2], seg[:, 2:]])  # end k belongs to wall k % n
    owner = np.arange(2 * n) % n
    pairs = cKDTree(ends).query_pairs(tol, output_type="ndarray")
    pairs = pairs[owner[pairs[:, 0]] != owner[pairs[:, 1]]]
    count = np.bincount(pairs.ravel(), minlength=2 * n)
    partner = np.full(2 * n, -1)
    single = pairs[(count[pairs[:, 0]] == 1) & (count[pairs[:, 1]] == 1)]
    partner[single[:, 0]], partner[single[:, 1]] = single[:, 1], single[:, 0]
    candidates = np.flatnonzero(partner >= 0)
    edge = seg[:, 2:] - seg[:, :2]
    # Direction from each end into its own wall.
    inward = np.where((np.arange(2 * n) < n)[:, None], edge[owner], -edge[owner])
    a, b = inward[candidates], inward[partner[candidates]]
    cross = np.abs(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0])
    scale = np.hypot(a[:, 0], a[:, 1]) * np.hypot(b[:, 0], b[:, 1])
    straight = (cross <= 1e-9 * scale) & (np.sum(a * b, axis=1) < 0.0)
    candidates = candidates[straight]
    crowded = _touching_count(seg, ends[candidates], tol) > 2  # a third wall meets the joint
    keep = np.ones(2 * n, dtype=bool)
    keep[candidates[~crowded]] = False
    points = ends[keep]
    return np.asarray(np.unique(np.round(points, 9), axis=0)) if points.size else points


def _touching_count(seg: FloatArray, points: FloatArray, tol: float) -> IntArray:
    """How many walls pass within ``tol`` of each point, shape (k,); blocks bound memory."""
    counts = np.zeros(points.shape[0], dtype=np.int64)
    a, edge = seg[:, :2], seg[:, 2:] - seg[:, :2]
    length2 = np.maximum(np.sum(edge * edge, axis=1), 1e-300)
    step = max(1, (1 << 18) // max(seg.shape[0], 1))
    for lo in range(0, points.shape[0], step):
        p = points[lo:lo + step]
        u = np.clip(np.einsum("kwj,wj->kw", p[:, None, :] - a[None], edge) / length2, 0.0, 1.0)
        near = a[None] + u[:, :, None] * edge[None]
        gap = np.hypot(p[:, None, 0] - near[..., 0], p[:, None, 1] - near[..., 1])
        counts[lo:lo + step] = np.sum(gap <= tol, axis=1)
    return counts


# --------------------------------------------------------------------------- beam tracing


@dataclass(frozen=True, eq=False)
class _Traced:
    """Per-firing results of the deterministic geometry (no randomness).

    ``echo_distance`` and ``echo_point`` (shapes (n, R) and (n, R, 2)) keep every ray that
    echoes diffusely, out to the crosstalk horizon: the raw material of late echoes.
    """

    direct_range: FloatArray
    direct_point: FloatArray
    multipath_range: FloatArray
    multipath_point: FloatArray
    echo_distance: FloatArray
    echo_point: FloatArray

    @classmethod
    def empty(cls, n: int, rays: int) -> _Traced:
        """Nothing heard yet by ``n`` firings of ``rays`` late-echo rays each."""
        return cls(
            direct_range=np.full(n, np.inf), direct_point=np.full((n, 2), np.nan),
            multipath_range=np.full(n, np.inf), multipath_point=np.full((n, 2), np.nan),
            echo_distance=np.full((n, rays), np.inf), echo_point=np.full((n, rays, 2), np.nan),
        )


def _trace_all(out: _Traced, walls: int, trace_chunk: Callable[[int, int], None],
               on_progress: Callable[[int, int], None] | None) -> _Traced:
    """Fill ``out`` batch by batch: ``trace_chunk(lo, hi)`` traces firings ``lo:hi`` into it
    (skipped when the world has no ``walls``)."""
    n = out.direct_range.shape[0]
    for lo in range(0, n, _CHUNK_FIRINGS):
        hi = min(lo + _CHUNK_FIRINGS, n)
        if walls:
            trace_chunk(lo, hi)
        if on_progress is not None:
            on_progress(hi, n)
    return out


def _trace_chunk(geometry: _WallGeometry, robot: RobotDescription, chunk: Firings,
                 physics: SonarPhysics, far_range: float, out: _Traced, offset: int) -> None:
    """Trace the beams of one batch of firings and write the results into ``out`` rows."""
    f, rays = len(chunk), physics.rays_per_beam
    rows = slice(offset, offset + f)
    box = (float(chunk.x.min()), float(chunk.y.min()), float(chunk.x.max()), float(chunk.y.max()))
    near_world, near_index, corners = geometry.near(*box, margin=robot.max_range)
    spread = np.linspace(-0.5, 0.5, rays) if rays > 1 else np.zeros(1)
    width = robot.beam_width[chunk.sensor]
    angle = (chunk.theta[:, None] + width[:, None] * spread[None, :]).reshape(-1)
    origin = np.repeat(np.column_stack((chunk.x, chunk.y)), rays, axis=0)
    distance, wall = _cast(near_world, near_index, origin, angle, robot.max_range)
    if far_range > robot.max_range:
        missed = np.flatnonzero(~np.isfinite(distance))
        if missed.size:
            far_world, far_index, _ = geometry.near(*box, margin=far_range)
            distance[missed], wall[missed] = _cast(far_world, far_index, origin[missed],
                                                   angle[missed], far_range)
    direction = np.column_stack((np.cos(angle), np.sin(angle)))
    hit = np.isfinite(distance)
    point = origin + np.where(hit, distance, 0.0)[:, None] * direction
    echoing = hit & _echoes_back(geometry, physics, direction, wall, point)

    # Direct echoes: the nearest echoing ray beyond the blanking distance (time of flight).
    heard = echoing & (distance >= robot.min_range) & (distance <= robot.max_range)
    ray_range = np.where(heard, distance, np.inf).reshape(f, rays)
    best = np.argmin(ray_range, axis=1)
    direct_range = ray_range[np.arange(f), best]
    direct_point = point.reshape(f, rays, 2)[np.arange(f), best]
    if physics.corner_echoes and corners.shape[0]:
        corner_range, corner_point = _corner_echoes(near_world, chunk, width, corners, robot)
        closer = corner_range < direct_range
        direct_range = np.where(closer, corner_range, direct_range)
        direct_point = np.where(closer[:, None], corner_point, direct_point)
    out.direct_range[rows] = direct_range
    out.direct_point[rows] = np.where(np.isfinite(direct_range)[:, None], direct_point, np.nan)
    out.echo_distance[rows] = np.where(echoing, distance, np.inf).reshape(f, rays)
    out.echo_point[rows] = point.reshape(f, rays, 2)

    if physics.multipath_probability > 0.0 and physics.specular:
        bounce = hit & ~echoing & (distance <= robot.max_range)
        _multipath(geometry, near_world, near_index, robot, physics, direction, wall, point,
                   distance, bounce, out, offset, rays)


def _cast(world: World, index: IntArray, origin: FloatArray, angle: FloatArray,
          limit: float) -> tuple[FloatArray, IntArray]:
    """``World.cast_rays`` on a sub-world, with wall indices mapped back to the full world."""
    if origin.shape[0] == 0 or index.size == 0:
        return np.full(origin.shape[0], np.inf), np.full(origin.shape[0], -1, dtype=np.int64)
    distance, local = world.cast_rays(origin, angle, max_range=limit)
    return distance, np.where(local >= 0, index[np.maximum(local, 0)], -1).astype(np.int64)


def _echoes_back(geometry: _WallGeometry, physics: SonarPhysics, direction: FloatArray,
                 wall: IntArray, point: FloatArray) -> BoolArray:
    """Whether each ray's hit returns sound to where the ray came from.

    A smooth wall returns it when the incidence angle (between the ray and the wall normal) is
    below the critical angle; corners and free ends within ``corner_radius`` always do.
    """
    hit = wall >= 0
    if not physics.specular:
        return hit
    normal = geometry.normals[np.maximum(wall, 0)]
    cos_incidence = np.abs(np.sum(direction * normal, axis=1))
    # The small slack keeps a ray exactly at the critical angle on the echoing side.
    facing = cos_incidence >= math.cos(physics.critical_angle) - 1e-12
    near = np.zeros_like(hit)
    candidates = np.flatnonzero(hit & ~facing)
    near[candidates] = geometry.near_corner(point[candidates], physics.corner_radius)
    return np.asarray(hit & (facing | near))


def _corner_echoes(world: World, chunk: Firings, width: FloatArray, corners: FloatArray,
                   robot: RobotDescription) -> tuple[FloatArray, FloatArray]:
    """Nearest corner or free wall end in each beam and in sight: range (f,), point (f, 2)."""
    dx = corners[None, :, 0] - chunk.x[:, None]
    dy = corners[None, :, 1] - chunk.y[:, None]
    dist = np.hypot(dx, dy)
    off_axis = np.abs(np.angle(np.exp(1j * (np.arctan2(dy, dx) - chunk.theta[:, None]))))
    inside = ((dist >= robot.min_range) & (dist <= robot.max_range)
              & (off_axis <= width[:, None] / 2.0 + 1e-12))
    f_idx, c_idx = np.nonzero(inside)
    corner_range = np.full(len(chunk), np.inf)
    corner_point = np.full((len(chunk), 2), np.nan)
    if f_idx.size == 0:
        return corner_range, corner_point
    target = dist[f_idx, c_idx]
    seen, _ = world.cast_rays(np.column_stack((chunk.x[f_idx], chunk.y[f_idx])),
                              np.arctan2(dy[f_idx, c_idx], dx[f_idx, c_idx]),
                              max_range=robot.max_range + 1.0)
    # In sight: nothing stops the ray before the corner (it may stop at the corner itself).
    visible = seen >= target * (1.0 - 1e-9) - 1e-9
    f_idx, c_idx, target = f_idx[visible], c_idx[visible], target[visible]
    order = np.lexsort((target, f_idx))  # per firing, nearest corner first
    first = order[np.r_[True, np.diff(f_idx[order]) != 0]] if order.size else order
    corner_range[f_idx[first]] = target[first]
    corner_point[f_idx[first]] = corners[c_idx[first]]
    return corner_range, corner_point


def _multipath(geometry: _WallGeometry, world: World, index: IntArray, robot: RobotDescription,
               physics: SonarPhysics, direction: FloatArray, wall: IntArray, point: FloatArray,
               distance: FloatArray, bounce: BoolArray, out: _Traced, offset: int,
               rays: int) -> None:
    """One specular bounce: reflected rays that meet a second wall head-on come back the same
    way, so the sensor hears them at the length of the bounced path (too long)."""
    which = np.flatnonzero(bounce)
    if which.size == 0:
        return
    normal = geometry.normals[wall[which]]
    d = direction[which]
    mirrored = d - 2.0 * np.sum(d * normal, axis=1)[:, None] * normal
    start = point[which] + _BOUNCE_OFFSET * mirrored
    second, wall2 = _cast(world, index, start, np.arctan2(mirrored[:, 1], mirrored[:, 0]),
                          robot.max_range)
    total = distance[which] + _BOUNCE_OFFSET + second
    hit2 = np.isfinite(second) & (total <= robot.max_range) & (total >= robot.min_range)
    end = start + np.where(hit2, second, 0.0)[:, None] * mirrored
    returns = hit2 & _echoes_back(geometry, physics, mirrored, np.where(hit2, wall2, -1), end)
    firing = which // rays
    path = np.where(returns, total, np.inf)
    order = np.lexsort((path, firing))
    first = order[np.r_[True, np.diff(firing[order]) != 0]]
    first = first[np.isfinite(path[first])]
    out.multipath_range[offset + firing[first]] = path[first]
    out.multipath_point[offset + firing[first]] = end[first]


# --------------------------------------------------------------------------- spurious echoes


def _crosstalk(robot: RobotDescription, firings: Firings, physics: SonarPhysics,
               traced: _Traced) -> FloatArray:
    """Apparent range of the first late echo of a recent ping, per firing (inf: none).

    Sensor k fires at t_k; the ping of an earlier firing j reflects (diffusely) at P on a wall
    at distance d_j and reaches sensor k after travelling d_j + |P − o_k|. Sensor k times it
    from its own firing, so it reads (d_j + |P − o_k|)/2 − c (t_k − t_j)/2.
    """
    n = len(firings)
    best = np.full(n, np.inf)
    if physics.crosstalk_probability <= 0.0:
        return best
    c = physics.sound_speed
    for lag in range(1, min(physics.crosstalk_lookback, n - 1) + 1):
        k = np.arange(lag, n)
        j = k - lag
        px = traced.echo_point[j, :, 0] - firings.x[k, None]
        py = traced.echo_point[j, :, 1] - firings.y[k, None]
        back = np.hypot(px, py)
        apparent = (traced.echo_distance[j] + back) / 2.0 - c * (firings.t[k] - firings.t[j])[
            :, None] / 2.0
        arrival = np.abs(np.angle(np.exp(1j * (np.arctan2(py, px) - firings.theta[k, None]))))
        ok = (np.isfinite(apparent) & (apparent >= robot.min_range)
              & (apparent <= robot.max_range) & (arrival <= physics.crosstalk_acceptance))
        best[k] = np.minimum(best[k], np.min(np.where(ok, apparent, np.inf), axis=1))
    return best


def _floor(robot: RobotDescription, firings: Firings, physics: SonarPhysics,
           draws: _Draws) -> FloatArray:
    """Floor echo range per firing (inf: none): sensors facing down a tilt hear the floor."""
    off = np.abs(np.angle(np.exp(1j * (robot.bearing[firings.sensor] - draws.tilt))))
    facing = np.isfinite(draws.tilt) & (off <= physics.floor_half_angle)
    heard = facing & (draws.floor_gate < physics.floor_probability)
    return np.asarray(np.where(heard, np.maximum(draws.floor_range, 0.0), np.inf))


# --------------------------------------------------------------------------- amplitude model


#: Codes of the amplitude model's candidate echo families, keying their noise draws.
_MIRROR, _DIFFUSE, _CORNER, _MULTIPATH, _FOLDED, _CROSSTALK = 1, 2, 3, 4, 5, 6


@dataclass(frozen=True, eq=False)
class _Corners:
    """The corners and free wall ends of a world (``_WallGeometry.scatter``), with what the
    amplitude model needs: which are right-angled two-wall corners (retro-reflectors seen from
    inside) and the directions ``u1``, ``u2`` (m, 2) of their two walls away from the corner.
    """

    points: FloatArray
    right: BoolArray
    u1: FloatArray
    u2: FloatArray

    @classmethod
    def make(cls, geometry: _WallGeometry, tolerance: float, tol: float = 1e-9) -> _Corners:
        points = geometry.scatter
        m = points.shape[0]
        u1, u2 = np.full((m, 2), np.nan), np.full((m, 2), np.nan)
        right = np.zeros(m, dtype=bool)
        seg = geometry.world.segments
        if m == 0 or seg.shape[0] == 0:
            return cls(points, right, u1, u2)
        ends = np.concatenate([seg[:, :2], seg[:, 2:]])
        others = np.concatenate([seg[:, 2:], seg[:, :2]])  # the far end of the same wall
        touching = _touching_count(seg, points, tol)
        for i, near in enumerate(cKDTree(ends).query_ball_point(points, tol)):
            if len(near) != 2 or touching[i] != 2:
                continue
            away = others[near] - points[i]
            away /= np.hypot(away[:, 0], away[:, 1])[:, None]
            if abs(float(away[0] @ away[1])) <= math.sin(tolerance) + 1e-12:
                right[i] = True
                u1[i], u2[i] = away
        return cls(points, right, u1, u2)


def _noise(key: int, firing: IntArray, family: int, source: IntArray) -> FloatArray:
    """Standard normal draws, one per (firing, family, source) triple, from a counter-based
    hash of ``key``: the same whatever the batching or the other candidates (splitmix64)."""
    h = _splitmix(np.asarray(firing, dtype=np.uint64).reshape(-1) + np.uint64(key))
    h = _splitmix(h ^ np.uint64(family))
    h = _splitmix(h + np.asarray(source, dtype=np.uint64).reshape(-1))
    u = ((h >> np.uint64(11)).astype(np.float64) + 0.5) * 2.0**-53
    return np.asarray(ndtri(u))


def _splitmix(x: npt.NDArray[np.uint64]) -> npt.NDArray[np.uint64]:
    # Array arithmetic on uint64 wraps modulo 2**64, as the algorithm wants.
    z = x + np.uint64(0x9E3779B97F4A7C15)
    z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    return np.asarray(z ^ (z >> np.uint64(31)))


def _heard(level: FloatArray, key: int, firing: IntArray, family: int, source: IntArray,
           amplitude: AmplitudeModel) -> BoolArray:
    """Which candidate echoes (levels in dB, shape (k,)) beat the threshold plus their noise."""
    if level.size == 0:
        return np.zeros(0, dtype=bool)
    z = _noise(key, firing, family, source) if amplitude.noise_db > 0.0 else 0.0
    return np.asarray(level + amplitude.noise_db * z >= amplitude.threshold_db)


def _wrap(angle: FloatArray) -> FloatArray:
    """Angles folded into [-π, π]."""
    return np.asarray(np.angle(np.exp(1j * angle)))


def _in_sight(world: World, origin: FloatArray, target: FloatArray, limit: float) -> BoolArray:
    """Whether nothing stops the straight line from each origin (k, 2) before its target."""
    if origin.shape[0] == 0:
        return np.zeros(0, dtype=bool)
    gap = target - origin
    length = np.hypot(gap[:, 0], gap[:, 1])
    seen, _ = world.cast_rays(origin, np.arctan2(gap[:, 1], gap[:, 0]), max_range=limit)
    return np.asarray(seen >= length * (1.0 - 1e-9) - 1e-9)


def _keep_first(firing: IntArray, rng_: FloatArray, point: FloatArray, f: int) -> tuple[
        FloatArray, FloatArray]:
    """Per firing (0..f-1) the candidate with the smallest range: range (f,), point (f, 2)."""
    best = np.full(f, np.inf)
    where = np.full((f, 2), np.nan)
    if firing.size == 0:
        return best, where
    order = np.lexsort((rng_, firing))
    first = order[np.r_[True, np.diff(firing[order]) != 0]]
    best[firing[first]] = rng_[first]
    where[firing[first]] = point[first]
    return best, where


#: Candidate echoes of one kind for a batch of firings: the firing (row in the batch) of each,
#: its range, metres, and its reflection point, shape (k, 2).
_Candidates = tuple[IntArray, FloatArray, FloatArray]


@dataclass(frozen=True, eq=False)
class _ChunkScene:
    """What the amplitude model's candidate finders share for one batch of firings: the walls
    near it (``world``, their indices ``index`` in the whole world), the sensors' origins
    (f, 2), the firings' global ids, the pruning level (dB) below which no echo can be heard,
    the sight-line limit (metres) and the noise key."""

    chunk: Firings
    robot: RobotDescription
    physics: SonarPhysics
    world: World
    index: IntArray
    box: tuple[float, float, float, float]
    origin: FloatArray
    firing_ids: IntArray
    low: float
    limit: float
    key: int


@dataclass(frozen=True, eq=False)
class _Fan:
    """The fan's rays of a batch (``rays`` per firing, firing-major), as the multipath step
    takes them: direction (f·rays, 2), the index of the first wall hit (as :func:`_cast`
    gives it), whether one was hit, and the hit point (the origin where none)."""

    rays: int
    direction: FloatArray
    wall: IntArray
    hit: BoolArray
    point: FloatArray


def _trace_amplitude_chunk(geometry: _WallGeometry, corners: _Corners, robot: RobotDescription,
                           chunk: Firings, physics: SonarPhysics, out: _Traced, offset: int,
                           key: int) -> None:
    """The amplitude model's direct and multipath echoes for one batch of firings.

    Candidates: each wall's mirror echo (:func:`_mirror_candidates`), each fan ray's diffuse
    echo (:func:`_diffuse_candidates`), each corner's or wall end's echo (retro-reflection or
    diffraction, :func:`_corner_candidates`), each bounce path's multipath echo; the nearest
    heard direct and multipath echo per firing are written into ``out`` rows.
    """
    amp = physics.amplitude
    f = len(chunk)
    box = (float(chunk.x.min()), float(chunk.y.min()), float(chunk.x.max()), float(chunk.y.max()))
    near_world, near_index, _ = geometry.near(*box, margin=robot.max_range)
    scene = _ChunkScene(
        chunk=chunk, robot=robot, physics=physics, world=near_world, index=near_index, box=box,
        origin=np.column_stack((chunk.x, chunk.y)), firing_ids=offset + np.arange(f),
        low=amp.threshold_db - _PRUNE_SIGMAS * amp.noise_db, limit=robot.max_range + 1.0,
        key=key,
    )
    found = [_mirror_candidates(scene)]
    fan, diffuse = _diffuse_candidates(scene, geometry)
    if diffuse is not None:
        found.append(diffuse)
    corner = _corner_candidates(scene, corners)
    if corner is not None:
        found.append(corner)

    firing = np.concatenate([x[0] for x in found])
    ranges = np.concatenate([x[1] for x in found])
    points = np.concatenate([x[2].reshape(-1, 2) for x in found])
    best, where = _keep_first(firing, ranges, points, f)
    rows = slice(offset, offset + f)
    out.direct_range[rows] = best
    out.direct_point[rows] = where

    if physics.multipath_probability > 0.0:
        bounce = np.flatnonzero(fan.hit)
        _multipath_amplitude(geometry, near_world, near_index, robot, physics, chunk,
                             scene.origin, fan.direction, fan.wall, fan.point, bounce, fan.rays,
                             out, offset, key)


def _mirror_candidates(scene: _ChunkScene) -> _Candidates:
    """Mirror echoes: the foot of the perpendicular from the sensor to each wall, heard."""
    amp, c = scene.physics.amplitude, scene.physics.sound_speed
    robot, origin = scene.robot, scene.origin
    seg = scene.world.segments
    a, edge = seg[:, :2], seg[:, 2:] - seg[:, :2]
    t = np.einsum("fwj,wj->fw", origin[:, None, :] - a[None], edge) / np.sum(edge * edge, axis=1)
    foot = a[None] + t[..., None] * edge[None]
    gap = foot - origin[:, None, :]
    d = np.hypot(gap[..., 0], gap[..., 1])
    beta = _wrap(np.arctan2(gap[..., 1], gap[..., 0]) - scene.chunk.theta[:, None])
    ok = (t >= 0.0) & (t <= 1.0) & (d >= robot.min_range) & (d <= robot.max_range)
    ok &= np.abs(beta) <= math.pi / 2
    fi, wi = np.nonzero(ok)
    level = mirror_echo_db(amp, d[fi, wi], beta[fi, wi], 1, c)
    keep = level >= scene.low
    fi, wi, level = fi[keep], wi[keep], level[keep]
    seen = _in_sight(scene.world, origin[fi], foot[fi, wi], scene.limit)
    fi, wi, level = fi[seen], wi[seen], level[seen]
    heard = _heard(level, scene.key, scene.firing_ids[fi], _MIRROR, scene.index[wi], amp)
    return fi[heard], d[fi[heard], wi[heard]], foot[fi[heard], wi[heard]]


def _diffuse_candidates(scene: _ChunkScene,
                        geometry: _WallGeometry) -> tuple[_Fan, _Candidates | None]:
    """The fan's rays cast to their first walls (the multipath step starts from them) and
    their heard diffuse echoes (None when the walls scatter nothing)."""
    amp, c, robot = scene.physics.amplitude, scene.physics.sound_speed, scene.robot
    f = len(scene.chunk)
    rays = amp.fan_rays
    spread = np.linspace(-amp.fan_half_angle, amp.fan_half_angle, rays) if rays > 1 \
        else np.zeros(1)
    angle = (scene.chunk.theta[:, None] + spread[None, :]).reshape(-1)
    start = np.repeat(scene.origin, rays, axis=0)
    distance, wall = _cast(scene.world, scene.index, start, angle, robot.max_range)
    direction = np.column_stack((np.cos(angle), np.sin(angle)))
    hit = np.isfinite(distance)
    point = start + np.where(hit, distance, 0.0)[:, None] * direction
    fan = _Fan(rays=rays, direction=direction, wall=wall, hit=hit, point=point)
    if not (amp.diffuse_fraction > 0.0 and amp.reflectivity > 0.0):
        return fan, None
    normal = geometry.normals[np.maximum(wall, 0)]
    which = np.flatnonzero(hit & (distance >= robot.min_range))
    incidence = np.arccos(np.minimum(np.abs(np.sum(direction[which] * normal[which],
                                                   axis=1)), 1.0))
    level = diffuse_echo_db(amp, distance[which], np.tile(spread, f)[which], incidence, c)
    heard = _heard(level, scene.key, scene.firing_ids[which // rays], _DIFFUSE, which % rays,
                   amp)
    which = which[heard]
    return fan, (which // rays, distance[which], point[which])


def _corner_candidates(scene: _ChunkScene, corners: _Corners) -> _Candidates | None:
    """Corners and wall ends near the batch: diffraction from any angle, retro-reflection from
    inside a right-angled corner, heard (None when no corner is near)."""
    amp, c = scene.physics.amplitude, scene.physics.sound_speed
    robot, origin = scene.robot, scene.origin
    box = scene.box
    box_keep = np.flatnonzero(
        (corners.points[:, 0] >= box[0] - robot.max_range)
        & (corners.points[:, 0] <= box[2] + robot.max_range)
        & (corners.points[:, 1] >= box[1] - robot.max_range)
        & (corners.points[:, 1] <= box[3] + robot.max_range))
    if not box_keep.size:
        return None
    cp = corners.points[box_keep]
    v = origin[:, None, :] - cp[None]  # corner to sensor
    dist = np.hypot(v[..., 0], v[..., 1])
    alpha = _wrap(np.arctan2(-v[..., 1], -v[..., 0]) - scene.chunk.theta[:, None])
    ok = (dist >= robot.min_range) & (dist <= robot.max_range)
    ok &= np.abs(alpha) <= math.pi / 2
    fi, ci = np.nonzero(ok)
    r, al = dist[fi, ci], alpha[fi, ci]
    level = point_echo_db(amp, r, al, amp.edge_db, c)
    g = box_keep[ci]
    retro = corners.right[g] & _inside_wedge(v[fi, ci], corners.u1[g], corners.u2[g])
    level = np.where(retro, np.maximum(level, mirror_echo_db(amp, r, al, 2, c)), level)
    keep = level >= scene.low
    fi, ci, level = fi[keep], ci[keep], level[keep]
    seen = _in_sight(scene.world, origin[fi], cp[ci], scene.limit)
    fi, ci, level = fi[seen], ci[seen], level[seen]
    heard = _heard(level, scene.key, scene.firing_ids[fi], _CORNER, box_keep[ci], amp)
    return fi[heard], dist[fi[heard], ci[heard]], cp[ci[heard]]


def _inside_wedge(v: FloatArray, u1: FloatArray, u2: FloatArray) -> BoolArray:
    """Whether each direction v (k, 2) lies strictly inside the angle from u1 to u2 (< π)."""
    def cross(p: FloatArray, q: FloatArray) -> FloatArray:
        return np.asarray(p[:, 0] * q[:, 1] - p[:, 1] * q[:, 0])

    turn = cross(u1, u2)
    with np.errstate(invalid="ignore"):
        inside = (cross(u1, v) * turn > 0.0) & (cross(v, u2) * turn > 0.0)
    return np.asarray(inside & np.isfinite(turn))


def _multipath_amplitude(geometry: _WallGeometry, world: World, index: IntArray,
                         robot: RobotDescription, physics: SonarPhysics, chunk: Firings,
                         origin: FloatArray, direction: FloatArray, wall: IntArray,
                         point: FloatArray, bounce: IntArray, rays: int, out: _Traced,
                         offset: int, key: int) -> None:
    """Bounce paths S → A → B → A → S: wall B seen in the mirror of wall A, too far.

    Two ways back: B's diffuse echo of each fan ray's mirrored ray (range: the folded ray's
    length, two specular reflections at A), and B's mirror echo seen from the sensor's image in
    A, solved exactly for each distinct pair (A, B) the fan meets (the foot F of the
    perpendicular from the image onto B, the crossing P of that line with A; range
    |image − F|, three specular reflections). In a world of right angles the second never
    happens: the image's perpendicular to B runs parallel to A.
    """
    amp, c = physics.amplitude, physics.sound_speed
    if bounce.size == 0:
        return
    f = len(chunk)
    normal = geometry.normals[wall[bounce]]
    d = direction[bounce]
    mirrored = d - 2.0 * np.sum(d * normal, axis=1)[:, None] * normal
    start = point[bounce] + _BOUNCE_OFFSET * mirrored
    first = np.hypot(*(point[bounce] - origin[bounce // rays]).T)
    second, wall2 = _cast(world, index, start, np.arctan2(mirrored[:, 1], mirrored[:, 0]),
                          robot.max_range)
    total = first + _BOUNCE_OFFSET + second
    good = (wall2 >= 0) & (wall2 != wall[bounce])
    found: list[tuple[IntArray, FloatArray, FloatArray]] = []
    if amp.diffuse_fraction > 0.0 and amp.reflectivity > 0.0:
        fold = np.flatnonzero(good & (total >= robot.min_range) & (total <= robot.max_range))
        end = start[fold] + second[fold, None] * mirrored[fold]
        incidence = np.arccos(np.minimum(np.abs(np.sum(
            mirrored[fold] * geometry.normals[wall2[fold]], axis=1)), 1.0))
        spread = np.linspace(-amp.fan_half_angle, amp.fan_half_angle, rays) if rays > 1 \
            else np.zeros(1)
        ray = bounce[fold] % rays
        level = (diffuse_echo_db(amp, total[fold], spread[ray], incidence, c)
                 + 2.0 * amp.specular_db)
        heard = _heard(level, key, offset + bounce[fold] // rays, _FOLDED, ray, amp)
        found.append((bounce[fold][heard] // rays, total[fold][heard], end[heard]))
    pairs = np.unique(np.column_stack((bounce[good] // rays, wall[bounce][good], wall2[good])),
                      axis=0)
    if pairs.shape[0]:
        found.append(_retrace_paths(geometry, world, robot, physics, chunk, origin, pairs,
                                    offset, key))
    firing = np.concatenate([x[0] for x in found]) if found else np.zeros(0, dtype=np.int64)
    ranges = np.concatenate([x[1] for x in found]) if found else np.zeros(0)
    points = np.concatenate([x[2].reshape(-1, 2) for x in found]) if found else np.zeros((0, 2))
    best, where = _keep_first(firing, ranges, points, f)
    rows = slice(offset, offset + f)
    out.multipath_range[rows] = best
    out.multipath_point[rows] = where


def _retrace_paths(geometry: _WallGeometry, world: World, robot: RobotDescription,
                   physics: SonarPhysics, chunk: Firings, origin: FloatArray, pairs: IntArray,
                   offset: int, key: int) -> tuple[IntArray, FloatArray, FloatArray]:
    """Heard mirror echoes of wall B seen in wall A, for (firing, A, B) rows of ``pairs``:
    firing rows, ranges, points on B."""
    amp, c = physics.amplitude, physics.sound_speed
    fi, wa, wb = pairs[:, 0], pairs[:, 1], pairs[:, 2]
    seg = geometry.world.segments
    o = origin[fi]
    a_a, e_a, n_a = seg[wa, :2], seg[wa, 2:] - seg[wa, :2], geometry.normals[wa]
    a_b, e_b = seg[wb, :2], seg[wb, 2:] - seg[wb, :2]
    image = o - 2.0 * np.sum((o - a_a) * n_a, axis=1)[:, None] * n_a
    t_b = np.sum((image - a_b) * e_b, axis=1) / np.sum(e_b * e_b, axis=1)
    foot = a_b + t_b[:, None] * e_b
    line = foot - image
    across = np.sum(line * n_a, axis=1)
    # A line parallel to A never crosses it: no path.
    s = np.sum((a_a - image) * n_a, axis=1) / np.where(np.abs(across) > 1e-12, across, np.inf)
    cross_a = image + s[:, None] * line
    t_a = np.sum((cross_a - a_a) * e_a, axis=1) / np.sum(e_a * e_a, axis=1)
    length = np.hypot(line[:, 0], line[:, 1])
    ok = ((t_b >= 0.0) & (t_b <= 1.0) & (s > 0.0) & (s < 1.0) & (t_a >= 0.0) & (t_a <= 1.0)
          & (length >= robot.min_range) & (length <= robot.max_range))
    gap = cross_a - o
    beta = _wrap(np.arctan2(gap[:, 1], gap[:, 0]) - chunk.theta[fi])
    ok &= np.abs(beta) <= math.pi / 2
    keep = np.flatnonzero(ok)
    level = path_echo_db(amp, 2.0 * length[keep], beta[keep], beta[keep], 3, c)
    keep = keep[level >= amp.threshold_db - _PRUNE_SIGMAS * amp.noise_db]
    limit = robot.max_range + 1.0
    leg2 = foot[keep] - cross_a[keep]
    leg2_unit = leg2 / np.maximum(np.hypot(leg2[:, 0], leg2[:, 1]), 1e-300)[:, None]
    seen = (_in_sight(world, o[keep], cross_a[keep] - _BOUNCE_OFFSET * leg2_unit, limit)
            & _in_sight(world, cross_a[keep] + _BOUNCE_OFFSET * leg2_unit, foot[keep], limit))
    keep = keep[seen]
    level = path_echo_db(amp, 2.0 * length[keep], beta[keep], beta[keep], 3, c)
    source = wa[keep] * len(geometry.world) + wb[keep]
    heard = keep[_heard(level, key, offset + fi[keep], _MULTIPATH, source, amp)]
    return fi[heard], length[heard], foot[heard]


def _crosstalk_amplitude(scenery: _Scenery, robot: RobotDescription, firings: Firings,
                         physics: SonarPhysics, far_range: float, key: int) -> FloatArray:
    """Apparent range of the first loud enough late echo of a recent ping (inf: none).

    The ping of firing j reaches sensor k, which fires ``lag`` firings later, by specular
    reflection off a wall: the image of j's sensor in the wall, seen from k's sensor, gives the
    path (length P, reflection point X); k reads P/2 − c (t_k − t_j)/2 and hears it when the
    level (directivity at both sensors, 20 log spreading of the path) is loud enough. Diffuse
    and edge echoes travel 14 m or more as small targets (40 log): far below the threshold.
    """
    n = len(firings)
    best = np.full(n, np.inf)
    if physics.crosstalk_probability <= 0.0 or scenery.walls == 0:
        return best
    amp, c = physics.amplitude, physics.sound_speed
    low = amp.threshold_db - _PRUNE_SIGMAS * amp.noise_db
    for lag in range(1, min(physics.crosstalk_lookback, n - 1) + 1):
        pieces = (piece for lo in range(lag, n, _CHUNK_FIRINGS)
                  for piece in scenery.pieces(lo, min(lo + _CHUNK_FIRINGS, n)))
        for first, stop, geometry in pieces:
            k = np.arange(first, stop)
            j = k - lag
            xs = np.concatenate((firings.x[k], firings.x[j]))
            ys = np.concatenate((firings.y[k], firings.y[j]))
            world, index, _ = geometry.near(float(xs.min()), float(ys.min()), float(xs.max()),
                                            float(ys.max()), margin=far_range)
            if len(world) == 0:
                continue
            seg = world.segments
            a, edge, normal = seg[:, :2], seg[:, 2:] - seg[:, :2], geometry.normals[index]
            emit = np.column_stack((firings.x[j], firings.y[j]))
            recv = np.column_stack((firings.x[k], firings.y[k]))
            side_e = np.einsum("fwj,wj->fw", emit[:, None, :] - a[None], normal)
            side_r = np.einsum("fwj,wj->fw", recv[:, None, :] - a[None], normal)
            image = emit[:, None, :] - 2.0 * side_e[..., None] * normal[None]
            line = recv[:, None, :] - image
            across = np.einsum("fwj,wj->fw", line, normal)
            # A path parallel to the wall never meets it (s = 0: no path either).
            s = -np.einsum("fwj,wj->fw", image - a[None], normal) / np.where(
                np.abs(across) > 1e-12, across, np.inf)
            x = image + s[..., None] * line
            t = np.einsum("fwj,wj->fw", x - a[None], edge) / np.sum(edge * edge, axis=1)
            path = np.hypot(line[..., 0], line[..., 1])
            apparent = path / 2.0 - c * (firings.t[k] - firings.t[j])[:, None] / 2.0
            ok = ((side_e * side_r > 0.0) & (t >= 0.0) & (t <= 1.0)
                  & (apparent >= robot.min_range) & (apparent <= robot.max_range))
            fi, wi = np.nonzero(ok)
            xp = x[fi, wi]
            to_e, to_r = xp - emit[fi], xp - recv[fi]
            emit_angle = _wrap(np.arctan2(to_e[:, 1], to_e[:, 0]) - firings.theta[j[fi]])
            recv_angle = _wrap(np.arctan2(to_r[:, 1], to_r[:, 0]) - firings.theta[k[fi]])
            level = path_echo_db(amp, path[fi, wi], emit_angle, recv_angle, 1, c)
            keep = np.flatnonzero((level >= low)
                                  & (np.abs(recv_angle) <= physics.crosstalk_acceptance))
            limit = far_range + 1.0
            keep = keep[_in_sight(world, emit[fi[keep]], xp[keep], limit)
                        & _in_sight(world, recv[fi[keep]], xp[keep], limit)]
            heard = keep[_heard(level[keep], key, k[fi[keep]], _CROSSTALK + 8 * lag,
                                index[wi[keep]], amp)]
            r = apparent[fi[heard], wi[heard]]
            np.minimum.at(best, k[fi[heard]], r)
    return best


def _bad(name: str, value: object, problem: str) -> None:
    msg = f"SonarPhysics.{name} {problem}, got {value!r}"
    raise SonarPhysicsError(msg)
