"""The evidence kernels: the detection model, the threshold and the exact helpers of the
kernels (beyond the paper)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numba import njit

from sonarcarve.geometry.evidence import (
    _bin_of_sine,
    _sort_in_place,
    detect_probability,
    evidence_threshold,
)

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


def _binary_search_bin(sine: float, edges: np.ndarray, bins: int) -> int:
    # The search _bin_of_sine replaced (the oracle): the largest k in 1 .. K - 1 with
    # edges[k] <= sine, else 0.
    lo, hi = 0, bins
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if edges[mid] <= sine:
            lo = mid
        else:
            hi = mid
    return lo


@pytest.mark.parametrize("beam", [math.radians(22.5), math.radians(60.0), math.radians(170.0),
                                  1e-40, 1e-300])  # narrow: guesses beyond int64
def test_the_bin_of_a_sine_is_the_binary_searchs_bin(beam: float) -> None:
    # The guess treats the sines as evenly spaced; the steps after it must land on the exact
    # bin, also on the edges themselves, beyond the beam and for wide beams (bad guesses).
    bins = 24
    edges = np.sin(-0.5 * beam + np.arange(bins + 1) * (beam / bins))
    scale = bins / (edges[-1] - edges[0])
    rng = np.random.default_rng(5)
    sines = np.concatenate([rng.uniform(-1.0, 1.0, 2000), edges, np.nextafter(edges, -2.0),
                            np.nextafter(edges, 2.0), [-1.0, 1.0, 0.0, -0.0, math.nan]])
    for sine in sines.tolist():
        assert _bin_of_sine(sine, edges, bins, scale) == _binary_search_bin(sine, edges, bins)


_numba_sort = njit(lambda values: np.sort(values))


@pytest.mark.parametrize("n", [0, 1, 2, 3, 7, 15, 16, 40])
def test_sorting_in_place_leaves_np_sorts_order_bit_for_bit(n: int) -> None:
    # The median of the crossings must not move in its last bit: ties of 0.0 and -0.0 and
    # NaNs must end where numba's np.sort (the code before) put them.
    rng = np.random.default_rng(n)
    for _ in range(50):
        values = rng.choice([-0.0, 0.0, 1.0, -1.0, 0.5, math.nan], size=n)
        values[: n // 2] = rng.uniform(-1.0, 1.0, n // 2)
        rng.shuffle(values)
        expected = _numba_sort(values.copy())
        buffer = np.concatenate([values, [7.0, 7.0]])  # the sort must stay within n
        _sort_in_place(buffer, n)
        np.testing.assert_array_equal(buffer[:n].view(np.int64), expected.view(np.int64))
        assert buffer[n:].tolist() == [7.0, 7.0]
