"""Fleets of logs: map many readings CSVs (or ROS bags) in parallel, one map per log.

:func:`read_log` reads one log whole, a readings CSV or a ROS bag (:func:`is_bag` tells them
apart; :class:`BagOptions` says how to read a bag, as ``sonarcarve convert rosbag`` does).

:func:`map_logs` sends one task per log to a :class:`~sonarcarve.runner.Runner` (this
process, a local Dask cluster or a scheduler's); each task reads its log, maps it with one method
(as ``sonarcarve process`` does) and writes ``OUT_DIR/<log name>.map.csv`` atomically. A log that
fails (unreadable, bad values, a crash of its worker) gets its one-line error in the summary
and does not stop the others. The summary (:class:`FleetRow` per log, in the order given) is
written to ``OUT_DIR/summary.csv``.

Mapping a log is a pure function of the log's content and the parameters, so the maps are the
same bytes whatever runs them. The task reads and writes the files itself: on a cluster the
logs and ``OUT_DIR`` must be on storage every worker sees (a shared file system).
"""

from __future__ import annotations

import csv
import io
import time
from collections.abc import Sequence
from dataclasses import astuple, dataclass, fields
from pathlib import Path

from sonarcarve.errors import SonarcarveError
from sonarcarve.filters import MapFilter, ReadingFilter
from sonarcarve.io import read_readings_csv, read_rosbag, write_map_csv
from sonarcarve.io.atomic import atomic_text, make_output_dir
from sonarcarve.io.rosbag import RosbagLog
from sonarcarve.methods import MethodConfig, make_method
from sonarcarve.pipeline import process_readings
from sonarcarve.readings import NO_MAX_RANGE, ReadingBatch
from sonarcarve.robot import load_robot
from sonarcarve.runner import ProgressCallback, Runner, SerialRunner, Task, TaskFailure

__all__ = [
    "BAG_SUFFIXES",
    "SUMMARY_NAME",
    "BagOptions",
    "FleetError",
    "FleetRow",
    "is_bag",
    "map_log",
    "map_logs",
    "map_name",
    "read_log",
    "write_summary",
]

#: File name of the summary table in the output folder.
SUMMARY_NAME = "summary.csv"

#: Endings of ROS bag files (a rosbag2 folder is recognised as a folder).
BAG_SUFFIXES = (".bag", ".mcap", ".db3")


def is_bag(path: str | Path) -> bool:
    """True when ``path`` names a ROS bag: a folder (rosbag2) or a ``*.bag``, ``*.mcap`` or
    ``*.db3`` file; anything else is read as a readings CSV.

    >>> is_bag("run.mcap"), is_bag("run.BAG"), is_bag("readings.csv")
    (True, True, False)
    """
    target = Path(path)
    return target.suffix.lower() in BAG_SUFFIXES or target.is_dir()


@dataclass(frozen=True)
class BagOptions:
    """How to read a ROS bag log: the options of ``sonarcarve convert rosbag``.

    Plain values only (a robot by name or file, not a loaded description), so that a task
    carrying them pickles to any worker.

    Attributes
    ----------
    robot : str or None
        Fallback sensor mounts: a built-in robot name or a robot YAML file
        (:func:`~sonarcarve.robot.load_robot`).
    range_topics : tuple of str
        Range topics in sensor order (empty: every Range topic, natural-sorted).
    odom_topic : str or None
        Odometry topic (None: the only one, else TF).
    frame : str or None
        The robot's base frame (None: the odometry's child frame, else base_link).
    beam_width : float or None
        φ in radians for messages without a ``field_of_view`` (None: the method's).
    no_echo : bool
        Keep the bag's no-echo readings (REP 117 +Inf, or a range at max_range: nothing heard
        up to max_range) as free-space readings (:meth:`RosbagLog.with_no_echo`); their rows
        then count in the reading ids.
    """

    robot: str | None = None
    range_topics: tuple[str, ...] = ()
    odom_topic: str | None = None
    frame: str | None = None
    beam_width: float | None = None
    no_echo: bool = False

    @property
    def given(self) -> bool:
        """True when any option differs from its default (a CSV log can use none of them)."""
        return self != BagOptions()

    def read(self, path: str | Path) -> RosbagLog:
        """Read the bag ``path`` with these options
        (:func:`~sonarcarve.io.rosbag.read_rosbag`; its errors are one line)."""
        robot = load_robot(self.robot) if self.robot is not None else None
        return read_rosbag(path, robot=robot, range_topics=list(self.range_topics) or None,
                           odom_topic=self.odom_topic, base_frame=self.frame,
                           beam_width=self.beam_width)

    def readings(self, log: RosbagLog) -> ReadingBatch:
        """The readings of a bag read with these options: the echoes, and with
        :attr:`no_echo` the no-echo readings merged in time order."""
        return log.with_no_echo() if self.no_echo else log.batch

    def dropped_no_echo(self, log: RosbagLog) -> int:
        """How many of the log's no-echo readings :meth:`readings` leaves out: all of them
        without :attr:`no_echo`, else none."""
        return 0 if self.no_echo else len(log.no_echo)


