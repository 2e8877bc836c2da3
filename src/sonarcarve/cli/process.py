"""``sonarcarve process``: map a readings CSV with one method and write the global map."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated

import typer
from rich.table import Table

from sonarcarve.cli.app import app, console, progress, summary_table
from sonarcarve.errors import SonarcarveError
from sonarcarve.filters import PAPER_MAX_RANGE, MapFilter, ReadingFilter
from sonarcarve.io import read_readings_csv, write_map_csv
from sonarcarve.io.atomic import check_output_file
from sonarcarve.methods import METHODS, MethodConfig, make_method
from sonarcarve.pipeline import ProcessResult, process_readings

__all__ = ["process"]

#: Logs shorter than this finish before a progress bar would be worth drawing.
_PROGRESS_MIN_READINGS = 20_000


class ParameterError(SonarcarveError):
    """A command-line parameter outside its valid range."""


@app.command()
def process(
    readings: Annotated[Path, typer.Argument(
        metavar="READINGS.csv",
        help="Readings CSV with a header `t,sensor,x,y,theta,range[,beam_width]`, one echo per "
             "row: t in seconds (never decreasing), sensor a whole number >= 0, x, y the "
             "sensor's position in metres, theta its axis in radians counter-clockwise from +x "
             "(world frame), range in metres (> 0), beam_width in radians (optional; blank or "
             "absent: --beam-width applies).")],
    out: Annotated[Path, typer.Option(
        "--out", "-o", metavar="MAP.csv",
        help="Where to write the global map CSV. Its folder must exist; never the input.")],
    method: Annotated[str, typer.Option(
        "--method", "-m", metavar="NAME",
        help="centerline | carve | atm | combined. `combined` runs carving and ATM on one history "
             "and keeps, per arc, the estimate with the smaller error bound.")] = "combined",
    history: Annotated[int, typer.Option(
        metavar="ARCS", help="Arcs kept in the history (paper: 250).")] = 250,
    beam_width: Annotated[float, typer.Option(
        metavar="DEGREES",
        help="Beam width φ in degrees, used only for readings without a beam_width value (no "
             "such column, or a blank cell); a beam_width column, in radians, wins.")] = 22.5,
    range_tolerance: Annotated[float, typer.Option(
        help="ε in metres: a newer reading's free space ends ε short of its range (0 = paper).")]
        = MethodConfig.range_tolerance,
    min_transversal: Annotated[float, typer.Option(
        help="ψ in degrees: ATM's minimum angle between two arcs at their intersection.")]
        = round(math.degrees(MethodConfig.min_transversal), 6),
    max_incidence: Annotated[float | None, typer.Option(
        help="β in degrees, in (0, 90]: specular-aware carving (beyond the paper; off by "
             "default). A newer reading then does not carve the part of an older arc whose "
             "implied wall (facing the older sensor) it would meet at more than β from the "
             "normal: smooth walls send no echo at such glancing angles, so the newer "
             "reading's free space says nothing there. 90 = off = the paper. Example: "
             "--max-incidence 30.")] = None,
    max_range: Annotated[float | None, typer.Option(
        help="Drop readings farther than this, metres (reading filter; off by default). The "
             f"paper used 150 in = {PAPER_MAX_RANGE:.2f} m on its robot; pick yours from your "
             "sensors' height and floor.", rich_help_panel="Filters")] = None,
    min_range: Annotated[float | None, typer.Option(
        help="Drop readings nearer than this, metres (reading filter).",
        rich_help_panel="Filters")] = None,
    jump_threshold: Annotated[float | None, typer.Option(
        help="Drop a reading whose range differs by more than this (metres) from the same "
             "sensor's previous reading: a jumping sensor is ignored for one reading.",
        rich_help_panel="Filters")] = None,
    outlier_radius: Annotated[float | None, typer.Option(
        help="Map filter: drop points with fewer than --outlier-neighbours other points within "
             "this radius, metres.", rich_help_panel="Filters")] = None,
    outlier_neighbours: Annotated[int, typer.Option(
        help="k of the outlier test (needs --outlier-radius).", rich_help_panel="Filters")] = 1,
    max_error: Annotated[float | None, typer.Option(
        help="Map filter: drop points whose error bound max_error exceeds this, metres "
             "(paper, Fig. 13b).", rich_help_panel="Filters")] = None,
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
    config = _config(method, history, beam_width, range_tolerance, min_transversal,
                     max_incidence)
    reading_filter, map_filter = _filters(max_range, min_range, jump_threshold, outlier_radius,
                                          outlier_neighbours, max_error)
    check_output_file(out, inputs=[readings], label=f"--out {out}")
    batch = read_readings_csv(readings)
    sonar = make_method(method, config)
    if len(batch) >= _PROGRESS_MIN_READINGS:
        with progress() as bar:
            task = bar.add_task(f"{method}", total=len(batch))
            result = process_readings(
                batch, sonar, on_progress=lambda n: bar.update(task, completed=n),
                reading_filter=reading_filter, map_filter=map_filter)
    else:
        result = process_readings(batch, sonar, reading_filter=reading_filter,
                                  map_filter=map_filter)
    write_map_csv(result.global_map, out)
    console.print(_summary(method, result, out))


def _config(method: str, history: int, beam_width_deg: float, tolerance: float,
            transversal_deg: float, incidence_deg: float | None = None) -> MethodConfig:
    if method not in METHODS:
        msg = f"unknown method {method!r}; choose one of {', '.join(METHODS)}"
        raise ParameterError(msg)
    if history < 1:
        msg = f"--history must be at least 1, got {history}"
        raise ParameterError(msg)
    if not 0.0 < beam_width_deg < 180.0:
        msg = f"--beam-width must lie in (0, 180) degrees, got {beam_width_deg}"
        raise ParameterError(msg)
    if not (tolerance >= 0.0 and math.isfinite(tolerance)):
        msg = f"--range-tolerance must be a finite number >= 0, got {tolerance}"
        raise ParameterError(msg)
    if not 0.0 <= transversal_deg <= 90.0:
        msg = f"--min-transversal must lie in [0, 90] degrees, got {transversal_deg}"
        raise ParameterError(msg)
    incidence = MethodConfig.max_incidence
    if incidence_deg is not None:
        if not 0.0 < incidence_deg <= 90.0:
            msg = f"--max-incidence must lie in (0, 90] degrees, got {incidence_deg}"
            raise ParameterError(msg)
        incidence = min(math.radians(incidence_deg), MethodConfig.max_incidence)
    return MethodConfig(history_size=history, beam_width=math.radians(beam_width_deg),
                        range_tolerance=tolerance, min_transversal=math.radians(transversal_deg),
                        max_incidence=incidence)


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
