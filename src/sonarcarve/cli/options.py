"""Options more than one command takes, declared once: how to read a ROS bag, bag outputs,
the sensors' max range, the method and its parameters.

``sonarcarve convert rosbag``, ``sonarcarve process`` and ``sonarcarve grid`` read bags the
same way; each takes the options below in its signature and turns them into a
:class:`~sonarcarve.fleet.BagOptions` with :func:`bag_options`; :func:`refuse_bag_options`
refuses them for a readings CSV input. ``sonarcarve process``, ``grid`` and ``view`` take
``--max-range`` (:data:`MAX_RANGE_HELP`): the readings CSV contract lets a no-echo row (range
``inf``) leave its ``max_range`` empty when the run gives one for all. ``sonarcarve process``
and ``view`` map with ``--method`` and its parameters (``--history``, ``--beam-width``,
``--range-tolerance``, ``--min-transversal``, ``--max-incidence``), turned into a
:class:`~sonarcarve.methods.MethodConfig` by :func:`method_config`.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Annotated, NamedTuple

import typer

from sonarcarve.cli.app import reworded
from sonarcarve.errors import ConfigError, SonarcarveError
from sonarcarve.filters import ReadingFilter, filter_readings
from sonarcarve.fleet import BagOptions, is_bag
from sonarcarve.geometry import NO_INCIDENCE_LIMIT
from sonarcarve.history import MAX_HISTORY_SIZE
from sonarcarve.io.atomic import check_output_file
from sonarcarve.io.errors import OutputError
from sonarcarve.io.rosbag import RosbagError, RosbagLog
from sonarcarve.methods.config import (
    DEFAULT_MIN_CONFIDENCE,
    DEFAULT_MIN_TRANSVERSAL,
    MethodConfig,
    check_degrees,
)
from sonarcarve.readings import MAX_READING_RANGE, NO_MAX_RANGE, ReadingBatch, reading_ids
from sonarcarve.robot import load_robot
from sonarcarve.typing import IntArray

__all__ = [
    "BAG_FLAGS",
    "BAG_PANEL",
    "DEFAULT_BEAM_WIDTH_DEG",
    "DEFAULT_TRANSVERSAL_DEG",
    "MAX_RANGE_HELP",
    "RUNNER_FLAGS",
    "BagOptionsError",
    "BeamWidthOpt",
    "FrameOpt",
    "HistoryOpt",
    "IncidenceOpt",
    "MaxRangeError",
    "MaxRangeOpt",
    "MethodNameError",
    "MethodOpt",
    "MinConfidenceOpt",
    "NearEchoes",
    "NoEchoOpt",
    "OdomTopicOpt",
    "PointCertainty",
    "RangeTopicOpt",
    "RobotOpt",
    "StampErrorOpt",
    "StampHeadingOpt",
    "ToleranceOpt",
    "TransversalOpt",
    "bag_options",
    "check_max_range",
    "check_method",
    "check_new_bag",
    "drop_far_echoes",
    "max_range_hint",
    "method_config",
    "read_bag",
    "refuse_bag_options",
]

#: The bag reader's parameters (:func:`~sonarcarve.io.rosbag.read_rosbag`) -> the options.
BAG_FLAGS = {"odom_topic": "--odom-topic", "range_topics": "--range-topic",
             "base_frame": "--frame"}
#: The runner's and the fleet's parameters (:class:`~sonarcarve.runner.RunnerSpec`,
#: :func:`~sonarcarve.fleet.map_logs`) -> the options (:func:`~sonarcarve.cli.app.reworded`).
RUNNER_FLAGS = {"workers": "--workers", "scheduler": "--scheduler",
                "connect_timeout": "--connect-timeout", "out_dir": "--out-dir"}

#: What ``--max-range`` means to every command that takes it (process adds its filter panel).
MAX_RANGE_HELP = (
    "The sensors' max range, metres: echoes farther are dropped (reading filter), and a "
    "readings CSV's no-echo rows (range inf) without a max_range of their own heard nothing up "
    "to it (free space). Off: every echo is kept, and such rows need a max_range column.")
MaxRangeOpt = Annotated[float | None, typer.Option(
    "--max-range", metavar="METRES", show_default="off", help=MAX_RANGE_HELP)]

#: The help panel the bag options are listed under.
BAG_PANEL = "ROS bag input"

RobotOpt = Annotated[str | None, typer.Option(
    metavar="NAME|ROBOT.yaml",
    help="Bag input: fallback sensor mounts when the bag's TF lacks them: a built-in robot "
         "(car-parking-12, p3dx, p3dx-front, roboND-8, scout2) or a YAML file; sensor i takes "
         "mount i. Refused when it does not fit the bag (sensor count, or TF mounts).",
    rich_help_panel=BAG_PANEL)]
RangeTopicOpt = Annotated[list[str] | None, typer.Option(
    metavar="TOPIC",
    help="Bag input: a Range topic; repeat in sensor order (default: every Range topic, "
         "natural-sorted by name; frame_ids number the sensors within a topic).",
    rich_help_panel=BAG_PANEL)]
OdomTopicOpt = Annotated[str | None, typer.Option(
    metavar="TOPIC",
    help="Bag input: the Odometry topic (default: the only one, else odom → base frame on "
         "/tf).",
    rich_help_panel=BAG_PANEL)]
FrameOpt = Annotated[str | None, typer.Option(
    metavar="FRAME",
    help="Bag input: the robot's base frame, where TF mounts end and odometry points to "
         "(default: the odometry's child_frame_id, else base_link).",
    rich_help_panel=BAG_PANEL)]


NoEchoOpt = Annotated[bool, typer.Option(
    "--no-echo",
    help="Bag input: keep the no-echo readings (REP 117 +Inf; or a range equal to max_range "
         "from a sensor that never reports +Inf, as Gazebo's plugins say it: nothing heard up "
         "to max_range) "
         "as free space: carving and the carved and Elfes grids clear with them, evidence "
         "carving weighs them as looks through their beams (ROS's range-sensor-layer drops "
         "+Inf, as on a robot); they add no point. Without it the summary counts those "
         "dropped.",
    rich_help_panel=BAG_PANEL)]


#: ``sonarcarve process`` and ``view``: the method and its parameters (:func:`method_config`).
MethodOpt = Annotated[str, typer.Option(
    "--method", "-m", metavar="NAME",
    help="centerline | carve | atm | combined | evidence. `combined` runs carving and ATM on "
         "one history and keeps, per arc, the estimate with the smaller error bound; "
         "`evidence` is evidence carving (beyond the paper): free-space evidence accumulated "
         "across each beam, ATM inside it, and a confidence column per point.")]
HistoryOpt = Annotated[int, typer.Option(
    metavar="ARCS", help=f"Arcs kept in the history (paper: 250; at most {MAX_HISTORY_SIZE}).")]
BeamWidthOpt = Annotated[float, typer.Option(
    metavar="DEGREES",
    help="Beam width φ in degrees, used only for readings without a beam_width value (no "
         "such column, or a blank cell); a beam_width column, in radians, wins.")]
ToleranceOpt = Annotated[float, typer.Option(
    metavar="METRES",
    help="ε in metres, 0 to 1: a newer reading's free space ends ε short of its range (0 = "
         "paper). "
         "With poses from a localiser good to σ metres, add 2σ (5 cm: 0.15), so that a beam "
         "stamped a little off does not carve the walls it passes (docs/RESULTS.md, 'Maps from "
         "wrong poses').")]
#: ``--beam-width``'s default, degrees (paper: 22.5°; MethodConfig's default, in radians).
DEFAULT_BEAM_WIDTH_DEG = 22.5
#: ``--min-transversal``'s default, degrees (the config's, in radians, rounded for the help).
DEFAULT_TRANSVERSAL_DEG = round(math.degrees(DEFAULT_MIN_TRANSVERSAL), 6)
TransversalOpt = Annotated[float, typer.Option(
    metavar="DEGREES",
    help="ψ in degrees, in (0, 90]: ATM's minimum angle between two arcs at their "
         "intersection.")]
IncidenceOpt = Annotated[float | None, typer.Option(
    metavar="DEGREES", show_default="off",
    help="β in degrees, in [0, 90]: specular-aware carving (beyond the paper; off by "
         "default). A newer reading then does not carve the part of an older arc whose "
         "implied wall (facing the older sensor) it would meet at more than β from the "
         "normal: smooth walls send no echo at such glancing angles, so the newer "
         "reading's free space says nothing there. 90 = off = the paper. Example: "
         "--max-incidence 30.")]

#: ``sonarcarve process`` and ``view``: evidence carving's certainty per point (section 6).
MinConfidenceOpt = Annotated[float | None, typer.Option(
    metavar="P", show_default=f"{DEFAULT_MIN_CONFIDENCE:g}",
    rich_help_panel="Evidence carving's certainty",
    help="With --method evidence: points whose confidence (the map's confidence column, the "
         "probability that the point is a real surface) is below P leave every map it makes, "
         "the live ones (a bag's local map, a Rerun recording) included; in [0, 1]. 0 keeps "
         "every point with a surviving piece; 0.8 keeps the surest. Example: "
         "--min-confidence 0.8.")]
StampErrorOpt = Annotated[float, typer.Option(
    metavar="METRES", rich_help_panel="Evidence carving's certainty",
    help="With --method evidence: how far a reading's stamped sensor position may be from "
         "where it fired, metres, finite and >= 0 (the paper's Appendix A: polled sonars' "
         "stamps are inferred while the robot moves). For a stamp bound Δt, a top speed v, a "
         "top turn rate ω (rad/s) and sensors d metres from the centre: Δt (v + ω d); docs/"
         "evidence-carving.md 'Certainty per point'. Added to every point's max_error. "
         "Example: --stamp-error 0.037 (Δt 62 ms, 0.4 m/s, 1 rad/s, d 0.2 m).")]
StampHeadingOpt = Annotated[float, typer.Option(
    metavar="DEGREES", rich_help_panel="Evidence carving's certainty",
    help="With --method evidence: how far a reading's stamped heading may be off, δ in "
         "[0, 90] degrees: the top turn rate times the stamp's bound, ω Δt, in degrees. A point "
         "r metres out moves up to 2 r sin(δ/2), added to its max_error. Example: "
         "--stamp-heading-error 3.5 (Δt 62 ms at 1 rad/s).")]


class PointCertainty(NamedTuple):
    """Evidence carving's certainty options as given (``--min-confidence``, ``--stamp-error``,
    ``--stamp-heading-error`` in degrees); the defaults are the method's."""

    min_confidence: float | None = None
    stamp_error: float = 0.0
    stamp_heading_deg: float = 0.0

    def given(self) -> list[str]:
        """The options given with other than their defaults, as spelled on the command line."""
        flags = (("--min-confidence", self.min_confidence is not None),
                 ("--stamp-error", self.stamp_error != 0.0),
                 ("--stamp-heading-error", self.stamp_heading_deg != 0.0))
        return [flag for flag, given in flags if given]


