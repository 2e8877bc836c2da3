"""Points behind a surface of the map (``geometry/occluded.py``): hand geometry, and the compiled
kernels against a brute-force reference over every pair of points."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sonarcarve.geometry import occluded
from sonarcarve.geometry.occluded import LINE_RATIO, occluded_points, surface_directions

DEPTH, REACH, RADIUS, NEIGHBOURS, CROSSING = 0.5, 0.05, 0.3, 3, math.radians(20.0)


def _hidden(xy: np.ndarray, origin: np.ndarray, blocks: np.ndarray | None = None) -> np.ndarray:
    return occluded_points(xy, origin, depth=DEPTH, reach=REACH, radius=RADIUS,
                           neighbours=NEIGHBOURS, crossing=CROSSING, blocks=blocks)


def _wall(start: tuple[float, float], angle: float, length: float,
          spacing: float = 0.05) -> np.ndarray:
    """Points every ``spacing`` along a straight wall from ``start`` at ``angle``."""
    s = np.arange(0.0, length + 1e-9, spacing)
    return np.column_stack([start[0] + s * math.cos(angle), start[1] + s * math.sin(angle)])


def _hidden_target(wall: np.ndarray, target: tuple[float, float]) -> bool:
    """Whether ``target``, heard from the origin, is hidden by ``wall`` (heard from afar, so
    the wall's own points are never hidden: their origins sit on the wall's far side)."""
    xy = np.vstack([wall, [target]])
    origin = np.vstack([wall + np.array([10.0, 0.0]), [[0.0, 0.0]]])
    return bool(_hidden(xy, origin)[-1])


# -- hand geometry ------------------------------------------------------------------------------

def test_a_wall_across_the_line_hides_a_point_behind_it() -> None:
    wall = _wall((1.0, -0.5), math.pi / 2, 1.0)  # x = 1, y from -0.5 to 0.5
    assert _hidden_target(wall, (2.0, 0.0))
    assert not _hidden_target(wall, (0.8, 0.0))  # in front of it
    assert not _hidden_target(wall, (2.0, 3.0))  # the line misses the wall


def test_depth_is_measured_along_the_line_from_the_wall() -> None:
    wall = _wall((1.0, -0.5), math.pi / 2, 1.0)
    # The nearest wall point on the line is (1, 0): 0.5 m in front of (1.5, 0) is not enough
    # (the test is strict), a millimetre more is.
    assert not _hidden_target(wall, (1.5, 0.0))
    assert _hidden_target(wall, (1.501, 0.0))


def test_a_wall_along_the_line_does_not_hide() -> None:
    for angle, hides in ((0.0, False), (math.radians(15.0), False), (math.radians(25.0), True),
                         (math.radians(90.0), True)):
        # A wall through (1, 0) at ``angle`` to the line from the origin to (2.5, 0).
        centre = np.array([1.0, 0.0])
        wall = _wall(tuple(centre - 0.5 * np.array([math.cos(angle), math.sin(angle)])),
                     angle, 1.0)
        assert _hidden_target(wall, (2.5, 0.0)) is hides, math.degrees(angle)


def test_a_lone_point_or_a_blob_is_no_surface() -> None:
    assert not _hidden_target(np.array([[1.0, 0.0]]), (2.0, 0.0))
    rng = np.random.default_rng(3)
    blob = np.array([1.0, 0.0]) + rng.normal(scale=0.05, size=(30, 2))
    assert not _hidden_target(blob, (2.0, 0.0))


def test_reach_the_line_must_pass_within() -> None:
    # A wall ending just short of the line: within reach it hides, beyond it does not.
    near = _wall((1.0, 0.04), math.pi / 2, 1.0)
    far = _wall((1.0, 0.06), math.pi / 2, 1.0)
    assert _hidden_target(near, (2.0, 0.0))
    assert not _hidden_target(far, (2.0, 0.0))


def test_a_wall_ending_just_within_reach_is_found_wherever_the_walk_steps() -> None:
    # The walk looks only at the cells around each step: a surface point at the edge of the
    # reach, between two steps, on lines at every angle and offset, must still be seen (cells
    # one reach wide, half what the walk needs, miss some of these).
    missed = []
    for degrees in range(0, 360, 7):
        u = np.array([math.cos(math.radians(degrees)), math.sin(math.radians(degrees))])
        n = np.array([-u[1], u[0]])
        for along in np.linspace(0.8, 1.2, 23):
            end = along * u + 0.999 * REACH * n  # the wall's end, just within reach
            wall = end + np.outer(np.arange(8) * 0.05, n)  # running away from the line
            xy = np.vstack([wall, [2.0 * u]])
            origin = np.vstack([wall + 10.0 * n, [[0.0, 0.0]]])
            if not _hidden(xy, origin)[-1]:
                missed.append((degrees, round(float(along), 3)))
    assert not missed


def test_points_hide_one_another_only_from_their_own_sensor() -> None:
    # Two walls of a corridor, each heard from the middle: none is behind the other.
    left = _wall((0.0, 1.0), 0.0, 4.0)
    right = _wall((0.0, -1.0), 0.0, 4.0)
    xy = np.vstack([left, right])
    origin = np.column_stack([xy[:, 0], np.zeros(len(xy))])
    assert not _hidden(xy, origin).any()
    # Heard through the left wall from across it (a multipath reading of the right wall as seen
    # from outside the corridor): every right-wall point behind the left wall is hidden.
    origin[len(left):, 1] = 3.0
    hidden = _hidden(xy, origin)
    assert not hidden[: len(left)].any()
    assert hidden[len(left):].sum() >= len(right) - 2  # the ends may fall short of a surface


def test_only_points_that_may_block_hide_others() -> None:
    wall = _wall((1.0, -0.5), math.pi / 2, 1.0)
    xy = np.vstack([wall, [[2.0, 0.0]]])
    origin = np.vstack([wall + np.array([10.0, 0.0]), [[0.0, 0.0]]])
    assert _hidden(xy, origin, np.ones(len(xy), dtype=bool))[-1]
    assert not _hidden(xy, origin, np.r_[np.zeros(len(wall), dtype=bool), True])[-1]
    # Half the wall may block: still a surface across the line.
    half = np.r_[np.arange(len(wall)) % 2 == 0, True]
    assert _hidden(xy, origin, half)[-1]


def test_mismatched_arrays_are_refused() -> None:
    xy = np.zeros((3, 2))
    with pytest.raises(ValueError, match="must match the 3 points"):
        _hidden(xy, np.zeros((2, 2)))
    with pytest.raises(ValueError, match="must match the 3 points"):
        _hidden(xy, np.zeros((3, 2)), np.ones(4, dtype=bool))


def test_neighbours_exactly_a_radius_apart_count() -> None:
    # Points 0.1 apart along x = 0 (the 0.3 m radius spans exactly three gaps): found by a
    # review, floor rounding put the first and fourth two cells apart when cells were exactly
    # one radius wide, and neither saw the other.
    xy = np.array([[0, -0.44], [0, -0.33999999999999997], [0, -0.24], [0, -0.14], [5, -4.34]])
    direction = surface_directions(xy, RADIUS, NEIGHBOURS)
    np.testing.assert_array_equal(np.isnan(direction[:, 0]), [False] * 4 + [True])


def test_a_map_spread_over_kilometres_finds_its_cells_by_search_with_the_same_answer() -> None:
    # Two rooms 40 km apart: a table of 0.1 m cells over that extent would hold 10^11 of them;
    # past MAX_CELLS the cells are found by binary search, and the masks are still the
    # brute-force ones.
    xy, origin = _random_map(4)
    far = np.vstack([xy, xy + 40_000.0])
    far_origin = np.vstack([origin, origin + 40_000.0])
    blocks = np.ones(len(far), dtype=bool)
    got = _hidden(far, far_origin)
    np.testing.assert_array_equal(
        got, _reference_hidden(far, far_origin, blocks, DEPTH, REACH, RADIUS))
    np.testing.assert_array_equal(got[: len(xy)], got[len(xy):])
    assert got.any()


def test_a_wall_ending_near_the_far_end_of_the_walk_is_found() -> None:
    # The walk's last step lands at d - depth exactly: a wall ending within reach of the line
    # just before it must be seen (a review's sweep: without that step, 14 of these were
    # missed). Every case is one scene, 10 m from the others (and a random part of a cell, so
    # that the cells fall differently across each), all mapped in one call.
    rng = np.random.default_rng(0)
    scenes, want, where = [], [], []
    for degrees in range(0, 360, 7):
        u = np.array([math.cos(math.radians(degrees)), math.sin(math.radians(degrees))])
        n = np.array([-u[1], u[0]])
        for along in np.linspace(1.0, 1.5, 501)[:-1]:
            for target in (1.95, 1.99):  # d - depth = 1.45, 1.49
                if abs(along - (target - DEPTH)) < 1e-9:
                    continue  # a tie, which the kernel and the reference may round apart
                end = along * u + 0.999 * REACH * n
                wall = end + np.outer(np.arange(8) * 0.05, n)
                shift = (10.0 * np.array([len(scenes) % 200, len(scenes) // 200])
                         + rng.uniform(0.0, 0.1, 2))
                scenes.append((np.vstack([wall, [target * u]]) + shift,
                               # the wall heard from 0.2 m: nearer than the depth, no walk
                               np.vstack([wall + 0.2 * n, [[0.0, 0.0]]]) + shift))
                want.append(along < target - DEPTH)  # strictly more than the depth in front
                where.append((degrees, round(float(along), 3), target))
    xy = np.vstack([scene[0] for scene in scenes])
    origin = np.vstack([scene[1] for scene in scenes])
    hidden = _hidden(xy, origin)[8::9]  # each scene's target, after its 8 wall points
    missed = [case for case, got, ok in zip(where, hidden, want, strict=True) if got != ok]
    assert not missed


def test_neighbours_a_radius_apart_count_wherever_the_cells_fall() -> None:
    # Four points on a line, the ends a hair less than one radius apart, slid across the
    # surface cells (a third of the radius and a hair) in steps of 1e-5 m: cells 0.3 % too
    # narrow lose the end pair only where the first point lies in the top 1 % of its cell.
    # Expected by hand: on a line every point is a surface with 3 others within the radius, so
    # the ends are when they are within it of each other, as the distance is computed in floats.
    disagree = []
    for offset in np.linspace(0.0, 0.1, 10_001):
        line = offset + np.array([0.0, 0.1, 0.2, RADIUS - 1e-12])
        xy = np.vstack([[-1.0, -1.0], np.column_stack([line, np.zeros(4)])])
        ends = (line[3] - line[0]) ** 2 <= RADIUS * RADIUS
        want = [True, not ends, False, False, not ends]  # the far point: never a surface
        if np.isnan(surface_directions(xy, RADIUS, NEIGHBOURS)[:, 0]).tolist() != want:
            disagree.append(round(float(offset), 5))
    assert not disagree


def test_empty_and_single_maps() -> None:
    assert _hidden(np.zeros((0, 2)), np.zeros((0, 2))).shape == (0,)
    assert not _hidden(np.array([[1.0, 1.0]]), np.zeros((1, 2))).any()
    assert surface_directions(np.zeros((0, 2)), RADIUS, NEIGHBOURS).shape == (0, 2)


def test_surface_directions_by_hand() -> None:
    angle = math.radians(30.0)
    wall = _wall((0.0, 0.0), angle, 1.0)
    direction = surface_directions(wall, RADIUS, NEIGHBOURS)
    assert np.all(np.isfinite(direction))
    np.testing.assert_allclose(np.abs(direction @ [math.cos(angle), math.sin(angle)]), 1.0,
                               atol=1e-9)
    # Exactly ``neighbours`` others within the radius (inclusive) make a surface; one fewer
    # does not.
    four = np.array([[0.0, 0.0], [0.1, 0.0], [0.2, 0.0], [0.3, 0.0]])
    assert np.isfinite(surface_directions(four, 0.3, 3)[0, 0])
    assert np.isnan(surface_directions(four[:3], 0.3, 3)[0, 0])
    assert np.isnan(surface_directions(four, 0.29, 3)[0, 0])
    # Four corners of a rectangle 0.2 m long: 6 cm wide its scatter's eigenvalues are
    # 0.1² : 0.03² = 11 to 1, a line; 8 cm wide, 0.1² : 0.04² = 6.25 to 1, not (a line needs
    # its spread along three times that across, 9 to 1).
    for half_width, line in ((0.03, True), (0.04, False)):
        corners = np.array([[sx * 0.1, sy * half_width] for sx in (-1, 1) for sy in (-1, 1)])
        assert bool(np.isfinite(surface_directions(corners, 0.3, 3)[:, 0]).all()) is line
    # A square's corners spread equally both ways: not a line.
    square = np.array([[0.0, 0.0], [0.1, 0.0], [0.0, 0.1], [0.1, 0.1]])
    assert np.isnan(surface_directions(square, 0.3, 3)).all()


# -- the kernels against brute force ------------------------------------------------------------

def _reference_directions(xy: np.ndarray, radius: float, neighbours: int) -> np.ndarray:
    out = np.full(xy.shape, np.nan)
    for i, p in enumerate(xy):
        near = xy[np.sum((xy - p) ** 2, axis=1) <= radius * radius]
        if len(near) - 1 < neighbours:
            continue
        values, vectors = np.linalg.eigh(np.cov(near.T, bias=True))
        if values[1] > 0.0 and values[1] >= LINE_RATIO * values[0]:
            out[i] = vectors[:, 1]
    return out


def _reference_hidden(xy: np.ndarray, origin: np.ndarray, blocks: np.ndarray,
                      depth: float, reach: float, radius: float) -> np.ndarray:
    direction = np.full(xy.shape, np.nan)
    direction[blocks] = _reference_directions(xy[blocks], radius, NEIGHBOURS)
    out = np.zeros(len(xy), dtype=bool)
    for i in range(len(xy)):
        v = xy[i] - origin[i]
        d = math.hypot(*v)
        if d <= depth:
            continue
        u = v / d
        w = xy - origin[i]
        in_front = w @ u
        across = np.abs(w[:, 0] * u[1] - w[:, 1] * u[0])
        crossing = np.abs(direction[:, 0] * u[1] - direction[:, 1] * u[0])
        hides = ((in_front > 0.0) & (in_front < d - depth) & (across <= reach)
                 & (crossing >= math.sin(CROSSING)))
        hides[i] = False
        out[i] = bool(hides.any())
    return out


def _random_map(seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Noisy walls and stray points in a 6 m room, each heard from a random origin (some far
    outside the points' extent, so that walks leave the bucketed cells)."""
    rng = np.random.default_rng(seed)
    walls = [_wall(tuple(rng.uniform(-3, 3, 2)), rng.uniform(0, math.pi), rng.uniform(0.3, 3),
                   rng.uniform(0.03, 0.15)) for _ in range(rng.integers(3, 9))]
    xy = np.vstack([*walls, rng.uniform(-3, 3, (rng.integers(0, 30), 2))])
    xy += rng.normal(scale=rng.uniform(0.0, 0.03), size=xy.shape)
    origin = rng.uniform(-5, 5, xy.shape)
    return xy, origin


