"""Evidence carving's occlusion rule (``geometry/evidence/occlusion.py``): what it must carve and
a case it carves that it should not (docs/RESULTS.md, "Evidence carving's occlusion rule in
clutter")."""

from __future__ import annotations

import math

import pytest

from sonarcarve.methods import EvidenceMethod
from sonarcarve.methods.evidence import EvidenceModel
from sonarcarve.readings import Reading

PHI = math.radians(22.5)


def _reading(t: float, x: float, y: float, theta: float, r: float, sensor: int) -> Reading:
    return Reading(t=t, sensor=sensor, x=x, y=y, theta=theta, range=r, beam_width=PHI)


def _occluded_share_of_last(readings: list[Reading]) -> float:
    """The share of the last reading's bins the occlusion rule carved when it arrived (the
    carving alone: confidence filter off)."""
    method = EvidenceMethod(min_confidence=0.0)
    for reading in readings:
        method.add(reading)
    model = method.models[0]
    assert isinstance(model, EvidenceModel)
    return float(model.occluded[int(method.history.slots()[-1])])


def test_multipath_echo_behind_a_wall_heard_from_two_viewpoints_is_occluded() -> None:
    # A wall at x = 2 heard head-on by sensor 0 twice from about one place (5 cm apart: one
    # viewpoint) and by sensor 1 from 0.3 m away (a second one). Each wall echo's circle is
    # tangent to the wall, so the circles meet at a shallow angle: a rule that wanted
    # triangulated support (circles crossing at a real angle) would not establish the wall.
    # Then an echo reads 3.5 m straight through it, 1.5 m behind the wall: multipath.
    wall = [_reading(0.0, 0.0, 0.0, 0.0, 2.0, sensor=0),
            _reading(0.05, 0.0, 0.05, 0.0, 2.0, sensor=0),
            _reading(0.1, 0.0, 0.3, 0.0, 2.0, sensor=1)]
    multipath = _reading(0.2, 0.0, 0.15, 0.0, 3.5, sensor=2)
    # Most of its beam lies behind the wall's established bins: at 2 m the wall's three arcs
    # (0.78 m long) cover the middle of the 3.5 m arc's beam.
    assert _occluded_share_of_last([*wall, multipath]) > 0.5


@pytest.mark.xfail(strict=True, reason="known loss, kept: a bin counts as established from "
                   "any readings' support, one viewpoint's included (docs/RESULTS.md, "
                   "\"Evidence carving's occlusion rule in clutter\": requiring distinct "
                   "viewpoints per bin fixes this case but finds no more legs in clutter)")
def test_a_leg_behind_a_point_supported_from_one_viewpoint_is_not_occluded() -> None:
    # Sensor 0 hears something at P = (1, 0) from three places within 0.2 m of each other
    # (one viewpoint: closer than viewpoint_spacing, 0.25 m): their echo circles all pass
    # through P, nearly tangent there. Then sensor 3, from 0.6 m to the side, hears a leg 1 m
    # behind P along its line of sight. Nothing but one viewpoint's repeated echoes says P is
    # a surface, so the leg's bins must not be carved as lying behind it.
    p = (1.0, 0.0)
    origins = [(0.0, 0.0), (0.0, 0.1), (0.0, -0.1)]
    heard = [_reading(0.05 * n, x, y, math.atan2(p[1] - y, p[0] - x),
                      math.hypot(p[0] - x, p[1] - y), sensor=0)
             for n, (x, y) in enumerate(origins)]
    side = (0.0, 0.6)
    leg = _reading(0.2, *side, math.atan2(p[1] - side[1], p[0] - side[0]),
                   math.hypot(p[0] - side[0], p[1] - side[1]) + 1.0, sensor=3)
    assert _occluded_share_of_last([*heard, leg]) == 0.0