def read_bag(bag: BagOptions, source: str | Path) -> RosbagLog:
    """``bag.read(source)``, its errors naming the options instead of the reader's
    parameters (``choose one with --odom-topic``)."""
    with reworded(RosbagError, BAG_FLAGS):
        return bag.read(source)


def no_echo_dropped_row(dropped: int) -> list[tuple[str, str]]:
    """A summary's row of the no-echo readings a bag input dropped for want of ``--no-echo``
    (:meth:`~sonarcarve.fleet.BagOptions.dropped_no_echo`; none when there are none). Said
    because a bag can hold almost as many silent firings as echoes (the t-junction tour: 496
    against 700), and they change the map: evidence carving removed 70 → 87 % of that tour's
    spurious echoes with them (docs/RESULTS.md, *evidence carving*). The default stays
    "dropped", as on a robot running ROS's layer, which drops +Inf."""
    return [("dropped: no-echo readings (--no-echo)", f"{dropped:,}")] if dropped else []


def bag_options(robot: str | None, range_topic: list[str] | None, odom_topic: str | None,
                frame: str | None, beam_width: float | None = None,
                no_echo: bool = False) -> BagOptions:
    """The bag options as given on the command line; a ``--robot`` that does not load fails
    here, once, with its one-line error (not once per log)."""
    if robot is not None:
        load_robot(robot)
    return BagOptions(robot=robot, range_topics=tuple(range_topic or ()),
                      odom_topic=odom_topic, frame=frame, beam_width=beam_width,
                      no_echo=no_echo)


