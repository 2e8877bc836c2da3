"""Appendix A: sonar polling's stamps stay within their bound and beat naive stamps."""

from __future__ import annotations

import numpy as np

from sonarcarve.lab.experiments.appendix_base import AppendixSettings
from sonarcarve.lab.experiments.polling import latest_firing, polling_experiment
from sonarcarve.polling import poll_readings, simulate_polls
from sonarcarve.robot import load_robot
from sonarcarve.sim.motion import follow_waypoints
from sonarcarve.sim.simulate import simulate
from sonarcarve.sim.world import load_world


def test_polling_stamps_are_within_their_bound_on_a_short_run() -> None:
    """Direct check, independent of the experiment code: every polled reading's true firing
    (same sensor, same value, nearest in time) lies within the stamp's error bound."""
    world, robot = load_world("office"), load_robot("scout2")
    assert world.tour is not None
    trajectory = follow_waypoints(world.tour[:3])
    sim = simulate(world, robot, trajectory, seed=1)
    fired = sim.firings
    rng = np.random.default_rng(0)
    poll_t = np.cumsum(rng.uniform(0.08, 0.12, int(trajectory.duration / 0.08) + 2))
    poll_t = poll_t[poll_t <= trajectory.t[-1]]
    log = simulate_polls(fired.t, fired.sensor, sim.echoes.range, poll_t, robot.n_sensors,
                         pose_at=trajectory.pose_at)
    mounts = np.column_stack((robot.mount_x, robot.mount_y, robot.bearing))
    polled = poll_readings(log, robot.firing_order, robot.firing_period, mounts,
                           min_interval=robot.firing_period)
    assert len(polled.batch) > 0.95 * len(sim.readings)
    b = polled.batch
    errors = []
    for k in range(len(b)):
        same = np.flatnonzero((fired.sensor == b.sensor[k]) & (sim.echoes.range == b.range[k]))
        errors.append(np.min(np.abs(fired.t[same] - b.t[k])))
    assert np.all(np.asarray(errors) <= polled.stamp_error + 1e-9)


def test_polling_experiment_bound_holds_and_polling_beats_naive() -> None:
    settings = AppendixSettings(quick=True, seeds=1, tour_length=25.0, poll_rates=(10.0,),
                                figure_rate=10.0)
    res, art = polling_experiment(settings)
    run = res.rates["10"]
    assert run["polled"]["time"]["within_percent"] == 100.0
    assert run["polled"]["position"]["within_percent"] == 100.0
    assert run["matched_percent"] == 100.0
    assert run["contradictions"] == 0
    # The naive host stamps late by up to a poll interval (0.1 s +- 20 %) and misses repeats.
    assert 0.0 < run["naive"]["time"]["mean"] <= 0.12
    assert run["readings"]["naive"] < run["readings"]["polled"] <= run["readings"]["true"]
    assert run["map_error"]["polled"]["median"] <= run["map_error"]["naive"]["median"]
    assert set(art["maps"]) == {"naive", "polled"}


def test_latest_firing_by_hand() -> None:
    t = [0.0, 0.1, 0.2, 0.3, 0.4]
    s = [0, 1, 0, 1, 0]
    assert latest_firing([1, 0, 1, 0], [0.05, 0.25, 0.3, 10.0], t, s).tolist() == [-1, 2, 3, 4]
