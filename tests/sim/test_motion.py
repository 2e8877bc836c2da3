"""Robot motion: driving polylines, exploring without collisions, odometry drift."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sonarcarve.sim import motion
from sonarcarve.sim.generate import random_world
from sonarcarve.sim.motion import (
    ROBOT_RADIUS,
    Trajectory,
    explore,
    follow_waypoints,
    with_localisation_noise,
    with_odometry_drift,
)
from sonarcarve.sim.world import World, WorldError, load_world


def _distance_to_polyline(points: np.ndarray, polyline: np.ndarray) -> np.ndarray:
    a, b = polyline[:-1], polyline[1:]
    edge = b - a
    u = np.clip(np.einsum("nmk,mk->nm", points[:, None, :] - a[None], edge)
                / np.sum(edge * edge, axis=1), 0.0, 1.0)
    nearest = a[None] + u[..., None] * edge[None]
    return np.asarray(np.linalg.norm(points[:, None, :] - nearest, axis=2).min(axis=1))


# --- follow_waypoints --------------------------------------------------------------------------

def test_square_turning_in_place_by_hand() -> None:
    square = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0], [0.0, 0.0]])
    tr = follow_waypoints(square, speed=0.5, dt=0.05, turn_rate=1.0)
    # 8 m at 0.5 m/s plus three quarter turns at 1 rad/s.
    assert tr.duration == pytest.approx(16.0 + 3 * math.pi / 2)
    assert tr.path_length == pytest.approx(8.0)
    assert (tr.x[0], tr.y[0], tr.heading[0]) == (0.0, 0.0, 0.0)
    assert (tr.x[-1], tr.y[-1]) == pytest.approx((0.0, 0.0))
    assert tr.heading[-1] == pytest.approx(3 * math.pi / 2)  # unwrapped: three left turns
    points = np.column_stack((tr.x, tr.y))
    assert _distance_to_polyline(points, square).max() < 1e-12
    steps = np.hypot(np.diff(tr.x), np.diff(tr.y))
    assert steps.max() <= 0.5 * 0.05 + 1e-12
    assert np.abs(np.diff(tr.heading)).max() <= 1.0 * 0.05 + 1e-12
    np.testing.assert_allclose(np.diff(tr.t)[:-1], 0.05)
    # After 1 s the robot is 0.5 m along the first leg.
    x, y, heading = tr.pose_at(1.0)
    assert (float(x), float(y), float(heading)) == pytest.approx((0.5, 0.0, 0.0))


def test_heading_is_unwrapped_across_minus_pi() -> None:
    zigzag = np.array([[0.0, 0.0], [-1.0, 0.01], [-2.0, -0.01], [-3.0, 0.01]])
    tr = follow_waypoints(zigzag, dt=0.01)
    assert np.abs(np.diff(tr.heading)).max() < 0.05
    assert abs(tr.heading[0]) == pytest.approx(math.pi, abs=0.02)


def test_rounded_corner_keeps_speed_and_cuts_the_corner_by_r_sqrt2_minus_1() -> None:
    r = 0.5
    corner = np.array([[-3.0, 0.0], [0.0, 0.0], [0.0, 3.0]])
    tr = follow_waypoints(corner, speed=0.4, dt=0.01, turn_rate=1.0, corner_radius=r)
    points = np.column_stack((tr.x, tr.y))
    # The arc's middle is r (sqrt 2 - 1) from the corner (hand geometry for a right angle).
    assert np.hypot(points[:, 0], points[:, 1]).min() == pytest.approx(r * (SQRT2 - 1), abs=1e-3)
    steps = np.hypot(np.diff(tr.x), np.diff(tr.y))
    np.testing.assert_allclose(steps[:-1], 0.4 * 0.01, rtol=1e-5)  # never stops (chords on arc)
    # 6 m minus the two cut tangents (r each) plus the quarter arc.
    assert tr.path_length == pytest.approx(6.0 - 2 * r + r * math.pi / 2, rel=1e-4)
    assert tr.heading[-1] == pytest.approx(math.pi / 2)
    assert (tr.x[-1], tr.y[-1]) == pytest.approx((0.0, 3.0))


SQRT2 = math.sqrt(2.0)


def test_follow_waypoints_bad_input() -> None:
    for waypoints in ([[0.0, 0.0]], [[1.0, 1.0], [1.0, 1.0]], [[0.0, np.nan], [1.0, 0.0]],
                      [0.0, 1.0, 2.0]):
        with pytest.raises(WorldError):
            follow_waypoints(waypoints)
    for kwargs in ({"speed": 0.0}, {"dt": -1.0}, {"turn_rate": np.inf}, {"corner_radius": -1.0}):
        with pytest.raises(WorldError):
            follow_waypoints([[0.0, 0.0], [1.0, 0.0]], **kwargs)  # type: ignore[arg-type]


def test_following_a_builtin_tour_never_comes_near_walls() -> None:
    world = load_world("t-junction")
    assert world.tour is not None
    tr = follow_waypoints(world.tour, corner_radius=0.3)
    clearance = world.distance_to_walls(np.column_stack((tr.x, tr.y)))
    assert clearance.min() >= ROBOT_RADIUS


# --- explore -----------------------------------------------------------------------------------

def _crossings(path: np.ndarray, openings: np.ndarray) -> int:
    """Proper crossings of a polyline with opening segments."""
    p, q = path[:-1], path[1:]
    count = 0
    for a, b in openings:
        side_a = (q[:, 0] - p[:, 0]) * (a[1] - p[:, 1]) - (q[:, 1] - p[:, 1]) * (a[0] - p[:, 0])
        side_b = (q[:, 0] - p[:, 0]) * (b[1] - p[:, 1]) - (q[:, 1] - p[:, 1]) * (b[0] - p[:, 0])
        side_p = (b[0] - a[0]) * (p[:, 1] - a[1]) - (b[1] - a[1]) * (p[:, 0] - a[0])
        side_q = (b[0] - a[0]) * (q[:, 1] - a[1]) - (b[1] - a[1]) * (q[:, 0] - a[0])
        count += int(np.sum((side_a * side_b < 0) & (side_p * side_q < 0)))
    return count


@pytest.fixture(scope="module")
def small_floor_run() -> tuple[object, Trajectory]:
    world = random_world(3, 24.0, 18.0)
    return world, explore(world, 240.0, seed=1)


def test_explorer_never_collides_and_respects_kinematics(
        small_floor_run: tuple[object, Trajectory]) -> None:
    world, tr = small_floor_run
    assert len(tr) == round(240.0 / 0.05) + 1
    clearance = world.distance_to_walls(np.column_stack((tr.x, tr.y)))  # type: ignore[attr-defined]
    assert clearance.min() >= ROBOT_RADIUS
    steps = np.hypot(np.diff(tr.x), np.diff(tr.y))
    assert steps.max() <= 0.4 * 0.05 + 1e-9
    assert np.abs(np.diff(tr.heading)).max() <= 1.0 * 0.05 + 1e-9
    # Between poses at least radius - step/2 (distance to walls is 1-Lipschitz).
    assert clearance.min() - steps.max() / 2 >= ROBOT_RADIUS - 1e-9


def test_explorer_keeps_moving_and_goes_through_doors(
        small_floor_run: tuple[object, Trajectory]) -> None:
    world, tr = small_floor_run
    assert tr.path_length >= 0.6 * 0.4 * 240.0
    # In every minute it covers ground, not just turning on the spot.
    minute = int(60.0 / 0.05)
    for start in range(0, len(tr) - minute, minute):
        assert tr.distance_at(tr.t[start + minute]) - tr.distance_at(tr.t[start]) > 5.0
    path = np.column_stack((tr.x, tr.y))
    assert _crossings(path, world.openings) >= 2  # type: ignore[attr-defined]
    # It spreads out: the poses cover many distinct 2 m cells.
    cells = {(int(x // 2.0), int(y // 2.0)) for x, y in path}
    assert len(cells) >= 20


def test_explorer_is_deterministic_per_seed() -> None:
    world = load_world("t-junction")
    first, again = explore(world, 40.0, seed=5), explore(world, 40.0, seed=5)
    np.testing.assert_array_equal(first.x, again.x)
    np.testing.assert_array_equal(first.heading, again.heading)
    other = explore(world, 40.0, seed=6)
    assert not np.array_equal(first.x, other.x)


def test_explorer_in_a_corridor_follows_it() -> None:
    world = load_world("t-junction")
    tr = explore(world, 60.0, seed=0, start=(0.0, 1.0, math.pi / 2))
    clearance = world.distance_to_walls(np.column_stack((tr.x, tr.y)))
    assert clearance.min() >= ROBOT_RADIUS
    assert tr.y.max() > 10.0  # went up the stem towards the junction


def test_explorer_rejects_a_start_inside_a_wall() -> None:
    world = load_world("t-junction")
    with pytest.raises(WorldError, match="closer than"):
        explore(world, 10.0, seed=0, start=(0.9, 5.0))
    with pytest.raises(WorldError):
        explore(world, 0.0, seed=0)


# --- odometry ----------------------------------------------------------------------------------

def _straight(length: float) -> Trajectory:
    return follow_waypoints([[0.0, 0.0], [length, 0.0]], speed=0.4, dt=0.05)


def test_odometry_without_noise_is_the_truth() -> None:
    truth = follow_waypoints(load_world("office").tour, dt=0.05)  # type: ignore[arg-type]
    dead = with_odometry_drift(truth, seed=0, translation_noise=0.0, rotation_noise=0.0,
                               heading_bias=0.0)
    np.testing.assert_allclose(dead.x, truth.x, atol=1e-9)
    np.testing.assert_allclose(dead.y, truth.y, atol=1e-9)
    np.testing.assert_allclose(dead.heading, truth.heading, atol=1e-12)
    np.testing.assert_array_equal(dead.t, truth.t)


def test_heading_bias_bends_a_straight_line_as_computed_by_hand() -> None:
    # With heading growing as b s along the way, the believed end of an L-metre straight run is
    # (sin(bL)/b, (1 - cos(bL))/b).
    b, length = 0.01, 20.0
    dead = with_odometry_drift(_straight(length), seed=0, translation_noise=0.0,
                               rotation_noise=0.0, heading_bias=b)
    expected = (math.sin(b * length) / b, (1.0 - math.cos(b * length)) / b)
    assert (dead.x[-1], dead.y[-1]) == pytest.approx(expected, abs=1e-4)
    assert dead.heading[-1] == pytest.approx(b * length)


def test_odometry_drift_grows_with_distance_and_is_deterministic() -> None:
    truth = _straight(100.0)
    errors = []
    for seed in range(20):
        dead = with_odometry_drift(truth, seed=seed)
        errors.append(np.hypot(dead.x - truth.x, dead.y - truth.y))
    mean_error = np.mean(errors, axis=0)
    at = [int(np.searchsorted(truth.x, d)) for d in (10.0, 40.0, 100.0)]
    assert mean_error[at[0]] < mean_error[at[1]] < mean_error[at[2]]
    assert mean_error[at[2]] > 0.5  # metres after 100 m: visible drift with the defaults
    first = with_odometry_drift(truth, seed=3)
    np.testing.assert_array_equal(first.x, with_odometry_drift(truth, seed=3).x)
    assert not np.array_equal(first.x, with_odometry_drift(truth, seed=4).x)


def test_odometry_bad_parameters() -> None:
    truth = _straight(1.0)
    for kwargs in ({"translation_noise": -1.0}, {"rotation_noise": np.nan},
                   {"heading_bias": np.inf}):
        with pytest.raises(WorldError):
            with_odometry_drift(truth, seed=0, **kwargs)  # type: ignore[arg-type]


# --- localisation noise ------------------------------------------------------------------------
# Expected values are the Ornstein-Uhlenbeck process's: stationary std σ and correlation
# exp(-Δ/τ) between errors Δ seconds apart. Tolerances are about 4 standard errors of the
# estimates (the large-sample formulas for a Gauss-Markov sequence's variance and lag
# correlations, Bartlett's), so the fixed seeds are not what makes them pass.

def _uneven(duration: float, short: float = 0.02, long: float = 0.08) -> Trajectory:
    """A straight run whose poses alternate ``short`` and ``long`` seconds apart."""
    steps = np.tile([short, long], round(duration / (short + long)))
    t = np.concatenate(([0.0], np.cumsum(steps)))
    return Trajectory(t, 0.4 * t, np.zeros_like(t), np.zeros_like(t))


def _lag_correlation(e: np.ndarray, first: np.ndarray, second: np.ndarray) -> float:
    return float(np.corrcoef(e[first], e[second])[0, 1])


def test_localisation_error_has_the_stationary_sigma() -> None:
    truth = _uneven(4000.0)  # 80,001 poses, 4000 τ: std of σ's estimate ≈ σ √(τ / 2T) ≈ 1.1 %
    noisy = with_localisation_noise(truth, seed=1, position_sigma=0.05, heading_sigma=0.02,
                                    correlation_time=1.0)
    assert np.std(noisy.x - truth.x) == pytest.approx(0.05, rel=0.05)
    assert np.std(noisy.y - truth.y) == pytest.approx(0.05, rel=0.05)
    assert np.std(noisy.heading - truth.heading) == pytest.approx(0.02, rel=0.05)
    assert abs(np.mean(noisy.x - truth.x)) < 0.05 * 0.1  # mean: std σ √(2τ/T) ≈ 0.022 σ


def test_localisation_error_forgets_itself_at_the_correlation_time() -> None:
    tau = 2.0
    truth = _uneven(8000.0)
    noisy = with_localisation_noise(truth, seed=2, position_sigma=0.03, heading_sigma=0.01,
                                    correlation_time=tau)
    n = len(truth)
    # Poses 20 apart are exactly 1 s apart; 40 apart, 2 s (= τ).
    for error in (noisy.x - truth.x, noisy.heading - truth.heading):
        for lag, seconds in ((20, 1.0), (40, 2.0), (100, 5.0)):
            first = np.arange(n - lag)
            assert _lag_correlation(error, first, first + lag) == pytest.approx(
                math.exp(-seconds / tau), abs=0.05)
        # One pose on: 0.02 s after even poses, 0.08 s after odd ones (the real time step
        # counts, not a mean one).
        even, odd = np.arange(0, n - 1, 2), np.arange(1, n - 1, 2)
        assert _lag_correlation(error, even, even + 1) == pytest.approx(
            math.exp(-0.02 / tau), abs=0.004)
        assert _lag_correlation(error, odd, odd + 1) == pytest.approx(
            math.exp(-0.08 / tau), abs=0.004)


def test_localisation_errors_in_x_y_and_heading_are_independent() -> None:
    truth = _uneven(4000.0)  # about 2,000 independent stretches: a correlation's std ≈ 0.02
    noisy = with_localisation_noise(truth, seed=5, position_sigma=0.05, heading_sigma=0.02)
    errors = np.vstack((noisy.x - truth.x, noisy.y - truth.y, noisy.heading - truth.heading))
    correlations = np.corrcoef(errors)
    for i, j in ((0, 1), (0, 2), (1, 2)):
        assert abs(correlations[i, j]) < 0.1, (i, j, correlations[i, j])


def test_localisation_error_is_stationary_from_the_first_pose() -> None:
    truth = _uneven(0.1)
    first = np.array([with_localisation_noise(truth, seed=seed, position_sigma=0.05).x[0]
                      for seed in range(800)])
    # 800 draws of N(0, σ²): std of σ's estimate σ / √1600 = 2.5 %.
    assert np.std(first) == pytest.approx(0.05, rel=0.12)


def test_localisation_noise_is_seeded() -> None:
    truth = _straight(10.0)
    first = with_localisation_noise(truth, seed=3)
    again = with_localisation_noise(truth, seed=3)
    for name in ("t", "x", "y", "heading"):
        np.testing.assert_array_equal(getattr(first, name), getattr(again, name))
    assert not np.array_equal(first.x, with_localisation_noise(truth, seed=4).x)


def test_localisation_noise_of_zero_sigma_is_the_truth() -> None:
    truth = follow_waypoints(load_world("office").tour, dt=0.05)  # type: ignore[arg-type]
    still = with_localisation_noise(truth, seed=0, position_sigma=0.0, heading_sigma=0.0)
    for name in ("t", "x", "y", "heading"):
        np.testing.assert_array_equal(getattr(still, name), getattr(truth, name))
    # Each sigma moves only its own coordinates.
    turned = with_localisation_noise(truth, seed=0, position_sigma=0.0, heading_sigma=0.02)
    np.testing.assert_array_equal(turned.x, truth.x)
    np.testing.assert_array_equal(turned.y, truth.y)
    assert not np.array_equal(turned.heading, truth.heading)
    moved = with_localisation_noise(truth, seed=0, position_sigma=0.02, heading_sigma=0.0)
    np.testing.assert_array_equal(moved.heading, truth.heading)
    assert not np.array_equal(moved.y, truth.y)


def test_localisation_noise_bad_parameters() -> None:
    truth = _straight(1.0)
    for kwargs, message in (
            ({"position_sigma": -0.01}, "position_sigma must be a finite number >= 0, got -0.01"),
            ({"heading_sigma": np.nan}, "heading_sigma must be a finite number >= 0, got nan"),
            ({"correlation_time": 0.0}, "correlation_time must be a finite number > 0, got 0.0"),
            ({"correlation_time": np.inf},
             "correlation_time must be a finite number > 0, got inf")):
        with pytest.raises(WorldError) as info:
            with_localisation_noise(truth, seed=0, **kwargs)  # type: ignore[arg-type]
        assert str(info.value) == message


# --- size limits -------------------------------------------------------------------------------

def test_waypoints_beyond_max_coordinate_are_refused() -> None:
    assert motion.MAX_COORDINATE == 1e5
    with pytest.raises(WorldError) as info:
        follow_waypoints([[0.0, 0.0], [1e300, 0.0]])
    assert str(info.value) == ("waypoints[1] (1e+300, 0) lies farther than the limit of 100000 m "
                               "(MAX_COORDINATE) from the origin in x or y")
    with pytest.raises(WorldError, match=r"waypoints\[0\] \(0, -100001\)"):
        follow_waypoints([[0.0, -100_001.0], [0.0, 0.0]])
    # At the limit itself: 200 km at 0.4 m/s is 500,000 s, 501 poses at dt = 1000 s.
    tr = follow_waypoints([[-1e5, 1e5], [1e5, 1e5]], dt=1000.0)
    assert len(tr) == 501


def test_a_path_needing_more_than_max_poses_is_refused_before_allocating() -> None:
    assert motion.MAX_POSES == 10_000_000
    # 100 km at 0.4 m/s = 250,000 s; every 1 ms that is 2.5e8 poses.
    with pytest.raises(WorldError) as info:
        follow_waypoints([[0.0, 0.0], [1e5, 0.0]], dt=1e-3)
    message = str(info.value)
    assert message.startswith("path of 250000 s sampled every 0.001 s needs 2.5e+08 poses")
    assert "limit of 10,000,000 (MAX_POSES)" in message


def test_max_poses_is_the_boundary(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(motion, "MAX_POSES", 11)
    # 1 m at 0.5 m/s every 0.2 s: t = 0, 0.2, ..., 2.0, that is 11 poses: allowed.
    assert len(follow_waypoints([[0.0, 0.0], [1.0, 0.0]], speed=0.5, dt=0.2)) == 11
    with pytest.raises(WorldError, match="MAX_POSES"):
        follow_waypoints([[0.0, 0.0], [1.2, 0.0]], speed=0.5, dt=0.2)  # 13 poses
    with pytest.raises(WorldError, match="MAX_POSES"):
        explore(load_world("t-junction"), 2.2, seed=0, dt=0.2)  # 12 poses
    monkeypatch.setattr(motion, "MAX_POSES", 12)
    assert len(explore(load_world("t-junction"), 2.2, seed=0, dt=0.2)) == 12


def test_explore_refuses_a_billion_seconds_at_once() -> None:
    with pytest.raises(WorldError) as info:
        explore(load_world("doorway"), 1e9, seed=0)
    # 1e9 s every 0.05 s is 2e10 poses (+1).
    assert str(info.value).startswith("exploration of 1e+09 s sampled every 0.05 s needs 2e+10 "
                                      "poses, more than the limit of 10,000,000 (MAX_POSES)")


def test_explore_refuses_a_world_too_big_for_its_planning_grid() -> None:
    # A 400 m square: (401 m / 0.1 m)^2 = 1.6e7 cells > 1e7.
    square = World(np.array([[0, 0, 400, 0], [400, 0, 400, 400], [400, 400, 0, 400],
                             [0, 400, 0, 0]], dtype=float), "plaza")
    with pytest.raises(WorldError, match=r"plaza: 400 m x 400 m is too big to explore: its "
                                         r"0\.1 m planning grid would have 1\.61e\+07 cells"):
        explore(square, 10.0, seed=0, start=(200.0, 200.0))


def test_seeded_motion_refuses_negative_seeds() -> None:
    tr = follow_waypoints([[0.0, 0.0], [1.0, 0.0]])
    with pytest.raises(WorldError, match=r"^seed must be an integer >= 0, got -1$"):
        with_odometry_drift(tr, seed=-1)
    with pytest.raises(WorldError, match=r"^seed must be an integer >= 0, got -3$"):
        explore(load_world("doorway"), 1.0, seed=-3)