def read_log(path: str | Path, bag: BagOptions | None = None, *,
             max_range: float | None = None) -> ReadingBatch:
    """The readings of one log, whole: a ROS bag (:func:`is_bag`, read with ``bag``) or a
    readings CSV (``bag`` unused; ``max_range``, metres, the run-wide max range of its no-echo
    rows that give none, as for :func:`~sonarcarve.io.readings_csv.iter_readings_csv`).

    Raises
    ------
    ReadingsError, RosbagError, RobotError
        A log (or robot file) that cannot be read: one line naming it.
    """
    return _read_log_counted(path, bag, max_range)[0]


def _read_log_counted(path: str | Path, bag: BagOptions | None,
                      max_range: float | None) -> tuple[ReadingBatch, int]:
    """:func:`read_log`, and how many of a bag's no-echo readings it left out."""
    if is_bag(path):
        options = bag if bag is not None else BagOptions()
        log = options.read(path)
        return options.readings(log), options.dropped_no_echo(log)
    return read_readings_csv(path, max_range=max_range), 0


class FleetError(SonarcarveError):
    """A fleet request that cannot start: no logs, or two logs with one output name."""


@dataclass(frozen=True)
class FleetRow:
    """One log's line of the summary.

    Attributes
    ----------
    log : str
        The input path, as given.
    map : str
        The map written (empty when the log failed).
    readings : int
        Readings mapped.
    points : int
        Points in the global map.
    fully_carved, split : int
        Arcs fully carved, and split (dropped). For evidence carving, ``fully_carved`` counts
        every arc it removed (carved, or below ``min_confidence``) and ``split`` is 0, as
        ``sonarcarve process`` says for one log ("removed (carved, low confidence)").
    unprocessed : float
        Mean share of unprocessed history rows, percent (the paper's Table I measure).
    seconds : float
        The method's wall time on the log (not part of the result's identity).
    error : str
        Empty, or the one-line reason the log has no map.
    readings_filtered, points_filtered : int
        Readings the reading filters dropped before the method, and points the map filters
        dropped from its map (0 when none ran; after ``error``, so the older columns keep
        their places).
    no_echo_dropped : int
        A bag's no-echo readings left out of the mapping (all of them without
        ``BagOptions.no_echo``, else 0; 0 for a readings CSV, whose no-echo rows are always
        mapped), as ``sonarcarve process`` reports for one log; the last column.
    """

    log: str
    map: str = ""
    readings: int = 0
    points: int = 0
    fully_carved: int = 0
    split: int = 0
    unprocessed: float = 0.0
    seconds: float = 0.0
    error: str = ""
    readings_filtered: int = 0
    points_filtered: int = 0
    no_echo_dropped: int = 0

    @property
    def ok(self) -> bool:
        """True when the log was mapped."""
        return not self.error


def map_name(log: str | Path) -> str:
    """The map's file name for ``log``: its name without the ending, plus ``.map.csv``.

    Examples
    --------
    >>> map_name("/data/robot-7/2024-05-01.csv")
    '2024-05-01.map.csv'
    >>> map_name("run.bag")
    'run.map.csv'
    """
    path = Path(log)
    return f"{path.stem if path.suffix else path.name}.map.csv"


