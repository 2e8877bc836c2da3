"""``sonarcarve grid``: map a log (readings CSV or ROS bag) into an occupancy grid, as a ROS
map_server map.

A bag is read as ``sonarcarve process`` reads it: the bag options of
:mod:`sonarcarve.cli.options` give a :class:`~sonarcarve.fleet.BagOptions`, whose
:meth:`~sonarcarve.fleet.BagOptions.read` and :meth:`~sonarcarve.fleet.BagOptions.readings`
give the readings (with ``--no-echo``, the silent firings as no-echo readings, which the carved
and Elfes grids take as free space; the range-sensor-layer drops them, as ROS's does).
"""

from __future__ import annotations

import math
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Annotated

import numpy as np
import typer

from sonarcarve.cli.app import app, console, summary_table
from sonarcarve.cli.options import (
    FrameOpt,
    NoEchoOpt,
    OdomTopicOpt,
    RangeTopicOpt,
    RobotOpt,
    bag_options,
    refuse_bag_options,
)
from sonarcarve.errors import SonarcarveError
from sonarcarve.fleet import BagOptions, is_bag
from sonarcarve.grids import (
    CarvedGrid,
    CarvedGridParams,
    OccupancyGrid,
    OccupancyMap,
    RangeSensorLayer,
    trinary,
)
from sonarcarve.io.atomic import check_output_file
from sonarcarve.io.map_server import write_map_server
from sonarcarve.io.readings_csv import read_readings_csv
from sonarcarve.io.sanity import likely_mistakes
from sonarcarve.readings import DEFAULT_BEAM_WIDTH, ReadingBatch

__all__ = ["GRID_MODELS", "build_grid", "grid", "read_log_for_grid", "readings_extent"]

Bounds = tuple[float, float, float, float]


class GridUsageError(SonarcarveError):
    """A bad option of ``sonarcarve grid``: unknown model, resolution or margin out of range."""


def _carved(resolution: float, bounds: Bounds, fresh_periods: float | None) -> OccupancyMap:
    params = None if fresh_periods is None else CarvedGridParams(fresh_periods=fresh_periods)
    return CarvedGrid(resolution, bounds, params=params)


def _layer(resolution: float, bounds: Bounds, fresh_periods: float | None) -> OccupancyMap:
    return RangeSensorLayer(resolution, bounds)


def _elfes(resolution: float, bounds: Bounds, fresh_periods: float | None) -> OccupancyMap:
    return OccupancyGrid(resolution, bounds)


#: ``--model`` name -> grid factory ``(resolution, bounds, fresh_periods)``; ``fresh_periods``
#: (None: the default) is the carved grid's alone, and :func:`build_grid` refuses it for the rest.
GRID_MODELS: dict[str, Callable[[float, Bounds, float | None], OccupancyMap]] = {
    "carved": _carved,
    "range-sensor-layer": _layer,
    "elfes": _elfes,
}


def readings_extent(batch: ReadingBatch, margin: float) -> Bounds:
    """``(xmin, ymin, xmax, ymax)`` of the sensors and their arcs (both beam edges and the
    axis at the range; a no-echo reading's at its ``max_range``, the free space it clears),
    grown by ``margin`` metres."""
    width = np.where(np.isnan(batch.beam_width), DEFAULT_BEAM_WIDTH, batch.beam_width)
    reach = np.where(np.isfinite(batch.range), batch.range, batch.max_range)
    xs, ys = [batch.x], [batch.y]
    for k in (-0.5, 0.0, 0.5):
        xs.append(batch.x + reach * np.cos(batch.theta + k * width))
        ys.append(batch.y + reach * np.sin(batch.theta + k * width))
    x, y = np.concatenate(xs), np.concatenate(ys)
    return (float(x.min()) - margin, float(y.min()) - margin,
            float(x.max()) + margin, float(y.max()) + margin)


def _check_fresh_periods(model: str, fresh_periods: float | None) -> None:
    """Refuse ``--fresh-periods`` for a model other than the carved grid, or out of its range
    (:attr:`~sonarcarve.grids.CarvedGridParams.fresh_periods`)."""
    if fresh_periods is None:
        return
    if model != "carved":
        msg = f"--fresh-periods applies to --model carved only, not {model}"
        raise GridUsageError(msg)
    if not fresh_periods >= 1.0:  # also NaN
        msg = (f"--fresh-periods must be a number >= 1 firing period (inf: keep the mark up to "
               f"2 s), got {fresh_periods}")
        raise GridUsageError(msg)


