"""The specular echo model: rays across the beam, smooth walls within the critical angle.

Each firing's beam is a fan of rays; a ray echoes when it meets a wall within the critical
angle of its normal or near a corner or free wall end, and the nearest echoing ray (or corner
in the beam and in sight) is the direct echo. Rays that glance off one wall and meet a second
head-on give the multipath echo; crosstalk (:mod:`~sonarcarve.sim.sonar.spurious`) comes from
the rays' diffuse echoes, and both are heard by their probabilities.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from sonarcarve.robot import RobotDescription
from sonarcarve.sim.sonar.draws import _Draws
from sonarcarve.sim.sonar.physics import SonarPhysics
from sonarcarve.sim.sonar.records import Firings
from sonarcarve.sim.sonar.scenery import _Scenery
from sonarcarve.sim.sonar.spurious import _crosstalk
from sonarcarve.sim.sonar.tracing import (
    _BOUNCE_OFFSET,
    _cast,
    _ModelEchoes,
    _trace_all,
    _Traced,
)
from sonarcarve.sim.sonar.wall_geometry import _WallGeometry
from sonarcarve.sim.world import World
from sonarcarve.typing import BoolArray, FloatArray, IntArray


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
