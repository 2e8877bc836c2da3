"""The centerline method (paper, section 2-A): one point on the beam's axis at range r.

Expected values are written out by hand from eq. 3.3 (``origin + r (cos θ, sin θ)``) and eq.
5.2-5.3 (``max_error = 2 r sin(φ / 4)``), never computed by the code under test.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from sonarcarve.methods import CenterlineMethod, make_method
from sonarcarve.readings import DEFAULT_BEAM_WIDTH, Reading, ReadingBatch

# Three readings whose centerline points have exact decimal coordinates.
READINGS = [
    Reading(t=0.0, sensor=0, x=1.0, y=2.0, theta=0.0, range=3.0),  # -> (4, 2)
    Reading(t=0.5, sensor=1, x=-1.0, y=0.5, theta=math.pi / 2, range=2.0),  # -> (-1, 2.5)
    Reading(t=1.0, sensor=2, x=0.0, y=0.0, theta=math.pi, range=0.75),  # -> (-0.75, 0)
    Reading(t=1.5, sensor=3, x=2.0, y=2.0, theta=-math.pi / 4, range=math.sqrt(2)),  # -> (3, 1)
]
EXPECTED_XY = [[4.0, 2.0], [-1.0, 2.5], [-0.75, 0.0], [3.0, 1.0]]


def test_points_are_on_the_axis_at_range_r() -> None:
    method = CenterlineMethod(history_size=10)
    for reading in READINGS:
        method.add(reading)
    local = method.local_map()
    assert local.reading_id.tolist() == [0, 1, 2, 3]
    np.testing.assert_allclose(local.xy, EXPECTED_XY, atol=1e-12)
    np.testing.assert_allclose(method.finish().xy, EXPECTED_XY, atol=1e-12)


def test_width_is_the_beam_width_and_max_error_the_chord_by_hand() -> None:
    phi = math.radians(30.0)
    method = CenterlineMethod(history_size=10, beam_width=phi)
    method.add(Reading(0.0, 0, 0.0, 0.0, 0.0, 2.0))  # default beam width: φ = 30°
    method.add(Reading(1.0, 0, 0.0, 0.0, 0.0, 1.0, math.pi / 3))  # its own: 60°
    points = method.finish()
    np.testing.assert_allclose(points.width, [phi, math.pi / 3], rtol=1e-15)
    # 2 r sin(φ / 4): 4 sin(7.5°) = 0.52210..., 2 sin(15°) = 0.51763...
    np.testing.assert_allclose(points.max_error, [0.5221047688802063, 0.5176380902050415],
                               rtol=1e-12)
    assert points.range.tolist() == [2.0, 1.0]


def test_default_beam_width_is_the_polaroid_22_5_degrees() -> None:
    method = CenterlineMethod(history_size=3)
    method.add(Reading(0.0, 0, 0.0, 0.0, 0.0, 4.0))
    points = method.finish()
    assert math.isclose(DEFAULT_BEAM_WIDTH, 0.39269908169872414)  # 22.5° = π/8
    assert float(points.width[0]) == pytest.approx(0.39269908169872414)
    # 2 · 4 · sin(π/32) = 0.78413...
    assert float(points.max_error[0]) == pytest.approx(0.7841371226364848, rel=1e-12)


def test_source_is_centerline_and_every_arc_is_processed_and_kept() -> None:
    method = make_method("centerline")
    assert isinstance(method, CenterlineMethod)
    assert method.name == "centerline"
    # Two readings from one pose, the second farther: carving would remove the first; the
    # centerline model keeps every arc.
    method.add(Reading(0.0, 0, 0.0, 0.0, 0.0, 1.0))
    method.add(Reading(0.1, 0, 0.0, 0.0, 0.0, 3.0))
    measures = method.measures()
    assert measures.unprocessed_share == 0.0  # Table I: 0 % for centerline
    assert (measures.fully_carved, measures.split) == (0, 0)
    assert measures.in_history == 2
    points = method.finish()
    assert points.source_labels() == ["centerline", "centerline"]
    np.testing.assert_allclose(points.xy, [[1.0, 0.0], [3.0, 0.0]], atol=1e-12)


def test_history_evicts_oldest_first() -> None:
    method = CenterlineMethod(history_size=2)
    batch = ReadingBatch.from_readings(READINGS)
    method.add_many(batch)
    # The history keeps the newest two; the oldest two have left, in arrival order.
    assert method.local_map().reading_id.tolist() == [2, 3]
    np.testing.assert_allclose(method.local_map().xy, EXPECTED_XY[2:], atol=1e-12)
    assert method.global_map().reading_id.tolist() == [0, 1]
    np.testing.assert_allclose(method.global_map().xy, EXPECTED_XY[:2], atol=1e-12)
    method.add(Reading(2.0, 0, 0.0, 0.0, 0.0, 1.0))
    assert method.local_map().reading_id.tolist() == [3, 4]
    assert method.global_map().reading_id.tolist() == [0, 1, 2]
    assert method.finish().reading_id.tolist() == [0, 1, 2, 3, 4]


def test_reading_ids_given_by_the_caller_are_kept() -> None:
    method = CenterlineMethod(history_size=2)
    for reading, rid in zip(READINGS, [10, 20, 35, 36], strict=True):
        method.add(reading, rid)
    assert method.finish().reading_id.tolist() == [10, 20, 35, 36]