def build_grid(batch: ReadingBatch, model: str, resolution: float,
               margin: float = 0.5, fresh_periods: float | None = None) -> OccupancyMap:
    """The grid ``model`` over the readings' extent plus ``margin``, with every reading in;
    ``fresh_periods`` (carved grid only; None: its default) as
    :attr:`~sonarcarve.grids.CarvedGridParams.fresh_periods`.

    Raises
    ------
    GridUsageError
        An unknown model, a resolution or margin that is not a finite positive number (margin:
        >= 0), a resolution larger than the area mapped, ``fresh_periods`` below 1 or for a
        model other than the carved grid, or no readings.
    """
    if model not in GRID_MODELS:
        msg = f"--model must be one of {' | '.join(GRID_MODELS)}, got {model!r}"
        raise GridUsageError(msg)
    if not (math.isfinite(resolution) and resolution > 0.0):
        msg = f"--resolution must be a finite number > 0 (metres), got {resolution}"
        raise GridUsageError(msg)
    if not (math.isfinite(margin) and margin >= 0.0):
        msg = f"--margin must be a finite number >= 0 (metres), got {margin}"
        raise GridUsageError(msg)
    _check_fresh_periods(model, fresh_periods)
    if not len(batch):
        msg = "no readings to map"
        raise GridUsageError(msg)
    bounds = readings_extent(batch, margin)
    width, height = bounds[2] - bounds[0], bounds[3] - bounds[1]
    if resolution > max(width, height):
        msg = (f"--resolution {resolution:g} m is larger than the area mapped ({width:.3g} x "
               f"{height:.3g} m: the readings' extent plus --margin); a cell must be smaller")
        raise GridUsageError(msg)
    built = GRID_MODELS[model](resolution, bounds, fresh_periods)
    assert isinstance(built, CarvedGrid | RangeSensorLayer | OccupancyGrid)
    built.add_many(batch)
    return built


def read_log_for_grid(source: Path, bag: BagOptions) -> ReadingBatch:
    """The readings of ``source``: a ROS bag (:func:`~sonarcarve.fleet.is_bag`) read with
    ``bag`` as ``sonarcarve process`` reads it, else a readings CSV (whose no-echo rows, range
    inf, are in it already).

    Raises
    ------
    ReadingsError, RosbagError, RobotError
        A log (or robot file) that cannot be read: one line naming it.
    GridUsageError
        No readings to map, naming ``source`` (and, for a bag whose Range messages all heard
        nothing, ``--no-echo``).
    """
    if not is_bag(source):
        batch, silent = read_readings_csv(source), 0
    else:
        log = bag.read(source)
        batch, silent = bag.readings(log), len(log.no_echo)
    if not len(batch):
        hint = (f" (its {silent:,} Range messages heard nothing, +Inf; --no-echo maps them as "
                "free space)" if silent else "")
        msg = f"{source}: no readings to map{hint}"
        raise GridUsageError(msg)
    return batch


