"""Fig. 7: maps from dead-reckoned poses drift with the pose, not with the local map."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sonarcarve.lab.experiments.appendix_base import AppendixSettings
from sonarcarve.lab.experiments.odometry import odometry_experiment, pose_corrected
from sonarcarve.sim.motion import Trajectory


def test_pose_correction_undoes_a_known_pose_error() -> None:
    t = np.array([0.0, 1.0, 2.0])
    truth = Trajectory(t, np.array([0.0, 1.0, 2.0]), np.zeros(3), np.zeros(3))
    # Believed: shifted 1 m in y and turned 90° about the believed position.
    belief = Trajectory(t, truth.x.copy(), np.ones(3), np.full(3, math.pi / 2))
    # A point 2 m ahead of the robot at t = 1: believed at (1, 1) + 2 (0, 1) = (1, 3).
    out = pose_corrected(np.array([[1.0, 3.0]]), np.array([1.0]), truth, belief)
    np.testing.assert_allclose(out, [[3.0, 0.0]], atol=1e-12)


def test_odometry_error_grows_with_distance() -> None:
    res, artifacts = odometry_experiment(AppendixSettings.make(quick=True))
    pose = [v for v in res.pose_error_by_distance["median"] if v is not None]
    assert pose[-1] > 3.0 * pose[0]
    assert set(artifacts["maps"]) == {"carving", "combined"}
    for entry in res.methods.values():
        shift = [v for v in entry["drift_shift"]["by_distance"]["median"] if v is not None]
        raw = [v for v in entry["odometry"]["by_distance"]["median"] if v is not None]
        assert shift[-1] > 3.0 * shift[0]
        assert raw[-1] > raw[0]
        # Removing the pose error brings the map back to the accuracy of true poses.
        assert entry["odometry_corrected"]["error"]["median"] < entry["odometry"]["error"][
            "median"]
        assert entry["odometry_corrected"]["error"]["median"] == pytest.approx(
            entry["true_poses"]["error"]["median"], abs=0.02)
