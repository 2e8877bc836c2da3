"""``sonarcarve simulate``: drive a simulated robot through a world and log its sonar readings.

The ending of ``--out`` picks what is written, from :data:`LOG_FORMATS`: a readings CSV, or
the ROS bag a real robot would have recorded (``.mcap``, ``.bag``, or a rosbag2 folder: no
ending); the truth file goes beside either.
"""

from __future__ import annotations

import math
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Annotated, NamedTuple

import numpy as np
import typer
from rich.table import Table

from sonarcarve.cli.app import app, console, progress, summary_table, warn
from sonarcarve.cli.options import check_new_bag
from sonarcarve.errors import SonarcarveError
from sonarcarve.io.atomic import atomic_path, check_output_file
from sonarcarve.robot import BUILTIN_ROBOTS, RobotDescription, load_robot
from sonarcarve.sim.bag import write_simulation_bag
from sonarcarve.sim.motion import (
    DEFAULT_DT,
    DEFAULT_SPEED,
    MAX_POSES,
    PLAN_MARGIN,
    Trajectory,
    explore,
    follow_waypoints,
    with_localisation_noise,
    with_odometry_drift,
)
from sonarcarve.sim.simulate import Simulation, simulate
from sonarcarve.sim.sonar import DEFAULT_PHYSICS, PHYSICS_NAMES, SonarPhysics, named_physics
from sonarcarve.sim.truth import TRUTH_SUFFIX, truth_path, write_simulation, write_truth_json
from sonarcarve.sim.waypoints import check_path_in_world, read_waypoint_places
from sonarcarve.sim.world import World, WorldError, load_world

__all__ = ["LOG_FORMATS", "LogFormat", "simulate_command"]

#: Runs shorter than this (firings) finish before a progress bar would be worth drawing.
_PROGRESS_MIN_FIRINGS = 5_000


class SimulateParameterError(SonarcarveError):
    """A ``simulate`` option outside its valid range or in conflict with another."""


class LogFormat(NamedTuple):
    """One kind of ``--out``: where its truth file goes, how to check the target before the
    simulation runs, and the writer (log and truth together, or neither)."""

    label: str
    truth: Callable[[Path], Path]
    check: Callable[[Path, list[Path], str], object]
    write: Callable[[Simulation, Path, Path], None]


def _check_csv(out: Path, inputs: list[Path], label: str) -> None:
    check_output_file(out, inputs=inputs, label=label)


def _check_bag(out: Path, inputs: list[Path], label: str) -> None:
    check_new_bag(out, inputs=inputs, label=label)


def _write_csv(sim: Simulation, out: Path, truth: Path) -> None:
    """The readings CSV and the truth file together (``truth`` is
    :func:`~sonarcarve.sim.truth.truth_path` of ``out``, where they go)."""
    write_simulation(sim, out)


def _bag_truth(out: Path) -> Path:
    """``run.mcap`` / ``run.bag`` / the folder ``run`` -> ``run.truth.json`` beside it."""
    return out.with_name(out.stem + TRUTH_SUFFIX)


def _write_bag(sim: Simulation, out: Path, truth: Path) -> None:
    # The truth file is renamed into place only when the bag (itself built in a temporary
    # folder and moved) is complete: never a truth file without its bag.
    with atomic_path(truth, suffix=".json") as tmp:
        write_truth_json(tmp, sim.world, sim.truth.kind, sim.truth.reflection)
        write_simulation_bag(out, sim)


#: Ending of ``--out`` (lower case; "" a rosbag2 folder) -> what is written there.
LOG_FORMATS: dict[str, LogFormat] = {
    ".csv": LogFormat("readings", truth_path, _check_csv, _write_csv),
    ".mcap": LogFormat("bag", _bag_truth, _check_bag, _write_bag),
    ".bag": LogFormat("bag", _bag_truth, _check_bag, _write_bag),
    "": LogFormat("bag", _bag_truth, _check_bag, _write_bag),
}


#: Fastest --speed, m/s: at 10 m/s a ring firing every 0.04 s moves 0.4 m between two
#: firings, past where any sonar map keeps up (a parking car drives at 1-2 m/s).
MAX_SPEED = 10.0


