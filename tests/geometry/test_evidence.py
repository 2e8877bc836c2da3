"""The evidence kernels: the detection model, the threshold and the exact helpers of the
kernels (beyond the paper)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numba import njit

from sonarcarve.geometry.evidence import (
    EstimateRules,
    detect_probability,
    evidence_estimates,
    evidence_threshold,
)
from sonarcarve.geometry.evidence.arrays import BinEvidence, CrossingArrays, ReadingRows
from sonarcarve.geometry.evidence.bins import bin_of_sine
from sonarcarve.geometry.evidence.runs import _sort_in_place

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
    # The search bin_of_sine replaced (the oracle): the largest k in 1 .. K - 1 with
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
        assert bin_of_sine(sine, edges, bins, scale) == _binary_search_bin(sine, edges, bins)


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


# Placement of a point (evidence_estimates) on one hand-made arc: r = 2 m, axis 0, a beam of
# 0.4 rad in K = 4 bins of 0.1 rad (edges -0.2, -0.1, 0, 0.1, 0.2). A bin is carved when its free
# evidence reaches T (bin 0 below: T + 1, the run is bins 1-3, [-0.1, 0.2], its middle 0.05).
_T = evidence_threshold(0.8)


def _place(free: list[float], located: list[float], crossings: tuple[float, ...] = (), *,
           posterior: bool = True, uncut: bool = False, min_crossings: int = 3,
           atm_bound: float = 0.01) -> tuple[float, float, bool]:
    """(bearing, bound, is_atm) of the arc's point."""
    f = np.array([free], dtype=np.float64)
    loc = np.array([located], dtype=np.float64)
    bearings = np.zeros((1, 8), dtype=np.float32)
    bearings[0, : len(crossings)] = crossings
    counts = np.array([len(crossings)], dtype=np.int32)
    one = np.zeros(1)
    readings = ReadingRows(x=one, y=one, r=np.array([2.0]), theta=one,
                           beam_width=np.array([0.4]), sensor=np.zeros(1, dtype=np.int64))
    rules = EstimateRules(threshold=_T, atm_bound=atm_bound, with_atm=True, place_located=True,
                          posterior=posterior, posterior_uncut=uncut,
                          min_crossings=min_crossings)
    raw = evidence_estimates(
        np.array([0], dtype=np.int64), readings, BinEvidence(free=f, support=loc.copy(),
                                                             located=loc),
        np.zeros(1, dtype=np.int8), CrossingArrays(bearings=bearings, counts=counts,
                                                   spill=np.zeros((1, 2))), rules)
    return float(raw.bearing[0]), float(raw.max_error[0]), bool(raw.is_atm[0])


def test_misses_lower_a_bins_weight_by_the_chance_they_were_all_misses() -> None:
    # Bin 2's free evidence ln 2: newer readings that would have heard a surface there with
    # P = 1/2 all missed it. Weights exp(-F) * located over bins 1-3: 0, 1/2, 1; half of 1.5
    # is 0.25 into bin 3. The rule before ignored the misses: the centre of the bin where the
    # located support 0, 1, 1 reaches half its sum (bin 2: 0.05).
    cut = _T + 1.0
    bearing, _, _ = _place([cut, 0, math.log(2.0), 0], [0, 0, 1, 1])
    assert bearing == pytest.approx(0.1 + 0.25 * 0.1, abs=1e-12)
    before, _, _ = _place([cut, 0, math.log(2.0), 0], [0, 0, 1, 1], posterior=False)
    assert before == pytest.approx(0.05, abs=1e-12)


def test_without_localised_support_the_misses_alone_place_the_point() -> None:
    # Weights 1/4, 1, 1 (free ln 4 on bin 1): half of 2.25 is 1.125, reached 0.875 into bin 2.
    # The rule before: the run's middle (0.05).
    cut = _T + 1.0
    bearing, _, _ = _place([cut, math.log(4.0), 0, 0], [0, 0, 0, 0])
    assert bearing == pytest.approx(0.0 + 0.875 * 0.1, abs=1e-12)
    before, _, _ = _place([cut, math.log(4.0), 0, 0], [0, 0, 0, 0], posterior=False)
    assert before == pytest.approx(0.05, abs=1e-12)