@app.command()
def grid(
    readings: Annotated[Path, typer.Argument(
        metavar="READINGS.csv|BAG",
        help="Readings CSV with a header `t,sensor,x,y,theta,range[,beam_width][,max_range]` "
             "(as for `sonarcarve process`; rows with range `inf` are no-echo readings). Or a "
             "ROS bag: `*.bag` (ROS 1), `*.mcap`, `*.db3` or a rosbag2 folder, read as "
             "`sonarcarve process` reads it (Range + odometry + TF; see the bag options).")],
    out: Annotated[Path, typer.Option(
        "--out", "-o", metavar="GRID.yaml",
        help="The map_server YAML to write; the trinary image GRID.pgm is written beside it. "
             "Its folder must exist.")],
    model: Annotated[str, typer.Option(
        "--model", "-m", metavar="NAME",
        help="carved (arc carving's grid) | range-sensor-layer (ROS's layer, its defaults) | "
             "elfes (the Elfes/octomap log-odds grid).")] = "carved",
    resolution: Annotated[float, typer.Option(
        metavar="METRES",
        help="Cell side, metres; at most the longer side of the area mapped (the readings' "
             "extent plus --margin): a larger cell would put the whole map in one cell.")] = 0.05,
    margin: Annotated[float, typer.Option(
        metavar="METRES", help="Margin around the readings' extent, metres.")] = 0.5,
    fresh_periods: Annotated[float | None, typer.Option(
        metavar="PERIODS",
        help="--model carved only: a sensor's newest echo marks the map at once until the "
             "sensor has fired again; in a log without its silent firings, until this many of "
             "its firing periods have passed (learnt from the log; default 1.1). `inf`: keep "
             "the mark up to 2 s, for logs that drop readings whose value did not change "
             "(naive polling, stale-repeat filters), where a missing reading does not mean "
             "the sensor heard nothing.")] = None,
    robot: RobotOpt = None,
    range_topic: RangeTopicOpt = None,
    odom_topic: OdomTopicOpt = None,
    frame: FrameOpt = None,
    no_echo: NoEchoOpt = False,
) -> None:
    """Map a readings CSV or a ROS bag into an occupancy grid, written as a ROS map_server map.

    The input is a readings CSV or a ROS bag (ROS 1 `.bag`, `.mcap`, `.db3` or a rosbag2
    folder: sensor_msgs/Range per transducer, odometry and TF), a bag read as `sonarcarve
    process` reads it, with the same bag options. A bag's silent firings (REP 117 +Inf) are
    left out unless --no-echo keeps them as no-echo readings, as a CSV's rows with range inf
    always are: the carved and Elfes grids take their beams, up to max_range, as free space;
    ROS's range-sensor-layer drops +Inf, as ROS does. The bag options apply to bags only.

    Writes GRID.yaml (image, resolution, origin, negate 0, occupied_thresh, free_thresh) and
    GRID.pgm beside it (trinary: occupied 0, free 254, unknown 205), both or neither. The grid
    covers the sensors and their arcs plus --margin.

    Readings in probably wrong units (theta in degrees, ranges in centimetres or millimetres)
    give one `sonarcarve: warning:` line each on stderr; the exit code is still 0.

    Example: `sonarcarve grid readings.csv --model carved --resolution 0.05 --out grid.yaml`

    Example: `sonarcarve grid run.mcap --no-echo --resolution 0.05 --out grid.yaml`

    Example: `sonarcarve grid run.bag --robot p3dx-front --model elfes --out grid.yaml` (a
    ROS 1 bag without TF mounts)

    Example: `sonarcarve grid polled.csv --fresh-periods inf --out grid.yaml` (a log that
    left out readings equal to the one before)
    """
    if model not in GRID_MODELS:
        msg = f"--model must be one of {' | '.join(GRID_MODELS)}, got {model!r}"
        raise GridUsageError(msg)
    _check_fresh_periods(model, fresh_periods)  # before anything is read
    bag = bag_options(robot, range_topic, odom_topic, frame, no_echo=no_echo)
    refuse_bag_options(readings, bag)
    check_output_file(out, inputs=[readings], label=f"--out {out}")
    check_output_file(Path(out).with_suffix(".pgm"), inputs=[readings],
                      label=f"--out {out} (image)")
    batch = read_log_for_grid(readings, bag)
    built = build_grid(batch, model, resolution, margin, fresh_periods)
    cells = trinary(built)
    yaml_path, pgm_path = write_map_server(cells, built.resolution,
                                           (built.bounds[0], built.bounds[1]), out)
    rows, cols = built.shape
    for line in likely_mistakes(batch):  # after the writing: a failed run prints one line only
        print(f"sonarcarve: warning: {line}", file=sys.stderr)
    silent = int(np.count_nonzero(batch.range == np.inf))
    console.print(summary_table(f"sonarcarve grid ({model})", [
        ("readings", f"{len(batch):,}" + (f" ({silent:,} no-echo)" if silent else "")),
        ("cells", f"{cols} x {rows} of {built.resolution:g} m"),
        ("occupied / free / unknown",
         f"{np.count_nonzero(cells == 100):,} / {np.count_nonzero(cells == 0):,} / "
         f"{np.count_nonzero(cells == -1):,}"),
        ("written", f"{yaml_path}, {pgm_path}"),
    ]))
