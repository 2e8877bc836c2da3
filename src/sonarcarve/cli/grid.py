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
from dataclasses import replace
from pathlib import Path
from typing import Annotated, Any

import numpy as np
import typer

from sonarcarve.cli.app import app, console, cut_short, flag_message, summary_table, warn
from sonarcarve.cli.options import (
    FrameOpt,
    MaxRangeOpt,
    NoEchoOpt,
    OdomTopicOpt,
    RangeTopicOpt,
    RobotOpt,
    bag_options,
    check_max_range,
    drop_far_echoes,
    max_range_hint,
    no_echo_dropped_row,
    read_bag,
    refuse_bag_options,
)
from sonarcarve.errors import SonarcarveError
from sonarcarve.fleet import BagOptions, is_bag
from sonarcarve.grids import (
    GRIDS,
    CarvedGridParams,
    GridError,
    make_grid,
    readings_extent,
    trinary,
)
from sonarcarve.grids import Grid as BuiltGrid
from sonarcarve.io.atomic import check_output_file
from sonarcarve.io.map_server import write_map_server
from sonarcarve.io.readings_csv import read_readings_csv
from sonarcarve.io.sanity import beam_width_mistake, likely_mistakes
from sonarcarve.readings import ReadingBatch

__all__ = ["build_grid", "few_sonars_hint", "grid", "grid_params", "read_log_for_grid"]

#: The library's parameter names (:func:`~sonarcarve.grids.make_grid`,
#: :func:`~sonarcarve.grids.readings_extent`, :class:`~sonarcarve.grids.CarvedGridParams`) ->
#: the options that set them, for its error messages.
_FLAGS = {"resolution": "--resolution", "margin": "--margin", "fresh_periods": "--fresh-periods",
          "free_threshold": "--free-below", "pose_sigma": "--pose-sigma",
          "range_tolerance": "--range-tolerance", "mark_length": "--mark-length"}


class GridUsageError(SonarcarveError):
    """A bad option of ``sonarcarve grid``: unknown model, resolution or margin out of range."""


def _check_model(model: str) -> None:
    """Refuse a ``--model`` that is no key of :data:`~sonarcarve.grids.GRIDS`, before anything
    is read (:func:`~sonarcarve.grids.make_grid` would refuse it only after)."""
    if model not in GRIDS:
        msg = f"--model must be one of {' | '.join(GRIDS)}, got {model!r}"
        raise GridUsageError(msg)


def grid_params(model: str, fresh_periods: float | None, free_below: float | None = None,
                pose_sigma: float | None = None, range_tolerance: float | None = None,
                mark_length: float | None = None) -> CarvedGridParams | None:
    """The grid's parameters from the options, for the carved grid only (None: the default):
    ``--fresh-periods`` as :attr:`~sonarcarve.grids.CarvedGridParams.fresh_periods`,
    ``--free-below`` as :attr:`~sonarcarve.grids.CarvedGridParams.free_threshold`,
    ``--pose-sigma`` as :attr:`~sonarcarve.grids.CarvedGridParams.pose_sigma`,
    ``--range-tolerance`` as :attr:`~sonarcarve.grids.CarvedGridParams.range_tolerance` (the
    band's ε and its carving's), ``--mark-length`` as
    :attr:`~sonarcarve.grids.CarvedGridParams.mark_length`.

    Raises
    ------
    GridUsageError
        Any of them for a model other than the carved grid, or out of its range.
    """
    options = {"fresh_periods": fresh_periods, "free_threshold": free_below,
               "pose_sigma": pose_sigma, "range_tolerance": range_tolerance,
               "mark_length": mark_length}
    given: dict[str, Any] = {field: value for field, value in options.items()
                             if value is not None}
    if not given:
        return None
    if model != "carved":
        msg = f"{_FLAGS[next(iter(given))]} applies to --model carved only, not {model}"
        raise GridUsageError(msg)
    try:
        return replace(CarvedGridParams(), **given)
    except GridError as err:
        raise GridUsageError(flag_message(str(err), _FLAGS)) from None