class BagOptionsError(SonarcarveError):
    """Bag options given with an input that is not a ROS bag."""


class MethodNameError(SonarcarveError):
    """A ``--method`` that names no method."""


def check_method(name: str) -> None:
    """Refuse a ``--method`` that names no method, naming the option (as ``grid --model``).

    Raises
    ------
    MethodNameError
        ``--method must be one of centerline | carve | ..., got 'carving'``.
    """
    from sonarcarve.methods import METHODS  # the methods' kernels: only when a command runs

    if name not in METHODS:
        msg = f"--method must be one of {' | '.join(METHODS)}, got {name!r}"
        raise MethodNameError(msg)


def refuse_bag_options(source: Path, bag: BagOptions) -> None:
    """Refuse bag options for a ``source`` that is not a bag (:func:`~sonarcarve.fleet.is_bag`):
    a readings CSV can use none of them, and silently ignoring one (``--no-echo``, say) would
    hide a mistake.

    Raises
    ------
    BagOptionsError
        One line naming ``source`` and the options.
    """
    if bag.given and not is_bag(source):
        msg = (f"{source} is a readings CSV; --robot, --range-topic, --odom-topic, --frame "
               "and --no-echo apply to ROS bag inputs only")
        raise BagOptionsError(msg)


def check_new_bag(path: Path, *, inputs: Iterable[Path] = (), label: str) -> Path:
    """Check, before any work, that a bag can be written at ``path`` (a ``*.bag`` or
    ``*.mcap`` file or a rosbag2 folder): it must not exist (a bag is never overwritten) and
    its folder must accept new files.

    Raises
    ------
    OutputError
        One line naming ``label`` and the reason.
    """
    # The file checks first: an existing folder, a device or "." get their own words.
    target = check_output_file(path, inputs=[p for p in inputs if p.is_file()], label=label)
    if target.exists() or target.is_symlink():
        msg = f"{label}: already exists; a bag is never overwritten, remove it or pick another name"
        raise OutputError(msg)
    return target


