"""The amplitude echo model's tracing: every candidate echo heard or not by its level.

For each batch of firings the direct candidates (:mod:`~sonarcarve.sim.sonar.amplitude_candidates`)
and the multipath paths (:mod:`~sonarcarve.sim.sonar.amplitude_paths`) are found and the first
heard kept; then the crosstalk paths. The levels themselves (the sonar equations) live in
:mod:`sonarcarve.sim.amplitude`.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from sonarcarve.robot import RobotDescription
from sonarcarve.sim.sonar.amplitude_candidates import (
    _ChunkScene,
    _corner_candidates,
    _diffuse_candidates,
    _mirror_candidates,
)
from sonarcarve.sim.sonar.amplitude_facets import _facets_of
from sonarcarve.sim.sonar.amplitude_hearing import _PRUNE_SIGMAS, _keep_first
from sonarcarve.sim.sonar.amplitude_paths import _crosstalk_amplitude, _multipath_amplitude
from sonarcarve.sim.sonar.draws import _Draws
from sonarcarve.sim.sonar.physics import SonarPhysics
from sonarcarve.sim.sonar.records import Firings
from sonarcarve.sim.sonar.scenery import _Scenery
from sonarcarve.sim.sonar.tracing import _ModelEchoes, _trace_all, _Traced
from sonarcarve.sim.sonar.wall_geometry import _Corners, _WallGeometry


def _amplitude_echoes(scenery: _Scenery, robot: RobotDescription, firings: Firings,
                      physics: SonarPhysics, far_range: float, draws: _Draws,
                      rng: np.random.Generator,
                      on_progress: Callable[[int, int], None] | None) -> _ModelEchoes:
    """The amplitude model: every candidate echo heard or not by its level (package doc)."""
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
        key=key, facets=_facets_of(geometry, amp.facet_turn) if amp.small_reflectors else None,
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
        if scene.facets is not None:  # a convex facet is no mirror for a bounce (module doc)
            bounce = bounce[~scene.facets.curved[fan.wall[bounce]]]
        _multipath_amplitude(geometry, near_world, near_index, robot, physics, chunk,
                             scene.origin, fan.direction, fan.wall, fan.point, bounce, fan.rays,
                             out, offset, key)
