"""The walls each firing meets: the world's, or the world's plus a scene's obstacles then.

:class:`_Scenery` cuts the firings into runs that meet the same walls and builds (and caches)
each run's :class:`~sonarcarve.sim.sonar.wall_geometry._WallGeometry`.
"""

from __future__ import annotations

import weakref
from collections import OrderedDict

import numpy as np

from sonarcarve.sim.scene import Scene
from sonarcarve.sim.sonar.records import Firings
from sonarcarve.sim.sonar.wall_geometry import _Corners, _WallGeometry
from sonarcarve.sim.world import World
from sonarcarve.typing import FloatArray, IntArray

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