@app.command("simulate")
def simulate_command(
    world: Annotated[str, typer.Option(
        "--world", "-w", metavar="WORLD",
        help="Built-in world (office, doorway, t-junction, narrow-hallway), random:SEED, a "
             "walls .json file or a ROS map .yaml.")],
    out: Annotated[Path, typer.Option(
        "--out", "-o", metavar="NAME.csv|NAME.mcap",
        help="Readings CSV to write, or, ending in .mcap or .bag or with no ending (a rosbag2 "
             "folder), the ROS bag a real robot would record: sensor_msgs/Range per sensor "
             "(+Inf when nothing was heard), Odometry, TF and TF static. The truth goes "
             "beside it as NAME.truth.json. Its folder must exist. Both are written together "
             "or not at all; a bag is never overwritten.")],
    robot: Annotated[str, typer.Option(
        "--robot", "-r", metavar="ROBOT",
        help=f"The sonars and their robot: {', '.join(BUILTIN_ROBOTS)}, or a robot YAML "
             "file.")] = "scout2",
    path: Annotated[Path | None, typer.Option(
        "--path", metavar="WAYPOINTS",
        help="Waypoints to drive through, metres: a CSV with a header x,y, or JSON "
             "[[x, y], ...]. Default: the world's built-in tour.")] = None,
    explore_seconds: Annotated[float | None, typer.Option(
        "--explore", metavar="SECONDS",
        help="Instead of a path, wander the world for this many seconds (seeded).")] = None,
    speed: Annotated[float, typer.Option(
        "--speed", metavar="M/S",
        help=f"Driving speed, metres per second, on --path, the tour or --explore (a robot "
             f"cruises at {DEFAULT_SPEED:g}; a car parks at 1-2), in (0, {MAX_SPEED:g}].")
    ] = DEFAULT_SPEED,
    seed: Annotated[int, typer.Option(
        help="Seeds noise, spurious echoes, exploration and drift: same seed, same bytes.")] = 0,
    odometry: Annotated[bool, typer.Option(
        "--odometry/--no-odometry",
        help="Stamp readings with drifting dead-reckoned poses instead of the true ones "
             "(echoes still come from the true poses).")] = False,
    pose_noise: Annotated[tuple[float, float] | None, typer.Option(
        "--pose-noise", metavar="METRES DEGREES",
        help="Stamp readings with a localiser's poses: the true (or, with --odometry, the "
             "dead-reckoned) ones plus a slowly wandering error of this standard deviation in "
             "position and heading (correlation time 1 s; echoes still come from the true "
             "poses). 0.03 1 is a good AMCL against a good map (assumed, not measured); "
             "docs/RESULTS.md, 'Maps from wrong poses', measures the methods at 0.02 0.5 and "
             "0.05 2.")] = None,
    clean: Annotated[bool, typer.Option(
        "--clean", help="Perfect sensors on smooth walls: no noise, no quantisation, no "
                        "crosstalk, floor or multipath echoes.")] = False,
    physics: Annotated[str, typer.Option(
        "--physics", metavar="MODEL",
        help="How echoes are decided. specular (default): rays across the nominal beam; a "
             "smooth wall echoes only within a critical angle (17.5°) of its normal, corners "
             "always; spurious echoes by fixed rates. amplitude: a sonar equation; the "
             "transducer's beam pattern (main lobe and side lobes, so strong reflectors are "
             "heard outside the nominal beam; the transducer is a Polaroid 600, about 25° "
             "between first nulls, whatever beam the robot file declares; set another with "
             "sonarcarve.sim.AmplitudeModel from Python), spreading and absorption with range, "
             "mirror, diffuse and corner echoes against a noisy detection threshold (weak glancing "
             "walls are missed, near ones heard at wide angles). amplitude-thin: amplitude with "
             "small reflectors: legs and columns (closed runs of short walls turning by at most "
             "30° at each joint) echo as convex cylinders: a leg of 2 cm radius 17 dB under a "
             "wall at 1 m, heard over a narrower angle and fading sooner.")] = "specular",
    no_echo: Annotated[bool, typer.Option(
        "--no-echo",
        help="CSV output: also record the firings that heard nothing, as rows with range inf "
             "and the robot's max_range (free space for the methods and grids). A bag always "
             "holds them, as REP 117 +Inf Range messages.")] = False,
) -> None:
    """Simulate a sonar log with ground truth: drive a robot through a world, record echoes.

    The robot's sensors fire one at a time in its firing order. Each ray of a beam echoes from a
    smooth wall only near normal incidence (or from a corner or wall end), so oblique walls are
    mirrors, as with real ultrasonic sensors; on top come range noise, quantisation and the
    spurious echoes of real rings (crosstalk, floor bounce, multipath). `--physics amplitude`
    decides every echo by its received level instead (beam pattern, range losses, threshold).

    Writes NAME.csv (readings CSV: `t,sensor,x,y,theta,range,beam_width`; seconds, metres,
    radians) and NAME.truth.json (the walls, and per reading its kind and true reflection
    point). Both are checked before the simulation runs and renamed into place together.
    With --out NAME.mcap (or .bag, or a folder) the log is a ROS bag instead, topics
    /sonar/<i> (frame sonar_<i>), /odom, /tf and /tf_static: `sonarcarve process NAME.mcap`
    maps it to the same map as the CSV (ranges to float32 precision).

    Example: `sonarcarve simulate --world office --robot scout2 --seed 1 --out office.csv`

    Example: `sonarcarve simulate --world office --out office.mcap` (open it in Foxglove)

    Example: `sonarcarve simulate --world office --pose-noise 0.05 2 --out noisy.csv` (readings
    stamped as a localiser good to 5 cm and 2° would stamp them)
    """
    _check_motion_options(path, explore_seconds, speed)
    _check_pose_noise(pose_noise)
    chosen = _physics(physics, clean)
    log_format = _log_format(out)
    if no_echo and log_format.label != "readings":
        msg = (f"--no-echo applies to a readings CSV output; the bag {out} always holds the "
               "silent firings as +Inf Range messages (read them with process --no-echo)")
        raise SimulateParameterError(msg)
    # Both outputs are checked before the (possibly long) simulation runs.
    truth = _check_outputs(out, log_format, [path, Path(world), Path(robot)])
    sharing = _logs_sharing_truth(out, truth)  # before this run's log exists
    the_world = load_world(world)
    the_robot = load_robot(robot)
    try:
        trajectory = _trajectory(the_world, path, explore_seconds, seed,
                                 the_robot.robot_radius, speed)
        drift = with_odometry_drift(trajectory, seed=seed) if odometry else None
        drift = _with_pose_noise(drift or trajectory, seed, pose_noise) or drift
        result = _simulate_with_progress(the_world, the_robot, trajectory, seed, chosen, drift,
                                         no_echo)
    except SonarcarveError as err:
        raise _with_speed_hint(err, speed) from None
    log_format.write(result, out, truth)
    console.print(_summary(result, out, truth, log_format.label))
    _warn_behind_walls(result)
    if explore_seconds is not None:
        _warn_if_never_moved(result, explore_seconds)
    if sharing:
        warn([f"{truth} was also the truth of {', '.join(map(str, sharing))}, and now holds "
              f"{out}'s: give logs of different runs different names"])


