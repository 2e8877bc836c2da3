"""``sonarcarve process``: map a readings CSV with one method and write the global map."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated

import typer
from rich.table import Table

from sonarcarve.cli.app import app, console, progress, summary_table
from sonarcarve.errors import ConfigError, SonarcarveError
from sonarcarve.filters import PAPER_MAX_RANGE, MapFilter, ReadingFilter
from sonarcarve.geometry import NO_INCIDENCE_LIMIT as DEFAULT_MAX_INCIDENCE
from sonarcarve.history import DEFAULT_HISTORY_SIZE, MAX_HISTORY_SIZE
from sonarcarve.io import write_map_csv
from sonarcarve.io.atomic import check_output_file
from sonarcarve.io.readings_csv import count_data_lines, iter_readings_csv
from sonarcarve.methods import MethodConfig, SonarMethod, make_method
from sonarcarve.methods.config import DEFAULT_MIN_TRANSVERSAL, DEFAULT_RANGE_TOLERANCE
from sonarcarve.pipeline import ProcessResult, process_chunks

__all__ = ["process"]

#: Logs shorter than this finish before a progress bar would be worth drawing.
_PROGRESS_MIN_READINGS = 20_000


class ParameterError(SonarcarveError):
    """A filter option outside its valid range (method parameters are checked by
    :class:`~sonarcarve.methods.MethodConfig`)."""


# The command's options, one alias each, so that the command's signature reads as a list.
_ReadingsArg = Annotated[Path, typer.Argument(
    metavar="READINGS.csv",
    help="Readings CSV with a header `t,sensor,x,y,theta,range[,beam_width]`, one echo per "
         "row: t in seconds (never decreasing), sensor a whole number >= 0, x, y the "
         "sensor's position in metres, theta its axis in radians counter-clockwise from +x "
         "(world frame), range in metres (> 0), beam_width in radians (optional; blank or "
         "absent: --beam-width applies).")]
_OutOpt = Annotated[Path, typer.Option(
    "--out", "-o", metavar="MAP.csv",
    help="Where to write the global map CSV. Its folder must exist; never the input.")]
_MethodOpt = Annotated[str, typer.Option(
    "--method", "-m", metavar="NAME",
    help="centerline | carve | atm | combined. `combined` runs carving and ATM on one history "
         "and keeps, per arc, the estimate with the smaller error bound.")]
_HistoryOpt = Annotated[int, typer.Option(
    metavar="ARCS", help=f"Arcs kept in the history (paper: 250; at most {MAX_HISTORY_SIZE}).")]
_BeamWidthOpt = Annotated[float, typer.Option(
    metavar="DEGREES",
    help="Beam width φ in degrees, used only for readings without a beam_width value (no "
         "such column, or a blank cell); a beam_width column, in radians, wins.")]
_ToleranceOpt = Annotated[float, typer.Option(
    help="ε in metres: a newer reading's free space ends ε short of its range (0 = paper).")]
_DEFAULT_TRANSVERSAL_DEG = round(math.degrees(DEFAULT_MIN_TRANSVERSAL), 6)
_TransversalOpt = Annotated[float, typer.Option(
    help="ψ in degrees: ATM's minimum angle between two arcs at their intersection.")]
_IncidenceOpt = Annotated[float | None, typer.Option(
    help="β in degrees, in [0, 90]: specular-aware carving (beyond the paper; off by "
         "default). A newer reading then does not carve the part of an older arc whose "
         "implied wall (facing the older sensor) it would meet at more than β from the "
         "normal: smooth walls send no echo at such glancing angles, so the newer "
         "reading's free space says nothing there. 90 = off = the paper. Example: "
         "--max-incidence 30.")]
_MaxRangeOpt = Annotated[float | None, typer.Option(
    help="Drop readings farther than this, metres (reading filter; off by default). The "
         f"paper used 150 in = {PAPER_MAX_RANGE:.2f} m on its robot; pick yours from your "
         "sensors' height and floor.", rich_help_panel="Filters")]
_MinRangeOpt = Annotated[float | None, typer.Option(
    help="Drop readings nearer than this, metres (reading filter).",
    rich_help_panel="Filters")]
_JumpOpt = Annotated[float | None, typer.Option(
    help="Drop a reading whose range differs by more than this (metres) from the same "
         "sensor's previous reading: a jumping sensor is ignored for one reading.",
    rich_help_panel="Filters")]
_OutlierRadiusOpt = Annotated[float | None, typer.Option(
    help="Map filter: drop points with fewer than --outlier-neighbours other points within "
         "this radius, metres.", rich_help_panel="Filters")]
_NeighboursOpt = Annotated[int, typer.Option(
    help="k of the outlier test (needs --outlier-radius).", rich_help_panel="Filters")]
_MaxErrorOpt = Annotated[float | None, typer.Option(
    help="Map filter: drop points whose error bound max_error exceeds this, metres "
         "(paper, Fig. 13b).", rich_help_panel="Filters")]


@app.command()
def process(
    readings: _ReadingsArg,
    out: _OutOpt,
    method: _MethodOpt = "combined",
    history: _HistoryOpt = DEFAULT_HISTORY_SIZE,
    beam_width: _BeamWidthOpt = 22.5,
    range_tolerance: _ToleranceOpt = DEFAULT_RANGE_TOLERANCE,
    min_transversal: _TransversalOpt = _DEFAULT_TRANSVERSAL_DEG,
    max_incidence: _IncidenceOpt = None,
    max_range: _MaxRangeOpt = None,
    min_range: _MinRangeOpt = None,
    jump_threshold: _JumpOpt = None,
    outlier_radius: _OutlierRadiusOpt = None,
    outlier_neighbours: _NeighboursOpt = 1,
    max_error: _MaxErrorOpt = None,
) -> None:
    """Map READINGS.csv with one method and write its global map to --out.

    The map CSV has one row per surviving reading: `id,t,sensor,x,y,source,width,max_error`
    (`source` is the model that placed the point: centerline, carved or atm; `width` the final
    angular width in radians; `max_error` the error bound in metres).

    Filters are off unless asked for: reading filters (--max-range, --min-range,
    --jump-threshold) drop readings before mapping, keeping the ids of the others as their input
    rows; map filters (--max-error, then --outlier-radius) drop points from the global map.

    The summary's "unprocessed (mean % of history rows)" is the paper's Table I latency: the
    share of the history's arcs that no newer reading has sharpened yet, averaged over the run.
    Arcs carving removed (fully carved or split) count as processed; the paper's history drops
    them instead, which gives a larger share for carving (docs/RESULTS.md reports both).

    Example: `sonarcarve process readings.csv --method carve --out map.csv`

    Example: `sonarcarve process readings.csv --max-range 3.81 --max-error 0.1 --out map.csv`
    """
    config = _config(history, beam_width, range_tolerance, min_transversal, max_incidence)
    reading_filter, map_filter = _filters(max_range, min_range, jump_threshold, outlier_radius,
                                          outlier_neighbours, max_error)
    sonar = make_method(method, config)
    check_output_file(out, inputs=[readings], label=f"--out {out}")
    # The file is read, checked and mapped a block at a time; a bad line stops the run with
    # nothing written, as the map is written only at the end.
    result = _run(readings, sonar, method, reading_filter, map_filter)
    write_map_csv(result.global_map, out)
    console.print(_summary(method, result, out))


def _config(history: int, beam_width_deg: float, tolerance: float, transversal_deg: float,
            incidence_deg: float | None) -> MethodConfig:
    """The options in SI units; :class:`MethodConfig` checks every value (one-line errors).

    The config speaks radians; an error about an option given in degrees is prefixed with the
    option as typed, so that "got 3.49" is not read as the user's number.
    """
    incidence = DEFAULT_MAX_INCIDENCE
    if incidence_deg is not None and incidence_deg != 90.0:  # 90° is π/2 exactly: off
        incidence = math.radians(incidence_deg)
    try:
        return MethodConfig(history_size=history, beam_width=math.radians(beam_width_deg),
                            range_tolerance=tolerance,
                            min_transversal=math.radians(transversal_deg),
                            max_incidence=incidence)
    except ConfigError as err:
        typed = {"beam_width": f"--beam-width {beam_width_deg:g}",
                 "min_transversal": f"--min-transversal {transversal_deg:g}",
                 "max_incidence": f"--max-incidence {incidence_deg}"}
        field = str(err).split(" ", 1)[0]
        if field in typed:
            msg = f"{typed[field]} (degrees): {err}"
            raise ConfigError(msg) from None
        raise


def _run(readings: Path, sonar: SonarMethod, label: str,
         reading_filter: ReadingFilter | None, map_filter: MapFilter | None) -> ProcessResult:
    """Map the file ``readings`` with ``sonar``, with a progress bar for long logs."""
    chunks = iter_readings_csv(readings)
    rows = count_data_lines(readings)  # the bar's total, from the line breaks alone
    if rows < _PROGRESS_MIN_READINGS:
        return process_chunks(chunks, sonar, reading_filter=reading_filter,
                              map_filter=map_filter)
    with progress() as bar:
        task = bar.add_task(label, total=rows)
        return process_chunks(chunks, sonar, on_progress=lambda n: bar.update(task, completed=n),
                              reading_filter=reading_filter, map_filter=map_filter)


def _filters(max_range: float | None, min_range: float | None, jump: float | None,
             radius: float | None, neighbours: int, max_error: float | None,
             ) -> tuple[ReadingFilter | None, MapFilter | None]:
    for name, value in (("--max-range", max_range), ("--min-range", min_range),
                        ("--jump-threshold", jump), ("--outlier-radius", radius),
                        ("--max-error", max_error)):
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
    points = MapFilter(max_error=max_error, outlier_radius=radius, outlier_neighbours=neighbours)
    return (readings if readings.active else None), (points if points.active else None)


def _summary(method: str, result: ProcessResult, out: Path) -> Table:
    rows: list[tuple[str, str]] = []
    dropped = result.reading_filter
    if dropped is None:
        rows.append(("readings in", f"{result.readings:,}"))
    else:
        rows += [("readings in", f"{dropped.total:,}"),
                 ("dropped: beyond --max-range", f"{dropped.too_far:,}"),
                 ("dropped: below --min-range", f"{dropped.too_near:,}"),
                 ("dropped: --jump-threshold", f"{dropped.jumps:,}"),
                 ("readings mapped", f"{result.readings:,}")]
    points = result.map_filter
    if points is not None:
        rows += [("points before map filters", f"{points.total:,}"),
                 ("dropped: above --max-error", f"{points.max_error:,}"),
                 ("dropped: outliers", f"{points.outliers:,}")]
    rows += [("points out", f"{len(result.global_map):,}"),
             ("fully carved", f"{result.fully_carved:,}"),
             ("split (dropped)", f"{result.split:,}"),
             # Removed arcs count as processed: see the command's help.
             ("unprocessed (mean % of history rows)",
              f"{100 * result.mean_unprocessed_share:.1f}"),
             ("readings per second", f"{result.readings_per_second:,.0f}"),
             ("map written to", str(out))]
    return summary_table(f"sonarcarve process --method {method}", rows)