def map_log(log: str, out: str, method: str, config: MethodConfig,
            reading_filter: ReadingFilter | None = None,
            map_filter: MapFilter | None = None,
            bag: BagOptions | None = None) -> FleetRow:
    """Map one log and write its global map to ``out``; never raises for a bad log.

    Parameters
    ----------
    log : str
        A readings CSV, or a ROS bag (``*.bag``, ``*.mcap``, a rosbag2 folder).
    out : str
        Where to write the map CSV (atomically: a failed log leaves nothing behind).
    method : str
        Method name (``combined``, ``carve``, ``atm``, ``centerline``, ...).
    config : MethodConfig
        The method's parameters.
    reading_filter, map_filter : optional
        As for :func:`~sonarcarve.pipeline.process_readings`.
    bag : BagOptions, optional
        How to read a bag log (:func:`read_log`).

    Returns
    -------
    FleetRow
        The log's summary line; ``error`` holds the reason when it failed.
    """
    try:
        # The max-range filter's value is also the run-wide max range of no-echo rows.
        max_range = None if reading_filter is None else reading_filter.max_range
        batch, no_echo_dropped = _read_log_counted(log, bag, max_range)
        tic = time.perf_counter()
        result = process_readings(batch, make_method(method, config),
                                  reading_filter=reading_filter, map_filter=map_filter)
        seconds = time.perf_counter() - tic
        write_map_csv(result.global_map, out)
    except Exception as err:  # one bad log must not stop the fleet: report it, go on
        text = " ".join(str(err).split())
        reason = text if isinstance(err, SonarcarveError) and text else (
            f"{type(err).__name__}: {text}" if text else type(err).__name__)
        if reason.endswith(NO_MAX_RANGE):  # the summary says how to give one, as process does
            reason += (" (add a max_range column, or give the run's max range: --max-range, "
                       "or ReadingFilter(max_range=...) in Python)")
        return FleetRow(log, error=reason)
    reading_report, map_report = result.reading_filter, result.map_filter
    return FleetRow(log, out, result.readings, len(result.global_map), result.fully_carved,
                    result.split, 100.0 * result.mean_unprocessed_share, seconds,
                    readings_filtered=0 if reading_report is None
                    else reading_report.total - reading_report.kept,
                    points_filtered=0 if map_report is None
                    else map_report.total - map_report.kept,
                    no_echo_dropped=no_echo_dropped)


def map_logs(
    logs: Sequence[str | Path],
    out_dir: str | Path,
    method: str = "combined",
    config: MethodConfig | None = None,
    *,
    runner: Runner | None = None,
    reading_filter: ReadingFilter | None = None,
    map_filter: MapFilter | None = None,
    bag: BagOptions | None = None,
    on_progress: ProgressCallback | None = None,
) -> list[FleetRow]:
    """Map every log in parallel, one map per log in ``out_dir``, and write the summary.

    Parameters
    ----------
    logs : sequence of path
        Readings CSVs or ROS bags.
    out_dir : path
        Output folder (created); gets ``<name>.map.csv`` per log (:func:`map_name`) and
        ``summary.csv``.
    method, config, reading_filter, map_filter
        As for ``sonarcarve process``; the config defaults to ``MethodConfig()``.
    runner : Runner, optional
        Where the logs are mapped (default: this process).
    bag : BagOptions, optional
        How to read the bag logs (:func:`read_log`); every bag takes the same options.
    on_progress : callable, optional
        ``on_progress("mapping", done, total)``.

    Returns
    -------
    list of FleetRow
        One per log, in the order of ``logs``; failed logs carry their error.

    Raises
    ------
    FleetError
        No logs, a log given twice, or two logs that would write the same map name.
    """
    if not logs:
        msg = "no logs to map"
        raise FleetError(msg)
    method_config = MethodConfig() if config is None else config
    make_method(method, method_config)  # an unknown method fails now, not once per log
    folder = make_output_dir(out_dir, label=f"out_dir {out_dir}")
    names: dict[str, str] = {}
    for log in logs:
        name = map_name(log)
        if name in names:
            msg = (f"{names[name]} and {log} would both write {name}; map them into "
                   "different folders or rename one")
            raise FleetError(msg)
        names[name] = str(log)
    outs = [str(folder / map_name(log)) for log in logs]
    tasks = [Task(map_log, (str(log), out, method, method_config, reading_filter, map_filter,
                            bag), "mapping") for log, out in zip(logs, outs, strict=True)]
    rows: dict[int, FleetRow] = {}
    own = runner if runner is not None else SerialRunner()
    for i, value in own.run(tasks, on_progress=on_progress, capture_errors=True):
        # A TaskFailure: the worker itself died on this log, more than Dask allows.
        rows[i] = (FleetRow(str(logs[i]), error=value.message)
                   if isinstance(value, TaskFailure) else value)
    ordered = [rows[i] for i in range(len(tasks))]
    write_summary(ordered, folder / SUMMARY_NAME)
    return ordered


def write_summary(rows: Sequence[FleetRow], path: str | Path) -> None:
    """Write the summary table (one line per log, the :class:`FleetRow` fields) atomically.

    A failed log's measures are empty cells, not 0 (a 0 reads as data), as in the terminal's
    table; its ``error`` cell says why.
    """
    text = io.StringIO()
    writer = csv.writer(text, lineterminator="\n")
    names = [f.name for f in fields(FleetRow)]
    writer.writerow(names)
    for row in rows:
        cells = [repr(v) if isinstance(v, float) else v for v in astuple(row)]
        if not row.ok:
            cells = [cell if name in ("log", "error") else ""
                     for name, cell in zip(names, cells, strict=True)]
        writer.writerow(cells)
    with atomic_text(path) as handle:
        handle.write(text.getvalue())
