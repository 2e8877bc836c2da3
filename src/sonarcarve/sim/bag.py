"""A simulated run as the bag a real robot would have recorded.

Topics (ROS 2 names; rosbag1 output uses the same ones):

- ``/sonar/<i>``: ``sensor_msgs/msg/Range`` per sensor ``i``, ``frame_id`` ``sonar_<i>``, one
  message per firing at its time: the range heard, or ``+Inf`` (REP 117: nothing within
  range) where the firing heard nothing; ``field_of_view`` the sensor's beam width,
  ``min_range``/``max_range`` the robot's, ``radiation_type`` ultrasound;
- ``/odom``: ``nav_msgs/msg/Odometry`` (``odom`` → ``base_link``) at every trajectory sample:
  the poses the readings were stamped with (the dead-reckoned ones when the simulation has
  odometry drift);
- ``/tf``: the same poses as ``odom`` → ``base_link`` transforms;
- ``/tf_static``: one ``base_link`` → ``sonar_<i>`` transform per sensor (its mount; the
  Range's beam along the frame's x axis), stamped at the first pose.

:func:`~sonarcarve.io.rosbag.read_rosbag` turns such a bag back into the simulation's readings
(ranges to float32 precision, the Range message's type).
"""

from __future__ import annotations

import math
from pathlib import Path

from sonarcarve.io.bag_out import BagOutReport, BagWriter, quaternion, stamp
from sonarcarve.sim.simulate import Simulation

__all__ = ["ODOM_FRAME", "ROBOT_FRAME", "sensor_frame", "sensor_topic", "write_simulation_bag"]

#: The odometry frame.
ODOM_FRAME = "odom"
#: The robot's frame.
ROBOT_FRAME = "base_link"
_ULTRASOUND = 0


def sensor_topic(index: int) -> str:
    """Range topic of sensor ``index``: ``/sonar/<index>``."""
    return f"/sonar/{index}"


def sensor_frame(index: int) -> str:
    """TF frame of sensor ``index``: ``sonar_<index>``."""
    return f"sonar_{index}"


def write_simulation_bag(path: str | Path, sim: Simulation, storage: str = "mcap",
                         ) -> BagOutReport:
    """Write ``sim`` as a bag of Range, Odometry, TF and TF static messages (module notes).

    Parameters
    ----------
    path : str or Path
        New bag: ``*.bag`` (ROS 1), ``*.mcap`` (bare MCAP file) or a rosbag2 folder.
    sim : Simulation
        The run.
    storage : str
        ``mcap`` or ``sqlite3`` for rosbag2 folders.

    Returns
    -------
    BagOutReport
        The messages written per topic.

    Raises
    ------
    OutputError
        The path exists, or its folder does not.
    """
    robot = sim.robot
    poses = sim.odometry if sim.odometry is not None else sim.trajectory
    t0 = float(poses.t[0])
    with BagWriter(path, storage) as out:
        transforms = [{
            "header": {"stamp": stamp(t0), "frame_id": ROBOT_FRAME},
            "child_frame_id": sensor_frame(i),
            "transform": {"translation": {"x": float(robot.mount_x[i]),
                                          "y": float(robot.mount_y[i])},
                          "rotation": quaternion(float(robot.bearing[i]))},
        } for i in range(robot.n_sensors)]
        out.write("/tf_static", "tf2_msgs/msg/TFMessage", t0, {"transforms": transforms})
        _write_poses(out, poses.t.tolist(), poses.x.tolist(), poses.y.tolist(),
                     poses.heading.tolist())
        firings, echoes = sim.firings, sim.echoes
        heard = echoes.heard.tolist()
        for t, sensor, r, was_heard in zip(firings.t.tolist(), firings.sensor.tolist(),
                                           echoes.range.tolist(), heard, strict=True):
            out.write(sensor_topic(sensor), "sensor_msgs/msg/Range", t, {
                "header": {"stamp": stamp(t), "frame_id": sensor_frame(sensor)},
                "radiation_type": _ULTRASOUND,
                "field_of_view": float(robot.beam_width[sensor]),
                "min_range": robot.min_range, "max_range": robot.max_range,
                "range": r if was_heard else math.inf,
            })
    return BagOutReport(path=out.path, format=out.format, messages=dict(out.counts))


def _write_poses(out: BagWriter, t: list[float], x: list[float], y: list[float],
                 heading: list[float]) -> None:
    for ti, xi, yi, hi in zip(t, x, y, heading, strict=True):
        header = {"stamp": stamp(ti), "frame_id": ODOM_FRAME}
        pose = {"position": {"x": xi, "y": yi}, "orientation": quaternion(hi)}
        out.write("/odom", "nav_msgs/msg/Odometry", ti,
                  {"header": header, "child_frame_id": ROBOT_FRAME, "pose": {"pose": pose}})
        out.write("/tf", "tf2_msgs/msg/TFMessage", ti, {"transforms": [{
            "header": header, "child_frame_id": ROBOT_FRAME,
            "transform": {"translation": {"x": xi, "y": yi}, "rotation": quaternion(hi)}}]})