def build_grid(batch: ReadingBatch, model: str, resolution: float,
               margin: float = 0.5, params: CarvedGridParams | None = None) -> BuiltGrid:
    """The grid ``model`` (:func:`~sonarcarve.grids.make_grid`) over the readings' extent
    plus ``margin`` (:func:`~sonarcarve.grids.readings_extent`), with every reading in;
    ``params`` the carved grid's (:func:`grid_params`; None: its defaults).

    Raises
    ------
    GridUsageError
        What the library refuses (an unknown model, a resolution or margin out of range, no
        readings), its parameters named as the options; a resolution larger than the area
        mapped.
    """
    _check_model(model)
    try:
        bounds = readings_extent(batch, margin)
        built = make_grid(model, resolution, bounds, params)
    except GridError as err:
        raise GridUsageError(flag_message(str(err), _FLAGS)) from None
    width, height = bounds[2] - bounds[0], bounds[3] - bounds[1]
    if resolution > max(width, height):
        msg = (f"--resolution {resolution:g} m is larger than the area mapped ({width:.3g} x "
               f"{height:.3g} m: the readings' extent plus --margin); a cell must be smaller")
        raise GridUsageError(msg)
    built.add_many(batch)
    return built


#: The most sensors a log may have for :func:`few_sonars_hint` to speak.
FEW_SONARS = 2


def few_sonars_hint(batch: ReadingBatch, model: str) -> str | None:
    """A note for a carved grid of a log from one or two sonars, else None.

    The carved grid is a ring's costmap: its free space is octomap's miss faded with range,
    which a ring makes up for by looking at each cell many times and one sonar cannot. Measured
    on held-out floors (docs/RESULTS.md, "One or two sonars"), it marked 37-44 % of the free
    floor near the path free where ROS's layer, which frees a near cell in one reading, marked
    47-84 %; it was the more precise in 7 of 8 settings. A note, not a warning: nothing in the
    log is wrong, and the user may prefer precision.

    Examples
    --------
    >>> one = ReadingBatch.from_arrays(t=[0, 1], sensor=[3, 3], x=[0, 0], y=[0, 0],
    ...                                theta=[0, 0], range=[2.0, 2.0])
    >>> few_sonars_hint(one, "carved")[:44]
    'Few sonars: 1 sonar in this log. With one or'
    >>> few_sonars_hint(one, "range-sensor-layer") is None
    True
    """
    sonars = np.unique(batch.sensor).size
    if model != "carved" or not 0 < sonars <= FEW_SONARS:
        return None
    return (f"Few sonars: {sonars} sonar{'s' if sonars > 1 else ''} in this log. With one or two "
            "sonars the carved grid marked 37-44 % of the free floor near the path free in our "
            "simulations, ROS's layer 47-84 % (docs/RESULTS.md, 'One or two sonars'): --model "
            "range-sensor-layer frees more of the floor, less precisely.")


