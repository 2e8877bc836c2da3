"""The evidence kernels: the detection model and the threshold (beyond the paper)."""

from __future__ import annotations

import math

from sonarcarve.geometry.evidence import detect_probability, evidence_threshold

HALF = math.radians(11.25)
MODEL = (math.sin(HALF), 0.5, math.cos(math.radians(10.0)), math.cos(math.radians(30.0)),
         0.05, 0.95, 20.0)


def _p(vx: float, vy: float, ex: float, ey: float) -> float:
    return detect_probability(vx, vy, ex, ey, 1.0, 0.0, *MODEL)


def test_head_on_on_axis_is_the_strongest() -> None:
    head_on = _p(2.0, 0.0, 1.0, 0.0)
    assert math.isclose(head_on, 0.95 / 1.1)
    edge = _p(2.0 * math.cos(HALF), 2.0 * math.sin(HALF), 1.0, 0.0)
    assert math.isclose(edge / head_on, 0.5 * 1.0 / 1.0, rel_tol=0.05)  # edge gain, γ small


def test_glancing_incidence_is_weak_but_not_zero() -> None:
    g = math.radians(60.0)  # the implied surface's normal 60° off the line of sight
    p = _p(2.0, 0.0, math.cos(g), math.sin(g))
    assert math.isclose(p, 0.05 * 0.95 / 1.1)


def test_detection_falls_with_range() -> None:
    assert _p(1.0, 0.0, 1.0, 0.0) > _p(4.0, 0.0, 1.0, 0.0) > _p(8.0, 0.0, 1.0, 0.0)


def test_threshold_is_one_reading_of_that_probability() -> None:
    assert math.isclose(evidence_threshold(0.8), -math.log(0.2))
