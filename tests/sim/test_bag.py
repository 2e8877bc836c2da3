"""A simulated run as a bag: read back, it gives the simulation's readings and the same map."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from rosbags.highlevel import AnyReader

from sonarcarve.io.rosbag import read_rosbag
from sonarcarve.methods import make_method
from sonarcarve.pipeline import process_readings
from sonarcarve.readings import ReadingBatch
from sonarcarve.robot import load_robot
from sonarcarve.sim.bag import write_simulation_bag
from sonarcarve.sim.motion import Trajectory
from sonarcarve.sim.simulate import Simulation, simulate
from sonarcarve.sim.world import World

ROOM = World(np.array([[0, 0, 8, 0], [8, 0, 8, 6], [8, 6, 0, 6], [0, 6, 0, 0],
                       [3, 2, 4, 2], [4, 2, 4, 3], [4, 3, 3, 3], [3, 3, 3, 2]], dtype=float),
             name="room")


@pytest.fixture(scope="module")
def sim() -> Simulation:
    """Half a turn (heading past ±π) round the pillar in 8 s: 201 firings of scout2."""
    t = np.linspace(0.0, 8.0, 161)
    phase = math.pi * t / 8.0
    trajectory = Trajectory(t, 3.5 + 2.2 * np.cos(phase), 2.5 + 2.2 * np.sin(phase),
                            phase + math.pi / 2)
    return simulate(ROOM, load_robot("scout2"), trajectory, seed=3)


def _float32_ranges(batch: ReadingBatch) -> ReadingBatch:
    """The batch with ranges as a Range message carries them (float32)."""
    return ReadingBatch.from_arrays(t=batch.t, sensor=batch.sensor, x=batch.x, y=batch.y,
                                    theta=batch.theta,
                                    range=batch.range.astype(np.float32).astype(np.float64),
                                    beam_width=batch.beam_width)


@pytest.mark.parametrize(("name", "storage"), [("run.mcap", "mcap"), ("run_db", "sqlite3"),
                                               ("run.bag", "mcap")])
def test_round_trip_gives_the_simulations_readings(tmp_path: Path, sim: Simulation, name: str,
                                                   storage: str) -> None:
    path = tmp_path / name
    report = write_simulation_bag(path, sim, storage=storage)
    assert report.messages["/tf_static"] == 1
    assert report.messages["/odom"] == 161
    assert sum(report.messages[f"/sonar/{i}"] for i in range(16)) == len(sim.firings)
    log = read_rosbag(path)
    a, b = sim.readings, log.batch
    assert len(b) == len(a) > 0
    np.testing.assert_array_equal(b.sensor, a.sensor)
    np.testing.assert_allclose(b.t, a.t, atol=1e-9)
    np.testing.assert_allclose(b.x, a.x, atol=1e-6)
    np.testing.assert_allclose(b.y, a.y, atol=1e-6)
    np.testing.assert_allclose(np.remainder(b.theta - a.theta + math.pi, 2 * math.pi),
                               math.pi, atol=1e-6)
    np.testing.assert_allclose(b.range, a.range, rtol=1e-6)
    np.testing.assert_allclose(b.beam_width, a.beam_width, rtol=1e-6)
    assert log.report.no_echo == len(sim.firings) - len(sim.readings)
    assert len(log.no_echo) == log.report.no_echo
    assert [s.mount for s in log.report.sources] == ["tf"] * 16
    assert [s.frame for s in log.report.sources] == [f"sonar_{i}" for i in range(16)]


def test_round_trip_gives_the_same_map(tmp_path: Path, sim: Simulation) -> None:
    path = write_simulation_bag(tmp_path / "run.mcap", sim).path
    from_bag = process_readings(read_rosbag(path).batch, make_method("carve")).global_map
    direct = process_readings(_float32_ranges(sim.readings), make_method("carve")).global_map
    np.testing.assert_array_equal(from_bag.reading_id, direct.reading_id)
    np.testing.assert_array_equal(from_bag.source, direct.source)
    np.testing.assert_allclose(from_bag.xy, direct.xy, atol=1e-6)
    np.testing.assert_allclose(from_bag.width, direct.width, atol=1e-6)


def test_bag_frames_and_types(tmp_path: Path, sim: Simulation) -> None:
    path = write_simulation_bag(tmp_path / "run.bag", sim).path
    with AnyReader([path]) as reader:
        types = {c.topic: c.msgtype for c in reader.connections}
        static = next(reader.deserialize(raw, c.msgtype)
                      for c, _, raw in reader.messages()
                      if c.topic == "/tf_static")
    assert types["/sonar/3"] == "sensor_msgs/msg/Range"
    assert types["/odom"] == "nav_msgs/msg/Odometry"
    assert types["/tf"] == types["/tf_static"] == "tf2_msgs/msg/TFMessage"
    assert [t.child_frame_id for t in static.transforms] == [f"sonar_{i}" for i in range(16)]
    assert {t.header.frame_id for t in static.transforms} == {"base_link"}
