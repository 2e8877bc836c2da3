"""``sonarcarve plot``: draw a map made with ``sonarcarve process``, without writing code."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from sonarcarve.cli.app import app, console, cut_short, flag_message, summary_table, warn
from sonarcarve.cli.drawing import draw_offscreen
from sonarcarve.cli.options import check_max_range, max_range_hint
from sonarcarve.errors import ConfigError, SonarcarveError
from sonarcarve.extras import require
from sonarcarve.filters import confidence_mask
from sonarcarve.io import read_map_csv
from sonarcarve.io.atomic import check_output_file
from sonarcarve.io.errors import InputError
from sonarcarve.io.readings_csv import read_readings_csv
from sonarcarve.maps import GlobalMap
from sonarcarve.plotting import (
    check_figure_path,
    map_origins,
    new_axes,
    plot_user_map,
    read_grid_image,
    save_figure,
)
from sonarcarve.readings import ReadingBatch

__all__ = ["plot"]

#: :func:`~sonarcarve.plotting.plot_user_map`'s parameters -> the options that set them.
_FLAGS = {"arcs": "--arcs", "readings": "--readings"}


class PlotUsageError(SonarcarveError):
    """Options of ``sonarcarve plot`` that do not go together or are out of range."""


@app.command()
def plot(
    map_csv: Annotated[Path, typer.Argument(
        metavar="MAP.csv",
        help="A map CSV as `sonarcarve process` writes it "
             "(`id,t,sensor,x,y,source,width,max_error[,confidence]`).")],
    out: Annotated[Path, typer.Option(
        "--out", "-o", metavar="FIGURE.png",
        help="Where to write the figure: .png, .svg or .pdf. Its folder must exist.")],
    readings: Annotated[Path | None, typer.Option(
        "--readings", "-r", metavar="READINGS.csv",
        help="The readings the map was made from: draws the robot's path (each sensor's "
             "origins over time) and lets --arcs draw each point's arc.")] = None,
    grid: Annotated[Path | None, typer.Option(
        "--grid", "-g", metavar="GRID.yaml",
        help="A ROS map_server map (YAML beside its image) drawn underneath, in grey.")] = None,
    error_bars: Annotated[bool, typer.Option(
        "--error-bars",
        help="Draw each point's error bound max_error as a circle of that radius.")] = False,
    arcs: Annotated[bool, typer.Option(
        "--arcs",
        help="Draw each point's final arc (its reading's range about the sensor, `width` "
             "wide, centred on the point); needs --readings.")] = False,
    confidence_min: Annotated[float | None, typer.Option(
        "--confidence-min", metavar="C",
        help="Keep only points whose confidence is at least C, in [0, 1]; points without a "
             "confidence (methods that do not model it) are kept.")] = None,
    title: Annotated[str | None, typer.Option(
        help="The figure's title (default: the counts of points by source).")] = None,
    max_range: Annotated[float | None, typer.Option(
        "--max-range", metavar="METRES", show_default="off",
        help="How far the --readings' no-echo rows (range inf) without a max_range of their "
             "own listened, as given to `sonarcarve process`; needed only for such rows. "
             "No echo is dropped here: a map's ids count every row of its readings.")] = None,
) -> None:
    """Draw a map CSV to a figure: points coloured by source, the robot's path, a grid map.

    Points are coloured by the model that placed them (centerline, carved, atm); on request
    each point's error bound (--error-bars) and final arc (--arcs, with --readings) are drawn
    too. Axes are in metres, with equal scale.

    Examples:

    - `sonarcarve plot map.csv --out map.png`: the points alone.
    - `sonarcarve plot map.csv --readings readings.csv --arcs --out map.png`: with the path
      and each point's arc.
    - `sonarcarve plot map.csv --grid building.yaml --error-bars --out map.png`: over a ROS map.
    """
    if confidence_min is not None and not 0.0 <= confidence_min <= 1.0:
        msg = f"--confidence-min must lie in [0, 1], got {confidence_min:g}"
        raise PlotUsageError(msg)
    check_figure_path(out, label=f"--out {out}")
    check_max_range(max_range)
    if max_range is not None and readings is None:  # said, not silently ignored
        msg = "--max-range applies to the --readings' no-echo rows; give --readings too"
        raise PlotUsageError(msg)
    inputs = [path for path in (map_csv, readings, grid) if path is not None]
    check_output_file(out, inputs=inputs, label=f"--out {out}")
    require("matplotlib", "plot", "Figures")
    points = read_map_csv(map_csv)
    total = len(points)
    with max_range_hint():  # a no-echo row without max_range: say how to give one
        batch = (read_readings_csv(readings, max_range=max_range) if readings is not None
                 else None)
    if batch is not None and readings is not None:  # another log's readings: refused
        _check_same_log(points, batch, readings, map_csv)
    if confidence_min is not None:
        points = points.select(confidence_mask(points.confidence, confidence_min))
    image = read_grid_image(grid) if grid is not None else None
    draw_offscreen()
    ax = new_axes(8.0, 7.0)
    try:
        plot_user_map(points, ax, readings=batch, grid=image, error_bounds=error_bars,
                      arcs=arcs, title=title)
    except ConfigError as err:  # --arcs without --readings
        raise PlotUsageError(flag_message(str(err), _FLAGS)) from None
    save_figure(ax, out)
    warn([cut_short(map_csv), None if readings is None else cut_short(readings)])
    rows = [("points in map", f"{total:,}")]
    if confidence_min is not None:
        rows.append((f"dropped: confidence < {confidence_min:g}", f"{total - len(points):,}"))
    rows += [("points drawn", f"{len(points):,}"), ("figure written to", str(out))]
    console.print(summary_table("sonarcarve plot", rows))


def _check_same_log(points: GlobalMap, batch: ReadingBatch, readings: Path,
                    map_csv: Path) -> None:
    """Refuse readings the map was not made from (:func:`map_origins`, naming the map's line).

    A map of a ROS bag made without ``--no-echo`` numbers the bag's echoes only, so the
    readings ``convert rosbag --no-echo`` wrote (the silent firings as rows too) do not fit
    it: the usual way to get here from a bag, which the message then names.
    """
    try:
        map_origins(points, batch, source=str(readings), map_file=str(map_csv))
    except InputError:
        silent = batch.no_echo
        if not silent.any() or not _fits(points, batch[~silent]):
            raise
        msg = (f"{map_csv}: its ids skip the {int(silent.sum()):,} no-echo rows (range inf) "
               f"of {readings}, as a map of a bag made without --no-echo does: give "
               "--readings converted without --no-echo")
        raise InputError(msg) from None


def _fits(points: GlobalMap, batch: ReadingBatch) -> bool:
    """Whether ``points`` were made from ``batch`` (:func:`map_origins` finds no mismatch)."""
    try:
        map_origins(points, batch)
    except InputError:
        return False
    return True
