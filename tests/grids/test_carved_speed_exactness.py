"""The carved grid's speed-ups that must not change a bit: free space's quick update, the final
band's heard bin, ATM's stored bearings.

:func:`~sonarcarve.grids.carved.free_space.free_space` computes a plain cell's update with cheap
stand-ins for its arctangent and fade and keeps the result only when an error bound proves it
is the exact update's float32; these tests check the bounds and the proof's test
(:func:`~sonarcarve.grids.carved.free_space._stored`), and compare whole beams bit for bit with
the exact update computed here.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from sonarcarve.grids import CarvedGridParams, scan
from sonarcarve.grids.carved import band
from sonarcarve.grids.carved import free_space as fs
from sonarcarve.grids.carved.heard import HEARD_BINS, heard_bin
from sonarcarve.grids.carved.model import Model, model_of
from sonarcarve.grids.scan import bearing_off
from sonarcarve.methods import atm

H = 0.1
XMIN, YMIN = -2.0, -2.0
SHAPE = (40, 40)


def _model(**changes: float) -> Model:
    params = CarvedGridParams(**changes)  # type: ignore[arg-type]
    return model_of(params, XMIN, YMIN, H, 0.5 * (H + params.range_tolerance))


def test_the_arctangent_series_stays_within_its_bound() -> None:
    ts = np.concatenate([np.linspace(-scan.SERIES_T, scan.SERIES_T, 20001), [1e-300, -1e-300]])
    for along in (1e-3, 0.37, 1.0, 6.5):
        worst = max(abs(scan.atan_series(t) - math.atan2(t * along, along)) for t in ts)
        assert worst <= scan.SERIES_ERROR


def test_the_exponential_fade_stays_within_its_bound() -> None:
    # 1 / (1 + e^{2u}) is (1 - tanh u) / 2: the quick update's fade against the exact one.
    for d_f in (0.3, 1.2, 4.0):
        d = np.linspace(0.0, 10.0, 200001)
        exact = np.array([0.5 * (1.0 - math.tanh(2.0 * (v - d_f))) for v in d])
        quick = np.array([1.0 / (1.0 + math.exp(4.0 * (v - d_f))) for v in d])
        assert np.max(np.abs(quick - exact)) <= fs.FADE_ERROR


def _float32_neighbours(v: float) -> tuple[float, float]:
    low = np.float32(v)
    return float(low), float(np.nextafter(low, np.float32(np.inf)))


def _clamped(total: float, m: Model) -> np.float32:
    return np.float32(min(m.l_max, max(m.l_min, total)))


def test_stored_leaves_open_a_sum_its_margin_cannot_place() -> None:
    # A sum exactly half-way between two float32s: a change off by the stated error either
    # way would round to the other one. _stored must then say NaN (or, if it decides, the
    # exact sum's float32); far from a midpoint it decides.
    m = _model()
    rng = np.random.default_rng(3)
    error = 1e-13
    decided = 0
    for _ in range(2000):
        cell = float(np.float32(rng.uniform(m.l_min, 0.0)))
        lo, hi = _float32_neighbours(cell + rng.uniform(-0.3, 0.0))
        change = 0.5 * (lo + hi) - cell  # exact: both are float32s near each other
        for off in (-error, 0.0, error):
            got = fs._stored(cell, change + off, error, m)
            assert math.isnan(got) or np.float32(got) == _clamped(cell + change, m)
        far = change + 0.25 * (hi - lo)
        got = fs._stored(cell, far, error, m)
        decided += not math.isnan(got)
        assert math.isnan(got) or np.float32(got) == _clamped(cell + far, m)
    assert decided == 2000
    # Zero is never decided: -0.0 and 0.0 compare equal and differ in their bits.
    assert math.isnan(fs._stored(0.0, 1e-60, 0.0, m))
    assert math.isnan(fs._stored(0.0, -1e-60, 0.0, m))


def _exact_free_space(base: np.ndarray, m: Model, x: float, y: float, theta: float, r: float,
                      half: float) -> np.ndarray:
    """The plain update of every cell of the beam (no cell believed occupied), as the kernel
    computed it before the quick update, over every cell of the grid."""
    out = base.copy()
    reach = r - m.band
    c, s, cos_half = math.cos(theta), math.sin(theta), math.cos(half)
    for i in range(base.shape[0]):
        dy = m.ymin + (i + 0.5) * m.h - y
        for j in range(base.shape[1]):
            dx = m.xmin + (j + 0.5) * m.h - x
            d2 = dx * dx + dy * dy
            along = dx * c + dy * s
            if d2 >= reach * reach or along < math.sqrt(d2) * cos_half:
                continue
            a = math.atan2(dy * c - dx * s, along)
            w = 1.0 - (a / half) ** 2
            miss = m.l_miss
            if m.fade < math.inf:
                miss *= 0.5 * (1.0 - math.tanh(2.0 * (math.sqrt(d2) - m.fade)))
            out[i, j] = min(m.l_max, max(m.l_min, float(base[i, j]) + w * miss))
    return out


def _random_base(rng: np.random.Generator, m: Model) -> np.ndarray:
    """Cells not believed occupied, in the states a map has: fresh (0), at the clamp's floor,
    anywhere below 0, and just below 0 (where a tiny faded update decides the bits)."""
    kinds = rng.integers(0, 4, SHAPE)
    values = np.select(
        [kinds == 0, kinds == 1, kinds == 2],
        [0.0, m.l_min, rng.uniform(m.l_min, 0.0, SHAPE)],
        -(10.0 ** rng.uniform(-30, -3, SHAPE)))
    return values.astype(np.float32)


@pytest.mark.parametrize("changes", [{}, {"fade_range": math.inf}, {"fade_range": 0.4}])
@pytest.mark.parametrize("half", [0.5 * math.radians(22.5), 0.05, 0.6])
def test_free_space_stores_the_exact_updates_bits(changes: dict[str, float],
                                                 half: float) -> None:
    # Beams of the Polaroid's width, narrower, and wider than the series reaches (their outer
    # cells take the exact path), from anywhere, at every range up to past the grid.
    m = _model(**changes)
    rng = np.random.default_rng(11)
    held = np.empty((fs.HELD, 7))
    heard = np.zeros(SHAPE, dtype=np.uint32)
    for _ in range(30):
        base = _random_base(rng, m)
        x, y = rng.uniform(-1.5, 1.5, 2)
        theta, r = rng.uniform(-math.pi, math.pi), rng.uniform(0.2, 5.0)
        expected = _exact_free_space(base, m, x, y, theta, r, half)
        fs.free_space(base, heard, m, fs.Beam(x, y, theta, r, half), held)
        np.testing.assert_array_equal(base.view(np.uint32), expected.view(np.uint32))


def test_without_surface_awareness_a_freed_cell_forgets_its_bearings_on_the_quick_path() -> None:
    # With surface_aware off, cells believed occupied take the plain update too (the quick path
    # included): the same bits, and a cell it brings from above 0 to 0 or below forgets where it
    # was heard from, the others keep it (a mutant the review rev10c found passing).
    m = _model(surface_aware=False)
    rng = np.random.default_rng(12)
    held = np.empty((fs.HELD, 7))
    freed = 0
    for _ in range(30):
        base = np.where(rng.random(SHAPE) < 0.5, _random_base(rng, m),
                        rng.uniform(0.0, 0.3, SHAPE)).astype(np.float32)
        heard = np.full(SHAPE, 0b101, dtype=np.uint32)
        before = base.copy()
        x, y = rng.uniform(-1.5, 1.5, 2)
        theta, r = rng.uniform(-math.pi, math.pi), rng.uniform(0.2, 5.0)
        expected = _exact_free_space(base, m, x, y, theta, r, 0.5 * math.radians(22.5))
        fs.free_space(base, heard, m, fs.Beam(x, y, theta, r, 0.5 * math.radians(22.5)), held)
        np.testing.assert_array_equal(base.view(np.uint32), expected.view(np.uint32))
        crossed = (before > 0.0) & (base <= 0.0)
        freed += int(crossed.sum())
        np.testing.assert_array_equal(heard == 0, crossed)
    assert freed > 20


def test_a_final_bands_heard_bin_is_the_exact_bearings() -> None:
    # Cells all round, and cells within 1e-16..1e-9 rad of a bin's edge (where a bearing off
    # by its rounding would land in the next bin), against the bin of the exact bearing.
    rng = np.random.default_rng(5)
    edges = -math.pi + 2.0 * math.pi / HEARD_BINS * np.arange(HEARD_BINS + 1)
    for k in range(20000):
        if k % 2:
            bearing = rng.choice(edges) + rng.choice([-1.0, 1.0]) * 10.0 ** rng.uniform(-16, -9)
        else:
            bearing = rng.uniform(-math.pi, math.pi)
        mid = bearing + rng.uniform(-0.25, 0.25)
        d = rng.uniform(0.05, 6.0)
        dx, dy = d * math.cos(bearing), d * math.sin(bearing)
        exact = heard_bin(mid + bearing_off(dx, dy, mid))
        assert band._heard_bin_of(dx, dy, mid, math.cos(mid), math.sin(mid)) == exact


@pytest.mark.parametrize("turns", [1e3, 1e5, -1e5])
def test_the_heard_bin_is_the_exact_bearings_for_an_interval_written_many_turns_out(
        turns: float) -> None:
    # The bearings' rounding grows with |mid|: near 2π·1e5 a 1e-12 margin was too small and
    # bins came out one off at their edges (review rev10c). Cells within 1e-9 of bin edges.
    rng = np.random.default_rng(6)
    edges = -math.pi + 2.0 * math.pi / HEARD_BINS * np.arange(HEARD_BINS + 1)
    for _ in range(5000):
        bearing = rng.choice(edges) + rng.choice([-1.0, 1.0]) * 10.0 ** rng.uniform(-12, -9)
        mid = bearing + rng.uniform(-0.25, 0.25) + 2.0 * math.pi * turns
        dx, dy = math.cos(bearing), math.sin(bearing)
        exact = heard_bin(mid + bearing_off(dx, dy, mid))
        assert band._heard_bin_of(dx, dy, mid, math.cos(mid), math.sin(mid)) == exact


def test_each_cell_of_a_final_band_records_the_bin_of_its_own_bearing() -> None:
    # A band over 10 bins: each cell records the bin it lies in as seen from the arc's origin,
    # one bit, not the bin of the interval's middle (a mutant the review rev10c found passing).
    m = _model()
    grid = np.zeros(SHAPE, np.float32)
    heard = np.zeros(SHAPE, np.uint32)
    x, y = 0.03, -0.02
    band.draw_arc(grid, True, heard, m, band.ArcBand(x, y, 1.5, -1.0, 1.0), 0.5)
    rows, cols = np.nonzero(heard)
    assert len(rows) > 40
    # And exactly the band's cells, as draw_arc defines it (plain Python: centre within the band
    # of the circle, bearing within the interval widened by half a cell), each given the value.
    widen = 0.5 * H / 1.5
    mid, half = 0.0, 1.0 + widen
    expected = np.zeros(SHAPE, bool)
    for i in range(SHAPE[0]):
        for j in range(SHAPE[1]):
            dx, dy = XMIN + (j + 0.5) * H - x, YMIN + (i + 0.5) * H - y
            if (abs(math.hypot(dx, dy) - 1.5) <= m.band
                    and abs(bearing_off(dx, dy, mid)) <= half):
                expected[i, j] = True
    assert np.array_equal(heard != 0, expected)
    assert np.array_equal(grid != 0, expected)
    bins = set()
    for i, j in zip(rows, cols, strict=True):
        dx, dy = XMIN + (j + 0.5) * H - x, YMIN + (i + 0.5) * H - y
        k = heard_bin(math.atan2(dy, dx))
        assert int(heard[i, j]) == 1 << k
        bins.add(k)
    assert len(bins) >= 9


@pytest.mark.parametrize("profile", [0.0, 1.5])
def test_moving_an_arc_in_one_pass_adds_what_taking_it_out_and_drawing_it_again_adds(
        profile: float) -> None:
    # redraw moves an arc whose interval or value changed in one pass over the union of its
    # old and new bands (band._move_arc); each cell must get the same two additions, in the
    # same order, as undrawing the old band and drawing the new: the same bits. On a live grid
    # full of random values, so that the order of the additions shows in the rounding.
    m = _model(band_profile=profile)
    rng = np.random.default_rng(17)
    changed = 0
    for _ in range(60):
        live = rng.normal(0.0, 1.0, SHAPE)
        heard = np.zeros(SHAPE, np.uint32)
        x, y, r = rng.uniform(-0.5, 0.5), rng.uniform(-0.5, 0.5), rng.uniform(0.3, 1.6)
        lo0 = rng.uniform(-math.pi, math.pi)
        hi0 = lo0 + rng.uniform(0.0, 0.8)
        lo1 = lo0 + rng.uniform(-0.3, 0.5)  # overlapping, apart, or nested
        hi1 = max(lo1, hi0 + rng.uniform(-0.6, 0.3))
        value0, value1 = rng.uniform(0.1, 1.0), rng.uniform(0.1, 1.0)
        old, new = band.ArcBand(x, y, r, lo0, hi0), band.ArcBand(x, y, r, lo1, hi1)
        drawn = np.zeros((3, 6))
        drawn[1] = (x, y, r, lo0, hi0, value0)
        drawn_seq = np.array([-1, 7, -1], dtype=np.int64)
        before = live.copy()
        expected = live.copy()
        band.draw_arc(expected, False, heard, m, old, -value0)
        band.draw_arc(expected, False, heard, m, new, value1)
        assert band.redraw(live, drawn, drawn_seq, 1, 7, new, value1, heard, m) == 1
        assert np.array_equal(live, expected)
        assert tuple(drawn[1]) == (x, y, r, lo1, hi1, value1)
        changed += not np.array_equal(live, before)
    assert changed == 60  # every case moved cells


def test_atm_stores_the_exact_bearings_float32() -> None:
    # Crossings all across the beam, and bearings within 1e-17..1e-12 of a float32 rounding
    # midpoint (where a bearing off by the series' error would round the other way).
    rng = np.random.default_rng(9)
    for k in range(20000):
        along = rng.uniform(0.05, 6.0)
        bearing = rng.uniform(-0.199, 0.199)
        if k % 2:
            low = np.float32(bearing)
            mid = 0.5 * (float(low) + float(np.nextafter(low, np.float32(1.0))))
            bearing = mid + rng.choice([-1.0, 1.0]) * 10.0 ** rng.uniform(-17, -12)
        cross = along * math.tan(bearing)
        got = np.float32(atm._bearing32(cross, along))
        assert got.view(np.uint32) == np.float32(math.atan2(cross, along)).view(np.uint32)