def _logs_sharing_truth(out: Path, truth: Path) -> list[Path]:
    """Other logs, already there, whose truth file is ``truth`` too: ``run.csv`` beside a
    new ``run.mcap`` (both keep their truth in ``run.truth.json``), which this run replaces."""
    if not truth.exists():
        return []
    stem = truth.name[: -len(TRUTH_SUFFIX)]
    sharing = []
    for ending in LOG_FORMATS:
        log = out.with_name(stem + ending)
        kind = LOG_FORMATS.get(log.suffix.lower())  # "run.v2" is no rosbag2 folder's name
        if (log != out and kind is not None and kind.truth(log) == truth
                and (log.is_file() or (log / "metadata.yaml").is_file())):
            sharing.append(log)
    return sharing


def _check_pose_noise(pose_noise: tuple[float, float] | None) -> None:
    """Raise :class:`SimulateParameterError` unless ``--pose-noise`` is absent or two finite
    standard deviations >= 0 (metres, degrees)."""
    if pose_noise is None:
        return
    position, heading_deg = pose_noise
    if not (math.isfinite(position) and position >= 0.0 and math.isfinite(heading_deg)
            and heading_deg >= 0.0):
        msg = (f"--pose-noise takes two standard deviations >= 0, metres and degrees, got "
               f"{position:g} {heading_deg:g}")
        raise SimulateParameterError(msg)


