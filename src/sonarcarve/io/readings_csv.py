"""The readings CSV, the interchange format of the design (``t,sensor,x,y,theta,range``).

One row per echo; an optional ``beam_width`` column (radians). Units: seconds, metres, radians
counter-clockwise from +x. Column order is free on reading; extra columns are ignored.

Reading is strict, so that a damaged file fails loudly instead of mapping the wrong numbers:
every line must have as many fields as the header, no column name may appear twice, and a
blank line is an error unless only blank lines follow it (a trailing newline or two at the end
of a file is common and harmless; a blank line in the middle usually marks two logs pasted
together). A UTF-8 byte-order mark, as spreadsheet programs write, is accepted.
"""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np

from sonarcarve.io.atomic import atomic_text
from sonarcarve.io.errors import InputError, parse_number
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
        or column, a duplicated column name, a line with more or fewer fields than the header,
        a blank line before the last data line, a non-numeric, NaN or infinite value, a sensor
        that is not a whole number, range <= 0, beam width outside (0, π), time going
        backwards.
    """
    path = Path(path)
    try:
        # utf-8-sig: a byte-order mark (Excel's "CSV UTF-8") would otherwise glue onto "t".
        with path.open(newline="", encoding="utf-8-sig") as handle:
            reader = csv.reader(handle)
            rows = [(reader.line_num, row) for row in reader]
    except FileNotFoundError:
        msg = f"{path}: no such file"
        raise InputError(msg) from None
    except (OSError, UnicodeDecodeError, csv.Error) as err:
        msg = f"{path}: cannot read as CSV ({err})"
        raise InputError(msg) from None
    while rows and not rows[-1][1]:
        rows.pop()  # blank lines at the end
    if not rows:
        msg = f"{path}: empty file, expected a header {','.join(READINGS_COLUMNS)}"
        raise InputError(msg)
    header = [name.strip() for name in rows[0][1]]
    _check_header(path, header)
    body = rows[1:]
    _check_shape(path, body, len(header))
    wanted = [*READINGS_COLUMNS, *([_OPTIONAL] if _OPTIONAL in header else [])]
    columns = {name: _column(path, body, header.index(name), name) for name in wanted}
    try:
        return ReadingBatch.from_arrays(**columns, source=str(path), first_line=2)
    except ReadingsError as err:
        raise InputError(str(err)) from None


def _check_header(path: Path, header: list[str]) -> None:
    seen: set[str] = set()
    for name in header:
        if name and name in seen:
            msg = f"{path}: line 1, column {name!r} appears twice (header: {','.join(header)})"
            raise InputError(msg)
        seen.add(name)
    missing = [name for name in READINGS_COLUMNS if name not in header]
    if missing:
        msg = f"{path}: line 1, missing column(s) {', '.join(missing)} (header: {','.join(header)})"
        raise InputError(msg)


def _check_shape(path: Path, body: list[tuple[int, list[str]]], width: int) -> None:
    """Every data line has the header's number of fields; no blank line among them."""
    for line, row in body:
        if not row:
            msg = f"{path}: line {line} is blank (blank lines are allowed only at the end)"
            raise InputError(msg)
        if len(row) != width:
            fields = f"{len(row)} field{'' if len(row) == 1 else 's'}"
            msg = f"{path}: line {line} has {fields}, the header has {width}"
            raise InputError(msg)


def _column(path: Path, body: list[tuple[int, list[str]]], index: int, name: str) -> np.ndarray:
    values = np.empty(len(body))
    for k, (line, row) in enumerate(body):
        text = row[index]
        if name == _OPTIONAL and not text.strip():
            values[k] = math.nan  # unknown beam width: the method's default applies
            continue
        # NaN and infinities pass here: validation names them with the row's context.
        values[k] = parse_number(text, f"{path}: line {line}", name, finite=False)
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
