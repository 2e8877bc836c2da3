"""Changing scenes: obstacles present only in their interval, where they are at each firing.

Expected ranges are plane geometry worked out by hand: one forward sensor at the origin, a
22.5° beam, a wall at x = 5 behind everything.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from sonarcarve.robot import RobotDescription, load_robot
from sonarcarve.sim import (
    DynamicObstacle,
    Firings,
    Scene,
    SonarPhysics,
    World,
    WorldError,
    changing_scene,
    fire_sonars,
    follow_waypoints,
    simulate,
)
from sonarcarve.sim.scene import CHANGING_SCENES

CLEAN = SonarPhysics.clean()
FAR_WALL = World(np.array([[5.0, -10.0, 5.0, 10.0]]))


def forward_sensor() -> RobotDescription:
    return RobotDescription(
        name="test", mount_x=np.zeros(1), mount_y=np.zeros(1), bearing=np.zeros(1),
        beam_width=np.full(1, math.radians(22.5)), firing_order=np.arange(1),
        firing_period=0.04, range_resolution=0.0, min_range=0.15, max_range=6.5,
        robot_radius=0.2)


def fire_at(times: list[float], scene: Scene, world: World = FAR_WALL,
            physics: SonarPhysics = CLEAN) -> tuple[np.ndarray, np.ndarray]:
    """Ranges and obstacle truth of one forward firing from the origin at each time."""
    n = len(times)
    firings = Firings(t=np.array(times), sensor=np.zeros(n, dtype=np.int64), x=np.zeros(n),
                      y=np.zeros(n), theta=np.zeros(n))
    echoes = fire_sonars(world, forward_sensor(), firings, physics, np.random.default_rng(0),
                         scene=scene)
    return echoes.range, echoes.obstacle


def test_disc_echoes_only_while_present() -> None:
    # A 0.4 m disc centred 2 m ahead: its vertex at angle π sits at x = 1.8, on the axis.
    disc = DynamicObstacle.disc((2.0, 0.0), 0.2, "person", appear=1.0, vanish=3.0)
    r, hit = fire_at([0.5, 1.0, 2.9, 3.0, 3.5], Scene((disc,)))
    np.testing.assert_allclose(r, [5.0, 1.8, 1.8, 5.0, 5.0], atol=1e-9)
    assert hit.tolist() == [-1, 0, 0, -1, -1]


def test_moving_disc_echoes_where_it_is_at_the_firing_time() -> None:
    # From (2, 3) down to (2, -3) between t = 0 and 6 s: on the axis at t = 3 only; at t = 1 it
    # is 2 m off the axis at 2 m (the beam's half-width there is 2 tan 11.25° = 0.4 m).
    disc = DynamicObstacle.disc((2.0, 3.0), 0.2, "person", shift=(0.0, -6.0), t0=0.0, t1=6.0)
    r, hit = fire_at([1.0, 3.0, 5.0, 7.0], Scene((disc,)))
    np.testing.assert_allclose(r, [5.0, 1.8, 5.0, 5.0], atol=1e-9)
    assert hit.tolist() == [-1, 0, -1, -1]
    np.testing.assert_allclose(disc.center_at([3.0, 9.0]), [[2.0, 0.0], [2.0, -3.0]])


def test_door_blocks_then_unblocks() -> None:
    # A wall at x = 3 with a 1.2 m gap on the axis; the door fills the gap from t = 2 to 4 s.
    world = World(np.array([[3.0, -5.0, 3.0, -0.6], [3.0, 0.6, 3.0, 5.0],
                            [5.0, -10.0, 5.0, 10.0]]))
    door = DynamicObstacle.wall((3.0, -0.6), (3.0, 0.6), "door", appear=2.0, vanish=4.0)
    r, hit = fire_at([1.0, 2.0, 3.0, 4.0, 5.0], Scene((door,)), world)
    np.testing.assert_allclose(r, [5.0, 3.0, 3.0, 5.0, 5.0], atol=1e-9)
    assert hit.tolist() == [-1, 0, 0, -1, -1]


def test_door_blocks_in_the_amplitude_model_too() -> None:
    world = World(np.array([[3.0, -5.0, 3.0, -0.6], [3.0, 0.6, 3.0, 5.0],
                            [5.0, -10.0, 5.0, 10.0]]))
    door = DynamicObstacle.wall((3.0, -0.6), (3.0, 0.6), "door", appear=2.0, vanish=4.0)
    physics = SonarPhysics(echo_model="amplitude", crosstalk_probability=0.0,
                           multipath_probability=0.0, floor_episode_rate=0.0, range_noise=0.0,
                           quantise=False)
    r, hit = fire_at([1.0, 3.0, 5.0], Scene((door,)), world, physics)
    np.testing.assert_allclose(r, [5.0, 3.0, 5.0], atol=1e-6)
    assert hit.tolist() == [-1, 0, -1]


def test_epochs_cut_at_changes_and_at_every_moving_firing() -> None:
    door = DynamicObstacle.wall((0, 0), (1, 0), appear=2.0, vanish=5.0)
    walker = DynamicObstacle.disc((0, 0), 0.2, shift=(1.0, 0.0), t0=10.0, t1=12.0)
    times = [0.0, 1.0, 2.0, 3.0, 5.0, 6.0, 10.0, 11.0, 12.0, 13.0]
    # Door: runs start at 2.0 and 5.0; walker: at 10 s it is still at its start (offset 0,
    # as at 6 s), moves at 11 and 12, and stays put after.
    assert Scene((door, walker)).epochs(times).tolist() == [0, 2, 4, 7, 8]
    assert Scene().epochs(times).tolist() == [0]


def test_obstacle_truth_names_the_obstacle_on_whose_outline_a_point_lies() -> None:
    a = DynamicObstacle.box(0.0, 0.0, 1.0, 1.0, "a", vanish=5.0)
    b = DynamicObstacle.wall((3.0, 0.0), (3.0, 1.0), "b")
    scene = Scene((a, b))
    points = [[1.0, 0.5], [1.0, 0.5], [3.0, 0.2], [2.0, 2.0], [math.nan, math.nan]]
    assert scene.obstacle_hit(points, [1.0, 6.0, 1.0, 1.0, 1.0]).tolist() == [0, -1, 1, -1, -1]
    # (1.5, 0.5): 0.5 m from the box's right side while it is there, else 1.5 m from b.
    np.testing.assert_allclose(scene.distance([[1.5, 0.5]], 1.0), [0.5])
    np.testing.assert_allclose(scene.distance([[1.5, 0.5]], 6.0), [1.5])
    assert Scene().distance([[1.5, 0.5]], 1.0).tolist() == [math.inf]


def test_bad_obstacles_are_refused() -> None:
    with pytest.raises(WorldError, match="appear"):
        DynamicObstacle.wall((0, 0), (1, 0), appear=3.0, vanish=2.0)
    with pytest.raises(WorldError, match="t0 < t1"):
        DynamicObstacle.disc((0, 0), 0.2, shift=(1.0, 0.0), t0=2.0, t1=2.0)
    with pytest.raises(WorldError, match="zero length"):
        DynamicObstacle.wall((0, 0), (0, 0))
    with pytest.raises(WorldError, match="unknown changing scene"):
        changing_scene("elevator")


def test_same_seed_same_simulation_and_an_empty_scene_changes_nothing() -> None:
    cs = changing_scene("door")
    robot, tr = load_robot("scout2"), follow_waypoints(cs.waypoints)
    a = simulate(cs.world, robot, tr, 3, scene=cs.scene)
    b = simulate(cs.world, robot, tr, 3, scene=cs.scene)
    c = simulate(cs.world, robot, tr, 4, scene=cs.scene)
    np.testing.assert_array_equal(a.echoes.range, b.echoes.range)
    np.testing.assert_array_equal(a.truth.obstacle, b.truth.obstacle)
    assert not np.array_equal(a.echoes.range, c.echoes.range, equal_nan=True)
    plain = simulate(cs.world, robot, tr, 3)
    empty = simulate(cs.world, robot, tr, 3, scene=Scene())
    np.testing.assert_array_equal(plain.echoes.range, empty.echoes.range)
    np.testing.assert_array_equal(plain.echoes.kind, empty.echoes.kind)
    assert np.all(plain.truth.obstacle == -1)


@pytest.mark.parametrize("name", sorted(CHANGING_SCENES))
def test_builtin_scenes_hear_their_obstacle_only_while_it_is_there(name: str) -> None:
    cs = changing_scene(name)
    sim = simulate(cs.world, load_robot("scout2"), follow_waypoints(cs.waypoints), 0,
                   scene=cs.scene)
    hit = sim.truth.obstacle >= 0
    assert hit.any()
    (obstacle,) = cs.scene.obstacles
    assert np.all(obstacle.present(sim.readings.t[hit]))
    # Every reading truth-marked as the obstacle's lies on its outline at the reading's time.
    for row in np.flatnonzero(hit)[:20]:
        t = float(sim.readings.t[row])
        gap = World(obstacle.segments_at(t)).distance_to_walls(sim.truth.reflection[row])
        assert gap[0] < 1e-6
