"""simulate(): firing schedule, pose stamping, odometry, truth, determinism, truth files."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from sonarcarve.io import read_readings_csv
from sonarcarve.robot import load_robot
from sonarcarve.sim.motion import Trajectory
from sonarcarve.sim.simulate import simulate
from sonarcarve.sim.sonar import NO_ECHO, EchoKind
from sonarcarve.sim.truth import read_truth_json, truth_path, write_simulation
from sonarcarve.sim.world import World

ROOM = World(np.array([[0, 0, 8, 0], [8, 0, 8, 6], [8, 6, 0, 6], [0, 6, 0, 0],
                       [3, 2, 4, 2], [4, 2, 4, 3], [4, 3, 3, 3], [3, 3, 3, 2]], dtype=float),
             name="room")


def loop(duration: float = 30.0) -> Trajectory:
    """A 2.5 m circle around the pillar at (3.5, 2.5), counter-clockwise, heading along it."""
    t = np.linspace(0.0, duration, int(duration * 20) + 1)
    phase = 2 * math.pi * t / duration
    return Trajectory(t, 3.5 + 2.2 * np.cos(phase), 2.8 + 2.2 * np.sin(phase),
                      phase + math.pi / 2)


def test_firings_follow_the_robots_schedule() -> None:
    robot = load_robot("scout2")
    sim = simulate(ROOM, robot, loop(), seed=1)
    firings = sim.firings
    assert len(firings) == math.floor(30.0 / robot.firing_period + 1e-9) + 1
    np.testing.assert_allclose(np.diff(firings.t), robot.firing_period)
    np.testing.assert_array_equal(firings.sensor, np.arange(len(firings)) % 16)
    assert len(sim.echoes) == len(firings)
    assert int(np.sum(sim.echoes.kind != NO_ECHO)) == len(sim.readings)
    rows = sim.firing_reading
    heard = rows >= 0
    np.testing.assert_array_equal(heard, sim.echoes.kind != NO_ECHO)
    np.testing.assert_array_equal(sim.readings.range[rows[heard]], sim.echoes.range[heard])


def test_readings_carry_the_sensor_pose_at_firing_time() -> None:
    robot = load_robot("scout2")
    trajectory = loop()
    sim = simulate(ROOM, robot, trajectory, seed=2)
    r = sim.readings
    # Independently: robot pose on the circle at each reading's time, mount rotated by heading.
    phase = 2 * math.pi * r.t / 30.0
    heading = phase + math.pi / 2
    cx, cy = 3.5 + 2.2 * np.cos(phase), 2.8 + 2.2 * np.sin(phase)
    angle = heading + robot.bearing[r.sensor]
    np.testing.assert_allclose(r.x, cx + 0.205 * np.cos(angle), atol=2e-3)  # 20 poses/s
    np.testing.assert_allclose(r.y, cy + 0.205 * np.sin(angle), atol=2e-3)
    np.testing.assert_allclose(np.angle(np.exp(1j * (r.theta - angle))), 0.0, atol=1e-3)
    np.testing.assert_allclose(r.beam_width, math.radians(22.5))
    np.testing.assert_array_equal(r.t, sim.firings.t[sim.truth.firing])


def test_truth_matches_the_readings() -> None:
    sim = simulate(ROOM, load_robot("scout2"), loop(), seed=3)
    truth, r = sim.truth, sim.readings
    assert len(truth) == len(r)
    assert sum(sim.kind_counts().values()) == len(r)
    direct = truth.kind == EchoKind.DIRECT
    assert direct.mean() > 0.5
    seen = np.hypot(truth.reflection[direct, 0] - r.x[direct],
                    truth.reflection[direct, 1] - r.y[direct])
    assert np.all(np.abs(seen - r.range[direct]) <= 5 * sim.physics.range_noise + 0.0127 + 1e-9)
    assert np.all(ROOM.distance_to_walls(truth.reflection[direct]) < 1e-9)
    assert truth.labels[int(np.argmax(direct))] == "direct"


def test_odometry_stamps_the_readings_but_echoes_come_from_the_truth() -> None:
    robot = load_robot("scout2")
    true = loop()
    drifted = Trajectory(true.t, true.x + 1.0, true.y - 0.5, true.heading)
    honest = simulate(ROOM, robot, true, seed=4)
    stamped = simulate(ROOM, robot, true, seed=4, odometry=drifted)
    np.testing.assert_array_equal(stamped.readings.range, honest.readings.range)
    np.testing.assert_allclose(stamped.readings.x, honest.readings.x + 1.0)
    np.testing.assert_allclose(stamped.readings.y, honest.readings.y - 0.5)
    np.testing.assert_array_equal(stamped.truth.reflection, honest.truth.reflection)
    assert stamped.odometry is drifted


def test_same_seed_same_simulation_other_seed_differs() -> None:
    robot = load_robot("p3dx-front")
    a, b, c = (simulate(ROOM, robot, loop(), seed=s) for s in (7, 7, 8))
    np.testing.assert_array_equal(a.readings.range, b.readings.range)
    np.testing.assert_array_equal(a.truth.kind, b.truth.kind)
    assert not np.array_equal(a.echoes.range, c.echoes.range, equal_nan=True)


def test_progress_reports_every_firing() -> None:
    calls: list[tuple[int, int]] = []
    sim = simulate(ROOM, load_robot("roboND-8"), loop(10.0), seed=0,
                   on_progress=lambda done, total: calls.append((done, total)))
    assert calls[-1] == (len(sim.firings), len(sim.firings))
    assert [d for d, _ in calls] == sorted(d for d, _ in calls)


def test_files_round_trip_and_are_byte_identical_per_seed(tmp_path: Path) -> None:
    robot = load_robot("scout2")
    paths = []
    for folder in ("a", "b"):
        out = tmp_path / folder / "run.csv"
        out.parent.mkdir()  # writers create no folders
        written = write_simulation(simulate(ROOM, robot, loop(), seed=5), out)
        assert written == truth_path(out) == out.with_name("run.truth.json")
        paths.append(out)
    assert paths[0].read_bytes() == paths[1].read_bytes()
    assert truth_path(paths[0]).read_bytes() == truth_path(paths[1]).read_bytes()

    sim = simulate(ROOM, robot, loop(), seed=5)
    back = read_readings_csv(paths[0])
    np.testing.assert_array_equal(back.range, sim.readings.range)
    truth = read_truth_json(truth_path(paths[0]))
    np.testing.assert_array_equal(truth.kind, sim.truth.kind)
    np.testing.assert_array_equal(truth.reflection, sim.truth.reflection)
    np.testing.assert_array_equal(truth.world.segments, ROOM.segments)


def test_truth_path_names() -> None:
    assert truth_path("x/run.csv") == Path("x/run.truth.json")
    assert truth_path("run.CSV") == Path("run.truth.json")
    assert truth_path("run") == Path("run.truth.json")


@pytest.mark.parametrize(
    ("text", "problem"),
    [
        ('{"world": {"segments": []}, "readings": [{"id": 1, "kind": "direct", '
         '"reflection": null}]}', "expected 0"),
        ('{"world": {"segments": []}, "readings": [{"id": 0, "kind": "echo", '
         '"reflection": null}]}', "unknown kind"),
        ('{"world": {"segments": []}, "readings": [{"id": 0, "kind": "direct", '
         '"reflection": [1]}]}', "reflection must be"),
        ('{"world": {"segments": []}, "readings": [', "not valid JSON"),
        ('{"readings": []}', "'world'"),
    ],
)
def test_bad_truth_files_fail_with_one_line(tmp_path: Path, text: str, problem: str) -> None:
    from sonarcarve.io.errors import InputError

    path = tmp_path / "bad.truth.json"
    path.write_text(text)
    with pytest.raises(InputError, match=problem) as info:
        read_truth_json(path)
    assert "\n" not in str(info.value)
    assert str(path) in str(info.value)


def test_no_echo_records_every_firing_and_keeps_the_echoes() -> None:
    robot = load_robot("scout2")
    echoes_only = simulate(ROOM, robot, loop(10.0), seed=2)
    every = simulate(ROOM, robot, loop(10.0), seed=2, no_echo=True)
    assert len(every.readings) == len(every.firings)
    silent = every.readings.no_echo
    np.testing.assert_array_equal(silent, every.echoes.kind == NO_ECHO)
    np.testing.assert_array_equal(every.truth.no_echo, silent)
    assert np.all(every.readings.max_range[silent] == robot.max_range)
    assert np.all(np.isnan(every.readings.max_range[~silent]))
    heard = every.readings[~silent]
    for name in ("t", "sensor", "x", "y", "theta", "range", "beam_width"):
        np.testing.assert_array_equal(getattr(heard, name), getattr(echoes_only.readings, name))
    assert every.truth.counts()["none"] == int(silent.sum())
    assert "none" not in echoes_only.truth.counts()
    assert set(np.array(every.truth.labels)[silent].tolist()) == {"none"}


def test_no_echo_files_round_trip(tmp_path: Path) -> None:
    sim = simulate(ROOM, load_robot("scout2"), loop(5.0), seed=3, no_echo=True)
    path = tmp_path / "run.csv"
    write_simulation(sim, path)
    back = read_readings_csv(path)
    np.testing.assert_array_equal(back.range, sim.readings.range)
    np.testing.assert_array_equal(back.max_range, sim.readings.max_range)
    truth = read_truth_json(truth_path(path))
    np.testing.assert_array_equal(truth.kind, sim.truth.kind)


def test_firings_behind_walls_counts_sensors_past_a_wall(tmp_path: Path) -> None:
    """A sensor mounted 2 m ahead of a robot whose disc is 0.3 m: driving from y = 0 to y = 3
    at 0.4 m/s towards a wall at y = 4, the sensor is past the wall once the robot is past y = 2,
    after t = 5 s (worked by hand). A sensor inside the disc never is."""
    from sonarcarve.sim.motion import follow_waypoints

    def robot(ahead: float) -> Path:
        path = tmp_path / f"r{ahead}.yaml"
        path.write_text(f"name: probe\nrobot_radius: 0.3\nrange_resolution: 0.001\n"
                        f"min_range: 0.1\nmax_range: 5.0\nfiring_period: 0.05\n"
                        f"beam_width_deg: 22.5\nsensors:\n"
                        f"  - {{x: {ahead}, y: 0.0, bearing_deg: 0.0}}\n")
        return path

    world = World(np.array([[-1.0, 4.0, 1.0, 4.0]]))
    drive = follow_waypoints([[0.0, 0.0], [0.0, 3.0]], speed=0.4)
    far = simulate(world, load_robot(robot(2.0)), drive, seed=0)
    assert far.firings_behind_walls() == int(np.count_nonzero(far.firings.t > 5.0 + 1e-9))
    assert far.firings_behind_walls() > 0
    near = simulate(world, load_robot(robot(0.2)), drive, seed=0)
    assert near.firings_behind_walls() == 0
