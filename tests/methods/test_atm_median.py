"""ATM places a point at the *median* of its arc's kept crossings (paper, section 2-D).

Arc A: radius 2 about the origin, axis 0, beam 0.9 rad. Each other reading B_k is built by hand
to cross A's circle at bearing b_k at right angles: its origin is P_k - (cos(b_k + π/2),
sin(b_k + π/2)) with P_k = 2 (cos b_k, sin b_k), range 1, axis b_k + π/2 pointing at P_k, beam
0.2 rad. The circles' other crossing is 2 atan(2/1) ≈ 127° away as seen from B_k's origin, far
outside B_k's beam, so A keeps exactly the bearings b_k, at a transversal angle of 90° (≥ ψ).
The bearings are picked so that their mean and median differ.
"""

from __future__ import annotations

import math

import pytest

from sonarcarve.maps import PointSource
from sonarcarve.methods import AtmMethod
from sonarcarve.readings import Reading

RADIUS = 2.0


def _crossing_reading(t: float, sensor: int, bearing: float) -> Reading:
    px, py = RADIUS * math.cos(bearing), RADIUS * math.sin(bearing)
    axis = bearing + 0.5 * math.pi
    return Reading(t, sensor, px - math.cos(axis), py - math.sin(axis), axis, 1.0, 0.2)


@pytest.mark.parametrize(("bearings", "median"), [
    ((-0.3, 0.0, 0.1), 0.0),  # mean -0.0667
    ((-0.3, -0.1, 0.2, 0.35), 0.05),  # even count: the middle two, averaged; mean 0.0375
])
def test_atm_point_is_at_the_median_bearing(bearings: tuple[float, ...], median: float) -> None:
    method = AtmMethod(history_size=10)
    method.add(Reading(0.0, 0, 0.0, 0.0, 0.0, RADIUS, 0.9))
    for k, bearing in enumerate(bearings):
        method.add(_crossing_reading(1.0 + k, 1 + k, bearing))
    points = method.local_map()
    first = points.reading_id.tolist().index(0)
    assert points.source[first] == PointSource.ATM
    x, y = points.xy[first]
    assert math.hypot(x, y) == pytest.approx(RADIUS)
    assert math.atan2(y, x) == pytest.approx(median, abs=1e-6)  # bearings stored as float32
    mean = sum(bearings) / len(bearings)
    assert abs(mean - median) > 0.01  # the scene tells the two apart
    assert points.width[first] == pytest.approx(max(bearings) - min(bearings), abs=1e-6)