@pytest.mark.parametrize("table", [True, False], ids=["cell table", "binary search"])
@pytest.mark.parametrize("seed", range(12))
def test_kernels_match_brute_force(seed: int, table: bool,
                                   monkeypatch: pytest.MonkeyPatch) -> None:
    if not table:  # as on a map too wide for the table of cell starts
        monkeypatch.setattr(occluded, "MAX_CELLS", 0)
    xy, origin = _random_map(seed)
    got = surface_directions(xy, RADIUS, NEIGHBOURS)
    want = _reference_directions(xy, RADIUS, NEIGHBOURS)
    np.testing.assert_array_equal(np.isnan(got[:, 0]), np.isnan(want[:, 0]))
    line = ~np.isnan(want[:, 0])
    np.testing.assert_allclose(np.abs(np.sum(got[line] * want[line], axis=1)), 1.0, atol=1e-9)
    # Other depths, reaches wider than half the radius (the walk's cells then follow the
    # reach), and only some points blocking.
    rng = np.random.default_rng(100 + seed)
    blocks = rng.random(len(xy)) < (1.0 if seed % 3 == 0 else 0.7)
    depth, reach, radius = ((DEPTH, REACH, RADIUS), (0.3, 0.3, 0.15), (0.8, 0.12, 0.4))[seed % 3]
    hidden = occluded_points(xy, origin, depth=depth, reach=reach, radius=radius,
                             neighbours=NEIGHBOURS, crossing=CROSSING, blocks=blocks)
    np.testing.assert_array_equal(
        hidden, _reference_hidden(xy, origin, blocks, depth, reach, radius))
    assert hidden.any()  # the comparison says something
    assert not hidden.all()
