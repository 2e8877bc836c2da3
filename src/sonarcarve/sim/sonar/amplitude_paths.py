"""The amplitude model's longer paths: multipath (bounces between two walls) and crosstalk.

Multipath: wall B seen in the mirror of wall A, by B's diffuse echo of a folded fan ray or by
its mirror echo seen from the sensor's image in A. Crosstalk: the ping of one firing reflected
specularly into a later firing's sensor. Both are heard by their levels
(:mod:`sonarcarve.sim.amplitude`, :mod:`~sonarcarve.sim.sonar.amplitude_hearing`).
"""

from __future__ import annotations

import math

import numpy as np

from sonarcarve.robot import RobotDescription
from sonarcarve.sim.amplitude import diffuse_echo_db, path_echo_db
from sonarcarve.sim.sonar.amplitude_facets import _facets_of
from sonarcarve.sim.sonar.amplitude_hearing import (
    _CROSSTALK,
    _FOLDED,
    _MULTIPATH,
    _PRUNE_SIGMAS,
    _heard,
    _keep_first,
)
from sonarcarve.sim.sonar.physics import SonarPhysics
from sonarcarve.sim.sonar.records import Firings
from sonarcarve.sim.sonar.scenery import _Scenery
from sonarcarve.sim.sonar.tracing import (
    _BOUNCE_OFFSET,
    _batches,
    _cast,
    _in_sight,
    _Traced,
    _wrap,
)
from sonarcarve.sim.sonar.wall_geometry import _WallGeometry
from sonarcarve.sim.world import World
from sonarcarve.typing import FloatArray, IntArray


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
    # Small reflectors: a convex facet echoes diffusely from its width 2ρ at most and is no
    # mirror for a retraced path (:mod:`sonarcarve.sim.amplitude`); a wall is as wide as any.
    width = np.full(wall2.shape, np.inf) if not amp.small_reflectors else \
        2.0 * _facets_of(geometry, amp.facet_turn).radius[np.maximum(wall2, 0)]
    mirror_b = good & np.isinf(width)
    found: list[tuple[IntArray, FloatArray, FloatArray]] = []
    if amp.diffuse_fraction > 0.0 and amp.reflectivity > 0.0:
        fold = np.flatnonzero(good & (total >= robot.min_range) & (total <= robot.max_range))
        end = start[fold] + second[fold, None] * mirrored[fold]
        incidence = np.arccos(np.minimum(np.abs(np.sum(
            mirrored[fold] * geometry.normals[wall2[fold]], axis=1)), 1.0))
        spread = np.linspace(-amp.fan_half_angle, amp.fan_half_angle, rays) if rays > 1 \
            else np.zeros(1)
        ray = bounce[fold] % rays
        level = (diffuse_echo_db(amp, total[fold], spread[ray], incidence, c, width[fold])
                 + 2.0 * amp.specular_db)
        heard = _heard(level, key, offset + bounce[fold] // rays, _FOLDED, ray, amp)
        found.append((bounce[fold][heard] // rays, total[fold][heard], end[heard]))
    pairs = np.unique(np.column_stack((bounce[mirror_b] // rays, wall[bounce][mirror_b],
                                       wall2[mirror_b])), axis=0)
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
        pieces = (piece for lo, hi in _batches(lag, n) for piece in scenery.pieces(lo, hi))
        for first, stop, geometry in pieces:
            k = np.arange(first, stop)
            j = k - lag
            xs = np.concatenate((firings.x[k], firings.x[j]))
            ys = np.concatenate((firings.y[k], firings.y[j]))
            world, index, _ = geometry.near(float(xs.min()), float(ys.min()), float(xs.max()),
                                            float(ys.max()), margin=far_range)
            if len(world) == 0:
                continue
            mirror = np.ones(len(world), dtype=bool) if not amp.small_reflectors else \
                ~_facets_of(geometry, amp.facet_turn).curved[index]  # facets: no mirrors
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
            ok = ((side_e * side_r > 0.0) & (t >= 0.0) & (t <= 1.0) & mirror[None]
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
