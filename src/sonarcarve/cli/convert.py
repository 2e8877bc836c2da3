"""``sonarcarve convert``: turn a data set's own files into the readings CSV."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Annotated

import numpy as np
import typer
from rich.table import Table

from sonarcarve.cli.app import app, console, summary_table, warn
from sonarcarve.cli.options import (
    BAG_PANEL,
    FrameOpt,
    OdomTopicOpt,
    RangeTopicOpt,
    RobotOpt,
    bag_options,
    read_bag,
)
from sonarcarve.constants import DEFAULT_BEAM_WIDTH
from sonarcarve.errors import SonarcarveError
from sonarcarve.fleet import BagOptions
from sonarcarve.io import read_robond, write_readings_csv
from sonarcarve.io.atomic import check_output_file
from sonarcarve.io.roboND import ROBOND_BEAM_WIDTH, bundled_robond_dir
from sonarcarve.io.rosbag import RosbagReport
from sonarcarve.readings import ReadingBatch

__all__ = ["CONVERTERS", "ConvertOptions", "convert"]


class ConvertError(SonarcarveError):
    """An unknown format or a bad parameter of ``convert``."""


@dataclass(frozen=True)
class ConvertOptions:
    """The options of ``convert``; each format uses some and rejects the others it cannot use.

    Attributes
    ----------
    beam_width : float or None
        φ in radians, or None for the format's default.
    keep_duplicates : bool
        roboND: keep repeats while standing.
    bag : BagOptions
        rosbag: how to read the bag (robot, topics, base frame; shared with ``process``).
    """

    beam_width: float | None = None
    keep_duplicates: bool = False
    bag: BagOptions = field(default_factory=BagOptions)


def _robond(directory: Path | None, out: Path, opts: ConvertOptions) -> Table:
    if opts.bag.given:
        msg = ("--robot, --range-topic, --odom-topic, --frame and --no-echo apply to the rosbag "
               "format only")
        raise ConvertError(msg)
    beam_width = opts.beam_width
    log = read_robond(directory, keep_duplicates=opts.keep_duplicates,
                      beam_width=ROBOND_BEAM_WIDTH if beam_width is None else beam_width)
    write_readings_csv(log.batch, out)
    r = log.report
    source = directory if directory is not None else f"{bundled_robond_dir()} (bundled)"
    # The source in a row, not the title: the bundled log's path would wrap a title over lines.
    return summary_table("convert roboND", [
        ("source", str(source)),
        ("records", f"{r.records:,}"),
        ("sensor values", f"{r.values:,}"),
        ("no echo (dropped)", f"{r.no_echo:,}"),
        ("repeats while moving (any value)", f"{r.repeats:,}"),
        ("stale echoes (dropped)", f"{r.stale:,}"),
        (f"repeats while standing ({'kept' if r.duplicates_kept else 'dropped'})",
         f"{r.duplicates:,}"),
        ("readings written", f"{r.readings:,}"),
        ("readings CSV", str(out)),
    ])


def _rosbag(source: Path | None, out: Path, opts: ConvertOptions) -> Table:
    if source is None:
        msg = "rosbag needs SOURCE: a rosbag1 file (*.bag), a rosbag2 folder or a *.mcap file"
        raise ConvertError(msg)
    if opts.keep_duplicates:
        msg = "--keep-duplicates applies to the roboND format only"
        raise ConvertError(msg)
    bag = replace(opts.bag, beam_width=opts.beam_width)
    log = read_bag(bag, source)
    batch = bag.readings(log)
    write_readings_csv(batch, out)
    r = log.report
    beams = _beam_widths(batch, len(r.sources))
    for line in _sensor_lines(r, beams):
        console.print(line, soft_wrap=True, highlight=False, markup=False)
    warn([_no_beam_warning(r, beams)])
    rows = [(f"messages on {topic}", f"{count:,}") for topic, count in r.messages.items()]
    parent, child = r.odometry_frames
    return summary_table("convert rosbag", [
        ("source", str(source)),
        *rows,
        ("odometry", f"{r.odometry_topic} ({parent or '?'} → {child or '?'})"),
        ("sensors", f"{len(r.sensors):,}"),
        ("no echo, +Inf or max_range (free space)",
         f"{r.no_echo:,} ({'written, range inf' if bag.no_echo else 'dropped; --no-echo keeps'})"),
        ("too close, -Inf (dropped)", f"{r.too_close:,}"),
        ("invalid, NaN (dropped)", f"{r.invalid:,}"),
        ("outside odometry span (dropped)", f"{r.outside_odometry:,}"),
        ("readings written", f"{len(batch):,}"),
        ("readings CSV", str(out)),
    ])


def _sensor_lines(report: RosbagReport, beams: list[float | None]) -> list[str]:
    """Which topic and frame became which sensor, where its mount came from, and its beam
    width (``beams``, :func:`_beam_widths`): one line each.

    Lines, not a table, so that narrow terminals do not cut the frame names.
    """
    return [f"sensor {i}: {s.topic} frame {s.frame or '(none)'} ← mount {s.mount} "
            f"({s.x:.3f} m, {s.y:.3f} m, {math.degrees(s.bearing):.1f}°), {s.radiation}"
            f"{_beam_text(beam)}"
            for i, (s, beam) in enumerate(zip(report.sources, beams, strict=True))]


def _beam_widths(batch: ReadingBatch, sensors: int) -> list[float | None]:
    """Per sensor, the beam width (radians) its rows were written with: NaN for none (its
    Range messages' ``field_of_view`` was 0 and no --beam-width was given), None for a sensor
    without rows."""
    widths: list[float | None] = []
    for i in range(sensors):
        mine = batch.beam_width[batch.sensor == i]
        widths.append(float(np.median(mine)) if len(mine) else None)
    return widths


def _beam_text(beam: float | None) -> str:
    if beam is None:
        return ""
    return ", beam not given" if math.isnan(beam) else f", beam {math.degrees(beam):.1f}°"


def _no_beam_warning(report: RosbagReport, beams: list[float | None]) -> str | None:
    """A warning naming the sensors whose rows carry no beam width, else None: the methods
    would take a default cone (22.5°) that may be far from the sensor's."""
    missing = [i for i, beam in enumerate(beams) if beam is not None and math.isnan(beam)]
    if not missing:
        return None
    named = ", ".join(f"{i} ({report.sources[i].topic})" for i in missing[:3])
    more = f" and {len(missing) - 3} more" if len(missing) > 3 else ""
    which = "sensor" if len(missing) == 1 else "sensors"
    return (f"{which} {named}{more}: field_of_view 0, so no beam_width is written and process "
            f"and grid will assume {math.degrees(DEFAULT_BEAM_WIDTH):g}°; give the sensors' "
            "cone with --beam-width DEGREES")


#: Format name (lower case) -> converter(source, out, options).
CONVERTERS: dict[str, Callable[[Path | None, Path, ConvertOptions], Table]] = {
    "robond": _robond,
    "rosbag": _rosbag,
}


@app.command()
def convert(
    fmt: Annotated[str, typer.Argument(
        metavar="FORMAT",
        help="Data set format: roboND (the bundled 8-sensor real log) or rosbag (ROS 1/2 bag "
             "of sensor_msgs/Range + nav_msgs/Odometry).")],
    out: Annotated[Path, typer.Option(
        "--out", "-o", metavar="READINGS.csv",
        help="Readings CSV to write (seconds, metres, radians). Its folder must exist.")],
    directory: Annotated[Path | None, typer.Argument(
        metavar="SOURCE",
        help="roboND: folder holding the log's files (default: the bundled copy); "
             "rosbag: a rosbag1 file (*.bag), an MCAP file (*.mcap) or a rosbag2 folder.")]
        = None,
    beam_width: Annotated[float | None, typer.Option(
        metavar="DEGREES",
        help="Beam width φ in degrees written with each reading (roboND default: 20).")] = None,
    keep_duplicates: Annotated[bool, typer.Option(
        help="roboND: keep values that repeat while the robot stands still (they add "
             "identical arcs).")]
        = False,
    robot: RobotOpt = None,
    range_topic: RangeTopicOpt = None,
    odom_topic: OdomTopicOpt = None,
    frame: FrameOpt = None,
    no_echo: Annotated[bool, typer.Option(
        "--no-echo",
        help="rosbag: also write the no-echo readings (REP 117 +Inf, or max_range from a "
             "sensor that never reports +Inf: nothing heard up to max_range) as rows with "
             "range inf and a max_range column, which the methods and the carved and Elfes "
             "grids take as free space (as process and grid --no-echo take them from the "
             "bag).",
        rich_help_panel=BAG_PANEL)] = False,
) -> None:
    """Convert a data set's files into the readings CSV (t,sensor,x,y,theta,range,beam_width).

    roboND: `poses.txt` (ms, mm, tenths of a degree) and `measurement.txt` (mm; 5110 = no
    echo) become one reading per echo in seconds, metres and radians (world frame). No-echo
    values are dropped, and so are stale repeats: a value equal to the same sensor's value in
    the previous record although the robot moved (the sensor had not fired again).

    rosbag (ROS 1 .bag, ROS 2 folder with sqlite3 or MCAP storage, or a bare .mcap): each
    sensor_msgs/Range echo (header stamp, s) from min_range up to max_range becomes a reading
    posed by the robot pose interpolated in nav_msgs/Odometry (or odom → base_link on /tf)
    composed with the sensor's mount, found in /tf_static (and /tf) by its frame_id; --robot
    gives mounts for bags without TF. Beam width = field_of_view when > 0. REP 117: -Inf (too
    close) and NaN (invalid) are counted, not written; +Inf, and a range equal to max_range
    from a sensor that never reports +Inf (Gazebo's way to say it), are no echo within range:
    counted, and written as free-space rows (range inf, max_range) with --no-echo.

    Example: `sonarcarve convert roboND --out roboND.csv` then
    `sonarcarve process roboND.csv --out map.csv`; or
    `sonarcarve convert rosbag run.mcap --out run.csv` (mounts from TF), or
    `sonarcarve convert rosbag run.bag --robot p3dx-front --out run.csv` (a bag without TF).
    """
    converter = CONVERTERS.get(fmt.lower())
    if converter is None:
        msg = f"unknown format {fmt!r}; choose one of: roboND, rosbag"
        raise ConvertError(msg)
    width = _beam_width_radians(beam_width)
    # The data set's own files must survive a --out that names one of them.
    check_output_file(out, inputs=_source_files(directory), label=f"--out {out}")
    options = ConvertOptions(beam_width=width, keep_duplicates=keep_duplicates,
                             bag=bag_options(robot, range_topic, odom_topic, frame,
                                             no_echo=no_echo))
    console.print(converter(directory, out, options))


def _beam_width_radians(beam_width: float | None) -> float | None:
    """``--beam-width`` (degrees, in (0, 180)) in radians; None when not given.

    Raises
    ------
    ConvertError
        A width outside (0, 180) degrees.
    """
    if beam_width is None:
        return None
    if not 0.0 < beam_width < 180.0:
        msg = f"--beam-width must lie in (0, 180) degrees, got {beam_width}"
        raise ConvertError(msg)
    return math.radians(beam_width)


def _source_files(directory: Path | None) -> list[Path]:
    """The data set's files: a folder's entries (sorted), the file itself, or none."""
    inputs = sorted(directory.iterdir()) if directory is not None and directory.is_dir() else []
    if directory is not None and directory.is_file():
        inputs = [directory]
    return inputs