@contextmanager
def max_range_hint() -> Iterator[None]:
    """Re-raise the error of a no-echo row (range inf) that gives no max_range (a readings
    CSV's :class:`~sonarcarve.io.errors.InputError`, a batch's
    :class:`~sonarcarve.readings.ReadingsError`) with the two ways to give one: the error
    names the row, the hint the remedy."""
    try:
        yield
    except SonarcarveError as err:
        if not str(err).endswith(NO_MAX_RANGE):
            raise
        raise type(err)(_with_max_range_hint(str(err))) from None


def _with_max_range_hint(message: str) -> str:
    """``message`` with the two ways to give a max range if it is the error of a no-echo row
    without one, else unchanged (a fleet's failed log says it itself: :mod:`sonarcarve.fleet`)."""
    if not message.endswith(NO_MAX_RANGE):
        return message
    return f"{message} (add a max_range column, or give the sensors' max range with --max-range)"


class MaxRangeError(SonarcarveError):
    """A ``--max-range`` that is not a finite number of metres in (0, 10,000]."""


def check_max_range(max_range: float | None) -> float | None:
    """``--max-range`` checked before anything is read: a finite number > 0, at most
    :data:`~sonarcarve.readings.MAX_READING_RANGE` (what a readings CSV accepts as a row's
    max_range), or None (off).

    Raises
    ------
    MaxRangeError
        One line naming the option and the value.
    """
    if max_range is not None and not 0.0 < max_range <= MAX_READING_RANGE:  # NaN fails too
        msg = (f"--max-range must be a finite number > 0 metres, at most "
               f"{MAX_READING_RANGE:,.0f}, got {max_range}")
        raise MaxRangeError(msg)
    return max_range