def test_equal_weights_give_the_runs_middle_and_the_bound_covers_the_hull() -> None:
    # Bin 0 carved, no support: equal weights, the run's middle 0.05 (eq. 3.6). The bound
    # reaches the far end, 0.15 away, plus half a bin: 2 r sin(0.2 / 2).
    bearing, bound, is_atm = _place([_T + 1.0, 0, 0, 0], [0, 0, 0, 0])
    assert bearing == pytest.approx(0.05, abs=1e-12)
    assert bound == pytest.approx(2.0 * 2.0 * math.sin(0.1), abs=1e-12)
    assert not is_atm


def test_an_uncut_beam_keeps_its_middle_unless_asked() -> None:
    # Nothing cut: the middle (0). With posterior_uncut, the localised support 0, 0, 1, 1
    # (exp(-0) = 1 everywhere): half of 2 is reached at the end of bin 2 (0.1).
    assert _place([0, 0, 0, 0], [0, 0, 1, 1])[0] == pytest.approx(0.0, abs=1e-12)
    assert _place([0, 0, 0, 0], [0, 0, 1, 1], uncut=True)[0] == pytest.approx(0.1, abs=1e-12)


def test_atms_median_places_the_point_from_three_crossings_in_the_run() -> None:
    # Two crossings (0.05, 0.15): their "median" is their mean, one ghost moves it anywhere:
    # the uncut beam keeps its middle (0). Three (0.05, 0.12, 0.15): the median 0.12 with
    # ATM's bound (0.01 here, below the hull's). With min_crossings 1, as before, two are
    # enough: their mean 0.1.
    two = (0.05, 0.15)
    bearing, bound, is_atm = _place([0, 0, 0, 0], [0, 0, 1, 1], two)
    assert not is_atm
    assert bearing == pytest.approx(0.0, abs=1e-12)
    assert bound > 0.01
    bearing, bound, is_atm = _place([0, 0, 0, 0], [0, 0, 1, 1], (0.05, 0.12, 0.15))
    assert is_atm
    assert bearing == pytest.approx(0.12, abs=1e-7)  # float32 crossings
    assert bound == 0.01
    bearing, _, is_atm = _place([0, 0, 0, 0], [0, 0, 1, 1], two, min_crossings=1)
    assert is_atm
    assert bearing == pytest.approx(0.1, abs=1e-7)


def test_atms_median_loses_to_a_smaller_bound() -> None:
    # Section 4's rule stays: ATM's point only where its bound is the smaller. A bound of 5 m
    # is larger than any on a 2 m arc: the posterior's point stays (0.125, as above).
    bearing, bound, is_atm = _place([_T + 1.0, 0, math.log(2.0), 0], [0, 0, 1, 1],
                                    (0.05, 0.12, 0.15), atm_bound=5.0)
    assert not is_atm
    assert bearing == pytest.approx(0.125, abs=1e-12)
    assert bound < 5.0


# Review rev9p: ties, rounding and the ATM rule of the posterior placement.
_CUT = _T + 1.0


@pytest.mark.parametrize(("free", "located"), [
    ([_CUT, 0, 0, 0], [0, 1, 0, 1]),               # located in bins 1 and 3, bin 2 between
    ([0, 0, 0, 0, 0, _CUT], [1, 0, 0, 0, 1, 0]),   # K = 6, a gap of three bins
])
def test_a_mirror_image_profile_gives_the_mirror_image_point(
        free: list[float], located: list[float]) -> None:
    # Equal weights on both sides of bins with none: every point of the gap is a median (the
    # weight below and above it is half each). The scan from the lower end took the gap's
    # lower end, so the mirrored profile (bearing -> -bearing) put its point elsewhere than the
    # mirror of the first: by the gap's whole width. The middle of the gap is the one choice
    # that does not depend on the direction of the scan (here the middle of the run's
    # support: bearing 0.05 for the first case, the gap's middle -0.0333... for the second).
    point = _place(free, located)[0]
    mirrored = _place(free[::-1], located[::-1])[0]
    assert point == pytest.approx(-mirrored, abs=1e-12)
    step = 0.4 / len(free)
    k = [i for i, v in enumerate(located) if v > 0]  # the two supported bins
    gap_middle = -0.2 + 0.5 * (k[0] + 1 + k[1]) * step
    assert point == pytest.approx(gap_middle, abs=1e-12)