def read_log_for_grid(source: Path, bag: BagOptions,
                      max_range: float | None = None) -> tuple[ReadingBatch, int]:
    """The readings of ``source`` and how many no-echo readings were dropped: a ROS bag
    (:func:`~sonarcarve.fleet.is_bag`) read with ``bag`` as ``sonarcarve process`` reads it
    (its no-echo readings dropped unless ``bag.no_echo``), else a readings CSV (whose no-echo
    rows, range inf, are in it already; ``max_range``, metres, is how far those that give none
    listened).

    Raises
    ------
    ReadingsError, RosbagError, RobotError
        A log (or robot file) that cannot be read: one line naming it.
    GridUsageError
        No readings to map, naming ``source`` (and, for a bag whose Range messages all heard
        nothing, ``--no-echo``).
    """
    if not is_bag(source):
        with max_range_hint():
            batch, silent, dropped = read_readings_csv(source, max_range=max_range), 0, 0
    else:
        log = read_bag(bag, source)
        batch, silent, dropped = bag.readings(log), len(log.no_echo), bag.dropped_no_echo(log)
    if not len(batch):
        hint = (f" (its {silent:,} Range messages heard nothing, +Inf or max_range; "
                "--no-echo maps them as free space)" if silent else "")
        msg = f"{source}: no readings to map{hint}"
        raise GridUsageError(msg)
    return batch, dropped


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
        help="carved (arc carving's grid, made for rings of sonars) | range-sensor-layer "
             "(ROS's layer, its defaults; with one or two sonars it marks far more of the floor "
             "free: docs/RESULTS.md, 'One or two sonars') | elfes (the Elfes/octomap log-odds "
             "grid).")] = "carved",
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
    free_below: Annotated[float | None, typer.Option(
        metavar="P",
        help="--model carved only: call a cell free when its occupancy probability is below P "
             "(default 0.35: as much evidence as 'occupied' above 0.65 needs). 0.196, ROS "
             "map_saver's free_thresh, keeps more of the floor unknown, for planners or "
             "frontier explorers that must not trust a weakly seen cell.")] = None,
    robot: RobotOpt = None,
    range_topic: RangeTopicOpt = None,
    odom_topic: OdomTopicOpt = None,
    frame: FrameOpt = None,
    pose_sigma: Annotated[float | None, typer.Option(
        metavar="METRES",
        help="--model carved only: the standard deviation of the log's pose error, metres, as "
             "your localiser reports it (its position σ; adding range times heading σ was not "
             "measured). A reading's free space then ends 2σ before its echo, so a beam "
             "stamped a few cm off does not clear the wall it heard. Default 0 (poses taken as "
             "exact). A trade: with 5 cm / 2° of localisation noise, σ = 0.05 raised office "
             "recall 0.792 → 0.834 at 0.05 m cells and cost precision 0.591 → 0.558.")] = None,
    range_tolerance: Annotated[float | None, typer.Option(
        metavar="METRES",
        help="--model carved only: ε in metres, the echo band's thickness beyond a cell, the "
             "range slack of its repeated-echo test, and how far short of its range a newer "
             "reading's free space ends when it carves (default 0.05, as process; ε + 2 "
             "--pose-sigma at most 1). For a sonar with range noise σ above 2.5 cm give 2σ, "
             "as process --range-tolerance: in our "
             "simulations at σ 5 cm, 0.10 raised recall 0.874 → 0.887 at 0.10 m cells "
             "(specular echoes; precision 0.811 → 0.807, phantom cells +47 %; docs/RESULTS.md, "
             "'Other sonars').")] = None,
    mark_length: Annotated[float | None, typer.Option(
        metavar="METRES",
        help="--model carved only: how much of its carved arc a sensor's newest echo marks "
             "occupied at once, metres (default 0: the echo's most likely cell; a planner "
             "inflates it as any obstacle). 0.2, the rule before 2026-12-04, marked a simulated "
             "crossing person 0.2 s sooner (its first echo came from a beam's edge) but closed "
             "a 0.85 m door at 1 m in 6 % of approaches at 0.10 m cells (docs/RESULTS.md, 'The "
             "narrow door of the paper').")
    ] = None,
    no_echo: NoEchoOpt = False,
    max_range: MaxRangeOpt = None,
    beam_width: Annotated[float | None, typer.Option(
        metavar="DEGREES",
        help="Beam width φ in degrees for readings that carry none: a CSV without a "
             "beam_width column (or a blank cell), a bag whose Range messages leave "
             "field_of_view 0. A beam_width value or a field_of_view > 0 wins. Default 22.5 "
             "(a Polaroid's).")] = None,
) -> None:
    """Map a readings CSV or a ROS bag into an occupancy grid, written as a ROS map_server map.

    The input is a readings CSV or a ROS bag (ROS 1 `.bag`, `.mcap`, `.db3` or a rosbag2
    folder: sensor_msgs/Range per transducer, odometry and TF), a bag read as `sonarcarve
    process` reads it, with the same bag options. A bag's silent firings (REP 117 +Inf, or a
    range equal to max_range from a sensor that never reports +Inf, as Gazebo's sonar plugins
    publish them) are left out unless
    --no-echo keeps them as no-echo readings, as a CSV's rows with range inf always are: the
    carved and Elfes grids take their beams, up to max_range, as free space; ROS's
    range-sensor-layer drops +Inf, as ROS does. The bag options apply to bags only.

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

    Example: `sonarcarve grid readings.csv --free-below 0.196 --out grid.yaml` (free only where
    the evidence is strong, as map_saver's threshold)

    Example: `sonarcarve grid amcl.csv --pose-sigma 0.05 --out grid.yaml` (poses from a
    localiser good to about 5 cm)

    Example: `sonarcarve grid noisy.csv --range-tolerance 0.10 --out grid.yaml` (a sonar
    whose ranges scatter by about 5 cm)

    Example: `sonarcarve grid gazebo.csv --max-range 5 --out grid.yaml` (a CSV whose silent
    firings are rows with range inf and no max_range column)
    """
    _check_model(model)  # these two before anything is read
    params = grid_params(model, fresh_periods, free_below, pose_sigma, range_tolerance,
                         mark_length)
    check_max_range(max_range)
    if beam_width is not None and not 0.0 < beam_width < 180.0:
        msg = f"--beam-width must lie in (0, 180) degrees, got {beam_width:g}"
        raise GridUsageError(msg)
    bag = bag_options(robot, range_topic, odom_topic, frame, no_echo=no_echo)
    refuse_bag_options(readings, bag)
    if out.suffix.lower() not in (".yaml", ".yml"):  # before the grid is built, not after
        msg = f"--out {out}: a map_server map's name must end in .yaml (GRID.pgm goes beside it)"
        raise GridUsageError(msg)
    check_output_file(out, inputs=[readings], label=f"--out {out}")
    check_output_file(Path(out).with_suffix(".pgm"), inputs=[readings],
                      label=f"--out {out} (image)")
    batch, dropped_silent = read_log_for_grid(readings, bag, max_range)
    batch, _, too_far = drop_far_echoes(batch, max_range)
    if beam_width is not None:
        batch = batch.with_beam_width(math.radians(beam_width))
    built = build_grid(batch, model, resolution, margin, params)
    cells = trinary(built)
    yaml_path, pgm_path = write_map_server(cells, built.resolution,
                                           (built.bounds[0], built.bounds[1]), out)
    rows, cols = built.shape
    # After the writing: a failed run prints one line only.
    warn([None if beam_width is None else beam_width_mistake(beam_width, "--beam-width"),
          *likely_mistakes(batch), None if is_bag(readings) else cut_short(readings)])
    silent = int(np.count_nonzero(batch.range == np.inf))
    console.print(summary_table(f"sonarcarve grid ({model})", [
        ("readings", f"{len(batch):,}" + (f" ({silent:,} no-echo)" if silent else "")),
        *no_echo_dropped_row(dropped_silent),
        *([("dropped: echoes beyond --max-range", f"{too_far:,}")] if max_range else []),
        ("cells", f"{cols} x {rows} of {built.resolution:g} m"),
        ("occupied / free / unknown",
         f"{np.count_nonzero(cells == 100):,} / {np.count_nonzero(cells == 0):,} / "
         f"{np.count_nonzero(cells == -1):,}"),
        ("written", f"{yaml_path}, {pgm_path}"),
    ]))
    hint = few_sonars_hint(batch, model)
    if hint is not None:
        console.print(hint, markup=False, highlight=False)
