"""Each metric on hand-made inputs whose answers are worked out by hand or from geometry."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sonarcarve.lab.metrics import (
    binned,
    combine_binned,
    count_near_segment,
    error_summary,
    first_at_least,
    free_width,
    gap_region,
    is_passable,
    off_beam,
    patch_index,
    patch_latency,
    patch_of_points,
    percent,
    range_bin_index,
    resolved_share_curve,
    segment_distance,
)


def test_range_binning_edges_are_half_open() -> None:
    edges = [0.0, 1.0, 2.0, 4.0]
    values = [0.0, 0.999, 1.0, 3.999, 4.0, -0.1, math.nan]
    assert range_bin_index(values, edges).tolist() == [0, 0, 1, 2, -1, -1, -1]


def test_binned_stats_by_hand() -> None:
    # Bin [0,1): values 1, 2, 3, 10 -> mean 4, median 2.5; bin [1,2): empty; bin [2,3): 5.
    keys = [0.1, 0.2, 0.3, 0.9, 2.5, 7.0]
    values = [1.0, 2.0, 3.0, 10.0, 5.0, 100.0]
    stats = binned(values, keys, [0.0, 1.0, 2.0, 3.0])
    assert stats.counts.tolist() == [4, 0, 1]
    assert stats.mean[0] == pytest.approx(4.0)
    assert stats.median[0] == pytest.approx(2.5)
    assert math.isnan(stats.mean[1])
    assert stats.median[2] == pytest.approx(5.0)
    np.testing.assert_allclose(stats.centers, [0.5, 1.5, 2.5])
    assert stats.as_dict()["mean"][1] is None


def test_percent() -> None:
    assert percent([True, True, False]) == pytest.approx(200.0 / 3.0)
    assert math.isnan(percent([]))


def test_segment_distance_by_hand() -> None:
    walls = np.array([[0.0, 0.0, 4.0, 0.0],  # along x
                      [5.0, -1.0, 5.0, 1.0]])  # vertical at x = 5
    points = np.array([
        [2.0, 3.0],   # above the first wall: 3 from it, 3.16 from (5, 1)
        [-3.0, -4.0],  # beyond the first wall's end (0, 0): 5
        [4.6, 0.5],   # 0.4 from the vertical wall, 0.64 from (4, 0)
    ])
    d, k = segment_distance(points, walls)
    np.testing.assert_allclose(d, [3.0, 5.0, 0.4])
    assert k.tolist() == [0, 0, 1]


def test_count_near_segment() -> None:
    wall = [0.0, 0.0, 0.0, 10.0]
    pts = [[0.05, 5.0], [-0.1, 2.0], [0.11, 3.0], [0.0, 10.09], [0.0, 10.2]]
    assert count_near_segment(pts, wall, 0.1) == 3


def test_error_summary_ignores_nan() -> None:
    s = error_summary([0.0, 1.0, 2.0, 3.0, np.nan])
    assert s.median == pytest.approx(1.5)
    assert s.mean == pytest.approx(1.5)
    assert s.p90 == pytest.approx(2.7)  # linear interpolation: 0.9 * 3 = 2.7
    assert s.n == 4
    assert error_summary([]).n == 0


def test_first_at_least() -> None:
    assert first_at_least([0, 2, 4, 1], 3) == 2
    assert first_at_least([], 1) == -1


class TestPassableGap:
    """A 1 m doorway from (0, 0) to (1, 0); the robot needs 0.46 m."""

    region = gap_region([0.0, 0.0], [1.0, 0.0], depth=0.25)

    def test_empty_gap_is_its_width(self) -> None:
        assert free_width(np.zeros((0, 2)), self.region) == pytest.approx(1.0)

    def test_points_split_the_gap(self) -> None:
        # Blocks at 0.3 and 0.6 -> stretches 0.3, 0.3, 0.4.
        pts = [[0.3, 0.1], [0.6, -0.2]]
        assert free_width(pts, self.region) == pytest.approx(0.4)
        assert not is_passable(pts, self.region, 0.46)
        assert is_passable(pts, self.region, 0.4)

    def test_points_outside_do_not_block(self) -> None:
        # Beyond the depth, or along the wall beyond the jambs.
        pts = [[0.5, 0.26], [0.5, -0.3], [-0.2, 0.0], [1.3, 0.0]]
        assert free_width(pts, self.region) == pytest.approx(1.0)

    def test_one_point_near_a_jamb(self) -> None:
        assert free_width([[0.9, 0.0]], self.region) == pytest.approx(0.9)

    def test_rotated_gap(self) -> None:
        # The same doorway rotated by 90 degrees: jambs (0, 0) and (0, 1).
        region = gap_region([0.0, 0.0], [0.0, 1.0], depth=0.25)
        assert free_width([[0.1, 0.3], [-0.1, 0.6]], region) == pytest.approx(0.4)

    def test_identical_jambs_raise(self) -> None:
        with pytest.raises(ValueError, match="jambs"):
            gap_region([1.0, 1.0], [1.0, 1.0], 0.1)

    @settings(max_examples=50, deadline=None)
    @given(st.lists(st.floats(0.0, 1.0), max_size=6))
    def test_matches_a_sampled_reference(self, positions: list[float]) -> None:
        # Slow reference: the widest run of free 1 mm cells along the gap.
        pts = np.column_stack((positions, np.zeros(len(positions))))
        cells = np.linspace(0.0, 1.0, 1001)
        free = np.ones(cells.size - 1, dtype=bool)
        for s in positions:
            free[min(int(s * 1000), 999)] = False
        best = run = 0
        for f in free:
            run = run + 1 if f else 0
            best = max(best, run)
        assert free_width(pts, self.region) == pytest.approx(best / 1000, abs=2.5e-3)


def test_patch_index_and_lookup() -> None:
    walls = np.array([[0.0, 0.0, 1.2, 0.0],  # 1.2 m -> 3 patches of 0.5 m (last 0.2 m)
                      [2.0, 0.0, 2.0, 0.5]])  # 0.5 m -> 1 patch
    patches = patch_index(walls, 0.5)
    assert len(patches) == 4
    assert patches.segment.tolist() == [0, 0, 0, 1]
    assert patches.piece.tolist() == [0, 1, 2, 0]
    pts = np.array([[0.1, 0.0], [0.75, 0.0], [1.2, 0.0], [2.0, 0.5], [np.nan, np.nan],
                    [0.5, 0.3]])
    assert patch_of_points(pts, walls, patches).tolist() == [0, 1, 2, 3, -1, -1]


def test_patch_latency_by_hand() -> None:
    # Two patches. Readings 0, 1 hit patch 0 at t = 1, 2; reading 2 hits patch 1 at t = 3;
    # reading 3 is not on any wall.
    reading_patch = [0, 0, 1, -1]
    reading_t = [1.0, 2.0, 3.0, 3.5]
    sample_t = [1.0, 2.0, 3.0, 4.0]
    # Local maps: sample 0 has reading 0 off by 0.2; sample 1 has readings 0 (0.2) and 1 (0.01):
    # half within 5 cm -> patch 0 resolved at t = 2 for 5 cm. Sample 2: patch 1 at 0.08 (only
    # within 10 cm). Sample 3: patch 1 at 0.03 -> resolved at 4 for 5 cm, at 3 for 10 cm.
    rows = [(0, 0, 0.2), (1, 0, 0.2), (1, 1, 0.01), (2, 2, 0.08), (2, 3, 0.0), (3, 2, 0.03)]
    sample, reading, error = (list(c) for c in zip(*rows, strict=True))
    args = {"reading_patch": reading_patch, "reading_t": reading_t, "sample_t": sample_t,
            "row_sample": sample, "row_reading": reading, "row_error": error, "n_patches": 3}
    seen, res5 = patch_latency(**args, tolerance=0.05)
    _, res10 = patch_latency(**args, tolerance=0.10)
    assert seen.tolist() == [1.0, 3.0, math.inf]
    assert res5.tolist() == [2.0, 4.0, math.inf]
    assert res10.tolist() == [2.0, 3.0, math.inf]
    # A stricter quorum (all points) never resolves patch 0 at 5 cm: 0.2 is always there.
    _, strict = patch_latency(**args, tolerance=0.05, quorum=1.0)
    assert strict.tolist() == [math.inf, 4.0, math.inf]


def test_patch_latency_ignores_samples_before_first_view() -> None:
    # A point from a later reading cannot resolve a patch before it is seen: here the sample at
    # t = 0 already (wrongly) holds reading 0, which is dated t = 1.
    seen, res = patch_latency(reading_patch=[0], reading_t=[1.0], sample_t=[0.0, 1.0],
                              row_sample=[0, 1], row_reading=[0, 0], row_error=[0.0, 0.0],
                              n_patches=1, tolerance=0.05)
    assert seen.tolist() == [1.0]
    assert res.tolist() == [1.0]


def test_resolved_share_curve() -> None:
    curve = resolved_share_curve([0.5, 2.0, math.inf, 1.0], [0.0, 1.0, 5.0])
    assert curve.tolist() == [0.0, 50.0, 75.0]


def test_combine_binned_averages_runs_per_bin_by_hand() -> None:
    edges = [0.0, 1.0, 2.0, 3.0]
    runs = [binned([0.5, 0.6, 1.5], [0.1, 0.2, 1.5], edges).as_dict(),  # bins 0 and 1
            binned([0.1, 0.9], [0.5, 0.7], edges).as_dict()]  # bin 0 only
    out = combine_binned(runs, "mean")
    assert out["edges"] == edges
    assert out["count"] == [4, 1, 0]
    # Bin 0: run means 0.55 and 0.5; bin 1: only the first run; bin 2: no run.
    assert out["value"][0] == pytest.approx(0.525)
    assert out["min"][0] == pytest.approx(0.5)
    assert out["max"][0] == pytest.approx(0.55)
    assert out["value"][1] == pytest.approx(1.5)
    assert out["value"][2] is None
    assert out["min"][2] is None
    assert combine_binned(runs, "median")["max"][0] == pytest.approx(0.55)


BEAM = math.radians(22.5)


def _off(theta: float, bearing_deg: float, r: float, beam: float = BEAM) -> bool:
    """off_beam of one echo heard by a sensor at (1, 2) aimed at ``theta``, its reflector
    ``r`` metres away at ``bearing_deg`` from the world's +x axis."""
    b = math.radians(bearing_deg)
    hit = [[1.0 + r * math.cos(b), 2.0 + r * math.sin(b)]]
    return bool(off_beam([[1.0, 2.0]], [theta], [beam], hit)[0])