def test_a_bin_lighter_than_one_ulp_of_the_total_does_not_push_the_point_past_it() -> None:
    # Weights 1, 0.75 ulp, 1 + ulp over bins 1-3 (bin 0 carved): half the total is reached,
    # to 1e-16, at the lower edge of bin 3 (0.1). In floating point acc + w rounds up to half
    # at the tiny bin 2 while half - acc is one ulp: the interpolation's fraction was 4/3, and
    # the point went a third of a bin into bin 3 (0.1333). The fraction of a bin is at most 1.
    u = 2.0 ** -52
    bearing, _, _ = _place([_CUT, 0, 0, 0], [0, 1.0, 0.75 * u, 1.0 + u])
    assert bearing == pytest.approx(0.1, abs=1e-12)


def test_atms_median_needs_a_strictly_smaller_bound() -> None:
    # Section 4: the estimate with the *smaller* bound; on a tie the posterior's point stays.
    # The posterior's bound is read with ATM out of reach, then given to ATM as its own.
    free, located, crossings = [_CUT, 0, 0, 0], [0, 0, 0, 0], (0.05, 0.12, 0.15)
    point, carved_bound, is_atm = _place(free, located, crossings, atm_bound=10.0)
    assert not is_atm
    assert point == pytest.approx(0.05, abs=1e-12)  # equal weights: the run's middle
    bearing, bound, is_atm = _place(free, located, crossings, atm_bound=carved_bound)
    assert not is_atm
    assert bearing == point
    assert bound == carved_bound


def test_on_a_split_arc_atms_median_has_the_hulls_bound_not_eq_5_4s() -> None:
    # Bins 0 and 2-3 survive (bin 1 carved): two runs, the hull [-0.2, 0.2]. Three crossings in
    # bin 2 ([0, 0.1]) keep run 2-3; the localised support in bin 3 puts the posterior's point
    # at bin 3's middle, 0.15: bound 2 r sin((0.35 + 0.05) / 2). ATM's median 0.05 may be
    # anywhere in the hull too (the echo may be in the other run): its bound is the hull's from
    # 0.05, 2 r sin((0.25 + 0.05) / 2), not eq. 5.4's 0.01; it is the smaller, so ATM places it.
    bearing, bound, is_atm = _place([0, _CUT, 0, 0], [0, 0, 0, 1], (0.01, 0.05, 0.08))
    assert is_atm
    assert bearing == pytest.approx(0.05, abs=1e-7)  # float32 crossings
    assert bound == pytest.approx(4.0 * math.sin(0.15), abs=1e-6)
    # Crossings whose median (0.18) lies farther from the hull's middle than 0.15: the hull
    # bound from there is the larger, the posterior's point stays (its bound as above).
    bearing, bound, is_atm = _place([0, _CUT, 0, 0], [0, 0, 0, 1], (0.17, 0.18, 0.19))
    assert not is_atm
    assert bearing == pytest.approx(0.15, abs=1e-12)
    assert bound == pytest.approx(4.0 * math.sin(0.2), abs=1e-12)


def test_localised_support_outside_the_kept_run_does_not_weigh_in_it() -> None:
    # Runs: bin 0 (localised support 0.5) and bins 2-3 (three crossings: kept, 3 > 0.5). The
    # kept run has no localised support, so its misses alone place the point: weights 1/4, 1
    # (free ln 4 on bin 2), half of 1.25 reached 0.375 into bin 3: 0.1375. Support in another
    # run must not switch the kept run's weights to the (zero) localised support (the middle,
    # 0.1). ATM needs 4 crossings here, so the three only pick the run.
    bearing, _, is_atm = _place([0, _CUT, math.log(4.0), 0], [0.5, 0, 0, 0],
                                (0.12, 0.15, 0.18), min_crossings=4)
    assert not is_atm
    assert bearing == pytest.approx(0.1 + 0.375 * 0.1, abs=1e-12)


def test_the_split_arc_keeps_the_run_with_localised_support_not_the_longer_one() -> None:
    # Runs: bin 0 with localised support, bins 2-3 without (longer). No crossings: the run with
    # the support is kept; its point is bin 0's middle, -0.15 (its only weighted bin).
    bearing, _, _ = _place([0, _CUT, 0, 0], [0.3, 0, 0, 0])
    assert bearing == pytest.approx(-0.15, abs=1e-12)


def test_the_kernels_default_atm_count_is_the_documented_three() -> None:
    # Nothing in the library makes EstimateRules without min_crossings, so a drifted default
    # would go unnoticed until someone did.
    rules = EstimateRules(threshold=_T, atm_bound=0.01, with_atm=True, place_located=True)
    assert rules.min_crossings == 3
    assert rules.posterior is True
    assert rules.posterior_uncut is False
