"""Scenarios: cutting a path to a length, stamping readings with believed poses."""

from __future__ import annotations

import numpy as np

from sonarcarve.lab.scenarios import Scenario, cut_polyline, run_simulation


def test_cut_polyline_by_hand() -> None:
    path = [[0.0, 0.0], [3.0, 0.0], [3.0, 4.0]]
    np.testing.assert_allclose(cut_polyline(path, 1.0), [[0, 0], [1, 0]])
    np.testing.assert_allclose(cut_polyline(path, 3.0), [[0, 0], [3, 0]])
    np.testing.assert_allclose(cut_polyline(path, 5.5), [[0, 0], [3, 0], [3, 2.5]])
    np.testing.assert_allclose(cut_polyline(path, 100.0), path)
    np.testing.assert_allclose(cut_polyline(path, None), path)


def test_localisation_noise_moves_the_stamps_not_the_echoes() -> None:
    plain = run_simulation(Scenario("doorway", 0, max_length=3.0))
    noisy = run_simulation(Scenario("doorway", 0, max_length=3.0,
                                    localisation_noise=(0.05, 0.02, 1.0)))
    np.testing.assert_array_equal(noisy.truth.reflection, plain.truth.reflection)
    np.testing.assert_array_equal(noisy.readings.range, plain.readings.range)
    assert noisy.odometry is not None
    assert plain.odometry is None
    # Sensor origins move by the believed pose's error: centimetres, not zero.
    moved = np.hypot(noisy.readings.x - plain.readings.x, noisy.readings.y - plain.readings.y)
    assert 0.0 < float(np.median(moved)) < 0.2
    still = run_simulation(Scenario("doorway", 0, max_length=3.0,
                                    localisation_noise=(0.0, 0.0, 1.0)))
    np.testing.assert_array_equal(still.readings.x, plain.readings.x)
    np.testing.assert_array_equal(still.readings.theta, plain.readings.theta)


def test_localisation_noise_stacks_on_odometry_drift() -> None:
    """With both, the believed poses are the dead-reckoned ones plus the same wandering error
    the true poses get: the error does not depend on the path it is added to."""
    noise = (0.05, 0.02, 1.0)
    both = run_simulation(Scenario("doorway", 0, max_length=3.0, odometry_drift=True,
                                   localisation_noise=noise))
    drift = run_simulation(Scenario("doorway", 0, max_length=3.0, odometry_drift=True))
    alone = run_simulation(Scenario("doorway", 0, max_length=3.0, localisation_noise=noise))
    assert both.odometry is not None
    assert drift.odometry is not None
    assert alone.odometry is not None
    for name in ("x", "y", "heading"):
        stacked = getattr(both.odometry, name) - getattr(drift.odometry, name)
        own = getattr(alone.odometry, name) - getattr(alone.trajectory, name)
        np.testing.assert_allclose(stacked, own, atol=1e-12)
        assert np.abs(own).max() > 0.0
    # The drift is still there under the noise: not the noise on the true path alone.
    assert np.abs(both.odometry.x - alone.odometry.x).max() > 0.0