def test_off_beam_inside_and_far_outside_the_beam() -> None:
    assert not _off(0.0, 5.7, 1.0)  # inside ±11.25°
    assert _off(0.0, 90.0, 1.0)  # heard abeam: a side lobe
    assert _off(0.0, -90.0, 1.0)  # either side
    assert _off(0.0, 180.0, 1.0)  # behind


def test_off_beam_tolerance_is_arc_length_past_the_edge() -> None:
    # 2 m away, 0.02 rad past the edge is 4 cm of arc (inside the 5 cm tolerance), 0.03 rad 6 cm.
    edge = math.degrees(BEAM / 2)
    assert not _off(0.0, edge + math.degrees(0.02), 2.0)
    assert _off(0.0, edge + math.degrees(0.03), 2.0)
    # the same angle past the edge at 1 m is 3 cm: inside
    assert not _off(0.0, edge + math.degrees(0.03), 1.0)


def test_off_beam_wraps_bearings_across_pi() -> None:
    # aimed at 179°, reflector at -179° (2° off the axis): inside; at -150° (31° off): outside
    assert not _off(math.radians(179.0), -179.0, 1.0)
    assert _off(math.radians(179.0), -150.0, 1.0)


def test_off_beam_uses_each_echo_s_told_width_and_skips_missing_reflectors() -> None:
    assert _off(0.0, 30.0, 1.0, beam=math.radians(45.0))
    assert not _off(0.0, 30.0, 1.0, beam=math.radians(75.0))
    nan = off_beam([[0.0, 0.0]], [0.0], [BEAM], [[np.nan, np.nan]])
    assert nan.tolist() == [False]


def test_off_beam_reads_each_row_s_own_width() -> None:
    # two echoes from the same reflector 30° off the axis, told 75° then 45°: inside, outside
    hit = [[math.cos(math.radians(30.0)), math.sin(math.radians(30.0))]] * 2
    widths = [math.radians(75.0), math.radians(45.0)]
    assert off_beam([[0.0, 0.0]] * 2, [0.0, 0.0], widths, hit).tolist() == [False, True]