def _with_pose_noise(believed: Trajectory, seed: int,
                     pose_noise: tuple[float, float] | None) -> Trajectory | None:
    """``believed`` with ``--pose-noise`` (metres, degrees) added, or None without it."""
    if pose_noise is None:
        return None
    position, heading_deg = pose_noise
    return with_localisation_noise(believed, seed, position, math.radians(heading_deg))


def _with_speed_hint(err: SonarcarveError, speed: float) -> SonarcarveError:
    """A drive too long for the simulator's limits (poses, firings) named by what the user
    can change (--speed, --path), not the library's ``dt``; any other error as it is."""
    text = str(err)
    if "(MAX_POSES)" not in text and "(MAX_FIRINGS)" not in text:
        return err
    return SimulateParameterError(f"{text.split('; use')[0]}: at --speed {speed:g} m/s the "
                                  "drive is too long; raise --speed or give a shorter --path")


def _warn_behind_walls(result: Simulation) -> None:
    """One stderr line when sensors fired from behind a wall (``firings_behind_walls``)."""
    behind = result.firings_behind_walls()
    if behind:
        robot = result.robot
        reach = float(np.max(np.hypot(robot.mount_x, robot.mount_y)))
        print(f"sonarcarve: warning: {behind:,} of {len(result.firings):,} firings "
              f"({100.0 * behind / len(result.firings):.1f} %) came from a sensor on the far "
              f"side of a wall: {robot.name}'s sensors reach {reach:.2f} m from its centre, "
              f"its body disc only {robot.robot_radius:g} m; give a --path that keeps "
              f"{reach:.2f} m from walls", file=sys.stderr)


def _warn_if_never_moved(result: Simulation, explore_seconds: float) -> None:
    """One stderr line when ``--explore`` left the robot where it started: its planner found no
    open place the robot's body could reach (a car in a world of narrow rooms), and a log from
    one spot is seldom what was wanted. Under a centimetre counts as still: turning in place
    (a car's slow start) moves the centre a little."""
    if result.trajectory.path_length >= 0.01:
        return
    radius = result.robot.robot_radius
    warn([f"the robot did not move in {explore_seconds:g} s: --explore found no open place its "
          f"{radius:g} m body could reach from where it starts; give a --path, or a world whose "
          f"rooms and corridors are wider than {2.0 * (radius + PLAN_MARGIN):.2f} m"])


def _check_motion_options(path: Path | None, explore_seconds: float | None,
                          speed: float = DEFAULT_SPEED) -> None:
    """Raise :class:`SimulateParameterError` unless at most one of --path and --explore is
    given, --explore, if given, is a finite number of seconds > 0, and --speed lies in
    (0, :data:`MAX_SPEED`]."""
    if not 0.0 < speed <= MAX_SPEED:  # False for NaN too
        msg = f"--speed must be a speed in (0, {MAX_SPEED:g}] m/s, got {speed:g}"
        raise SimulateParameterError(msg)
    if path is not None and explore_seconds is not None:
        msg = "give either --path or --explore, not both"
        raise SimulateParameterError(msg)
    if explore_seconds is not None and not (math.isfinite(explore_seconds)
                                            and explore_seconds > 0.0):
        msg = f"--explore must be a positive number of seconds, got {explore_seconds}"
        raise SimulateParameterError(msg)
    if explore_seconds is not None and explore_seconds / DEFAULT_DT > MAX_POSES:
        limit = MAX_POSES * DEFAULT_DT
        msg = (f"--explore must be at most {limit:,.0f} seconds ({limit / 3600:.0f} hours, the "
               f"simulator's limit of {MAX_POSES:,} poses), got {explore_seconds:g}")
        raise SimulateParameterError(msg)


