"""``sonarcarve process``: map a log (readings CSV or ROS bag) with one method and write the
global map, a ROS bag or a Rerun recording; or map a fleet of logs into a folder.

OUT's ending picks the writer from :data:`OUTPUTS` (a dispatch table, not a chain of tests):
``.csv`` the global map CSV (the contract), ``.bag`` / ``.mcap`` / no ending (a rosbag2 folder)
a ROS bag, ``.rrd`` a Rerun recording. ``--out-dir`` maps every INPUT on the runner
(:mod:`sonarcarve.fleet`, :mod:`sonarcarve.runner`).
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, NamedTuple

import typer

from sonarcarve.cli.app import (
    app,
    console,
    cut_short,
    err_console,
    progress,
    readings_progress,
    reworded,
    summary_table,
    warn,
)
from sonarcarve.cli.options import (
    DEFAULT_BEAM_WIDTH_DEG,
    DEFAULT_TRANSVERSAL_DEG,
    MAX_RANGE_HELP,
    RUNNER_FLAGS,
    BeamWidthOpt,
    FrameOpt,
    HistoryOpt,
    IncidenceOpt,
    MethodOpt,
    MinConfidenceOpt,
    NoEchoOpt,
    OdomTopicOpt,
    PointCertainty,
    RangeTopicOpt,
    RobotOpt,
    StampErrorOpt,
    StampHeadingOpt,
    ToleranceOpt,
    TransversalOpt,
    bag_options,
    check_max_range,
    check_method,
    check_new_bag,
    drop_far_echoes,
    max_range_hint,
    method_config,
    no_echo_dropped_row,
    read_bag,
    refuse_bag_options,
)
from sonarcarve.errors import SonarcarveError
from sonarcarve.filters import PAPER_MAX_RANGE, BodyFootprint, MapFilter, ReadingFilter
from sonarcarve.fleet import SUMMARY_NAME, BagOptions, FleetRow, is_bag
from sonarcarve.history import DEFAULT_HISTORY_SIZE
from sonarcarve.io import read_readings_csv, write_map_csv
from sonarcarve.io.atomic import check_output_file
from sonarcarve.io.map_csv import MapCsvSink, map_csv_sink
from sonarcarve.io.readings_csv import count_data_lines, iter_readings_csv
from sonarcarve.io.sanity import beam_width_mistake, likely_mistakes
from sonarcarve.methods import MethodConfig, SonarMethod, make_method
from sonarcarve.methods.config import DEFAULT_RANGE_TOLERANCE
from sonarcarve.pipeline import ProcessResult, process_chunks, process_readings
from sonarcarve.readings import ReadingBatch
from sonarcarve.robot import FIRING_PERIOD_RANGE, load_robot

if TYPE_CHECKING:  # the grid, bag, Rerun and fleet writers are imported by their output only
    from rich.table import Table

    from sonarcarve.grids import CarvedGrid
    from sonarcarve.io.rosbag import RosbagLog
    from sonarcarve.runner import RunnerSpec

__all__ = ["EXIT_SOME_LOGS_FAILED", "OUTPUTS", "Output", "process"]

#: Exit code of a fleet run (``--out-dir``) in which at least one log failed (bad input's code).
EXIT_SOME_LOGS_FAILED = 2

#: Local maps per second of log time in a bag output, unless --map-rate says otherwise.
_DEFAULT_MAP_RATE = 2.0

#: Logs shorter than this finish before a progress bar would be worth drawing.
_PROGRESS_MIN_READINGS = 20_000


class ParameterError(SonarcarveError):
    """A filter option outside its valid range (method parameters are checked by
    :class:`~sonarcarve.methods.MethodConfig`), or options that do not go together."""


@dataclass(frozen=True)
class _Job:
    """One INPUT mapped to one OUT: what every writer of :data:`OUTPUTS` gets."""

    source: Path
    out: Path
    method: str
    config: MethodConfig
    reading_filter: ReadingFilter | None
    map_filter: MapFilter | None
    bag: BagOptions
    map_rate: float
    grid_resolution: float
    #: Likely mistakes the writer found in the readings, printed as warnings if the run succeeds.
    warnings: list[str] = field(default_factory=list)
    #: Rows the input's reader adds to the summary under "readings in" (a bag's no-echo
    #: readings, mapped or dropped).
    input_rows: list[tuple[str, str]] = field(default_factory=list)

    def sonar(self) -> SonarMethod:
        """A fresh method."""
        return make_method(self.method, self.config)

    def read_bag_log(self) -> RosbagLog:
        """The bag input, read with the bag options, its no-echo readings counted for the
        summary."""
        log = read_bag(self.bag, self.source)
        if self.bag.no_echo and len(log.no_echo):
            self.input_rows[:] = [("no-echo readings mapped as free space",
                                   f"{len(log.no_echo):,}")]
        else:
            self.input_rows[:] = no_echo_dropped_row(self.bag.dropped_no_echo(log))
        return log

    @property
    def max_range(self) -> float | None:
        """``--max-range``: also how far a readings CSV's no-echo rows without a max_range
        listened (the readings CSV contract's run-wide max range)."""
        return None if self.reading_filter is None else self.reading_filter.max_range


class Output(NamedTuple):
    """One kind of ``--out``: how to check the target before any work, and the writer (which
    returns the summary's rows)."""

    label: str
    check: Callable[[_Job], object]
    write: Callable[[_Job], list[tuple[str, str]]]


# The command's options, one alias each, so that the command's signature reads as a list.
_InputsArg = Annotated[list[Path], typer.Argument(
    metavar="READINGS.csv|BAG",
    help="Readings CSV with a header `t,sensor,x,y,theta,range[,beam_width][,max_range]`, "
         "one echo per row: t in seconds (never decreasing), sensor a whole number >= 0, x, y "
         "the sensor's position in metres, theta its axis in radians counter-clockwise from "
         "+x (world frame), range in metres (> 0, or `inf` for a reading that heard nothing: "
         "then max_range must be given), beam_width in radians (optional; blank or absent: "
         "--beam-width applies), max_range in metres (optional: how far the sensor listened; "
         "a no-echo row's free space reaches it). Or a ROS bag: `*.bag` (ROS 1), `*.mcap`, "
         "`*.db3` or a rosbag2 folder, read as `sonarcarve convert rosbag` reads it (Range + "
         "odometry + TF; see the bag options). Several logs need --out-dir.")]
_OutOpt = Annotated[Path | None, typer.Option(
    "--out", "-o", metavar="OUT",
    help="Where to write, for one INPUT; the ending picks what: `.csv` the global map CSV; "
         "`.mcap`, `.bag` or no ending (a rosbag2 folder) a ROS bag with the input bag's "
         "topics copied through plus /sonarcarve/local_map (PointCloud2), "
         "/sonarcarve/arcs (MarkerArray) and /sonarcarve/grid (OccupancyGrid, the carved "
         "grid: --grid-resolution); `.rrd` a Rerun recording. Its folder must exist; "
         "never the input; a bag is never overwritten. Bag and .rrd outputs, and bag inputs, "
         "hold the whole log in memory; CSV to CSV streams (the map too, unless a map filter "
         "is on).",
    show_default=False)]
_OutDirOpt = Annotated[Path | None, typer.Option(
    "--out-dir", metavar="FOLDER",
    help="Map every INPUT (CSVs or bags) in parallel into this folder (created): one "
         "NAME.map.csv per log and summary.csv. A log that fails gets its one-line error in "
         "the summary and does not stop the others; the exit code is 0 when every log was "
         "mapped, 2 when any failed.", rich_help_panel="Fleets of logs", show_default=False)]
_WorkersOpt = Annotated[int | None, typer.Option(
    "--workers", "-w", metavar="N",
    help="--out-dir: Dask worker processes of a local cluster (default: one per log, at most "
         "one per CPU); 1 maps in this process, without Dask.",
    rich_help_panel="Fleets of logs", show_default=False)]
_SchedulerOpt = Annotated[str | None, typer.Option(
    "--scheduler", metavar="ADDRESS",
    help="--out-dir: map on an existing Dask cluster, its scheduler's address, e.g. "
         "tcp://HOST:8786 (default $DASK_SCHEDULER_ADDRESS); the logs and FOLDER must be on "
         "storage every worker sees.", rich_help_panel="Fleets of logs", show_default=False)]
#: Cell side of the carved grid a bag output carries as /sonarcarve/grid, metres.
_DEFAULT_BAG_GRID = 0.10
_GridResolutionOpt = Annotated[float | None, typer.Option(
    metavar="METRES",
    help=f"Bag output: the side of the cells of the carved grid published as /sonarcarve/grid "
         f"(nav_msgs/OccupancyGrid) with every local map; 0: no grid [default: "
         f"{_DEFAULT_BAG_GRID:g}].", show_default=False)]
_MapRateOpt = Annotated[float | None, typer.Option(
    metavar="PER_SECOND",
    help=f"Bag output: local maps (and arc markers) per second of log time [default: "
         f"{_DEFAULT_MAP_RATE:g}].", show_default=False)]
_MaxRangeOpt = Annotated[float | None, typer.Option(
    metavar="METRES", show_default="off",
    help=f"{MAX_RANGE_HELP} No-echo rows that give a max_range keep theirs. The paper "
         f"used 150 in = {PAPER_MAX_RANGE:.2f} m on its robot; pick yours from your sensors' "
         "height and floor.", rich_help_panel="Filters")]
_MinRangeOpt = Annotated[float | None, typer.Option(
    metavar="METRES", show_default="off",
    help="Drop readings nearer than this, metres (reading filter).",
    rich_help_panel="Filters")]
_JumpOpt = Annotated[float | None, typer.Option(
    metavar="METRES", show_default="off",
    help="Drop a reading whose range differs by more than this (metres) from the same "
         "sensor's previous reading: a jumping sensor is ignored for one reading.",
    rich_help_panel="Filters")]
_OutlierRadiusOpt = Annotated[float | None, typer.Option(
    metavar="METRES", show_default="off",
    help="Map filter: drop points with fewer than --outlier-neighbours other points within "
         "this radius, metres.", rich_help_panel="Filters")]
_NeighboursOpt = Annotated[int, typer.Option(
    metavar="POINTS",
    help="k of the outlier test (needs --outlier-radius).", rich_help_panel="Filters")]
_MaxErrorOpt = Annotated[float | None, typer.Option(
    metavar="METRES", show_default="off",
    help="Map filter: drop points whose error bound max_error exceeds this, metres "
         "(paper, Fig. 13b).", rich_help_panel="Filters")]
_OcclusionOpt = Annotated[float | None, typer.Option(
    metavar="METRES", show_default="off",
    help="Map filter: drop points lying more than this far behind a surface of the finished "
         "map, on the line from the sensor that heard them (multipath echoes: the sound "
         "glanced off a wall and read too long). Only points whose error bound is at most half "
         "of it make up surfaces. 0.5 is a good start with carve, combined or evidence; not "
         "for centerline maps. docs/RESULTS.md, \"Points behind a surface of the map\".",
    rich_help_panel="Filters")]
_LateEchoOpt = Annotated[str | None, typer.Option(
    "--late-echo-period", metavar="SECONDS|ROBOT", show_default="off",
    help="Map filter: drop points that are late echoes: the echo of one of the previous two "
         "firings off a far wall of the map, read c·Δt/2 short. They form ghost walls when "
         "a sensor fires faster than the round trip of its hearing range (62 ms for a "
         "Polaroid hearing 10.7 m). Give the time between consecutive firings of your "
         "robot's sensors in seconds, or a robot (a built-in name or a robot YAML: its "
         "firing_period). It caught 69 % of a lone sonar's ghosts and 43 % of a car's (86 % "
         "and 69 % with --driven-through), for about 0.1 % of direct echoes or less where "
         "late echoes exist (0.02-0.7 % where none do, so it is off by default); "
         "docs/RESULTS.md, \"Both ghost filters together\". It runs before every other map "
         "filter.",
    rich_help_panel="Filters")]
_DrivenOpt = Annotated[str | None, typer.Option(
    "--driven-through", metavar="ROBOT|METRES", show_default="off",
    help="Map filter: drop points that the robot's body covered later in the log: no static "
         "obstacle stands where the robot has since driven. It removes ghost walls (a sonar "
         "fired faster than its hearing range hears the previous ping's far echo, every time, "
         "a few metres in front of the real wall it then drives towards), floor echoes, and "
         "whatever has moved away. ROBOT (a built-in name such as scout2 or car-parking-12, or "
         "a robot YAML) gives the body: its sensor mounts and robot_radius (best: it caught "
         "83 % of a lone sonar's ghosts and 48 % of a car's); METRES, without a robot "
         "description, a disc of that radius around each sensor's origin (0.05, a "
         "transducer's size; it catches fewer, 58 % and 8 %). The map is then the current "
         "one: whatever the robot later drove over is dropped, a person or a shut door too; "
         "under odometry drift a revisit can drop a wall (docs/RESULTS.md, \"The body drove "
         "through it\").",
    rich_help_panel="Filters")]


@app.command()
def process(
    inputs: _InputsArg,
    out: _OutOpt = None,
    out_dir: _OutDirOpt = None,
    method: MethodOpt = "combined",
    history: HistoryOpt = DEFAULT_HISTORY_SIZE,
    beam_width: BeamWidthOpt = DEFAULT_BEAM_WIDTH_DEG,
    range_tolerance: ToleranceOpt = DEFAULT_RANGE_TOLERANCE,
    min_transversal: TransversalOpt = DEFAULT_TRANSVERSAL_DEG,
    max_incidence: IncidenceOpt = None,
    min_confidence: MinConfidenceOpt = None,
    stamp_error: StampErrorOpt = 0.0,
    stamp_heading_error: StampHeadingOpt = 0.0,
    max_range: _MaxRangeOpt = None,
    min_range: _MinRangeOpt = None,
    jump_threshold: _JumpOpt = None,
    outlier_radius: _OutlierRadiusOpt = None,
    outlier_neighbours: _NeighboursOpt = 1,
    max_error: _MaxErrorOpt = None,
    occlusion_depth: _OcclusionOpt = None,
    driven_through: _DrivenOpt = None,
    late_echo_period: _LateEchoOpt = None,
    map_rate: _MapRateOpt = None,
    grid_resolution: _GridResolutionOpt = None,
    robot: RobotOpt = None,
    range_topic: RangeTopicOpt = None,
    odom_topic: OdomTopicOpt = None,
    frame: FrameOpt = None,
    no_echo: NoEchoOpt = False,
    workers: _WorkersOpt = None,
    scheduler: _SchedulerOpt = None,
) -> int:
    """Map a readings CSV or a ROS bag with one method and write its global map to --out.

    INPUT is a readings CSV or a ROS bag (file or rosbag2 folder); the ending of --out picks
    the output: `.csv` the global map, `.mcap` / `.bag` / a folder name a ROS bag for Foxglove
    or RViz, `.rrd` a Rerun recording. A readings CSV mapped to a CSV is streamed in blocks;
    a bag input or a bag or `.rrd` output holds the whole log in memory. With --out-dir,
    every INPUT is mapped in parallel to FOLDER/NAME.map.csv with a summary (summary.csv);
    the exit code is then 2 if any log failed, 0 if all were mapped.

    The map CSV has one row per surviving reading:
    `id,t,sensor,x,y,source,width,max_error,confidence` (`source` is the model that placed the
    point: centerline, carved or atm; `width` the final angular width in radians; `max_error`
    the error bound in metres; `confidence` the probability that the point is a real surface,
    given by `--method evidence` and empty for the other methods).

    A run that succeeds on probably wrong units (theta in degrees, ranges in centimetres or
    millimetres, --beam-width in radians) prints one `sonarcarve: warning:` line for each on
    stderr; the exit code is still 0.

    Filters are off unless asked for: reading filters (--max-range, --min-range,
    --jump-threshold) drop readings before mapping, keeping the ids of the others as their input
    rows; map filters (--late-echo-period, --max-error, --driven-through, --occlusion-depth,
    then --outlier-radius) drop points from the global map. With a bag or .rrd output only
    --max-range applies (a recording shows the live maps of the readings as they came).
    Without map filters a map CSV is written as it is made (memory stays flat however long the
    log); map filters need the whole map, so with them it is held in memory until the end.

    The summary's "unprocessed (mean % of history rows)" is the paper's Table I latency: the
    share of the history's arcs that no newer reading has sharpened yet, averaged over samples
    taken every tenth of the history (25 readings) for the first 1,000 samples, then every
    1,009 readings (a tenth of the history rounded up to a prime, for histories over 10,090
    arcs), each weighted by its step.
    Arcs carving removed (fully carved or split) count as processed; the paper's history drops
    them instead, which gives a larger share for carving (docs/RESULTS.md reports both).

    Example: `sonarcarve process readings.csv --method carve --out map.csv`

    Example: `sonarcarve process readings.csv --max-range 3.81 --max-error 0.1 --out map.csv`

    Example: `sonarcarve process readings.csv --method evidence --occlusion-depth 0.5 --out
    map.csv` (evidence carving, then multipath points behind walls dropped)

    Example: `sonarcarve process readings.csv --method evidence --driven-through scout2 --out
    map.csv` (evidence carving, then points the Scout2's body later drove over dropped)

    Example: `sonarcarve process readings.csv --method evidence --late-echo-period 0.04
    --driven-through scout2 --out map.csv` (and, first, late echoes of a ring firing every
    40 ms dropped)

    Example: `sonarcarve process run.mcap --out run-map.mcap` (then open run-map.mcap in
    Foxglove)

    Example: `sonarcarve process run.mcap --method evidence --no-echo --out map.csv` (the
    bag's silent firings weighed as looks through their beams: more spurious echoes removed)

    Example: `sonarcarve process logs/*.csv logs/*.bag --out-dir maps --workers 4`
    """
    check_method(method)  # an unknown method fails before any file is touched
    config = method_config(history, beam_width, range_tolerance, min_transversal, max_incidence,
                           method=method,
                           certainty=PointCertainty(min_confidence, stamp_error,
                                                    stamp_heading_error))
    reading_filter, map_filter = _filters(max_range, min_range, jump_threshold, outlier_radius,
                                          outlier_neighbours, max_error, occlusion_depth,
                                          driven_through, late_echo_period)
    make_method(method, config)  # and so does a config the method refuses
    beam_warning = beam_width_mistake(beam_width, "--beam-width")
    bag = bag_options(robot, range_topic, odom_topic, frame, no_echo=no_echo)
    if out_dir is not None:
        _check_fleet_options(out, map_rate)
        code = _fleet(inputs, out_dir, method, config, reading_filter, map_filter, bag,
                      workers, scheduler)
        if code == 0:  # every log checked, as a single log is: a killed logger is likeliest here
            warn([beam_warning, *(cut_short(log) for log in inputs if not is_bag(log))])
        return code
    if out is None:
        msg = "missing option '--out' (or --out-dir FOLDER for one map per log)"
        raise ParameterError(msg)
    source = _single_input(inputs, workers, scheduler)
    output = _output_kind(out)
    refuse_bag_options(source, bag)
    if output.label != "csv" and _filters_beyond_max_range(reading_filter, map_filter):
        # A bag or a recording shows the live maps of every reading as it came; --max-range
        # alone is also the readings' own contract (how far a no-echo row listened), so it
        # applies to every output.
        msg = (f"--out {out}: the filters (--min-range, --jump-threshold, --max-error, "
               "--late-echo-period, --driven-through, --occlusion-depth, --outlier-radius) "
               "apply to a map CSV output only; --max-range applies to every output")
        raise ParameterError(msg)
    if map_rate is not None and output.label != "bag":
        msg = f"--map-rate applies to a bag output only, not to --out {out}"
        raise ParameterError(msg)
    rate = _DEFAULT_MAP_RATE if map_rate is None else map_rate
    cell = _bag_grid_resolution(grid_resolution, output.label, out)
    if not (math.isfinite(rate) and rate > 0.0):
        msg = f"--map-rate must be a number > 0 (local maps per second), got {rate}"
        raise ParameterError(msg)
    job = _Job(source, out, method, config, reading_filter, map_filter, bag, rate, cell)
    output.check(job)  # before the (possibly long) run: a bad --out wastes no time
    with max_range_hint():  # a no-echo row without max_range: say how to give one
        rows = output.write(job)
    # Only now: a failed run prints its error line alone.
    warn([beam_warning, *job.warnings, None if is_bag(source) else cut_short(source)])
    console.print(summary_table(f"sonarcarve process --method {method}", rows))
    return 0


def _filters_beyond_max_range(reading_filter: ReadingFilter | None,
                              map_filter: MapFilter | None) -> bool:
    """Whether any filter other than ``--max-range`` was asked for."""
    if map_filter is not None:
        return True
    return reading_filter is not None and reading_filter != ReadingFilter(
        max_range=reading_filter.max_range)


def _first_checked(chunks: Iterable[ReadingBatch], found: list[str]) -> Iterator[ReadingBatch]:
    """``chunks`` unchanged; the likely mistakes of the first (about 15,000 readings, enough
    to see a unit) added to ``found``, so that a streamed log costs no extra pass."""
    first = True
    for batch in chunks:
        if first:
            found.extend(likely_mistakes(batch))
            first = False
        yield batch


def _bag_grid_resolution(given: float | None, output: str, out: Path) -> float:
    """The carved grid's cell side for a bag output (0: none); refused for other outputs."""
    if given is None:
        return _DEFAULT_BAG_GRID if output == "bag" else 0.0
    if output != "bag":
        msg = f"--grid-resolution applies to a bag output only, not to --out {out}"
        raise ParameterError(msg)
    if not (math.isfinite(given) and given >= 0.0):
        msg = f"--grid-resolution must be a number >= 0 (metres; 0: no grid), got {given}"
        raise ParameterError(msg)
    return given


def _single_input(inputs: Sequence[Path], workers: int | None, scheduler: str | None) -> Path:
    """The one INPUT of a ``--out`` run; the fleet options refused."""
    if len(inputs) != 1:
        msg = (f"--out takes one INPUT, got {len(inputs)}; map several logs with "
               "--out-dir FOLDER")
        raise ParameterError(msg)
    if workers is not None or scheduler is not None:
        msg = "--workers and --scheduler apply to --out-dir (a fleet of logs) only"
        raise ParameterError(msg)
    return inputs[0]


def _check_fleet_options(out: Path | None, map_rate: float | None) -> None:
    if out is not None:
        msg = "give either --out (one log) or --out-dir (one map per log), not both"
        raise ParameterError(msg)
    if map_rate is not None:
        msg = "--map-rate applies to a bag output (--out NAME.mcap) only, not to --out-dir"
        raise ParameterError(msg)


def _output_kind(out: Path) -> Output:
    """The entry of :data:`OUTPUTS` for the ending of ``out``; a one-line error naming the
    endings for any other."""
    output = OUTPUTS.get(out.suffix.lower())
    if output is None:
        msg = (f"--out {out}: unknown ending {out.suffix!r}; use .csv (map), .mcap or .bag or "
               "no ending (ROS bag), or .rrd (Rerun recording)")
        raise ParameterError(msg)
    return output


def _check_file(job: _Job) -> None:
    check_output_file(job.out, inputs=[job.source], label=f"--out {job.out}")


def _check_bag(job: _Job) -> None:
    check_new_bag(job.out, inputs=[job.source], label=f"--out {job.out}")


def _write_csv(job: _Job) -> list[tuple[str, str]]:
    """The global map CSV. A readings CSV is read, checked and mapped a block at a time.

    Without map filters the map streams to a temporary file beside ``--out`` as arcs leave the
    history (memory stays flat however long the log) and is renamed into place at the end; with
    them (they need the whole map) it is kept in memory and written at the end. Either way a bad
    line stops the run with nothing written."""
    if job.map_filter is not None:
        result = _map(job, None)
        write_map_csv(result.global_map, job.out)
    else:
        with map_csv_sink(job.out) as sink:
            result = _map(job, sink)
    rows = _summary_rows(result, job.out, job.method)
    return rows[:1] + job.input_rows + rows[1:]


def _map(job: _Job, sink: MapCsvSink | None) -> ProcessResult:
    """Run the job's method over its input, the map to ``sink`` (None: kept in the result)."""
    sonar = job.sonar()
    if is_bag(job.source):
        batch = job.bag.readings(job.read_bag_log())
        job.warnings.extend(likely_mistakes(batch))
        return process_readings(batch, sonar, reading_filter=job.reading_filter,
                                map_filter=job.map_filter, sink=sink)
    return _run(job.source, sonar, job.method, job.reading_filter, job.map_filter,
                job.warnings, sink)


def _write_bag(job: _Job) -> list[tuple[str, str]]:
    """A ROS bag: the input bag's messages copied through, the live local map and arcs."""
    from sonarcarve.io.bag_out import ARCS_TOPIC, GRID_TOPIC, LOCAL_MAP_TOPIC, write_map_bag

    if is_bag(job.source):
        log = job.read_bag_log()
        batch, (parent, child) = job.bag.readings(log), log.report.odometry_frames
        copy_from: Path | None = job.source
    else:
        batch = read_readings_csv(job.source, max_range=job.max_range)
        parent, child, copy_from = "", "", None
    batch, ids, too_far = drop_far_echoes(batch, job.max_range)
    job.warnings.extend(likely_mistakes(batch))
    grid = None if job.grid_resolution == 0.0 or len(batch) == 0 else _bag_grid(job, batch)
    with readings_progress(job.method, len(batch)) as on_progress:
        report = write_map_bag(job.out, batch, job.sonar(), copy_from=copy_from,
                               frame=parent or "odom", base_frame=child or "base_link",
                               rate=job.map_rate, grid=grid, ids=ids, on_progress=on_progress)
    ours = (LOCAL_MAP_TOPIC, ARCS_TOPIC, GRID_TOPIC)
    copied = sum(n for topic, n in report.messages.items() if topic not in ours)
    return [("readings in", f"{len(batch) + too_far:,}"), *job.input_rows,
            *_dropped_far_row(job, too_far),
            ("messages copied from the input", f"{copied:,}"),
            *((f"messages on {topic}", f"{report.messages.get(topic, 0):,}") for topic in ours),
            ("bag written to", f"{report.path} ({report.format.value})")]


def _bag_grid(job: _Job, batch: ReadingBatch) -> CarvedGrid:
    """The carved grid a bag output publishes: ``--grid-resolution`` cells over the readings
    plus 0.5 m, carving with the run's ``--range-tolerance`` as ``grid --range-tolerance``
    does (the grid's own method, specular-aware, is otherwise its default)."""
    from sonarcarve.grids import CarvedGrid, CarvedGridParams, readings_extent

    params = CarvedGridParams(range_tolerance=job.config.range_tolerance)
    return CarvedGrid(job.grid_resolution, readings_extent(batch, margin=0.5), params=params)


def _write_rrd(job: _Job) -> list[tuple[str, str]]:
    """A Rerun recording of the run (no walls: a log has no ground truth)."""
    from sonarcarve.io.rerun_out import write_rerun

    batch, ids, too_far = drop_far_echoes(_read_whole(job), job.max_range)
    job.warnings.extend(likely_mistakes(batch))
    with readings_progress(job.method, len(batch)) as on_progress:
        global_map = write_rerun(job.out, batch, job.sonar(), ids=ids, on_progress=on_progress)
    return [("readings in", f"{len(batch) + too_far:,}"), *job.input_rows,
            *_dropped_far_row(job, too_far),
            ("points out", f"{len(global_map):,}"), ("recording written to", str(job.out))]


def _dropped_far_row(job: _Job, too_far: int) -> list[tuple[str, str]]:
    """The summary's row of echoes ``--max-range`` dropped (none without the option)."""
    if job.max_range is None:
        return []
    return [("dropped: echoes beyond --max-range", f"{too_far:,}")]


def _read_whole(job: _Job) -> ReadingBatch:
    if is_bag(job.source):
        return job.bag.readings(job.read_bag_log())
    return read_readings_csv(job.source, max_range=job.max_range)


#: Ending of ``--out`` (lower case; "" a rosbag2 folder) -> what is written there.
OUTPUTS: dict[str, Output] = {
    ".csv": Output("csv", _check_file, _write_csv),
    ".mcap": Output("bag", _check_bag, _write_bag),
    ".bag": Output("bag", _check_bag, _write_bag),
    "": Output("bag", _check_bag, _write_bag),
    ".rrd": Output("rrd", _check_file, _write_rrd),
}


def _fleet(inputs: Sequence[Path], out_dir: Path, method: str, config: MethodConfig,
           reading_filter: ReadingFilter | None, map_filter: MapFilter | None,
           bag: BagOptions, workers: int | None, scheduler: str | None) -> int:
    """Map every log into ``out_dir`` on the runner; print the summary; the exit code."""
    from rich.progress import TaskID

    from sonarcarve.fleet import map_logs
    from sonarcarve.io.errors import OutputError
    from sonarcarve.runner import RunnerError, RunnerSpec, open_runner

    count = workers if workers is not None else max(1, min(len(inputs), os.cpu_count() or 1))
    with reworded(RunnerError, RUNNER_FLAGS):
        spec = RunnerSpec.from_env(count, scheduler)
        runner = open_runner(spec)
    with runner, progress(label_width=8, elapsed=True) as bar:
        tasks: dict[str, TaskID] = {}

        def on_progress(stage: str, done: int, total: int) -> None:
            if stage not in tasks:
                tasks[stage] = bar.add_task(stage, total=total)
            bar.update(tasks[stage], completed=done, total=total)

        with reworded(OutputError, RUNNER_FLAGS):  # out_dir that cannot be made
            rows = map_logs(inputs, out_dir, method, config, runner=runner,
                            reading_filter=reading_filter, map_filter=map_filter, bag=bag,
                            on_progress=on_progress)
    console.print(_fleet_table(method, rows, spec))
    failed = sum(not row.ok for row in rows)
    console.print(f"summary written to {Path(out_dir) / SUMMARY_NAME}", highlight=False)
    dropped = [row.no_echo_dropped for row in rows if row.no_echo_dropped]
    if dropped:  # as a single log's summary says it (no_echo_dropped_row), once for them all
        console.print(f"dropped: {sum(dropped):,} no-echo readings of {len(dropped)} bag"
                      f"{'s' if len(dropped) > 1 else ''} (--no-echo maps them as free space; "
                      "per log in the summary's no_echo_dropped)", highlight=False)
    if failed:
        err_console.print(f"sonarcarve: error: {failed} of {len(rows)} logs failed; the "
                          "summary gives each one's reason", highlight=False, soft_wrap=True)
        return EXIT_SOME_LOGS_FAILED
    return 0


def _fleet_table(method: str, rows: Sequence[FleetRow], spec: RunnerSpec) -> Table:
    """One line per log: its counts and map, or its error (summary.csv has every column)."""
    from rich.table import Table
    from rich.text import Text

    ok = sum(row.ok for row in rows)
    table = Table(title=f"sonarcarve process --method {method}: {ok} of {len(rows)} logs "
                        f"mapped on {spec.describe()}")
    table.add_column("log", overflow="fold")
    for name in ("readings", "points", "seconds"):
        table.add_column(name, justify="right")
    table.add_column("map, or why not", overflow="fold")
    for row in rows:
        if row.ok:
            table.add_row(row.log, f"{row.readings:,}", f"{row.points:,}", f"{row.seconds:.2f}",
                          Path(row.map).name)
        else:
            table.add_row(row.log, "", "", "", Text(row.error, style="red"))
    return table


def _run(readings: Path, sonar: SonarMethod, label: str,
         reading_filter: ReadingFilter | None, map_filter: MapFilter | None,
         warnings: list[str], sink: MapCsvSink | None = None) -> ProcessResult:
    """Map the file ``readings`` with ``sonar`` (the map to ``sink``, if given), with a
    progress bar for long logs; the likely mistakes of its first block added to ``warnings``."""
    max_range = None if reading_filter is None else reading_filter.max_range
    chunks = _first_checked(iter_readings_csv(readings, max_range=max_range), warnings)
    rows = count_data_lines(readings)  # the bar's total, from the line breaks alone
    if rows < _PROGRESS_MIN_READINGS:
        result = process_chunks(chunks, sonar, reading_filter=reading_filter,
                                map_filter=map_filter, sink=sink)
    else:
        with progress() as bar:
            task = bar.add_task(label, total=rows)
            result = process_chunks(chunks, sonar,
                                    on_progress=lambda n: bar.update(task, completed=n),
                                    reading_filter=reading_filter, map_filter=map_filter,
                                    sink=sink)
    if result.readings == 0:  # a valid file (a header only), so not an error: say so
        warnings.append(f"{readings} has no readings, only a header: the map is empty")
    return result


def _filters(max_range: float | None, min_range: float | None, jump: float | None,
             radius: float | None, neighbours: int, max_error: float | None,
             occlusion_depth: float | None = None, driven_through: str | None = None,
             late_echo_period: str | None = None,
             ) -> tuple[ReadingFilter | None, MapFilter | None]:
    check_max_range(max_range)  # also what a readings CSV accepts as a row's max_range
    for name, value in (("--max-range", max_range), ("--min-range", min_range),
                        ("--jump-threshold", jump), ("--outlier-radius", radius),
                        ("--max-error", max_error), ("--occlusion-depth", occlusion_depth)):
        if value is not None and not (math.isfinite(value) and value > 0.0):
            msg = f"{name} must be a finite number > 0 (metres), got {value}"
            raise ParameterError(msg)
    if max_range is not None and min_range is not None and min_range > max_range:
        msg = f"--min-range ({min_range}) exceeds --max-range ({max_range})"
        raise ParameterError(msg)
    if neighbours < 1:
        msg = f"--outlier-neighbours must be at least 1, got {neighbours}"
        raise ParameterError(msg)
    if neighbours != 1 and radius is None:
        msg = "--outlier-neighbours needs --outlier-radius"
        raise ParameterError(msg)
    readings = ReadingFilter(max_range=max_range, min_range=min_range, jump_threshold=jump)
    points = MapFilter(max_error=max_error, outlier_radius=radius, outlier_neighbours=neighbours,
                       occlusion_depth=occlusion_depth, driven_through=_body(driven_through),
                       late_echo_period=_firing_period(late_echo_period))
    return (readings if readings.active else None), (points if points.active else None)


def _firing_period(spec: str | None) -> float | None:
    """``--late-echo-period``'s seconds: given, or a robot's ``firing_period``."""
    if spec is None:
        return None
    try:
        period = float(spec)
    except ValueError:
        if _looks_like_seconds(spec):
            msg = f"--late-echo-period takes plain seconds (0.04) or a robot, got {spec!r}"
            raise ParameterError(msg) from None
        if spec.strip():
            return load_robot(spec).firing_period  # a name or a YAML; its one-line RobotError
        period = math.nan  # empty (load_robot would read the folder "."): refused below
    low, high = FIRING_PERIOD_RANGE  # what a robot file accepts
    if not (math.isfinite(period) and low <= period <= high):
        msg = (f"--late-echo-period must be a robot (name or YAML) or a firing period in "
               f"{low:g}..{high:g} (seconds), got {spec!r}")
        raise ParameterError(msg)
    return period


def _looks_like_seconds(spec: str) -> bool:
    """``0.04s``, ``40ms``: a number with a unit, not a robot's name."""
    number = spec.strip().lower().removesuffix("ms").removesuffix("s").strip()
    try:
        float(number)
    except ValueError:
        return False
    return True


def _body(spec: str | None) -> BodyFootprint | None:
    """``--driven-through``'s body: a disc of METRES around each sensor, or a robot's."""
    if spec is None:
        return None
    try:
        radius = float(spec)
    except ValueError:
        if not spec.strip():
            radius = math.nan  # empty (load_robot would read the folder "."): refused below
        else:
            robot = load_robot(spec)  # a name or a YAML; its one-line RobotError otherwise
            return BodyFootprint.of_robot(robot.mount_x, robot.mount_y, robot.bearing,
                                          robot.robot_radius)
    if not (math.isfinite(radius) and radius > 0.0):
        msg = (f"--driven-through must be a robot (name or YAML) or a clearance radius > 0 "
               f"(metres), got {spec!r}")
        raise ParameterError(msg)
    return BodyFootprint.around_sensors(radius)


def _removed_rows(result: ProcessResult, method: str) -> list[tuple[str, str]]:
    """The summary's count of arcs the method removed. Evidence carving keeps a piece of a
    split arc and also removes points below --min-confidence (EvidenceMethod.measures counts
    both), so its row says so instead of the paper's two."""
    if method == "evidence":
        return [("removed (carved, low confidence)", f"{result.fully_carved:,}")]
    return [("fully carved", f"{result.fully_carved:,}"),
            ("split (dropped)", f"{result.split:,}")]


def _summary_rows(result: ProcessResult, out: Path, method: str) -> list[tuple[str, str]]:
    rows: list[tuple[str, str]] = []
    dropped = result.reading_filter
    if dropped is None:
        rows.append(("readings in", f"{result.readings:,}"))
    else:
        rows += [("readings in", f"{dropped.total:,}"),
                 ("dropped: echoes beyond --max-range", f"{dropped.too_far:,}"),
                 ("dropped: below --min-range", f"{dropped.too_near:,}"),
                 ("dropped: --jump-threshold", f"{dropped.jumps:,}"),
                 ("readings mapped", f"{result.readings:,}")]
    points = result.map_filter
    if points is not None:
        rows += [("points before map filters", f"{points.total:,}"),
                 ("dropped: late echoes", f"{points.late_echoes:,}"),
                 ("dropped: above --max-error", f"{points.max_error:,}"),
                 ("dropped: driven through", f"{points.driven_through:,}"),
                 ("dropped: behind a surface", f"{points.occluded:,}"),
                 ("dropped: outliers", f"{points.outliers:,}")]
    rows += [("points out", f"{result.points:,}"), *_removed_rows(result, method),
             # Removed arcs count as processed: see the command's help.
             ("unprocessed (mean % of history rows)",
              f"{100 * result.mean_unprocessed_share:.1f}"),
             ("readings per second", f"{result.readings_per_second:,.0f}"),
             ("map written to", str(out))]
    return rows