class NearEchoes(NamedTuple):
    """A log without its echoes beyond ``--max-range`` (:func:`drop_far_echoes`)."""

    batch: ReadingBatch
    #: The input row of each kept reading: its reading id, so that map ids, arc markers and a
    #: recording's timeline still point at the input (the id contract).
    ids: IntArray
    dropped: int


def drop_far_echoes(batch: ReadingBatch, max_range: float | None) -> NearEchoes:
    """``batch`` without its echoes farther than ``max_range`` (None: all kept), the kept
    rows and how many were dropped: ``--max-range`` as ``sonarcarve process`` applies it (a
    no-echo row keeps its own max_range)."""
    if max_range is None:
        return NearEchoes(batch, reading_ids(len(batch)), 0)
    kept = filter_readings(batch, ReadingFilter(max_range=max_range))
    return NearEchoes(kept.batch, kept.ids, kept.report.too_far)


def method_config(history: int, beam_width_deg: float, tolerance: float,
                  transversal_deg: float, incidence_deg: float | None, *,
                  method: str, certainty: PointCertainty) -> MethodConfig:
    """The method options (``--history``, ...) in SI units; :class:`MethodConfig` checks
    every value (one-line errors).

    The config speaks radians and its own field names; the options given in degrees are
    checked here first, in degrees, and any other error names the option (``--history``), not
    the field (``history_size``). ``certainty`` is refused for a ``method`` other than
    evidence carving.
    """
    check_degrees("beam_width", beam_width_deg, "--beam-width")
    check_degrees("min_transversal", transversal_deg, "--min-transversal")
    if incidence_deg is not None:
        check_degrees("max_incidence", incidence_deg, "--max-incidence")
    check_degrees("stamp_heading_error", certainty.stamp_heading_deg, "--stamp-heading-error")
    _refuse_certainty_unless_evidence(method, certainty)
    incidence = NO_INCIDENCE_LIMIT
    if incidence_deg is not None and incidence_deg != 90.0:  # 90° is π/2 exactly: off
        incidence = math.radians(incidence_deg)
    confidence = certainty.min_confidence
    with reworded(ConfigError, _OPTION_OF_FIELD):
        return MethodConfig(history_size=history, beam_width=math.radians(beam_width_deg),
                            range_tolerance=tolerance,
                            min_transversal=math.radians(transversal_deg),
                            max_incidence=incidence,
                            min_confidence=(DEFAULT_MIN_CONFIDENCE if confidence is None
                                            else confidence),
                            stamp_error=certainty.stamp_error,
                            stamp_heading_error=math.radians(certainty.stamp_heading_deg))


def _refuse_certainty_unless_evidence(method: str, certainty: PointCertainty) -> None:
    """Refuse the certainty options given for a method other than evidence carving, the only
    one whose points carry a confidence and a stamped bound (so they would do nothing)."""
    given = certainty.given()
    if not given or method == "evidence":
        return
    named = given[0] if len(given) == 1 else f"{', '.join(given[:-1])} and {given[-1]}"
    verb = "applies" if len(given) == 1 else "apply"
    msg = (f"{named} {verb} to --method evidence only (its points carry a confidence and a "
           f"bound with the stamping error), not to {method}")
    raise ConfigError(msg)


#: MethodConfig's field -> the option that sets it, for its error messages.
_OPTION_OF_FIELD = {"history_size": "--history", "range_tolerance": "--range-tolerance",
                    "beam_width": "--beam-width", "min_transversal": "--min-transversal",
                    "max_incidence": "--max-incidence", "min_confidence": "--min-confidence",
                    "stamp_error": "--stamp-error"}