def _physics(echo_model: str, clean: bool) -> SonarPhysics:
    """The sensor model of ``--physics`` and ``--clean``; a one-line error for an unknown model
    (:class:`~sonarcarve.sim.sonar.SonarPhysicsError`, naming the choices)."""
    if echo_model not in PHYSICS_NAMES:
        choices = f"{', '.join(PHYSICS_NAMES[:-1])} or {PHYSICS_NAMES[-1]}"
        msg = f"--physics {echo_model}: unknown model; choose {choices}"
        raise SimulateParameterError(msg)
    return named_physics(echo_model, SonarPhysics.clean() if clean else DEFAULT_PHYSICS)


def _log_format(out: Path) -> LogFormat:
    """The entry of :data:`LOG_FORMATS` for the ending of ``out``; a one-line error naming the
    endings for any other."""
    log_format = LOG_FORMATS.get(out.suffix.lower())
    if log_format is None:
        msg = (f"--out {out}: unknown ending {out.suffix!r}; use .csv (readings), .mcap or "
               ".bag or no ending (ROS bag)")
        raise SimulateParameterError(msg)
    return log_format


def _check_outputs(out: Path, log_format: LogFormat, sources: list[Path | None]) -> Path:
    """Check the log ``out`` and its truth file can be written; return the truth path.

    ``sources`` are the command's input paths (None or not a file: ignored); neither output may
    name one of them.
    """
    inputs = [p for p in sources if p is not None and p.is_file()]
    log_format.check(out, inputs, f"--out {out}")
    truth = log_format.truth(out)
    check_output_file(truth, inputs=inputs, label=f"the truth file {truth} (beside --out)")
    return truth


def _simulate_with_progress(world: World, robot: RobotDescription, trajectory: Trajectory,
                            seed: int, physics: SonarPhysics,
                            drift: Trajectory | None, no_echo: bool = False) -> Simulation:
    """:func:`~sonarcarve.sim.simulate.simulate`, with a progress bar for long trajectories.

    The bar appears from ``_PROGRESS_MIN_FIRINGS`` firings (one every
    ``robot.firing_period`` seconds of ``trajectory``) on; the result is the same either way.
    """
    firings = math.floor(trajectory.duration / robot.firing_period) + 1
    if firings >= _PROGRESS_MIN_FIRINGS:
        with progress() as bar:
            task = bar.add_task(f"simulating {world.name}", total=firings)
            return simulate(world, robot, trajectory, seed, physics, drift,
                            on_progress=lambda done, _: bar.update(task, completed=done),
                            no_echo=no_echo)
    return simulate(world, robot, trajectory, seed, physics, drift, no_echo=no_echo)


def _trajectory(world: World, path: Path | None, explore_seconds: float | None, seed: int,
                robot_radius: float, speed: float = DEFAULT_SPEED) -> Trajectory:
    if explore_seconds is not None:
        return explore(world, explore_seconds, seed=seed, speed=speed, robot_radius=robot_radius)
    if path is not None:
        points, places = read_waypoint_places(path)
        check_path_in_world(points, places, world, path)
        return follow_waypoints(points, speed=speed)
    if world.tour is None:
        msg = f"world {world.name!r} has no built-in tour: give --path FILE or --explore SECONDS"
        raise WorldError(msg)
    return follow_waypoints(world.tour, speed=speed)


def _summary(result: Simulation, out: Path, truth: Path, label: str) -> Table:
    rows = [("seconds simulated", f"{result.trajectory.duration:,.1f}"),
            ("metres travelled", f"{result.trajectory.path_length:,.1f}"),
            ("firings", f"{len(result.firings):,}"),
            ("readings (echoes heard)", f"{len(result.readings):,}")]
    rows += [(f"  {kind}", f"{count:,}") for kind, count in result.kind_counts().items()]
    rows += [(f"{label} written to", str(out)), ("truth written to", str(truth))]
    return summary_table(f"sonarcarve simulate: {result.world.name}, {result.robot.name}", rows)
