"""The amplitude model's direct candidate echoes of one batch: mirror, diffuse and corner.

Each wall's mirror echo (the foot of the perpendicular), each fan ray's diffuse echo and each
corner's or free wall end's echo (retro-reflection or diffraction), given their levels by
:mod:`sonarcarve.sim.amplitude` and kept when heard
(:mod:`~sonarcarve.sim.sonar.amplitude_hearing`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from sonarcarve.robot import RobotDescription
from sonarcarve.sim.amplitude import (
    convex_mirror_db,
    diffuse_echo_db,
    mirror_echo_db,
    point_echo_db,
)
from sonarcarve.sim.sonar.amplitude_facets import _Facets, _nearest_on_curves
from sonarcarve.sim.sonar.amplitude_hearing import _CORNER, _DIFFUSE, _MIRROR, _heard
from sonarcarve.sim.sonar.physics import SonarPhysics
from sonarcarve.sim.sonar.records import Firings
from sonarcarve.sim.sonar.tracing import _cast, _in_sight, _wrap
from sonarcarve.sim.sonar.wall_geometry import _Corners, _WallGeometry
from sonarcarve.sim.world import World
from sonarcarve.typing import BoolArray, FloatArray, IntArray

#: Candidate echoes of one kind for a batch of firings: the firing (row in the batch) of each,
#: its range, metres, and its reflection point, shape (k, 2).
_Candidates = tuple[IntArray, FloatArray, FloatArray]


@dataclass(frozen=True, eq=False)
class _ChunkScene:
    """What the amplitude model's candidate finders share for one batch of firings: the walls
    near it (``world``, their indices ``index`` in the whole world), the sensors' origins
    (f, 2), the firings' global ids, the pruning level (dB) below which no echo can be heard,
    the sight-line limit (metres), the noise key and the walls that are facets of curves
    (None: ``small_reflectors`` off, every wall a plane mirror)."""

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
    facets: _Facets | None = None


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
    on_wall = (t >= 0.0) & (t <= 1.0)
    radius = None  # of the curve each wall is a facet of (inf: a plane wall)
    if scene.facets is not None:
        # A facet of a curve echoes from its circle's point nearest the sensor.
        # From inside its circle (a round room's wall) a facet stays a plane mirror.
        radius = np.repeat(scene.facets.radius[scene.index][None], origin.shape[0], axis=0)
        curved = np.flatnonzero(np.isfinite(scene.facets.radius[scene.index]))
        point, distance, on_arc = _nearest_on_curves(scene.facets, scene.index[curved], origin,
                                                     seg[curved])
        outside = distance > 0.0
        foot[:, curved] = np.where(outside[..., None], point, foot[:, curved])
        d[:, curved] = np.where(outside, distance, d[:, curved])
        on_wall[:, curved] = np.where(outside, on_arc, on_wall[:, curved])
        radius[:, curved] = np.where(outside, radius[:, curved], np.inf)
        gap = foot - origin[:, None, :]
    beta = _wrap(np.arctan2(gap[..., 1], gap[..., 0]) - scene.chunk.theta[:, None])
    ok = on_wall & (d >= robot.min_range) & (d <= robot.max_range)
    ok &= np.abs(beta) <= math.pi / 2
    fi, wi = np.nonzero(ok)
    level = mirror_echo_db(amp, d[fi, wi], beta[fi, wi], 1, c)
    if radius is not None:
        level += convex_mirror_db(radius[fi, wi], d[fi, wi])
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
    width = np.inf if scene.facets is None else 2.0 * scene.facets.radius[wall[which]]
    level = diffuse_echo_db(amp, distance[which], np.tile(spread, f)[which], incidence, c, width)
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
    still = np.ones(corners.points.shape[0], dtype=bool) if scene.facets is None \
        else scene.facets.corner  # the joints of a curve's facets are no edges
    box_keep = np.flatnonzero(
        still & (corners.points[:, 0] >= box[0] - robot.max_range)
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
