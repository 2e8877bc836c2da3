"""The readings CSV, the interchange format of the design (``t,sensor,x,y,theta,range``).

One row per echo; an optional ``beam_width`` column (radians). Units: seconds, metres, radians
counter-clockwise from +x. Column order is free on reading; extra columns are ignored.
"""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np

from sonarcarve.io.atomic import atomic_text
from sonarcarve.io.errors import InputError
from sonarcarve.readings import ReadingBatch, ReadingsError

__all__ = ["READINGS_COLUMNS", "read_readings_csv", "write_readings_csv"]

#: Required columns, in the order they are written.
READINGS_COLUMNS = ("t", "sensor", "x", "y", "theta", "range")
_OPTIONAL = "beam_width"


def read_readings_csv(path: str | Path) -> ReadingBatch:
    """Read and validate a readings CSV.

    Raises
    ------
    InputError
        One line naming the file, the line and the column of the first problem: a missing file
        or column, a non-numeric, NaN or infinite value, range <= 0, beam width outside (0, π),
        time going backwards.
    """
    path = Path(path)
    try:
        with path.open(newline="", encoding="utf-8") as handle:
            rows = list(csv.reader(handle))
    except FileNotFoundError:
        msg = f"{path}: no such file"
        raise InputError(msg) from None
    except (OSError, UnicodeDecodeError, csv.Error) as err:
        msg = f"{path}: cannot read as CSV ({err})"
        raise InputError(msg) from None
    if not rows:
        msg = f"{path}: empty file, expected a header {','.join(READINGS_COLUMNS)}"
        raise InputError(msg)
    header = [name.strip() for name in rows[0]]
    missing = [name for name in READINGS_COLUMNS if name not in header]
    if missing:
        msg = f"{path}: line 1, missing column(s) {', '.join(missing)} (header: {','.join(header)})"
        raise InputError(msg)
    wanted = [*READINGS_COLUMNS, *([_OPTIONAL] if _OPTIONAL in header else [])]
    columns = {name: _column(path, rows, header.index(name), name) for name in wanted}
    try:
        return ReadingBatch.from_arrays(**columns, source=str(path), first_line=2)
    except ReadingsError as err:
        raise InputError(str(err)) from None


def _column(path: Path, rows: list[list[str]], index: int, name: str) -> np.ndarray:
    values = np.empty(len(rows) - 1)
    for line, row in enumerate(rows[1:], start=2):
        if name == _OPTIONAL and index < len(row) and not row[index].strip():
            values[line - 2] = math.nan  # unknown beam width: the method's default applies
            continue
        try:
            values[line - 2] = float(row[index])
        except (ValueError, IndexError):
            text = row[index] if index < len(row) else ""
            msg = f"{path}: line {line}, column {name!r} is not a number: {text!r}"
            raise InputError(msg) from None
        if name == "sensor" and not float(row[index]).is_integer():
            msg = f"{path}: line {line}, column 'sensor' is not a whole number: {row[index]!r}"
            raise InputError(msg)
    return values


def write_readings_csv(batch: ReadingBatch, path: str | Path) -> None:
    """Write ``batch`` as a readings CSV (atomically); ``beam_width`` only where known."""
    with_width = not bool(np.all(np.isnan(batch.beam_width)))
    header = [*READINGS_COLUMNS, *([_OPTIONAL] if with_width else [])]
    with atomic_text(path) as handle:
        writer = csv.writer(handle, lineterminator="\n")
        writer.writerow(header)
        for reading in batch:
            row = [_fmt(reading.t), str(reading.sensor), _fmt(reading.x), _fmt(reading.y),
                   _fmt(reading.theta), _fmt(reading.range)]
            if with_width:
                row.append("" if math.isnan(reading.beam_width) else _fmt(reading.beam_width))
            writer.writerow(row)


def _fmt(value: float) -> str:
    """Shortest text that reads back to the same float."""
    return repr(float(value))
