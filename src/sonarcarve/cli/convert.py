"""``sonarcarve convert``: turn a data set's own files into the readings CSV."""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path
from typing import Annotated

import typer
from rich.table import Table

from sonarcarve.cli.app import app, console, summary_table
from sonarcarve.errors import SonarcarveError
from sonarcarve.io import read_robond, write_readings_csv
from sonarcarve.io.atomic import check_output_file
from sonarcarve.io.roboND import ROBOND_BEAM_WIDTH, bundled_robond_dir

__all__ = ["CONVERTERS", "convert"]


class ConvertError(SonarcarveError):
    """An unknown format or a bad parameter of ``convert``."""


def _robond(directory: Path | None, out: Path, beam_width: float | None,
            keep_duplicates: bool) -> Table:
    log = read_robond(directory, keep_duplicates=keep_duplicates,
                      beam_width=ROBOND_BEAM_WIDTH if beam_width is None else beam_width)
    write_readings_csv(log.batch, out)
    r = log.report
    source = directory if directory is not None else f"{bundled_robond_dir()} (bundled)"
    return summary_table(f"roboND log: {source}", [
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


#: Format name (lower case) -> converter(directory, out, beam width rad or None, keep dups).
CONVERTERS: dict[str, Callable[[Path | None, Path, float | None, bool], Table]] = {
    "robond": _robond,
}


@app.command()
def convert(
    fmt: Annotated[str, typer.Argument(
        metavar="FORMAT", help="Data set format: roboND (the bundled 8-sensor real log).")],
    out: Annotated[Path, typer.Option(
        "--out", "-o", metavar="READINGS.csv",
        help="Readings CSV to write (seconds, metres, radians). Its folder must exist.")],
    directory: Annotated[Path | None, typer.Argument(
        metavar="FOLDER",
        help="Folder holding the data set's files; default: the copy bundled with sonarcarve.")]
        = None,
    beam_width: Annotated[float | None, typer.Option(
        metavar="DEGREES",
        help="Beam width φ in degrees written with each reading (roboND default: 20).")] = None,
    keep_duplicates: Annotated[bool, typer.Option(
        help="Keep values that repeat while the robot stands still (they add identical arcs).")]
        = False,
) -> None:
    """Convert a data set's files into the readings CSV (t,sensor,x,y,theta,range,beam_width).

    roboND: `poses.txt` (ms, mm, tenths of a degree) and `measurement.txt` (mm; 5110 = no
    echo) become one reading per echo in seconds, metres and radians (world frame). No-echo
    values are dropped, and so are stale repeats: a value equal to the same sensor's value in
    the previous record although the robot moved (the sensor had not fired again).

    Example: `sonarcarve convert roboND --out roboND.csv` then
    `sonarcarve process roboND.csv --out map.csv`.
    """
    converter = CONVERTERS.get(fmt.lower())
    if converter is None:
        msg = f"unknown format {fmt!r}; choose one of: roboND"
        raise ConvertError(msg)
    width = None
    if beam_width is not None:
        if not 0.0 < beam_width < 180.0:
            msg = f"--beam-width must lie in (0, 180) degrees, got {beam_width}"
            raise ConvertError(msg)
        width = math.radians(beam_width)
    # The data set's own files must survive a --out that names one of them.
    inputs = sorted(directory.iterdir()) if directory is not None and directory.is_dir() else []
    check_output_file(out, inputs=inputs, label=f"--out {out}")
    console.print(converter(directory, out, width, keep_duplicates))
