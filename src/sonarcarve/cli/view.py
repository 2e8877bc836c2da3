"""``sonarcarve view``: a run as a Rerun recording, opened in the viewer when there is one."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Annotated

import typer

from sonarcarve.cli.app import (
    app,
    console,
    cut_short,
    readings_progress,
    reworded,
    summary_table,
    warn,
)
from sonarcarve.cli.options import (
    DEFAULT_BEAM_WIDTH_DEG,
    DEFAULT_TRANSVERSAL_DEG,
    BeamWidthOpt,
    FrameOpt,
    HistoryOpt,
    IncidenceOpt,
    MaxRangeOpt,
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
    drop_far_echoes,
    max_range_hint,
    method_config,
    no_echo_dropped_row,
    read_bag,
    refuse_bag_options,
)
from sonarcarve.errors import ConfigError, SonarcarveError
from sonarcarve.extras import require
from sonarcarve.fleet import BagOptions, is_bag
from sonarcarve.history import DEFAULT_HISTORY_SIZE
from sonarcarve.io.atomic import check_output_file
from sonarcarve.io.readings_csv import read_readings_csv
from sonarcarve.io.rerun_out import DEFAULT_EVERY, write_rerun
from sonarcarve.io.sanity import beam_width_mistake
from sonarcarve.methods import make_method
from sonarcarve.methods.config import DEFAULT_RANGE_TOLERANCE
from sonarcarve.readings import ReadingBatch
from sonarcarve.typing import FloatArray

__all__ = ["find_viewer", "open_viewer", "view"]

#: The suffix of the truth file ``sonarcarve simulate`` writes beside its readings.
_TRUTH_SUFFIX = ".truth.json"


class ViewUsageError(SonarcarveError):
    """A ``sonarcarve view`` option out of range."""


@app.command()
def view(
    readings: Annotated[Path, typer.Argument(
        metavar="READINGS.csv|BAG",
        help="Readings CSV (`t,sensor,x,y,theta,range[,beam_width]`), e.g. from "
             "`sonarcarve simulate` or `sonarcarve convert`. Or a ROS bag: `*.bag` (ROS 1), "
             "`*.mcap`, `*.db3` or a rosbag2 folder, read as `sonarcarve process` reads it "
             "(Range + odometry + TF; see the bag options).")],
    out: Annotated[Path | None, typer.Option(
        "--out", "-o", metavar="RUN.rrd",
        help="Where to save the recording. Default: beside the readings, NAME.rrd.",
        show_default=False)] = None,
    method: MethodOpt = "combined",
    history: HistoryOpt = DEFAULT_HISTORY_SIZE,
    beam_width: BeamWidthOpt = DEFAULT_BEAM_WIDTH_DEG,
    range_tolerance: ToleranceOpt = DEFAULT_RANGE_TOLERANCE,
    min_transversal: TransversalOpt = DEFAULT_TRANSVERSAL_DEG,
    max_incidence: IncidenceOpt = None,
    min_confidence: MinConfidenceOpt = None,
    stamp_error: StampErrorOpt = 0.0,
    stamp_heading_error: StampHeadingOpt = 0.0,
    world: Annotated[str | None, typer.Option(
        "--world", "-w", metavar="WORLD",
        help="Draw this world's walls (built-in name, random:SEED, walls .json, ROS map "
             ".yaml). Default: the walls of NAME.truth.json beside a simulated log, if "
             "any.")] = None,
    every: Annotated[int, typer.Option(
        metavar="READINGS",
        help="Log the local map, the carved arcs and the path every this many "
             "readings.")] = DEFAULT_EVERY,
    open_: Annotated[bool, typer.Option(
        "--open/--no-open",
        help="Open the recording in the Rerun viewer when one can be started (a display "
             "and the `rerun` program).")] = True,
    max_range: MaxRangeOpt = None,
    robot: RobotOpt = None,
    range_topic: RangeTopicOpt = None,
    odom_topic: OdomTopicOpt = None,
    frame: FrameOpt = None,
    no_echo: NoEchoOpt = False,
) -> None:
    """Record a run for the Rerun viewer: robot path, each reading's arc, the map growing.

    The readings are mapped with one method; the recording (a `.rrd` file) has, on a `time`
    timeline in the readings' seconds, the sensor origins and their paths, each new reading's
    beam, every arc in the history as carved so far and the local map coloured by source
    (point size: the error bound), the global map at the end, and the true walls of a
    simulated run. It opens in the viewer when one can be started; otherwise the command says
    where it saved it (open it later with `rerun RUN.rrd`).

    Example: `sonarcarve view run.csv --method carve --out run.rrd`

    Example: `sonarcarve view run.mcap --no-echo` (a ROS bag; writes run.rrd)

    Example: `sonarcarve view run.csv --range-tolerance 0.15 --max-incidence 30` (the method's
    options are process's)
    """
    target = out if out is not None else readings.with_suffix(".rrd")
    check_output_file(target, inputs=[readings], label=f"--out {target}")
    if target.suffix.lower() != ".rrd":
        msg = f"--out {target}: a Rerun recording's name must end in .rrd"
        raise ViewUsageError(msg)
    # The method and its parameters as process checks them, so that a recording can show a run
    # mapped as process mapped it.
    check_method(method)
    config = method_config(history, beam_width, range_tolerance, min_transversal, max_incidence,
                           method=method,
                           certainty=PointCertainty(min_confidence, stamp_error,
                                                    stamp_heading_error))
    sonar = make_method(method, config)
    beam_warning = beam_width_mistake(beam_width, "--beam-width")
    check_max_range(max_range)
    bag = bag_options(robot, range_topic, odom_topic, frame, no_echo=no_echo)
    refuse_bag_options(readings, bag)
    require("rerun", "viz", "Rerun recordings")
    walls = _walls(readings, world)
    batch, dropped_silent = _read_log(readings, bag, max_range)
    batch, ids, too_far = drop_far_echoes(batch, max_range)
    with (reworded(ConfigError, {"every": "--every"}),  # write_rerun checks every first
          readings_progress(method, len(batch)) as on_progress):
        global_map = write_rerun(target, batch, sonar, walls=walls, every=every, ids=ids,
                                 on_progress=on_progress)
    viewer = find_viewer() if open_ else None
    # Counted as process counts them: every row read, then the ones --max-range dropped.
    rows = [("readings in", f"{len(batch) + too_far:,}"), *no_echo_dropped_row(dropped_silent),
            ("points in global map", f"{len(global_map):,}"),
            *([("dropped: echoes beyond --max-range", f"{too_far:,}")] if max_range else []),
            ("true walls", f"{len(walls):,}" if walls is not None else "none"),
            ("recording saved to", str(target))]
    if viewer is not None:
        open_viewer(viewer, target)
        rows.append(("opened in", str(viewer)))
    console.print(summary_table(f"sonarcarve view --method {method}", rows))
    if viewer is None:
        reason = "" if open_ else " (--no-open)"
        console.print(f"no viewer opened{reason}; open the recording with `rerun {target}`")
    if not len(batch):  # a valid file (a header only), so not an error: say so, as process does
        what = "no readings" if is_bag(readings) else "no readings, only a header"
        warn([f"{readings} has {what}: the recording is empty"])
    warn([beam_warning, None if is_bag(readings) else cut_short(readings)])


def _read_log(source: Path, bag: BagOptions,
              max_range: float | None) -> tuple[ReadingBatch, int]:
    """The readings of a ROS bag, read with ``bag`` as ``sonarcarve process`` reads it, or of
    a readings CSV (``max_range``, metres: how far its no-echo rows without one listened), and
    how many of the bag's no-echo readings were dropped (all of them without ``--no-echo``)."""
    if is_bag(source):
        log = read_bag(bag, source)
        return bag.readings(log), bag.dropped_no_echo(log)
    with max_range_hint():
        return read_readings_csv(source, max_range=max_range), 0


def _walls(readings: Path, world: str | None) -> FloatArray | None:
    """The walls of ``--world``, else of the truth file beside a simulated log, else None.

    The simulator is imported only here, only when there is a world to read.
    """
    if world is not None:
        from sonarcarve.sim.world import load_world

        return load_world(world).segments
    stem = readings.name[: -len(readings.suffix)] if readings.suffix else readings.name
    truth = readings.with_name(stem + _TRUTH_SUFFIX)
    if not truth.is_file():
        return None
    from sonarcarve.sim.truth import read_truth_json

    return read_truth_json(truth).world.segments


def find_viewer() -> Path | None:
    """The ``rerun`` program, if a viewer window could be opened here; otherwise None.

    Needs a display (``DISPLAY`` or ``WAYLAND_DISPLAY``, or macOS / Windows) and the ``rerun``
    program on the ``PATH`` or beside this Python. Nothing is started, so this never hangs.
    """
    has_display = (sys.platform in ("darwin", "win32") or bool(os.environ.get("DISPLAY"))
                   or bool(os.environ.get("WAYLAND_DISPLAY")))
    if not has_display:
        return None
    beside = Path(sys.executable).parent / ("rerun.exe" if sys.platform == "win32" else "rerun")
    if beside.is_file() and os.access(beside, os.X_OK):
        return beside
    found = shutil.which("rerun")
    return Path(found) if found is not None else None


def open_viewer(viewer: Path, recording: Path) -> None:
    """Start ``viewer`` on ``recording`` in the background, detached from this process."""
    subprocess.Popen([str(viewer), str(recording)], stdin=subprocess.DEVNULL,
                     stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                     start_new_session=True)
